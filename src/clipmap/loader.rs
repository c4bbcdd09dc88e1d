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
//!
//! # Cancelling
//! Each request carries a ticket, one of `pool` cancel flags shared with the
//! thread. Every frame the clipmap raises the flag of each queued node no
//! view wants any more (and lowers it again if a view wants it back); the
//! thread skips a request whose flag is up and returns its buffer unread
//! ([`Outcome::Cancelled`]). A read already under way finishes.
//!
//! # Failed reads
//! [`Loader::failure`] decides what a failed read means:
//! - an I/O error ([`NodeError::Io`]) may pass: the node is read again after
//!   [`RETRY_FIRST_DELAY_FRAMES`] frames, then after twice as many each time
//!   (4, 8, 16, 32 frames: 67 ms to 0.5 s at 60 frames per second), and
//!   given up after [`READ_ATTEMPTS`] failed reads, about a second in all;
//! - a checksum failure ([`NodeError::Corrupt`]) is not retried: the bytes
//!   come from the page cache of a file Ridgeline never changes in place, so
//!   reading again reads the same bad bytes;
//! - a node outside the source is not retried either.
//!
//! A node given up is never requested again; the views fall back to its
//! finest resident ancestor. The waiting retries live in a table sized at
//! construction; only more than [`RETRY_TABLE`] simultaneous failing nodes
//! would make it grow (and failures are not steady-state frames).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, SyncSender, TryRecvError, TrySendError};
use std::sync::Arc;
use std::thread::JoinHandle;

use super::hash::{node_map, node_set, NodeMap, NodeSet};
use crate::node::{NodeData, NodeError, NodeId, NodeLayout, NodeSource};

/// Reads of one node that may fail with an I/O error before the node is given
/// up and treated as missing.
pub const READ_ATTEMPTS: u32 = 5;
/// Frames between a node's first failed read and its second; each further
/// wait doubles.
pub const RETRY_FIRST_DELAY_FRAMES: u64 = 4;
/// Nodes waiting for a retry that the table holds without allocating.
const RETRY_TABLE: usize = 64;

/// Where nodes are produced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LoaderMode {
    /// On the updating thread, at most `budget` per frame, in priority order.
    Inline,
    /// On a loader thread; `queue` requests may wait in its bounded queue.
    Thread {
        /// Requests that may wait in the loader's bounded queue.
        queue: usize,
    },
}

/// What became of a request.
pub(crate) enum Outcome {
    /// The node's data is in the buffer.
    Read,
    Failed(NodeError),
    /// Cancelled before the thread read it; the buffer is untouched.
    Cancelled,
}

/// A finished load.
pub(crate) struct Loaded {
    pub id: NodeId,
    pub data: NodeData,
    pub outcome: Outcome,
}

struct Request {
    id: NodeId,
    data: NodeData,
    /// Index of the request's cancel flag.
    ticket: usize,
}

/// What a failed read means for the node (see the module notes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Verdict {
    /// Read it again, not before `frame`; `failures` reads have failed.
    RetryAt { frame: u64, failures: u32 },
    /// The I/O error persisted through [`READ_ATTEMPTS`] reads.
    GaveUp,
    /// Its bytes failed their check.
    Damaged,
    /// The source has no such node or cannot produce it.
    Refused,
}

/// A node whose last read failed with an I/O error.
#[derive(Clone, Copy, Debug)]
struct Backoff {
    failures: u32,
    /// The first frame it may be requested again.
    due: u64,
}

/// The loader thread and its two channels.
struct Worker {
    requests: Option<SyncSender<Request>>,
    results: Option<Receiver<Loaded>>,
    stop: Arc<AtomicBool>,
    handle: Option<JoinHandle<()>>,
}

