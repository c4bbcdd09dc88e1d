//! The receiver: a thread that owns the UDP socket and the protocol's
//! decoder, takes or ignores each datagram, and publishes the live state
//! for frames to read.
//!
//! The frame never waits on it: the thread holds the state's lock only to
//! copy a finished state in, and a frame only tries the lock
//! ([`LiveInput::snapshot`]); when the thread holds it at that instant the
//! frame keeps the copy it took last. Decoding, checking and recording all
//! happen on the thread, into a fixed receive buffer. Every datagram is
//! counted once, as taken or as ignored with its reason ([`Counts`]).

use std::net::{SocketAddr, UdpSocket};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, TryLockError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::record::{RecordError, Recorder};
use super::state::{LiveState, LiveView};
use super::update::Ignored;
use super::{Decoder, InputKind, InputSpec};

/// The largest datagram taken, bytes: FlightGear's 552, X-Plane's `DATA`
/// with a hundred groups, a GDL 90 datagram of several uplinks. Larger
/// ones are ignored as [`Ignored::Oversize`].
pub const MAX_DATAGRAM_BYTES: usize = 4096;
/// How often the thread looks at its stop flag, and asks X-Plane again.
const POLL: Duration = Duration::from_millis(50);
/// How often an `RPOS` request is repeated while no data come.
const REQUEST_EVERY: Duration = Duration::from_secs(2);

/// Datagrams counted by outcome.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    /// Datagrams taken (they changed the live state).
    pub taken: u64,
    /// Datagrams ignored, by reason, in [`Ignored::ALL`] order.
    pub ignored: [u64; Ignored::ALL.len()],
    /// Socket errors the thread carried on after.
    pub socket_errors: u64,
}

impl Counts {
    /// Every datagram ignored.
    pub fn ignored_total(&self) -> u64 {
        self.ignored.iter().sum()
    }

    /// Every datagram counted.
    pub fn datagrams(&self) -> u64 {
        self.taken + self.ignored_total()
    }

    /// Datagrams ignored for `reason`.
    pub fn ignored_for(&self, reason: Ignored) -> u64 {
        self.ignored[reason as usize]
    }
}

impl serde::Serialize for Counts {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let mut s = serializer.serialize_struct("Counts", 4)?;
        s.serialize_field("taken", &self.taken)?;
        s.serialize_field("ignored", &self.ignored_total())?;
        let by_reason: std::collections::BTreeMap<&str, u64> =
            Ignored::ALL.iter().map(|&r| (r.name(), self.ignored_for(r))).collect();
        s.serialize_field("ignored_by_reason", &by_reason)?;
        s.serialize_field("socket_errors", &self.socket_errors)?;
        s.end()
    }
}

/// How the receiver runs.
#[derive(Clone, Debug, PartialEq)]
pub struct ReceiverOptions {
    /// A frame this long after the newest valid sample is stale (also the
    /// silence after which a jump is taken as a reposition).
    pub stale: Duration,
    /// The geoid's height above the WGS 84 ellipsoid, metres (GDL 90).
    pub geoid_m: f64,
    /// Record the poses taken to this CSV file.
    pub record: Option<PathBuf>,
    /// Ask X-Plane at this address for `RPOS` (sent from the input's own
    /// socket, so X-Plane answers to it).
    pub xplane_request: Option<SocketAddr>,
}

impl Default for ReceiverOptions {
    fn default() -> Self {
        ReceiverOptions {
            stale: Duration::from_millis(1000),
            geoid_m: 0.0,
            record: None,
            xplane_request: None,
        }
    }
}

