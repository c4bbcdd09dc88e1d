//! [`LodSurface`]: the surface the LOD display drew, evaluated on the CPU at
//! any ground point, from the frame's draw list and the tile blocks in the
//! allocator's staging copy (byte for byte what the GPU holds): each tile's
//! own vertices and triangles, whatever its mesh. Each vertex is morphed as
//! `shaders/gles/terrain.vert` does ([`crate::lod::morph`]), from the same
//! f32 uniforms, and lowered by the earth's curvature as the shader lowers
//! it, per vertex (so the drawn triangles sag below the curved surface
//! between vertices, as the GPU's do); between vertices the surface is the
//! block's triangle there, interpolated linearly. Skirts are not part of
//! the surface.

use std::collections::HashMap;

use glam::DVec2;

use super::skirt_probe::{tiles_across, CoverageProbe, SkirtProbe, EDGE_NAMES};
use super::tile_triangles::TileTriangles;
use crate::camera::EARTH_RADIUS_M;
use crate::lod::morph::{morph_factor, morphed_height};
use crate::lod::TileKey;
use crate::render::{DrawList, DrawnTile, PostFrame, TileUniforms};
use crate::tiles::vertex::is_no_data;
use crate::tiles::TileBlock;

/// How close to a tile edge, in posts, a drawn point counts as on it (a
/// skirt's points lie on the edge's vertical plane; 2/1000 of a post is
/// a few centimetres, above f32 rounding at 100 km).
pub const EDGE_TOLERANCE_POSTS: f64 = 2e-3;

/// The drawn tiles of one frame, indexed by key, and their triangles.
#[derive(Debug, Default)]
pub struct LodSurface {
    /// Each drawn tile's place in `drawn`.
    tiles: HashMap<TileKey, usize>,
    drawn: Vec<TileUniforms>,
    /// The frame's tiles sorted by key, with their sources.
    sources: Vec<DrawnTile>,
    triangles: TileTriangles,
    levels: u8,
    grid_size: u32,
    /// Level-0 post spacing, metres east and north.
    spacing_m: [f64; 2],
    eye: DVec2,
    posts: PostFrame,
    /// The data's last post, local metres east and north: the terrain
    /// program clips there.
    last_m: [f64; 2],
    /// The shader's f32 altitude and 1 / (2 R) (0 for a flat earth), widened.
    altitude: f64,
    curvature: f64,
    /// The frame's morphs' start over their end.
    start_share: f32,
    /// `u_earth` when drawn on the ellipsoid: [`Self::earth_height_at`]
    /// morphs by the shader's camera-relative points and drops nothing.
    earth: Option<[f32; 8]>,
}

impl LodSurface {
    /// Indexes `list`'s tiles (drawn from `eye` with tiles of `grid_size`
    /// cells over level-0 posts `spacing_m` apart) and their triangles, from
    /// their blocks in `staging`.
    pub fn new(
        list: &DrawList,
        staging: &[u8],
        grid_size: u32,
        spacing_m: [f64; 2],
        eye: DVec2,
    ) -> LodSurface {
        let tiles = list.tiles.iter().enumerate().map(|(k, t)| (t.key, k)).collect();
        let triangles = TileTriangles::new(&list.tiles, staging, grid_size);
        let levels = list.tiles.iter().map(|t| t.key.level + 1).max().unwrap_or(0);
        let altitude = list.uniforms.map_or(0.0, |f| f.camera_altitude as f32 as f64);
        let earth = list.uniforms.and_then(|f| f.earth.map(|e| e.uniforms()));
        let curvature = list.uniforms.map_or(0.0, |f| {
            if f.curvature {
                (1.0 / (2.0 * EARTH_RADIUS_M)) as f32 as f64
            } else {
                0.0
            }
        });
        let posts = list.uniforms.map_or(PostFrame::default(), |f| f.posts);
        let last_m = list
            .uniforms
            .map_or([f64::INFINITY; 2], |f| [0, 1].map(|k| f.last_post[k] as f64 * spacing_m[k]));
        LodSurface {
            tiles,
            drawn: list.tiles.clone(),
            sources: list.drawn.clone(),
            triangles,
            levels,
            grid_size,
            spacing_m,
            eye,
            posts,
            last_m,
            altitude,
            start_share: list.uniforms.map_or(0.0, |f| f.morph_start_share),
            curvature,
            earth,
        }
    }

