//! Hand-written cases for the allocator's documented behaviour: the run is
//! contiguous and sorted by format, the transfer cap cuts it into pieces,
//! frames in flight delay reuse, and every refusal leaves the state untouched.

use ridgeline::allocator::{
    AllocError, AllocatorConfig, ConfigError, ContiguousAllocator, GeneratorId, Request,
    VertexFormat,
};

fn request(generator: u32, format: u16, size: u32) -> Request {
    Request { generator: GeneratorId(generator), format: VertexFormat(format), size }
}

fn allocator(capacity: u32, generators: u32) -> ContiguousAllocator {
    ContiguousAllocator::new(AllocatorConfig::new(capacity, generators)).unwrap()
}

#[test]
fn run_is_contiguous_and_sorted_by_format() {
    let mut alloc = allocator(1024, 8);
    let requests = [request(0, 2, 16), request(1, 1, 8), request(2, 2, 4), request(3, 1, 12)];
    let plan = alloc.allocate(&requests).unwrap();
    // Format 1 first (requests 1 and 3 in request order), then format 2.
    assert_eq!(plan.range(1), 0..8);
    assert_eq!(plan.range(3), 8..20);
    assert_eq!(plan.range(0), 20..36);
    assert_eq!(plan.range(2), 36..40);
    assert_eq!(plan.dirty_ranges(), std::slice::from_ref(&(0..40)));
}

#[test]
fn sizes_round_up_to_the_alignment() {
    let mut alloc = allocator(64, 4);
    let requests = [request(0, 0, 3), request(1, 0, 5)];
    let plan = alloc.allocate(&requests).unwrap();
    assert_eq!(plan.range(0), 0..4);
    assert_eq!(plan.range(1), 4..12);
}

#[test]
fn transfer_cap_cuts_the_run_between_blocks() {
    let config = AllocatorConfig { transfer_cap: Some(32), ..AllocatorConfig::new(1024, 8) };
    let mut alloc = ContiguousAllocator::new(config).unwrap();
    let requests: Vec<Request> = (0..5).map(|g| request(g, 0, 16)).collect();
    let plan = alloc.allocate(&requests).unwrap();
    assert_eq!(plan.dirty_ranges(), &[0..32, 32..64, 64..80]);
}

#[test]
fn a_capped_piece_fills_a_gap_the_whole_run_would_not() {
    let config = AllocatorConfig { transfer_cap: Some(16), ..AllocatorConfig::new(64, 8) };
    let mut alloc = ContiguousAllocator::new(config).unwrap();
    let fill: Vec<Request> = (0..4).map(|g| request(g, 0, 16)).collect();
    alloc.allocate(&fill).unwrap();
    // Free 0..16 and 32..48, then ask for two blocks of 16 again: uncapped they
    // would need 32 contiguous bytes; capped each finds its own gap.
    alloc.release(GeneratorId(0)).unwrap();
    alloc.release(GeneratorId(2)).unwrap();
    let requests = [request(4, 0, 16), request(5, 0, 16)];
    let plan = alloc.allocate(&requests).unwrap();
    assert_eq!(plan.dirty_ranges(), &[0..16, 32..48]);
}

#[test]
fn frames_in_flight_keep_released_bytes_out_of_reuse() {
    let config = AllocatorConfig { frames_in_flight: 2, ..AllocatorConfig::new(64, 4) };
    let mut alloc = ContiguousAllocator::new(config).unwrap();
    alloc.begin_frame();
    alloc.allocate(&[request(0, 0, 32)]).unwrap();
    alloc.begin_frame();
    // Reallocating moves the block: the old bytes are still being read by the GPU.
    assert_eq!(alloc.allocate(&[request(0, 0, 32)]).unwrap().range(0), 32..64);
    assert_eq!(alloc.stats().retiring_bytes, 32);
    alloc.begin_frame();
    assert!(matches!(alloc.allocate(&[request(1, 0, 16)]), Err(AllocError::OutOfSpace { .. })));
    alloc.begin_frame();
    assert_eq!(alloc.stats().retiring_bytes, 0);
    assert_eq!(alloc.allocate(&[request(1, 0, 16)]).unwrap().range(0), 0..16);
}

#[test]
fn failure_reports_the_largest_gap_and_changes_nothing() {
    let mut alloc = allocator(100, 8);
    let requests = [request(0, 0, 40), request(1, 0, 20), request(2, 0, 40)];
    let mut plan = alloc.allocate(&requests).unwrap();
    plan.fill(|_, r, bytes| bytes.fill(r.generator.0 as u8 + 1));
    let before: Vec<_> = (0..3).map(|g| alloc.block_range(GeneratorId(g))).collect();
    let staging = alloc.staging().to_vec();
    // Reallocating 1 (20 bytes) with 24 more for a new generator needs 44 contiguous.
    let error = alloc.allocate(&[request(1, 0, 20), request(3, 0, 24)]).unwrap_err();
    assert_eq!(
        error,
        AllocError::OutOfSpace { asked: 44, piece: 44, blocks: 2, largest_gap: 20, capacity: 100 }
    );
    let after: Vec<_> = (0..3).map(|g| alloc.block_range(GeneratorId(g))).collect();
    assert_eq!(before, after);
    assert_eq!(alloc.block_range(GeneratorId(3)), None);
    assert_eq!(alloc.staging(), &staging[..]);
    alloc.check_invariants().unwrap();
    // The retry with less succeeds in the gap.
    assert_eq!(alloc.allocate(&[request(1, 0, 20)]).unwrap().range(0), 40..60);
}

