//! Numerical stress on the GPU, headless on EGL (the GL halves of
//! `scene_precision` and `scene_soak`).
//!
//! Earth scale: one landscape of the procedural earth drawn twice, 10^7 m
//! out and at the origin. The second earth is the first moved by
//! [`SHIFT_POSTS`] posts ([`ProceduralEarth::shifted`]), a whole tile and a
//! whole node of every level the views draw, so both displays must select
//! the same tiles (moved by whole tiles) from the same data. Positions are
//! numbered in posts from an anchor post next to the camera (in integers,
//! before they become f32), so the tile uniforms, every vertex the shader
//! places and every pixel must agree (one colour step allowed; measured:
//! none differs). The far view redrawn with its posts placed the naive way
//! (f32 absolute post numbers and the f32 camera) must fail the same checks.
//!
//! Soak: 10^4 frames at 64 x 36 around a closed circuit over the earth,
//! paged by the loader thread as when flying, in a process of its own. Each
//! lap ends at the same pose, settled there, with the same tiles, the same
//! allocator bytes in use and the same picture; once the node atlas is full,
//! resident memory stays flat, and the allocator's workspace (where
//! fragmentation shows) does not grow from the first laps to the last.
//!
//! EGL is mandatory, as for the other render tests: a missing context fails.

use glam::{DVec3, UVec2};
use image::RgbaImage;
use ridgeline::camera::Camera;
use ridgeline::clipmap::LoaderMode;
use ridgeline::display::{DisplayConfig, DisplayParts};
use ridgeline::gl::GlBackend;
use ridgeline::lod::TileKey;
use ridgeline::node::NodeSource;
use ridgeline::procedural::{EarthParams, ProceduralEarth};
use ridgeline::render::{palette, DrawList, PostFrame, TileUniforms};
use ridgeline::scene::TerrainSummary;
use ridgeline::tiles::TileVertex;
use std::collections::{BTreeMap, BTreeSet};
use std::sync::Arc;
use std::time::Instant;
use testkit::camera;
use testkit::compare::{difference_image, save_evidence};
use testkit::flight::{self, Frame, Settle};
use testkit::gl::{child_test, run_child, take_turn};
use testkit::render::{redraw, render};

/// The earth of [`EarthParams::earth`] (2^24 posts of 2.4 m, 40 000 km a
/// side, nodes of 64 cells) with posts `2^thin` times as far apart, and two
/// border posts. At 2.4 m one settled view of the earth-scale test pages
/// 65 000 nodes (a minute): the 9.2 km height range widens every ring.
fn earth_params(thin: u32) -> EarthParams {
    EarthParams {
        node_size: 64,
        levels: 19 - thin as u8,
        border: 2,
        spacing_m: 2.4 * (1u32 << thin) as f64,
        seed: 11,
    }
}

/// Per-level error and height range, from the earth's own bounds.
fn summary(earth: &ProceduralEarth) -> TerrainSummary {
    TerrainSummary::from_procedural(earth)
}

fn open(config: &DisplayConfig, earth: Arc<ProceduralEarth>) -> DisplayParts {
    let summary = summary(&earth);
    DisplayParts::open(config, earth, summary).expect("EGL display")
}

// ---------------------------------------------------------------- earth scale

/// Posts of 38.4 m.
const EARTH_THIN: u32 = 4;
/// Level-0 posts between the two places, east and north: 2^18 posts of
/// 38.4 m, 10 066 330 m. A multiple of the tile span of every level up to 13
/// (32-cell tiles) and of the node span of every level up to 12; the root
/// level is 14.
const SHIFT_POSTS: u32 = 1 << 18;
const EARTH_SIZE: UVec2 = UVec2::new(256, 144);
/// Vertex positions must agree, and lie this close to the exact ones.
const CENTIMETRE: f64 = 0.01;
/// Within this distance of the camera f32 itself resolves a centimetre
/// (its spacing at 65 km is 4 mm), so positions are checked against f64.
const EXACT_RADIUS_M: f64 = 65_000.0;

/// Horizon culling off: the views check the precision of every level
/// drawn far out, and the band view's last tiles lie below the horizon.
fn earth_config() -> DisplayConfig {
    let mut config = DisplayConfig {
        loader: LoaderMode::Inline,
        load_budget: 1000,
        ..DisplayConfig::new(GlBackend::Egl, EARTH_SIZE)
    };
    config.scene.horizon_culling = false;
    config
}

