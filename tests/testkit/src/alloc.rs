//! Counts heap allocations and the bytes in use, and their peak: a global allocator that forwards to the system
//! one. A test binary that declares `mod alloc_counter;` counts every
//! allocation of its process, so such binaries hold one test each.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

static ALLOCATIONS: AtomicU64 = AtomicU64::new(0);
static IN_USE: AtomicU64 = AtomicU64::new(0);
static PEAK: AtomicU64 = AtomicU64::new(0);
/// Set by [`trace`]: each allocation then prints where it was made.
static TRACING: AtomicBool = AtomicBool::new(false);

thread_local! {
    /// Inside a traced allocation: the backtrace allocates too.
    static IN_TRACE: Cell<bool> = const { Cell::new(false) };
    /// Allocations and reallocations made on this thread.
    static ON_THREAD: Cell<u64> = const { Cell::new(0) };
}

/// Counts one allocation, the process's and its thread's.
fn counted() {
    ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
    ON_THREAD.with(|n| n.set(n.get() + 1));
    traced();
}

/// Prints the backtrace of an allocation made while tracing is on: which
/// scratch grew when a test counts allocations where none are allowed.
fn traced() {
    if !TRACING.load(Ordering::Relaxed) || IN_TRACE.with(Cell::get) {
        return;
    }
    IN_TRACE.with(|t| t.set(true));
    eprintln!("allocation at:\n{}", std::backtrace::Backtrace::force_capture());
    IN_TRACE.with(|t| t.set(false));
}

fn grew(bytes: usize) {
    let now = IN_USE.fetch_add(bytes as u64, Ordering::Relaxed) + bytes as u64;
    PEAK.fetch_max(now, Ordering::Relaxed);
}

/// The system allocator, counting allocations and reallocations.
struct Counting;

// SAFETY: every call is forwarded unchanged to the system allocator, which
// upholds GlobalAlloc's contract; the counter is only an atomic increment.
#[allow(unsafe_code)]
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        counted();
        grew(layout.size());
        // SAFETY: forwarded with the caller's guarantees.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        IN_USE.fetch_sub(layout.size() as u64, Ordering::Relaxed);
        // SAFETY: `ptr` came from `System.alloc` with this layout.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        counted();
        IN_USE.fetch_sub(layout.size() as u64, Ordering::Relaxed);
        grew(new_size);
        // SAFETY: forwarded with the caller's guarantees.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Allocations and reallocations so far in this process.
pub fn allocations() -> u64 {
    ALLOCATIONS.load(Ordering::Relaxed)
}

/// Allocations and reallocations so far on the calling thread: what a
/// frame loop makes, without the test harness's own (libtest's main thread
/// formats a note when a test runs past 60 seconds).
pub fn thread_allocations() -> u64 {
    ON_THREAD.with(Cell::get)
}

/// Heap bytes in use now (a failed allocation is counted as made).
pub fn bytes_in_use() -> u64 {
    IN_USE.load(Ordering::Relaxed)
}

/// The most heap bytes in use at once since [`reset_peak`] (or the start).
pub fn peak_bytes() -> u64 {
    PEAK.load(Ordering::Relaxed)
}

/// Starts a new peak from the bytes in use now.
pub fn reset_peak() {
    PEAK.store(IN_USE.load(Ordering::Relaxed), Ordering::Relaxed);
}

/// Prints a backtrace for every allocation from now until `trace(false)`,
/// when `RIDGELINE_TRACE_ALLOCATIONS` is set: a test that must not allocate
/// arms it over the frames it counts, so a failure can be traced to its scratch.
/// The variable is read once, on the first call (reading it allocates).
pub fn trace(on: bool) {
    static WANTED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let wanted = *WANTED.get_or_init(|| std::env::var_os("RIDGELINE_TRACE_ALLOCATIONS").is_some());
    TRACING.store(on && wanted, Ordering::Relaxed);
}