/// Invariants: `spare.len() + in_flight.len()` is the pool size, and so is
/// `tickets.len() + in_flight.len()` with a thread.
pub(crate) struct Loader {
    source: Arc<dyn NodeSource>,
    spare: Vec<NodeData>,
    /// Requested nodes and their tickets.
    in_flight: NodeMap<usize>,
    /// Tickets no request holds.
    tickets: Vec<usize>,
    /// One cancel flag per ticket, shared with the thread.
    cancel: Arc<[AtomicBool]>,
    /// Nodes waiting for another read after an I/O error.
    retries: NodeMap<Backoff>,
    /// Nodes given up for good (damaged, refused, or unreadable).
    given_up: NodeSet,
    worker: Option<Worker>,
    pool: usize,
    /// Fit each buffer read to its node (an atlas counted in bytes).
    fit: bool,
}

impl Loader {
    /// A loader over `source`; with `fit`, each buffer read is fitted to
    /// its node ([`NodeData::fit`]) for an atlas counted in bytes.
    pub fn new(source: Arc<dyn NodeSource>, mode: LoaderMode, fit: bool) -> std::io::Result<Self> {
        let layout: NodeLayout = *source.layout();
        let pool = match mode {
            LoaderMode::Inline => 1,
            LoaderMode::Thread { queue } => queue + 2,
        };
        let cancel: Arc<[AtomicBool]> = (0..pool).map(|_| AtomicBool::new(false)).collect();
        let worker = match mode {
            LoaderMode::Inline => None,
            LoaderMode::Thread { queue } => {
                Some(spawn(source.clone(), queue, pool, cancel.clone(), fit)?)
            }
        };
        Ok(Loader {
            source,
            spare: (0..pool).map(|_| NodeData::with_capacity(&layout)).collect(),
            in_flight: node_map(2 * pool),
            tickets: (0..pool).rev().collect(),
            cancel,
            retries: node_map(RETRY_TABLE),
            given_up: node_set(RETRY_TABLE),
            worker,
            pool,
            fit,
        })
    }

    pub fn is_threaded(&self) -> bool {
        self.worker.is_some()
    }

    pub fn is_loading(&self, id: NodeId) -> bool {
        self.in_flight.contains_key(&id)
    }

    pub fn in_flight(&self) -> u32 {
        self.in_flight.len() as u32
    }