/// A view near the origin; the far one is the same view moved by the shift.
struct EarthView {
    name: &'static str,
    camera: Camera,
    /// Whether a metre moves a sharp edge of this picture by a pixel, so the
    /// picture alone must show the f32 fault.
    sharp: bool,
}

/// The views near the origin, both looking north-east (away from the data's
/// edges). The earth is gentle at this post spacing (its short wavelengths
/// are low), so the picture is smooth but for the terrain-awareness bands:
/// - "horizon": 900 m above the ground, nose 8 degrees down, every level out
///   to the horizon;
/// - "band": nose 20 degrees down, the aircraft the caution band (304.8 m)
///   above the ground 250 m ahead, so the amber band's sharp edge crosses the
///   picture where a metre is about a pixel.
fn near_views(earth: &ProceduralEarth) -> [EarthView; 2] {
    let ground = |x: f64, y: f64| earth.exact_height(x, y).expect("inside the earth") as f64;
    let (x, y) = (30_000.0, 30_000.0);
    let ahead = 250.0 * std::f64::consts::FRAC_1_SQRT_2;
    let band_edge = ground(x + ahead, y + ahead) + palette::DEFAULT_CAUTION_BELOW_M as f64;
    [
        EarthView {
            name: "horizon",
            camera: camera(EARTH_SIZE.into(), DVec3::new(x, y, ground(x, y) + 900.0), 45.0, -8.0),
            sharp: false,
        },
        EarthView {
            name: "band",
            camera: camera(EARTH_SIZE.into(), DVec3::new(x, y, band_edge), 45.0, -20.0),
            sharp: true,
        },
    ]
}

/// One drawn tile: its uniforms and its block's vertices (position, this
/// level's height, the morph target and the normals) as the GPU buffer
/// holds them.
struct Drawn {
    uniforms: TileUniforms,
    /// The frame's post numbering.
    posts: PostFrame,
    vertices: Vec<TileVertex>,
}

/// The draws of the display's last frame, keyed by tile.
fn drawn(display: &DisplayParts, list: &DrawList) -> BTreeMap<TileKey, Drawn> {
    let (staging, _) = display.pipeline.scene().uploads();
    list.tiles
        .iter()
        .map(|tile| {
            let vertices = tile.block(staging).vertices().collect();
            (
                tile.key,
                Drawn {
                    uniforms: *tile,
                    posts: list.uniforms.expect("a drawn frame").posts,
                    vertices,
                },
            )
        })
        .collect()
}

/// Where the vertex shader puts vertex `v` of a tile, relative to the
/// camera, computed as it does in f32 (before morphing, which only blends
/// heights by this position's distance).
fn shader_position(tile: &Drawn, v: usize, altitude: f64) -> [f32; 3] {
    let vertex = tile.vertices[v];
    let [i, j] = vertex.post.map(f32::from);
    let [x, y] = tile.uniforms.post_position(&tile.posts, i, j);
    [x, y, vertex.height - altitude as f32]
}

/// The same vertex placed exactly in f64 from the tile key and the camera.
fn exact_position(tile: &Drawn, grid: u32, v: usize, eye: DVec3, spacing_m: f64) -> DVec3 {
    let key = tile.uniforms.key;
    let vertex = tile.vertices[v];
    let post =
        |k: u32, n: u16| ((k as u64 * grid as u64 + n as u64) << key.level) as f64 * spacing_m;
    DVec3::new(post(key.x, vertex.post[0]), post(key.y, vertex.post[1]), vertex.height as f64) - eye
}

/// How the far view's tiles and vertices compare with the near view's.
#[derive(Debug, Default)]
struct Agreement {
    /// Largest difference between matching vertices of the two views, metres.
    between_views_m: f64,
    /// Largest error against f64 within [`EXACT_RADIUS_M`], of either view.
    against_exact_m: f64,
    vertices: usize,
    near_vertices: usize,
    /// Tiles whose uniforms (relative to each view's anchor) or vertex data differ.
    other_differences: Vec<TileKey>,
}