    /// Surface triangles of the drawn tiles, skirts left out.
    pub fn surface_triangles(&self) -> u64 {
        self.triangles.surface_triangles()
    }

    /// Height of the drawn surface at the local point `(x_m, y_m)`, metres
    /// above the datum with the curvature drop taken off (what the GPU drew
    /// there plus the camera altitude); `None` where no tile was drawn, or
    /// where the tile's triangle there touches a post without data (the
    /// display drops such triangles), and past the data's last post (the
    /// display clips there).
    pub fn height_at(&self, staging: &[u8], x_m: f64, y_m: f64) -> Option<f64> {
        // Within rounding of the last post: on it (the truth's points there
        // come through f32 positions too).
        let tolerance = EDGE_TOLERANCE_POSTS * self.spacing_m[0].max(self.spacing_m[1]);
        if x_m > self.last_m[0] + tolerance || y_m > self.last_m[1] + tolerance {
            return None;
        }
        let (tile, local) = self.locate(x_m, y_m)?;
        let height = self.tile_surface(staging, tile, local, false)?;
        height.is_finite().then_some(height)
    }

    /// [`Self::height_at`] as drawn on the ellipsoid: the height the
    /// shader raised the point along its geodetic up, morphed by its
    /// distance there, with no drop (the ellipsoid bends the surface). The
    /// chart's height where the frame was drawn in the chart.
    pub fn earth_height_at(&self, staging: &[u8], x_m: f64, y_m: f64) -> Option<f64> {
        if self.earth.is_none() {
            return self.height_at(staging, x_m, y_m);
        }
        let tolerance = EDGE_TOLERANCE_POSTS * self.spacing_m[0].max(self.spacing_m[1]);
        if x_m > self.last_m[0] + tolerance || y_m > self.last_m[1] + tolerance {
            return None;
        }
        let (tile, local) = self.locate(x_m, y_m)?;
        let height = self.tile_surface(staging, tile, local, true)?;
        height.is_finite().then_some(height)
    }

    /// The level of the drawn tile covering `(x_m, y_m)`.
    pub fn level_at(&self, x_m: f64, y_m: f64) -> Option<u8> {
        self.locate(x_m, y_m).map(|(tile, _)| self.drawn[tile].key.level)
    }

    /// Whether a drawn tile covers `(x_m, y_m)` (with or without data there).
    pub fn has_tile(&self, x_m: f64, y_m: f64) -> bool {
        self.locate(x_m, y_m).is_some()
    }

    /// Whether `(x_m, y_m)` lies on the edge of the drawn tile there (within
    /// `EDGE_TOLERANCE_POSTS`), where skirts hang.
    pub fn on_tile_edge(&self, x_m: f64, y_m: f64) -> bool {
        let g = self.grid_size as f64;
        self.locate(x_m, y_m)
            .is_some_and(|(_, [u, v])| u.min(g - u).min(v).min(g - v) < EDGE_TOLERANCE_POSTS)
    }

