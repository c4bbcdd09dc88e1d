//! [`SkirtProbe`]: which skirt a pixel shows. Where the accuracy tool finds
//! a view's worst skirt pixel, it follows the pixel's drawn point to the
//! tile and the edge it hangs from, and reports what decided that skirt:
//! its depth, the tile's edges that hang one, the tiles drawn across that
//! edge, and how far the point is from the data's last post.

use crate::lod::TileKey;
use crate::render::draw_list::for_each_across;
use crate::render::DrawnTile;

/// What the skirt a pixel shows hangs from.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SkirtProbe {
    /// Row-major pixel index (from the top left) of the probed pixel.
    pub pixel: usize,
    /// Its error, pixels.
    pub error_px: f32,
    /// The tile the skirt hangs from: level, column, row.
    pub tile: [u32; 3],
    /// The level its heights came from, and whether it was cut from a node mesh.
    pub source_level: u8,
    /// Cut from its source node's mesh (else a regular grid of posts).
    pub node_mesh: bool,
    /// Its sub-level (`tiles::errors`): tiles of one node mesh share their
    /// edges only at the same one.
    pub sub_level: u8,
    /// The tile edge: `south`, `east`, `north` or `west`.
    pub edge: &'static str,
    /// The tile's skirt depth, metres.
    pub skirt_depth_m: f32,
    /// The tile's edges that hang a skirt (bit 0 south, 1 east, 2 north, 3 west).
    pub skirt_edges: u8,
    /// How far below the tile's surface the drawn point is, metres.
    pub below_surface_m: f64,
    /// The drawn tiles across the edge: level, column, row, source level,
    /// node mesh (1) or grid (0), sub-level. One of the tile's level, source
    /// and sub-level across an edge that hangs a skirt lies in another
    /// node: the two node meshes chose their edge vertices apart.
    pub across: Vec<[u32; 6]>,
    /// The point's distance to the data's last post east and north, metres
    /// (negative inside the data).
    pub past_last_post_m: [f64; 2],
    /// The tile is drawn by the program that drops posts without data and
    /// clips at the last post.
    pub partial: bool,
}

/// What the LOD drew at a ground point the truth shows terrain at and the
/// LOD none: the tile there and its triangle's vertices.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct CoverageProbe {
    /// Row-major pixel index (from the top left) of the probed pixel.
    pub pixel: usize,
    /// The ground point, local metres.
    pub ground_m: [f64; 2],
    /// The tile there (level, column, row), if one was drawn.
    pub tile: Option<[u32; 3]>,
    /// The level its heights came from.
    pub source_level: Option<u8>,
    /// Cut from its source node's mesh (else a regular grid of posts).
    pub node_mesh: bool,
    /// The triangle drawn there: each vertex's post in the tile's posts and
    /// height (`None` for a post without data).
    pub triangle: Vec<([f64; 2], Option<f32>)>,
}

/// Edge names in skirt-bit order.
pub const EDGE_NAMES: [&str; 4] = ["south", "east", "north", "west"];

/// The tiles of `drawn` (sorted by key) across edge `edge` of `key`, as
/// [`SkirtProbe::across`] lists them.
pub fn tiles_across(key: TileKey, edge: usize, drawn: &[DrawnTile]) -> Vec<[u32; 6]> {
    let mut across = Vec::new();
    for_each_across(key, edge, drawn, |d| {
        let k = d.key;
        let (source, mesh, sub) = (d.source_level as u32, d.node_mesh as u32, d.sub_level as u32);
        across.push([k.level as u32, k.x, k.y, source, mesh, sub]);
    });
    across
}