/// Compares the far view's draws, moved back by [`SHIFT_POSTS`], with the
/// near view's. Panics if they are not the same tiles.
fn agreement(
    far: &BTreeMap<TileKey, Drawn>,
    far_eye: DVec3,
    near: &BTreeMap<TileKey, Drawn>,
    near_eye: DVec3,
    grid: u32,
) -> Agreement {
    let moved: BTreeMap<TileKey, &Drawn> =
        far.iter().map(|(&key, tile)| (moved_back(key, grid), tile)).collect();
    let (far_keys, near_keys): (BTreeSet<TileKey>, BTreeSet<TileKey>) =
        (moved.keys().copied().collect(), near.keys().copied().collect());
    let only_far: Vec<_> = far_keys.difference(&near_keys).collect();
    let only_near: Vec<_> = near_keys.difference(&far_keys).collect();
    assert!(
        only_far.is_empty() && only_near.is_empty(),
        "different tiles: only far {only_far:?}, only near {only_near:?}"
    );
    let spacing_m = earth_params(EARTH_THIN).spacing_m;
    let mut result = Agreement::default();
    for (key, near_tile) in near {
        let far_tile = moved[key];
        let (a, b) = (far_tile.uniforms, near_tile.uniforms);
        if a.first_post != b.first_post
            || a.post_step != b.post_step
            || a.morph != b.morph
            || a.skirt_depth != b.skirt_depth
            || far_tile.vertices != near_tile.vertices
        {
            result.other_differences.push(*key);
        }
        // The surface's vertices (skirts repeat edge posts), matched by
        // number: the far tile shows what the near one shows.
        let count = near_tile.vertices.len().min(far_tile.vertices.len());
        let surface = (0..count).filter(|&v| near_tile.vertices[v].edge() == 0);
        for v in surface {
            let p = shader_position(far_tile, v, far_eye.z);
            let q = shader_position(near_tile, v, near_eye.z);
            let apart = (0..3).map(|c| (p[c] as f64 - q[c] as f64).abs()).fold(0.0, f64::max);
            result.between_views_m = result.between_views_m.max(apart);
            result.vertices += 1;
            for (tile, position, eye) in [(far_tile, p, far_eye), (near_tile, q, near_eye)] {
                let exact = exact_position(tile, grid, v, eye, spacing_m);
                if exact.truncate().length() <= EXACT_RADIUS_M {
                    let error =
                        (0..3).map(|c| (position[c] as f64 - exact[c]).abs()).fold(0.0, f64::max);
                    result.against_exact_m = result.against_exact_m.max(error);
                    result.near_vertices += 1;
                }
            }
        }
    }
    result
}

/// The tile of the shifted earth that shows what `key` shows here.
fn moved_back(key: TileKey, grid: u32) -> TileKey {
    let span = (grid as u64) << key.level;
    assert_eq!(
        SHIFT_POSTS as u64 % span,
        0,
        "tile {key:?}: the shift is not a whole tile of level {}",
        key.level
    );
    let shift = (SHIFT_POSTS as u64 / span) as u32;
    TileKey::new(key.level, key.x - shift, key.y - shift)
}

/// The fault this test exists for: posts placed in f32 absolute
/// coordinates (absolute post numbers and the camera each narrowed to f32).
fn origins_in_f32_absolute(list: &mut DrawList, eye: DVec3, grid: u32) {
    if let Some(frame) = &mut list.uniforms {
        frame.posts.anchor = [0, 0];
        frame.posts.offset = [eye.x as f32, eye.y as f32];
    }
    for tile in &mut list.tiles {
        let span = (grid as u64) << tile.key.level;
        tile.first_post = [(tile.key.x as u64 * span) as f32, (tile.key.y as u64 * span) as f32];
    }
}

/// Pixels where some channel differs at all, and by more than one step.
fn count_differing(a: &RgbaImage, b: &RgbaImage) -> (usize, usize) {
    let mut counts = (0, 0);
    for (p, q) in a.pixels().zip(b.pixels()) {
        let d = (0..3).map(|c| p.0[c].abs_diff(q.0[c])).max().unwrap_or(0);
        counts.0 += usize::from(d > 0);
        counts.1 += usize::from(d > 1);
    }
    counts
}

/// Saves both pictures and their difference; returns where, for a panic.
fn evidence(name: &str, [(a_name, a), (b_name, b)]: [(&str, &RgbaImage); 2]) -> [String; 3] {
    [
        save_evidence(a, &format!("{name}-{a_name}")),
        save_evidence(b, &format!("{name}-{b_name}")),
        save_evidence(&difference_image(a, b, 1), &format!("{name}-diff")),
    ]
}

/// One view drawn at both places and compared, then the far one redrawn
/// with [`origins_in_f32_absolute`] and compared again.
struct BothPlaces {
    tiles: usize,
    levels: BTreeSet<u8>,
    positions: Agreement,
    /// Pixels that differ at all, and by more than one step.
    pixels: (usize, usize),
    images: [RgbaImage; 2],
    fault_positions: Agreement,
    fault_pixels: (usize, usize),
    fault_image: RgbaImage,
}

