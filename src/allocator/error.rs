//! Typed failures of the contiguous allocator.

/// Why [`ContiguousAllocator::new`](super::ContiguousAllocator::new) refused a configuration.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ConfigError {
    #[error("allocator capacity must be at least one byte")]
    ZeroCapacity,
    #[error("allocator needs room for at least one generator")]
    NoGenerators,
    #[error("alignment {0} is not a power of two")]
    BadAlignment(u32),
    #[error("capacity {capacity} is not a multiple of the alignment {alignment}")]
    UnalignedCapacity { capacity: u32, alignment: u32 },
    #[error("transfer cap must be at least one byte")]
    ZeroTransferCap,
    #[error("{generators} generators with {frames_in_flight} frames in flight need more block records than fit in 32 bits")]
    TableTooLarge { generators: u32, frames_in_flight: u32 },
}

/// Why a call to the allocator failed. After any of these every block that was
/// live before the call is still live, at the same offset, with its bytes untouched.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum AllocError {
    #[error(
        "no room for the run: asked {asked} bytes in {blocks} blocks, a piece of {piece} bytes \
         found no gap; the largest free gap is {largest_gap} bytes of {capacity}"
    )]
    OutOfSpace {
        /// Total bytes of every request in the call (after alignment).
        asked: u64,
        /// Bytes of the run piece that did not fit.
        piece: u64,
        /// Number of requests in the call.
        blocks: usize,
        /// Largest gap with this call's old blocks released, before anything was placed.
        largest_gap: u32,
        capacity: u32,
    },
    #[error("generator {generator} is outside the table of {max_generators} generators")]
    UnknownGenerator { generator: u32, max_generators: u32 },
    #[error("generator {0} appears twice in one call")]
    DuplicateGenerator(u32),
    #[error("generator {0} asked for 0 bytes")]
    ZeroSize(u32),
    #[error("generator {generator} asked for {size} bytes, more than the capacity {capacity}")]
    TooLarge { generator: u32, size: u32, capacity: u32 },
    #[error("{requests} requests in one call, the table holds {max_generators} generators")]
    TooManyRequests { requests: usize, max_generators: u32 },
    #[error(
        "{waiting} blocks are waiting out the frames in flight and {more} more would exceed \
         the queue of {max}; call begin_frame between frames"
    )]
    RetireQueueFull { waiting: usize, more: usize, max: usize },
}