#[test]
fn invalid_requests_are_refused_before_anything_changes() {
    let mut alloc = allocator(64, 2);
    alloc.allocate(&[request(0, 0, 8)]).unwrap();
    let cases = [
        (vec![request(1, 0, 8), request(1, 0, 8)], AllocError::DuplicateGenerator(1)),
        (vec![request(0, 0, 8), request(1, 0, 0)], AllocError::ZeroSize(1)),
        (vec![request(5, 0, 8)], AllocError::UnknownGenerator { generator: 5, max_generators: 2 }),
        (vec![request(0, 0, 65)], AllocError::TooLarge { generator: 0, size: 65, capacity: 64 }),
        (
            vec![request(0, 0, u32::MAX)],
            AllocError::TooLarge { generator: 0, size: u32::MAX, capacity: 64 },
        ),
        (
            vec![request(0, 0, 1), request(1, 0, 1), request(0, 0, 1)],
            AllocError::TooManyRequests { requests: 3, max_generators: 2 },
        ),
    ];
    for (requests, expected) in cases {
        assert_eq!(alloc.allocate(&requests).err(), Some(expected));
        assert_eq!(alloc.block_range(GeneratorId(0)), Some(0..8));
        assert_eq!(alloc.block_range(GeneratorId(1)), None);
        alloc.check_invariants().unwrap();
    }
    let message =
        AllocError::OutOfSpace { asked: 9, piece: 9, blocks: 1, largest_gap: 4, capacity: 64 };
    assert!(
        message.to_string().contains("asked 9 bytes")
            && message.to_string().contains("largest free gap is 4")
    );
}

#[test]
fn impossible_configurations_are_refused() {
    let base = AllocatorConfig::new(64, 4);
    let cases = [
        (AllocatorConfig { capacity: 0, ..base }, ConfigError::ZeroCapacity),
        (AllocatorConfig { max_generators: 0, ..base }, ConfigError::NoGenerators),
        (AllocatorConfig { alignment: 3, ..base }, ConfigError::BadAlignment(3)),
        (
            AllocatorConfig { capacity: 66, ..base },
            ConfigError::UnalignedCapacity { capacity: 66, alignment: 4 },
        ),
        (AllocatorConfig { transfer_cap: Some(0), ..base }, ConfigError::ZeroTransferCap),
        (
            AllocatorConfig { max_generators: u32::MAX, frames_in_flight: 3, ..base },
            ConfigError::TableTooLarge { generators: u32::MAX, frames_in_flight: 3 },
        ),
    ];
    for (config, expected) in cases {
        assert_eq!(ContiguousAllocator::new(config).err(), Some(expected));
    }
}

#[test]
fn releasing_merges_free_space_on_both_sides() {
    let mut alloc = allocator(64, 4);
    let requests: Vec<Request> = (0..4).map(|g| request(g, 0, 16)).collect();
    alloc.allocate(&requests).unwrap();
    alloc.release(GeneratorId(0)).unwrap();
    alloc.release(GeneratorId(2)).unwrap();
    assert_eq!(alloc.stats().free_gaps, 2);
    alloc.release(GeneratorId(1)).unwrap();
    let stats = alloc.stats();
    assert_eq!((stats.free_gaps, stats.largest_gap, stats.workspace_end), (1, 48, 64));
    assert!(!alloc.release(GeneratorId(1)).unwrap(), "nothing left to release");
}

/// Windows (what the cluster cache keeps its vertex blocks in): a reserved
/// fence between windows, and each window's run placed inside it.
#[test]
fn runs_placed_within_a_window_stay_inside_it() {
    let mut alloc = allocator(256, 8);
    // Two windows of 120 bytes, fenced by bytes 120..128.
    alloc.reserve(GeneratorId(7), 120..128).unwrap();
    assert_eq!(
        alloc.reserve(GeneratorId(6), 124..132),
        Err(AllocError::NotFree { generator: 6, start: 124, end: 132 }),
        "part of it is taken"
    );
    assert!(alloc.reserve(GeneratorId(7), 200..204).is_err(), "the generator owns a block");
    assert_eq!(alloc.largest_gap_in(0..120), 120);
    assert_eq!(alloc.largest_gap_in(128..256), 128);
    let (first, second) = ([request(0, 0, 100)], [request(1, 0, 40), request(2, 0, 20)]);
    let plan = alloc.allocate_within(&first, 0..120).unwrap();
    assert_eq!(plan.range(0), 0..100);
    // 40 bytes do not fit in the first window's last 20: the call fails,
    // and a call for the second window places them at its start.
    let in_first = alloc.allocate_within(&second[..1], 0..120);
    assert!(matches!(in_first, Err(AllocError::OutOfSpace { .. })), "{in_first:?}");
    let plan = alloc.allocate_within(&second, 128..256).unwrap();
    assert_eq!((plan.range(0), plan.range(1)), (128..168, 168..188));
    assert_eq!(alloc.largest_gap_in(0..120), 20);
    assert_eq!(alloc.largest_gap_in(128..256), 68);
    // Released, the first window's block merges with the gap after it
    // but not across the fence.
    alloc.release(GeneratorId(0)).unwrap();
    assert_eq!(alloc.largest_gap_in(0..120), 120);
    alloc.check_invariants().unwrap();
}