fn draw_at_both_places(
    far: &mut DisplayParts,
    near: &mut DisplayParts,
    near_camera: &Camera,
) -> BothPlaces {
    let grid = earth_config().scene.lod.grid_size;
    let shift_m = SHIFT_POSTS as f64 * earth_params(EARTH_THIN).spacing_m;
    let far_camera = Camera {
        position: near_camera.position + DVec3::new(shift_m, shift_m, 0.0),
        ..*near_camera
    };
    let (far_image, far_stats) = render(far, &far_camera);
    let (near_image, near_stats) = render(near, near_camera);
    assert_eq!(
        far_stats.scene.coarsened + near_stats.scene.coarsened,
        0,
        "the GPU buffer was full"
    );
    let far_list = far.pipeline.scene().draw_list().clone();
    let near_tiles = drawn(near, near.pipeline.scene().draw_list());
    let positions = agreement(
        &drawn(far, &far_list),
        far_camera.position,
        &near_tiles,
        near_camera.position,
        grid,
    );
    let fault_image = redraw(far, |list| origins_in_f32_absolute(list, far_camera.position, grid));
    let mut fault_list = far_list;
    origins_in_f32_absolute(&mut fault_list, far_camera.position, grid);
    let fault_positions = agreement(
        &drawn(far, &fault_list),
        far_camera.position,
        &near_tiles,
        near_camera.position,
        grid,
    );
    BothPlaces {
        tiles: near_stats.scene.tiles,
        levels: near_tiles.keys().map(|key| key.level).collect(),
        positions,
        pixels: count_differing(&far_image, &near_image),
        fault_pixels: count_differing(&fault_image, &near_image),
        images: [far_image, near_image],
        fault_positions,
        fault_image,
    }
}

#[test]
fn a_view_ten_thousand_km_out_draws_the_same_picture_as_at_the_origin() {
    let _turn = take_turn();
    let started = Instant::now();
    let config = earth_config();
    let base = ProceduralEarth::new(earth_params(EARTH_THIN)).expect("earth");
    let shifted = base.clone().shifted([SHIFT_POSTS; 2]);
    let views = near_views(&shifted);
    let (mut far, mut near) = (open(&config, Arc::new(base)), open(&config, Arc::new(shifted)));
    for EarthView { name, camera, sharp } in views {
        let both = draw_at_both_places(&mut far, &mut near, &camera);
        let [far_image, near_image] = &both.images;
        let (positions, fault) = (&both.positions, &both.fault_positions);
        println!(
            "{name}: {} tiles of levels {:?}; {} vertices apart by at most {:.1e} m, the {} within {:.0} km off f64 by at most \
             {:.1e} m; {} pixels differ, {} by more than one step",
            both.tiles, both.levels, positions.vertices, positions.between_views_m, positions.near_vertices,
            EXACT_RADIUS_M / 1000.0, positions.against_exact_m, both.pixels.0, both.pixels.1
        );
        println!(
            "{name}, origins in f32 absolute coordinates: vertices apart by {:.2} m, off f64 by {:.2} m; {} pixels differ, \
             {} by more than one step",
            fault.between_views_m, fault.against_exact_m, both.fault_pixels.0, both.fault_pixels.1
        );
        assert!(both.tiles > 30, "{name}: only {} tiles drawn", both.tiles);
        assert!(
            positions.other_differences.is_empty(),
            "{name}: other uniforms or data in {:?}",
            positions.other_differences
        );
        assert!(
            positions.between_views_m < CENTIMETRE,
            "{name}: vertices apart by {} m",
            positions.between_views_m
        );
        assert!(
            positions.against_exact_m < CENTIMETRE,
            "{name}: vertices off by {} m",
            positions.against_exact_m
        );
        if both.pixels.1 > 0 {
            let saved = evidence(name, [("far", far_image), ("near", near_image)]);
            panic!("{name}: {} pixels differ by more than one step: {saved:#?}", both.pixels.1);
        }
        // The checks catch the fault they exist for.
        assert!(
            fault.between_views_m > CENTIMETRE && fault.against_exact_m > CENTIMETRE,
            "{name}: the f32 fault moves no vertex"
        );
        if sharp && both.fault_pixels.1 == 0 {
            let saved = evidence(
                &format!("{name}-f32-fault"),
                [("far", &both.fault_image), ("near", near_image)],
            );
            panic!("{name}: the f32 fault leaves the picture within one step: {saved:#?}");
        }
    }
    println!("earth scale: {:.1} s", started.elapsed().as_secs_f64());
}

