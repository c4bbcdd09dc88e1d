//! Producing nodes for the atlas (Ulrich section 15): either inline, on the
//! caller's thread (deterministic, for tests), or on a loader thread fed
//! through a bounded queue whose results come back through a second channel.
//!
//! Height buffers circulate instead of being allocated: each request carries
//! a spare buffer to the loader, the atlas swaps a loaded buffer into its slot
//! and hands the slot's old buffer back as a spare. The pool holds
//! `queue + 2` buffers with a thread (queued, being read, being returned),
//! one inline, so in-flight loads never exceed it and the result channel,
//! sized to the pool, never blocks the loader.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, SyncSender, TryRecvError, TrySendError};
use std::sync::Arc;
use std::thread::JoinHandle;

use super::hash::{node_set, NodeSet};
use crate::node::{NodeData, NodeError, NodeId, NodeLayout, NodeSource};

/// Where nodes are produced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LoaderMode {
    /// On the updating thread, at most `budget` per frame, in priority order.
    Inline,
    /// On a loader thread; `queue` requests may wait in its bounded queue.
    Thread { queue: usize },
}

/// A finished load.
pub(crate) struct Loaded {
    pub id: NodeId,
    pub data: NodeData,
    pub outcome: Result<(), NodeError>,
}

struct Request {
    id: NodeId,
    data: NodeData,
}

/// The loader thread and its two channels.
struct Worker {
    requests: Option<SyncSender<Request>>,
    results: Option<Receiver<Loaded>>,
    stop: Arc<AtomicBool>,
    handle: Option<JoinHandle<()>>,
}

/// Invariant: `spare.len() + in_flight.len()` is the pool size.
pub(crate) struct Loader {
    source: Arc<dyn NodeSource>,
    spare: Vec<NodeData>,
    in_flight: NodeSet,
    worker: Option<Worker>,
    pool: usize,
}

impl Loader {
    pub fn new(source: Arc<dyn NodeSource>, mode: LoaderMode) -> std::io::Result<Self> {
        let layout: NodeLayout = *source.layout();
        let (pool, worker) = match mode {
            LoaderMode::Inline => (1, None),
            LoaderMode::Thread { queue } => {
                (queue + 2, Some(spawn(source.clone(), queue, queue + 2)?))
            }
        };
        Ok(Loader {
            source,
            spare: (0..pool).map(|_| NodeData::with_capacity(&layout)).collect(),
            in_flight: node_set(2 * pool),
            worker,
            pool,
        })
    }

    pub fn is_threaded(&self) -> bool {
        self.worker.is_some()
    }

    pub fn is_loading(&self, id: NodeId) -> bool {
        self.in_flight.contains(&id)
    }

    pub fn in_flight(&self) -> u32 {
        self.in_flight.len() as u32
    }

    /// Reads `id` on this thread into a spare buffer.
    pub fn load_now(&mut self, id: NodeId) -> Loaded {
        let mut data = self.spare.pop().expect("the inline loader's buffer is out");
        let outcome = self.source.read_node(id, &mut data);
        Loaded { id, data, outcome }
    }

    /// Queues `id` for the loader thread; false when the queue is full, no
    /// buffer is spare or the thread is gone.
    pub fn request(&mut self, id: NodeId) -> bool {
        let Some(sender) = self.worker.as_ref().and_then(|w| w.requests.as_ref()) else {
            return false;
        };
        let Some(data) = self.spare.pop() else {
            return false;
        };
        match sender.try_send(Request { id, data }) {
            Ok(()) => {
                self.in_flight.insert(id);
                true
            }
            Err(TrySendError::Full(back) | TrySendError::Disconnected(back)) => {
                self.spare.push(back.data);
                false
            }
        }
    }

    /// The next load the thread finished, if any; `Err` when the thread has
    /// died (a source panicked).
    pub fn try_finished(&mut self) -> Result<Option<Loaded>, LoaderStopped> {
        let Some(results) = self.worker.as_ref().and_then(|w| w.results.as_ref()) else {
            return Ok(None);
        };
        match results.try_recv() {
            Ok(loaded) => {
                let was_loading = self.in_flight.remove(&loaded.id);
                debug_assert!(was_loading, "{:?} came back without a request", loaded.id);
                Ok(Some(loaded))
            }
            Err(TryRecvError::Empty) => Ok(None),
            Err(TryRecvError::Disconnected) => Err(LoaderStopped),
        }
    }

    /// Takes back a buffer (a slot's old one, or a load that was not used).
    pub fn recycle(&mut self, data: NodeData) {
        self.spare.push(data);
        debug_assert_eq!(self.spare.len() + self.in_flight.len(), self.pool);
    }
}

/// The loader thread has stopped.
#[derive(Debug)]
pub(crate) struct LoaderStopped;

fn spawn(source: Arc<dyn NodeSource>, queue: usize, pool: usize) -> std::io::Result<Worker> {
    let (request_tx, request_rx) = mpsc::sync_channel::<Request>(queue);
    let (result_tx, result_rx) = mpsc::sync_channel::<Loaded>(pool);
    let stop = Arc::new(AtomicBool::new(false));
    let stop_flag = stop.clone();
    let handle =
        std::thread::Builder::new().name("ridgeline-node-loader".into()).spawn(move || {
            while let Ok(Request { id, mut data }) = request_rx.recv() {
                if stop_flag.load(Ordering::Relaxed) {
                    break;
                }
                let outcome = source.read_node(id, &mut data);
                if result_tx.send(Loaded { id, data, outcome }).is_err() {
                    break;
                }
            }
        })?;
    Ok(Worker { requests: Some(request_tx), results: Some(result_rx), stop, handle: Some(handle) })
}

impl Drop for Worker {
    fn drop(&mut self) {
        // Closing both channels ends the thread after at most one read.
        self.stop.store(true, Ordering::Relaxed);
        self.requests.take();
        self.results.take();
        if let Some(handle) = self.handle.take() {
            let _ = handle.join(); // a panic in the source was already reported by update
        }
    }
}