/// Why the receiver could not start or finish.
#[derive(Debug, thiserror::Error)]
pub enum ReceiverError {
    /// The socket could not be bound.
    #[error("--input {kind}: cannot listen on {address}: {source}")]
    Bind {
        /// The protocol.
        kind: &'static str,
        /// The address asked for.
        address: SocketAddr,
        /// Why.
        source: std::io::Error,
    },
    /// The recording could not be written.
    #[error(transparent)]
    Record(#[from] RecordError),
    /// The thread could not be started, or ended in a panic (a bug).
    #[error("the input thread: {0}")]
    Thread(String),
}

struct Shared {
    state: Mutex<LiveState>,
    taken: AtomicU64,
    ignored: [AtomicU64; Ignored::ALL.len()],
    socket_errors: AtomicU64,
    stop: AtomicBool,
}

/// A live input: the receiver thread and the frame's side of it.
pub struct LiveInput {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<Result<u64, RecordError>>>,
    local: SocketAddr,
    kind: InputKind,
    /// The frame's copy of the state, kept when the lock is busy.
    last: LiveState,
}

impl LiveInput {
    /// Binds `spec`'s address and starts the receiver thread.
    pub fn start(spec: &InputSpec, options: &ReceiverOptions) -> Result<LiveInput, ReceiverError> {
        let bind =
            |source| ReceiverError::Bind { kind: spec.kind.name(), address: spec.address, source };
        let socket = UdpSocket::bind(spec.address).map_err(bind)?;
        socket.set_read_timeout(Some(POLL)).map_err(bind)?;
        let local = socket.local_addr().map_err(bind)?;
        let recorder = options.record.as_deref().map(Recorder::create).transpose()?;
        let shared = Arc::new(Shared {
            state: Mutex::new(LiveState::default()),
            taken: AtomicU64::new(0),
            ignored: std::array::from_fn(|_| AtomicU64::new(0)),
            socket_errors: AtomicU64::new(0),
            stop: AtomicBool::new(false),
        });
        let mut worker = Worker {
            socket,
            decoder: Decoder::new(spec.kind, options.geoid_m),
            state: LiveState::default(),
            shared: Arc::clone(&shared),
            stale: options.stale,
            recorder,
            xplane_request: options.xplane_request,
        };
        let thread = std::thread::Builder::new()
            .name(format!("input-{}", spec.kind.name()))
            .spawn(move || worker.run())
            .map_err(|e| ReceiverError::Thread(e.to_string()))?;
        Ok(LiveInput {
            shared,
            thread: Some(thread),
            local,
            kind: spec.kind,
            last: LiveState::default(),
        })
    }

    /// The address the socket is bound to (the port the system chose for port 0).
    pub fn local_addr(&self) -> SocketAddr {
        self.local
    }

    /// The protocol.
    pub fn kind(&self) -> InputKind {
        self.kind
    }

    /// The newest state the thread published, without waiting: when the
    /// thread is publishing at this instant, the copy taken last time.
    pub fn snapshot(&mut self) -> LiveState {
        match self.shared.state.try_lock() {
            Ok(state) => self.last = *state,
            Err(TryLockError::Poisoned(state)) => self.last = *state.into_inner(),
            Err(TryLockError::WouldBlock) => {}
        }
        self.last
    }

    /// The datagrams counted so far.
    pub fn counts(&self) -> Counts {
        let load = |a: &AtomicU64| a.load(Ordering::Acquire);
        Counts {
            taken: load(&self.shared.taken),
            ignored: std::array::from_fn(|k| load(&self.shared.ignored[k])),
            socket_errors: load(&self.shared.socket_errors),
        }
    }

    /// Stops the thread and finishes the recording; the rows recorded.
    pub fn stop(mut self) -> Result<u64, ReceiverError> {
        self.join()
    }

    fn join(&mut self) -> Result<u64, ReceiverError> {
        self.shared.stop.store(true, Ordering::Release);
        match self.thread.take().map(JoinHandle::join) {
            None => Ok(0),
            Some(Ok(recorded)) => Ok(recorded?),
            Some(Err(_)) => Err(ReceiverError::Thread("panicked".to_owned())),
        }
    }
}

impl Drop for LiveInput {
    fn drop(&mut self) {
        let _ = self.join();
    }
}

/// The thread's side.
struct Worker {
    socket: UdpSocket,
    decoder: Decoder,
    state: LiveState,
    shared: Arc<Shared>,
    stale: Duration,
    recorder: Option<Recorder>,
    xplane_request: Option<SocketAddr>,
}

impl Worker {
    fn run(&mut self) -> Result<u64, RecordError> {
        let mut buffer = [0u8; MAX_DATAGRAM_BYTES + 1];
        let mut requested: Option<Instant> = None;
        let mut record_error = None;
        while !self.shared.stop.load(Ordering::Acquire) {
            self.request_rpos(&mut requested);
            let length = match self.socket.recv_from(&mut buffer) {
                Ok((length, _)) => length,
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                    ) =>
                {
                    continue
                }
                Err(_) => {
                    // An ICMP error from an earlier send, say: count, go on.
                    self.shared.socket_errors.fetch_add(1, Ordering::AcqRel);
                    std::thread::sleep(POLL);
                    continue;
                }
            };
            let now = Instant::now();
            match self.take(&buffer[..length.min(buffer.len())], now) {
                Ok(()) => {
                    if let Err(e) = self.record(now) {
                        record_error.get_or_insert(e);
                        self.recorder = None;
                    }
                }
                Err(reason) => {
                    self.shared.ignored[reason as usize].fetch_add(1, Ordering::AcqRel);
                }
            }
        }
        match (record_error, self.recorder.take()) {
            (Some(error), _) => Err(error),
            (None, Some(recorder)) => recorder.finish(),
            (None, None) => Ok(0),
        }
    }