// ---------------------------------------------------------------- soak

/// Posts of 153.6 m: llvmpipe transforms every vertex of every tile (about
/// 150 ns each on this machine, whatever the viewport), and the rings are
/// widened by the earth's 9.2 km height range, so finer posts mean more
/// vertices per frame. With 8-cell tiles a frame draws about 50 tiles.
const SOAK_THIN: u32 = 6;
const SOAK_GRID: u32 = 8;
const SOAK_SIZE: UVec2 = UVec2::new(64, 36);
/// Frames per lap of the circuit, and laps: 10^4 frames.
const LAP: u32 = 400;
const LAPS: usize = 25;
/// How far resident memory may wander once the node atlas is full: the
/// driver and malloc move it in steps of 1 MiB (measured: within 1.02 MiB
/// over 18 laps). A leak of a kilobyte a frame would exceed it.
const RSS_NOISE: u64 = 4 << 20;

/// The process's resident set, bytes (Linux).
fn resident_bytes() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").expect("/proc/self/status");
    let line =
        status.lines().find(|line| line.starts_with("VmRSS:")).expect("VmRSS in /proc/self/status");
    let kib: u64 =
        line.split_whitespace().nth(1).and_then(|n| n.parse().ok()).expect("VmRSS in kB");
    kib * 1024
}

/// Frame `frame` of the circuit: a circle of 300 km radius, heading along
/// it, 3000 m above the ground with the nose 30 degrees down, 2.4 km a frame,
/// one lap every [`LAP`] frames. The loader keeps paging: the circle covers
/// more nodes than the atlas holds.
fn circuit(earth: &ProceduralEarth, frame: u32) -> Camera {
    let a = std::f64::consts::TAU * (frame % LAP) as f64 / LAP as f64;
    let (x, y) = (1_000_000.0 + 300_000.0 * a.cos(), 1_000_000.0 + 300_000.0 * a.sin());
    let ground = earth.exact_height(x, y).expect("inside the earth") as f64;
    let heading = (270.0 - a.to_degrees()).rem_euclid(360.0);
    camera(SOAK_SIZE.into(), DVec3::new(x, y, ground + 3000.0), heading, -30.0)
}

/// One lap: sums over its frames, then its end, drawn settled at the pose
/// every lap starts from.
#[derive(Default)]
struct Lap {
    nodes_loaded: u64,
    bytes_uploaded: u64,
    workspace_sum: f64,
    used_bytes: u64,
    workspace_bytes: u32,
    tiles: BTreeSet<TileKey>,
    image: RgbaImage,
    resident_bytes: u64,
    atlas_full: bool,
    seconds: f64,
}

impl Lap {
    fn mean_workspace(&self) -> f64 {
        self.workspace_sum / LAP as f64
    }

    /// Settles at the start pose, draws it and records the end of the lap.
    fn end(&mut self, display: &mut DisplayParts, start: &Camera, started: Instant) {
        let (image, stats) = render(display, start);
        let atlas = display.pipeline.clipmap().atlas();
        self.used_bytes = stats.scene.allocator_used_bytes;
        self.workspace_bytes = stats.scene.allocator_workspace_bytes;
        self.tiles =
            display.pipeline.scene().draw_list().tiles.iter().map(|tile| tile.key).collect();
        self.image = image;
        self.resident_bytes = resident_bytes();
        self.atlas_full = atlas.resident_count() == atlas.slot_count();
        self.seconds = started.elapsed().as_secs_f64();
    }
}

fn fly_the_circuit(display: &mut DisplayParts, earth: &ProceduralEarth) -> Vec<Lap> {
    let mut laps = Vec::with_capacity(LAPS);
    for _ in 0..LAPS {
        let (started, mut lap) = (Instant::now(), Lap::default());
        let cameras = (0..LAP).map(|frame| circuit(earth, frame));
        flight::fly(display, cameras, Settle::Never, |Frame { stats, .. }| {
            lap.nodes_loaded += stats.nodes_loaded as u64;
            lap.bytes_uploaded += stats.scene.bytes_uploaded;
            lap.workspace_sum += stats.scene.allocator_workspace_bytes as f64;
        });
        lap.end(display, &circuit(earth, 0), started);
        laps.push(lap);
    }
    laps
}