    /// The skirt a LOD pixel (`pixel`, erring by `error_px`) shows, drawn
    /// at `drawn_m` over `(x_m, y_m)`: the tile there and the edge it lies
    /// on (see [`SkirtProbe`]); `None` off tile edges.
    pub fn probe_skirt(
        &self,
        staging: &[u8],
        (pixel, error_px): (usize, f32),
        [x_m, y_m]: [f64; 2],
        drawn_m: f64,
    ) -> Option<SkirtProbe> {
        let g = self.grid_size as f64;
        let (k, [u, v]) = self.locate(x_m, y_m)?;
        let distances = [v, g - u, g - v, u];
        let edge = (0..4).min_by(|&a, &b| distances[a].total_cmp(&distances[b]))?;
        if distances[edge] >= EDGE_TOLERANCE_POSTS {
            return None;
        }
        let tile = &self.drawn[k];
        let source = self.sources.iter().find(|d| d.key == tile.key);
        let surface = self.tile_surface(staging, k, [u, v], false).unwrap_or(f64::NAN);
        Some(SkirtProbe {
            pixel,
            error_px,
            tile: [tile.key.level as u32, tile.key.x, tile.key.y],
            source_level: source.map_or(tile.key.level, |d| d.source_level),
            node_mesh: source.is_some_and(|d| d.node_mesh),
            sub_level: source.map_or(0, |d| d.sub_level),
            edge: EDGE_NAMES[edge],
            skirt_depth_m: tile.skirt_depth,
            skirt_edges: tile.skirt_edges,
            below_surface_m: surface - drawn_m,
            across: tiles_across(tile.key, edge, &self.sources),
            past_last_post_m: [x_m - self.last_m[0], y_m - self.last_m[1]],
            partial: tile.no_data,
        })
    }

    /// What the LOD drew over the ground point `ground_m` (see
    /// [`CoverageProbe`]), probed for pixel `pixel`.
    pub fn probe_coverage(
        &self,
        staging: &[u8],
        pixel: usize,
        ground_m: [f64; 2],
    ) -> CoverageProbe {
        let located = self.locate(ground_m[0], ground_m[1]);
        let tile = located.map(|(k, _)| &self.drawn[k]);
        let source = tile.and_then(|t| self.sources.iter().find(|d| d.key == t.key));
        let triangle = located.map_or(Vec::new(), |(k, local)| {
            let block = self.drawn[k].block(staging);
            self.triangles.at(k, &block, local).map_or(Vec::new(), |(corners, _)| {
                corners
                    .iter()
                    .map(|&(post, v)| {
                        let height = block.vertex(v).height;
                        (post, (!is_no_data(height)).then_some(height))
                    })
                    .collect()
            })
        });
        CoverageProbe {
            pixel,
            ground_m,
            tile: tile.map(|t| [t.key.level as u32, t.key.x, t.key.y]),
            source_level: source.map(|d| d.source_level),
            node_mesh: source.is_some_and(|d| d.node_mesh),
            triangle,
        }
    }

    /// The drawn tile over `(x_m, y_m)` (its place in `drawn`) and the
    /// point's position in it, in posts of the tile's level from its
    /// south-west corner.
    fn locate(&self, x_m: f64, y_m: f64) -> Option<(usize, [f64; 2])> {
        let g = self.grid_size as f64;
        (0..self.levels).find_map(|level| {
            let post = [
                self.spacing_m[0] * (1u64 << level) as f64,
                self.spacing_m[1] * (1u64 << level) as f64,
            ];
            let (u, v) = (x_m / post[0], y_m / post[1]);
            // Within rounding of the first post (f32 positions): on it.
            let tolerance = EDGE_TOLERANCE_POSTS / (1u64 << level) as f64;
            if u < -tolerance || v < -tolerance {
                return None;
            }
            let (u, v) = (u.max(0.0), v.max(0.0));
            let (tx, ty) = ((u / g).floor() as u32, (v / g).floor() as u32);
            // A point exactly on a tile's east or north edge belongs to the
            // tile beyond, or, at the edge of the tiled area, to this one.
            let beside =
                |t: u32, w: f64| if t > 0 && w == t as f64 * g { [t, t - 1] } else { [t, t] };
            let (xs, ys) = (beside(tx, u), beside(ty, v));
            let keys = [(xs[0], ys[0]), (xs[1], ys[0]), (xs[0], ys[1]), (xs[1], ys[1])];
            keys.iter().find_map(|&(x, y)| {
                let key = TileKey::new(level, x, y);
                self.tiles.get(&key).map(|&k| (k, [u - x as f64 * g, v - y as f64 * g]))
            })
        })
    }