    /// Decodes, checks and takes one datagram, and publishes the new state.
    fn take(&mut self, datagram: &[u8], now: Instant) -> Result<(), Ignored> {
        if datagram.len() > MAX_DATAGRAM_BYTES {
            return Err(Ignored::Oversize);
        }
        let update = self.decoder.decode(datagram, now)?;
        self.state.take(&update, now, self.stale)?;
        // The counter moves with the state, under its lock, so a reader
        // never sees a sample taken and not counted.
        let mut published = self.shared.state.lock().unwrap_or_else(|e| e.into_inner());
        *published = self.state;
        self.shared.taken.fetch_add(1, Ordering::AcqRel);
        Ok(())
    }

    /// Records the pose the state shows now, if it is live.
    fn record(&mut self, now: Instant) -> Result<(), RecordError> {
        let Some(recorder) = &mut self.recorder else { return Ok(()) };
        match self.state.view(now, self.stale) {
            LiveView::Live { pose, .. } => recorder.write(&pose, now),
            LiveView::Stale { .. } => Ok(()),
        }
    }

    /// Asks X-Plane for `RPOS` at 60 Hz, again every [`REQUEST_EVERY`]
    /// while no data come (X-Plane forgets a request when it restarts).
    fn request_rpos(&mut self, requested: &mut Option<Instant>) {
        let Some(xplane) = self.xplane_request else { return };
        let now = Instant::now();
        let fresh = self.state.newest().is_some_and(|at| now.duration_since(at) < self.stale);
        let due = requested.is_none_or(|at| now.duration_since(at) >= REQUEST_EVERY);
        if fresh || !due {
            return;
        }
        *requested = Some(now);
        // "RPOS", a NUL, the rate as text in ten bytes (X-Plane's request).
        let mut request = [0u8; 15];
        request[..4].copy_from_slice(b"RPOS");
        request[5..7].copy_from_slice(b"60");
        if self.socket.send_to(&request, xplane).is_err() {
            self.shared.socket_errors.fetch_add(1, Ordering::AcqRel);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::pose::{Attitude, Position, Track, Turning};

    fn spec() -> InputSpec {
        "flightgear:127.0.0.1:0".parse().unwrap()
    }

    fn packet(lat: f64) -> Vec<u8> {
        let track = Track {
            position: Position { lat_deg: lat, lon_deg: 40.0, alt_m: 2000.0 },
            velocity_ned: Some([50.0, 0.0, 0.0]),
            vertical_known: true,
        };
        crate::input::flightgear::encode(
            24,
            &track,
            &Turning { attitude: Attitude::default(), rates_dps: None },
        )
    }

    /// Waits (bounded) until the receiver has counted `n` datagrams.
    fn wait_for(input: &LiveInput, n: u64) -> Counts {
        let deadline = Instant::now() + Duration::from_secs(10);
        loop {
            let counts = input.counts();
            if counts.datagrams() >= n || Instant::now() > deadline {
                return counts;
            }
            std::thread::sleep(Duration::from_millis(2));
        }
    }

    #[test]
    fn datagrams_are_counted_once_each_by_outcome() {
        let mut input = LiveInput::start(&spec(), &ReceiverOptions::default()).unwrap();
        let sender = UdpSocket::bind("127.0.0.1:0").unwrap();
        let to = input.local_addr();
        sender.send_to(&packet(39.0), to).unwrap();
        sender.send_to(&packet(39.0)[..100], to).unwrap();
        sender.send_to(&packet(f64::NAN), to).unwrap();
        sender.send_to(&vec![0u8; MAX_DATAGRAM_BYTES + 10], to).unwrap();
        let counts = wait_for(&input, 4);
        assert_eq!(counts.taken, 1, "{counts:?}");
        assert_eq!(counts.ignored_for(Ignored::Length), 1);
        assert_eq!(counts.ignored_for(Ignored::NotFinite), 1);
        assert_eq!(counts.ignored_for(Ignored::Oversize), 1);
        assert_eq!(input.snapshot().taken, 1);
        input.stop().unwrap();
    }

    /// The structural guarantee: a frame reading the state while the
    /// receiver holds its lock gets its last copy back at once instead of
    /// waiting. (Were `snapshot` to wait, the helper thread would never
    /// answer while the lock is held; the timeout only turns that hang
    /// into a failure.)
    #[test]
    fn a_frame_never_waits_for_the_receiver() {
        let mut input = LiveInput::start(&spec(), &ReceiverOptions::default()).unwrap();
        let shared = Arc::clone(&input.shared);
        let held = shared.state.lock().unwrap();
        let (tx, rx) = std::sync::mpsc::channel();
        let reader = std::thread::spawn(move || {
            let state = input.snapshot();
            tx.send(state.taken).unwrap();
            input
        });
        let answered = rx.recv_timeout(Duration::from_secs(20));
        drop(held);
        assert_eq!(answered, Ok(0), "snapshot waited for the receiver's lock");
        reader.join().unwrap().stop().unwrap();
    }
}