fn mean(laps: &[Lap], of: impl Fn(&Lap) -> f64) -> f64 {
    laps.iter().map(of).sum::<f64>() / laps.len() as f64
}

/// The soak runs in a process of its own: memory another test freed stays
/// resident and would hide a leak of up to that size.
#[test]
fn ten_thousand_gl_frames_keep_memory_and_free_space_flat() {
    let _turn = take_turn();
    run_child(&mut child_test("soak_in_a_process_of_its_own"), "soak");
}

#[test]
#[ignore = "run by ten_thousand_gl_frames_keep_memory_and_free_space_flat in a process of its own"]
fn soak_in_a_process_of_its_own() {
    let started = Instant::now();
    let earth = Arc::new(ProceduralEarth::new(earth_params(SOAK_THIN)).expect("earth"));
    // The loader thread pages nodes, as when flying.
    let mut config = DisplayConfig::new(GlBackend::Egl, SOAK_SIZE);
    config.scene.lod.grid_size = SOAK_GRID;
    let mut display = open(&config, earth.clone());
    let laps = fly_the_circuit(&mut display, &earth);
    for (k, lap) in laps.iter().enumerate() {
        println!(
            "lap {k:2}: {} tiles, {} bytes used, workspace {} (lap mean {:.0}), {:.2} MiB resident, atlas {}, \
             {} nodes loaded, {} bytes uploaded, {:.2} s",
            lap.tiles.len(), lap.used_bytes, lap.workspace_bytes, lap.mean_workspace(), lap.resident_bytes as f64 / 1048576.0,
            if lap.atlas_full { "full" } else { "filling" }, lap.nodes_loaded, lap.bytes_uploaded, lap.seconds
        );
    }
    println!("soak: {} frames in {:.1} s", LAP as usize * LAPS, started.elapsed().as_secs_f64());

    // The same pose after every lap: the same tiles, bytes in use and picture.
    let first = &laps[0];
    for (k, lap) in laps.iter().enumerate().skip(1) {
        assert!(
            (lap.used_bytes, &lap.tiles) == (first.used_bytes, &first.tiles),
            "lap {k} ends with {} tiles in {} bytes, the first lap with {} tiles in {} bytes (same tiles: {})",
            lap.tiles.len(), lap.used_bytes, first.tiles.len(), first.used_bytes, lap.tiles == first.tiles
        );
        if count_differing(&lap.image, &first.image).0 > 0 {
            let saved = evidence(
                &format!("soak-lap-{k}"),
                [("end", &lap.image), ("first-end", &first.image)],
            );
            panic!("lap {k} ends with another picture: {saved:#?}");
        }
    }
    assert!(laps.iter().all(|lap| lap.bytes_uploaded > 0), "the circuit keeps changing tiles");
    // Memory: the node atlas takes its memory up front but touches it as it
    // fills, so resident memory may grow until then and not after.
    let warm = laps.iter().position(|lap| lap.atlas_full).expect("the atlas fills");
    assert!(warm < LAPS / 2, "the atlas filled only after lap {warm}");
    let after = &laps[warm + 1..];
    assert!(
        after.iter().map(|lap| lap.nodes_loaded).sum::<u64>() > 0,
        "the loader stopped paging once the atlas was full"
    );
    let (at_warm, last) = (laps[warm].resident_bytes, laps[LAPS - 1].resident_bytes);
    let highest = after.iter().map(|lap| lap.resident_bytes).max().unwrap_or(at_warm);
    println!(
        "resident: {:.2} MiB when the atlas filled (lap {warm}), {:.2} MiB at the end, at most {:.2} MiB between",
        at_warm as f64 / 1048576.0, last as f64 / 1048576.0, highest as f64 / 1048576.0
    );
    assert!(
        highest <= at_warm + RSS_NOISE,
        "resident memory grows after warm-up: {at_warm} then up to {highest} bytes"
    );
    // Free space: no trend in the workspace (where fragmentation shows),
    // averaged over each lap's frames, from the first third of the laps to the last.
    let third = LAPS / 3;
    let (early, late) = (
        mean(&laps[1..=third], Lap::mean_workspace),
        mean(&laps[LAPS - third..], Lap::mean_workspace),
    );
    println!("workspace: {early:.0} bytes in laps 1 to {third}, {late:.0} in the last {third}");
    assert!(
        late <= early * 1.1,
        "the allocator's workspace grows: {early:.0} then {late:.0} bytes"
    );
}
