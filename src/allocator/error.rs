//! Typed failures of the contiguous allocator.

/// Why [`ContiguousAllocator::new`](super::ContiguousAllocator::new) refused a configuration.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ConfigError {
    /// The configured capacity is 0 bytes.
    #[error("allocator capacity must be at least one byte")]
    ZeroCapacity,
    /// `max_generators` is 0, so no generator could ever be named.
    #[error("allocator needs room for at least one generator")]
    NoGenerators,
    /// The alignment, in bytes, is not a power of two.
    #[error("alignment {0} is not a power of two")]
    BadAlignment(u32),
    /// The capacity is not a whole number of alignment units.
    #[error("capacity {capacity} is not a multiple of the alignment {alignment}")]
    UnalignedCapacity {
        /// Configured address space, bytes.
        capacity: u32,
        /// Configured alignment, bytes.
        alignment: u32,
    },
    /// The transfer cap is `Some(0)`: no run piece could carry any bytes.
    #[error("transfer cap must be at least one byte")]
    ZeroTransferCap,
    /// The block records that `generators` and `frames_in_flight` may need, at most
    /// 2 (generators + generators × frames_in_flight) + 1, do not fit a 32-bit index.
    #[error("{generators} generators with {frames_in_flight} frames in flight need more block records than fit in 32 bits")]
    TableTooLarge {
        /// Configured `max_generators`.
        generators: u32,
        /// Configured frames a released block stays out of reuse.
        frames_in_flight: u32,
    },
}

/// Why a call to the allocator failed. After any of these every block that was
/// live before the call is still live, at the same offset, with its bytes untouched.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum AllocError {
    /// A piece of the call's run found no free gap large enough, even with the call's
    /// own old blocks released; nothing was placed.
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
        /// Bytes in the whole address space.
        capacity: u32,
    },
    /// A generator index is not below `max_generators`.
    #[error("generator {generator} is outside the table of {max_generators} generators")]
    UnknownGenerator {
        /// The index asked for.
        generator: u32,
        /// Generators the table can name.
        max_generators: u32,
    },
    /// One call named the same generator in two requests.
    #[error("generator {0} appears twice in one call")]
    DuplicateGenerator(u32),
    /// A request asked for 0 bytes (the field is the generator's index).
    #[error("generator {0} asked for 0 bytes")]
    ZeroSize(u32),
    /// A request, rounded up to the alignment, is larger than the whole address space.
    #[error("generator {generator} asked for {size} bytes, more than the capacity {capacity}")]
    TooLarge {
        /// The generator that asked.
        generator: u32,
        /// Bytes it asked for, before alignment.
        size: u32,
        /// Bytes in the whole address space.
        capacity: u32,
    },
    /// One call holds more requests than the table has generators.
    #[error("{requests} requests in one call, the table holds {max_generators} generators")]
    TooManyRequests {
        /// Requests in the call.
        requests: usize,
        /// Generators the table can name.
        max_generators: u32,
    },
    /// With frames in flight, releasing or replacing these blocks would queue more
    /// retiring blocks than the queue holds (`max_generators` × `frames_in_flight`).
    #[error(
        "{waiting} blocks are waiting out the frames in flight and {more} more would exceed \
         the queue of {max}; call begin_frame between frames"
    )]
    RetireQueueFull {
        /// Blocks already waiting out their frames in flight.
        waiting: usize,
        /// Blocks this call would add to the queue.
        more: usize,
        /// Blocks the queue holds.
        max: usize,
    },
    /// A reservation asked for bytes that are not all free, or a generator
    /// that already owns a block.
    #[error("cannot reserve bytes {start}..{end} for generator {generator}: not free")]
    NotFree {
        /// The generator that asked.
        generator: u32,
        /// First byte asked for.
        start: u32,
        /// One past the last byte asked for.
        end: u32,
    },
}