    /// The nodes with the loader thread.
    pub fn in_flight_ids(&self) -> impl Iterator<Item = NodeId> + '_ {
        self.in_flight.keys().copied()
    }

    /// Whether `id` may be requested in `frame`: not loading, not given up,
    /// and not waiting out a retry delay.
    pub fn may_request(&self, id: NodeId, frame: u64) -> bool {
        !self.in_flight.contains_key(&id)
            && !self.given_up.contains(&id)
            && self.retries.get(&id).is_none_or(|b| frame >= b.due)
    }

    /// Whether `id` was given up (damaged, refused or unreadable).
    pub fn has_given_up(&self, id: NodeId) -> bool {
        self.given_up.contains(&id)
    }

    /// Reads `id` on this thread into a spare buffer.
    pub fn load_now(&mut self, id: NodeId) -> Loaded {
        let mut data = self.spare.pop().expect("the inline loader's buffer is out");
        let outcome = read(self.source.as_ref(), id, &mut data, self.fit);
        Loaded { id, data, outcome }
    }

    /// Queues `id` for the loader thread; false when the queue is full, no
    /// buffer is spare or the thread is gone.
    pub fn request(&mut self, id: NodeId) -> bool {
        let Some(sender) = self.worker.as_ref().and_then(|w| w.requests.as_ref()) else {
            return false;
        };
        let (Some(data), Some(&ticket)) = (self.spare.pop(), self.tickets.last()) else {
            return false;
        };
        self.cancel[ticket].store(false, Ordering::Release);
        match sender.try_send(Request { id, data, ticket }) {
            Ok(()) => {
                self.tickets.pop();
                self.in_flight.insert(id, ticket);
                true
            }
            Err(TrySendError::Full(back) | TrySendError::Disconnected(back)) => {
                self.spare.push(back.data);
                false
            }
        }
    }

    /// Raises the cancel flag of every queued node `wanted` says no view
    /// wants, and lowers it for the others; returns how many are raised.
    pub fn cancel_unwanted(&mut self, wanted: impl Fn(NodeId) -> bool) -> u32 {
        let mut raised = 0;
        for (&id, &ticket) in &self.in_flight {
            let cancel = !wanted(id);
            self.cancel[ticket].store(cancel, Ordering::Release);
            raised += cancel as u32;
        }
        raised
    }

    /// The next load the thread finished, if any; `Err` when the thread has
    /// died (a source panicked).
    pub fn try_finished(&mut self) -> Result<Option<Loaded>, LoaderStopped> {
        let Some(results) = self.worker.as_ref().and_then(|w| w.results.as_ref()) else {
            return Ok(None);
        };
        match results.try_recv() {
            Ok(loaded) => {
                let ticket = self.in_flight.remove(&loaded.id);
                debug_assert!(ticket.is_some(), "{:?} came back without a request", loaded.id);
                self.tickets.extend(ticket);
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

    /// A read of `id` succeeded: forget its failures.
    pub fn succeeded(&mut self, id: NodeId) {
        if !self.retries.is_empty() {
            self.retries.remove(&id);
        }
    }

    /// A read of `id` in `frame` failed with `error`: schedules a retry or
    /// gives the node up (see the module notes).
    pub fn failure(&mut self, id: NodeId, error: &NodeError, frame: u64) -> Verdict {
        let verdict = match error {
            NodeError::Io { .. } => {
                let failures = self.retries.get(&id).map_or(0, |b| b.failures) + 1;
                if failures >= READ_ATTEMPTS {
                    Verdict::GaveUp
                } else {
                    let delay = RETRY_FIRST_DELAY_FRAMES << (failures - 1);
                    Verdict::RetryAt { frame: frame + delay, failures }
                }
            }
            NodeError::Corrupt { .. } => Verdict::Damaged,
            NodeError::OutOfRange { .. }
            | NodeError::OutsideData { .. }
            | NodeError::Absent { .. } => Verdict::Refused,
        };
        match verdict {
            Verdict::RetryAt { frame, failures } => {
                self.retries.insert(id, Backoff { failures, due: frame });
            }
            _ => {
                self.retries.remove(&id);
                self.given_up.insert(id);
            }
        }
        verdict
    }
}

/// Reads `id` into `data`, fitting its buffers to it when `fit`.
fn read(source: &dyn NodeSource, id: NodeId, data: &mut NodeData, fit: bool) -> Outcome {
    match source.read_node(id, data) {
        Ok(()) => {
            if fit {
                data.fit();
            }
            Outcome::Read
        }
        Err(error) => Outcome::Failed(error),
    }
}

/// The loader thread has stopped.
#[derive(Debug)]
pub(crate) struct LoaderStopped;

fn spawn(
    source: Arc<dyn NodeSource>,
    queue: usize,
    pool: usize,
    cancel: Arc<[AtomicBool]>,
    fit: bool,
) -> std::io::Result<Worker> {
    let (request_tx, request_rx) = mpsc::sync_channel::<Request>(queue);
    let (result_tx, result_rx) = mpsc::sync_channel::<Loaded>(pool);
    let stop = Arc::new(AtomicBool::new(false));
    let stop_flag = stop.clone();
    let handle =
        std::thread::Builder::new().name("ridgeline-node-loader".into()).spawn(move || {
            while let Ok(Request { id, mut data, ticket }) = request_rx.recv() {
                if stop_flag.load(Ordering::Relaxed) {
                    break;
                }
                let outcome = if cancel[ticket].load(Ordering::Acquire) {
                    Outcome::Cancelled
                } else {
                    read(source.as_ref(), id, &mut data, fit)
                };
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