    /// Tile `k`'s morphed surface at `local` posts from its south-west
    /// corner: its triangle there, interpolated. NaN where that triangle
    /// touches a vertex without data; `None` where the tile has no triangle.
    fn tile_surface(
        &self,
        staging: &[u8],
        k: usize,
        local: [f64; 2],
        on_earth: bool,
    ) -> Option<f64> {
        let tile = &self.drawn[k];
        let block = tile.block(staging);
        let (corners, [_, wb, wc]) = self.triangles.at(k, &block, local)?;
        let [a, b, c] = corners.map(|(_, v)| self.vertex_height(&block, tile, v, on_earth));
        let along = a + wb * (b - a) + wc * (c - a);
        match self.earth.as_ref().filter(|_| on_earth && along.is_finite()) {
            Some(earth) => {
                let vertices = corners.map(|(_, v)| block.vertex(v).post.map(f32::from));
                Some(chord_height(earth, tile, vertices, [a, b, c], local).unwrap_or(along))
            }
            None => Some(along),
        }
    }

    /// Vertex `v`'s drawn height: the shader's morph
    /// and curvature drop, with its f32 inputs (the altitude is added back).
    fn vertex_height(
        &self,
        block: &TileBlock<'_>,
        tile: &TileUniforms,
        v: usize,
        on_earth: bool,
    ) -> f64 {
        let vertex = block.vertex(v);
        if is_no_data(vertex.height) {
            return f64::NAN;
        }
        // The shader's own f32 inputs: the vertex's post and step.
        let [i, j] = vertex.post.map(f32::from);
        if let Some(earth) = self.earth.as_ref().filter(|_| on_earth) {
            let post = [
                tile.first_post[0] + i * tile.vertex_step,
                tile.first_post[1] + j * tile.vertex_step,
            ];
            let distance = tile.place.vertex(earth, post, vertex.height).length() as f64;
            let [start, end] = tile.vertex_morph(&vertex, self.start_share);
            let factor = morph_factor(distance, start as f64, end as f64);
            return morphed_height(vertex.height, vertex.target, factor);
        }
        let [x, y] = tile.vertex_position(&self.posts, i, j).map(f64::from);
        let distance = (x * x + y * y + (vertex.height as f64 - self.altitude).powi(2)).sqrt();
        let [start, end] = tile.vertex_morph(&vertex, self.start_share);
        let factor = morph_factor(distance, start as f64, end as f64);
        morphed_height(vertex.height, vertex.target, factor) - (x * x + y * y) * self.curvature
    }

    /// The camera's ground position the tiles were placed relative to.
    pub fn eye(&self) -> DVec2 {
        self.eye
    }
}

/// The height, along the geodetic up at `local` (tile posts), of the
/// triangle the GPU draws through vertices at tile posts `vertices` (in
/// vertex steps) raised to `heights`: a chord, which sags below the
/// heights interpolated along the ellipsoid between its vertices by up to
/// a quarter of its mesh's error (`tiles::extract::sag_extent`). `None`
/// for a triangle seen edge-on from above.
fn chord_height(
    earth: &[f32; 8],
    tile: &TileUniforms,
    vertices: [[f32; 2]; 3],
    heights: [f64; 3],
    local: [f64; 2],
) -> Option<f64> {
    let at = |post: [f32; 2], step: f32, height: f32| {
        let post = [0, 1].map(|k| tile.first_post[k] + post[k] * step);
        tile.place.vertex(earth, post, height).as_dvec3()
    };
    let [a, b, c] = [0, 1, 2].map(|k| at(vertices[k], tile.vertex_step, heights[k] as f32));
    let ground = [local[0] as f32, local[1] as f32];
    let surface = at(ground, tile.post_step, 0.0);
    // Over 10 km, so that the f32 positions' rounding (millimetres at
    // tens of kilometres) turns the direction by under a microradian.
    let up = (at(ground, tile.post_step, 10_000.0) - surface) / 10_000.0;
    let normal = (b - a).cross(c - a);
    let across = normal.dot(up);
    (across.abs() > 1e-9 * normal.length() * up.length()).then(|| normal.dot(a - surface) / across)
}
