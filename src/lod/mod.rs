//! UDLOD on the CPU (Kühnert 4.4, 5.1) with Ulrich's screen-space error bound:
//! an implicit quadtree of equal-resolution tiles over the terrain, refined by
//! distance each frame, culled against the frustum, and morphed per vertex so
//! that neighbouring levels meet without cracks and switch without pops.
//!
//! What differs from the thesis, and why:
//! - tile posts sit on the data's posts (a tile of level `l` samples every
//!   `2^l`-th post), so the pyramid's per-node delta is exactly the tile's
//!   geometric error; Kühnert's continuous `tile_scale` becomes the discrete
//!   `grid_size` (cells per tile side);
//! - the distance rings are widened wherever Ulrich's bound needs it: a tile of
//!   level `l` is never drawn nearer than `delta_l * K / (tau * (1 - morph_range))`,
//!   so even its morph toward the parent stays within `tau` pixels;
//! - rings also grow fast enough that neighbours differ by at most one level
//!   and the coarser one is unmorphed where they meet (see [`rings`]);
//! - tiles below the horizon are culled beside the frustum ([`horizon`]).

pub mod budget;
pub mod census;
pub mod horizon;
pub mod life;
pub mod morph;
pub mod rings;
pub mod select;
pub mod split_zone;

pub use rings::LevelRings;
pub use select::{SelectedTile, TileSelector};

/// Names one tile of the implicit quadtree. A tile of level `level` covers
/// level-0 posts `[x * span, (x + 1) * span]` east and `[y * span, (y + 1) * span]`
/// north, `span = grid_size << level`, sampling every `1 << level`-th post.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
pub struct TileKey {
    /// Level of the tile: 0 is the finest, each level doubles the post spacing.
    pub level: u8,
    /// Column of the tile among its level's tiles, from the west edge.
    pub x: u32,
    /// Row of the tile among its level's tiles, from the south edge.
    pub y: u32,
}

impl TileKey {
    /// The tile of `level` at column `x` and row `y`.
    pub fn new(level: u8, x: u32, y: u32) -> Self {
        TileKey { level, x, y }
    }

    /// The four tiles one level finer, south-west first.
    pub fn children(self) -> [TileKey; 4] {
        debug_assert!(self.level > 0, "level-0 tiles have no children");
        let (l, x, y) = (self.level - 1, self.x * 2, self.y * 2);
        [
            TileKey::new(l, x, y),
            TileKey::new(l, x + 1, y),
            TileKey::new(l, x, y + 1),
            TileKey::new(l, x + 1, y + 1),
        ]
    }

    /// The tile one level coarser that contains this one.
    pub fn parent(self) -> TileKey {
        TileKey::new(self.level + 1, self.x / 2, self.y / 2)
    }
}

/// Parameters of the tiling (the thesis' Table 1, adapted as the module says).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct LodConfig {
    /// Cells per tile side; a power of two no larger than the pyramid's node size.
    pub grid_size: u32,
    /// A tile is split while the camera is nearer than this many tile sizes
    /// (Kühnert's `view_distance`, here per tile rather than per leaf node).
    pub view_distance: f64,
    /// Fraction of each ring, at its far end, over which vertices morph toward
    /// the parent level, in (0, 0.5].
    pub morph_range: f64,
    /// Ulrich's screen-space error bound tau, in pixels.
    pub tau_px: f64,
    /// Most tiles one frame may select; refinement stops (keeping coarser
    /// tiles, never leaving a hole) rather than exceed it.
    pub max_tiles: usize,
    /// The camera's declared largest move a frame, metres: split tests are
    /// redone only when their valid life runs out ([`life`]). `None`:
    /// every tile is tested every frame.
    pub max_travel_m: Option<f64>,
}

impl Default for LodConfig {
    fn default() -> Self {
        LodConfig {
            grid_size: 32,
            view_distance: 3.0,
            morph_range: 0.3,
            tau_px: 1.0,
            max_tiles: 2048,
            max_travel_m: None,
        }
    }
}

/// Why a tiling configuration cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LodError {
    /// `grid_size` is not a power of two in 2..=256.
    #[error("grid size {0} is not a power of two between 2 and 256")]
    GridSize(u32),
    /// `grid_size` does not divide the pyramid's node size.
    #[error("grid size {grid} does not divide the node size {node}")]
    GridNotInNode {
        /// Cells per tile side.
        grid: u32,
        /// Cells per node side.
        node: u32,
    },
    /// `view_distance` is not finite or is below 1 tile.
    #[error("view distance {0} must be a finite number of at least 1 tile")]
    ViewDistance(f64),
    /// `morph_range` is outside (0, 0.5].
    #[error("morph range {0} must lie in (0, 0.5]")]
    MorphRange(f64),
    /// `tau_px` is not a finite number above 0 pixels.
    #[error("tau {0} px must be a finite number above 0")]
    Tau(f64),
    /// `max_tiles` is 0.
    #[error("max tiles must be at least 1")]
    MaxTiles,
    /// `max_travel_m` is not a finite number above 0 metres.
    #[error("the declared travel {0} m a frame must be a finite number above 0")]
    MaxTravel(f64),
}

impl LodConfig {
    /// Checks the configuration against the pyramid's node size.
    pub fn validate(&self, node_size: u32) -> Result<(), LodError> {
        let g = self.grid_size;
        if !(g.is_power_of_two() && (2..=256).contains(&g)) {
            return Err(LodError::GridSize(g));
        }
        if node_size % g != 0 {
            return Err(LodError::GridNotInNode { grid: g, node: node_size });
        }
        if !(self.view_distance.is_finite() && self.view_distance >= 1.0) {
            return Err(LodError::ViewDistance(self.view_distance));
        }
        if !(self.morph_range > 0.0 && self.morph_range <= 0.5) {
            return Err(LodError::MorphRange(self.morph_range));
        }
        if !(self.tau_px.is_finite() && self.tau_px > 0.0) {
            return Err(LodError::Tau(self.tau_px));
        }
        if self.max_tiles == 0 {
            return Err(LodError::MaxTiles);
        }
        if let Some(travel) = self.max_travel_m.filter(|t| !(t.is_finite() && *t > 0.0)) {
            return Err(LodError::MaxTravel(travel));
        }
        Ok(())
    }
}
