//! Why a grid or a mesh is refused.

/// What is wrong with a height grid or a requested mesh.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    /// The grid is not `2^k + 1` posts a side.
    #[error("grid side {0} is not 2^k + 1 posts with 1 <= k <= 15")]
    Side(u32),
    /// The heights do not fill the grid.
    #[error("grid has {found} heights, {expected} expected")]
    Length {
        /// Posts in the grid.
        expected: usize,
        /// Heights given.
        found: usize,
    },
    /// A height is NaN or infinite.
    #[error("height at post ({i}, {j}) is not a finite number")]
    NotFinite {
        /// Post column.
        i: u32,
        /// Post row.
        j: u32,
    },
    /// A regular grid's stride does not fit the grid.
    #[error("stride {stride} does not divide the {side}-post grid into a power-of-two grid")]
    Stride {
        /// Posts a side of the grid.
        side: u32,
        /// The stride asked for.
        stride: u32,
    },
    /// The forced edge step is not a power of two.
    #[error("edge step {0} is not a power of two")]
    EdgeStep(u32),
    /// The error bound is negative or not a number.
    #[error("maximum error {0} is not a finite number at or above zero")]
    MaxError(f64),
    /// View refinement asked of an error map built without bounds.
    #[error(
        "the error map was built without bounds (RtinOptions::bounds), which view refinement needs"
    )]
    NoBounds,
    /// A view's tau or K is not positive.
    #[error("view tau {tau} and K {k} must both be positive")]
    View {
        /// Screen-space error in pixels.
        tau: f64,
        /// The projection's pixels per unit of angle.
        k: f64,
    },
    /// The mesh would need more vertices than 16-bit indices address.
    #[error("mesh needs {count} vertices, more than 16-bit indices address (65536)")]
    TooManyVertices {
        /// Vertices the mesh would need.
        count: usize,
    },
}
