//! Layered pyramids: a coarse and a fine layer of different spacings and
//! lattices built into one pyramid. Finer data win where they exist, the
//! seam is continuous where the layers agree and blends over
//! `BLEND_MARGIN_M` where they disagree, levels hold nodes only where data
//! of their resolution are (the rest are absent, and read as absent), each
//! stored delta equals a brute-force recomputation against the best data,
//! large voids are filled from the coarse layer or stay no-data, and layers
//! that cannot be stacked are refused with a reason.

use ridgeline::dem::{voids, ElevationGrid, RawGrid};
use ridgeline::geo::{Crs, GeoRef};
use ridgeline::node::{NodeData, NodeError, NodeId, NodeSource};
use ridgeline::pyramid::{build_layers, BuildOptions, Pyramid, Silent, BLEND_MARGIN_M, FILE_NAME};
use testkit::fresh_dir;

/// Coarse layer: 900 m posts, 60 x 60 (53 km).
const COARSE: [f64; 2] = [900.0, 900.0];
/// Fine layer: 90 m posts, 240 x 200, its south-west post at this offset
/// from the coarse layer's (not on the coarse lattice).
const FINE: [f64; 2] = [90.0, 90.0];
const FINE_ORIGIN: [f64; 2] = [15_030.0, 12_060.0];
const FINE_POSTS: [u32; 2] = [240, 200];

/// A smooth non-linear terrain, metres.
fn terrain(x: f64, y: f64) -> f64 {
    800.0 + 300.0 * (x / 7000.0).sin() * (y / 9000.0).cos() + 0.01 * x
}

fn layer(
    origin: [f64; 2],
    spacing: [f64; 2],
    posts: [u32; 2],
    h: impl Fn(f64, f64) -> f64,
) -> ElevationGrid {
    testkit::pyramid::projected_grid(origin, spacing, posts, h)
}

fn coarse(h: impl Fn(f64, f64) -> f64) -> ElevationGrid {
    layer([0.0, 0.0], COARSE, [60, 60], h)
}

fn fine(h: impl Fn(f64, f64) -> f64) -> ElevationGrid {
    layer(FINE_ORIGIN, FINE, FINE_POSTS, h)
}

/// Builds and writes `layers`, and opens the result.
fn open(layers: &[ElevationGrid], case: &str) -> Pyramid {
    let dir = fresh_dir(&format!("layers-{case}"));
    let options = BuildOptions { node_size: 32, border: 2 };
    let built = build_layers(layers, &options, &Silent).expect("build the layers");
    let path = dir.join(FILE_NAME);
    ridgeline::pyramid::write_atomic(&built, &path, &Silent).expect("write");
    let pyramid = Pyramid::open(&path).expect("open");
    pyramid.verify().expect("every present node verifies");
    pyramid
}

/// Local-frame position of a point given in the layers' coordinates (the
/// pyramid's origin is the union's south-west post).
fn local(pyramid: &Pyramid, x: f64, y: f64) -> (f64, f64) {
    let origin = pyramid.info().georef.origin;
    (x - origin[0], y - origin[1])
}

fn height(pyramid: &Pyramid, x: f64, y: f64) -> f64 {
    let (x, y) = local(pyramid, x, y);
    NodeSource::exact_height(pyramid, x, y).expect("inside the data") as f64
}

#[test]
fn the_finer_layer_wins_on_its_own_lattice_and_levels_hold_only_their_data() {
    let pyramid = open(&[coarse(terrain), fine(|x, y| terrain(x, y) + 40.0)], "wins");
    let info = pyramid.info();
    let layout = *pyramid.layout();
    // Level 0 is the fine lattice over the union of both layers.
    assert_eq!(info.georef.spacing, FINE);
    assert_eq!(info.layers, 2);
    assert_eq!(layout.posts, [591, 591]);
    assert_eq!(info.finest.posts, FINE_POSTS);
    // Deep inside the fine layer (farther than the blend margin from its
    // edge) every level-0 post is the fine data, bit for bit.
    let inside = (BLEND_MARGIN_M / FINE[0]).ceil() as u32 + 1;
    for j in (inside..FINE_POSTS[1] - inside).step_by(17) {
        for i in (inside..FINE_POSTS[0] - inside).step_by(13) {
            let (x, y) = (FINE_ORIGIN[0] + i as f64 * FINE[0], FINE_ORIGIN[1] + j as f64 * FINE[1]);
            assert_eq!(
                height(&pyramid, x, y) as f32,
                (terrain(x, y) + 40.0) as f32,
                "post ({i}, {j})"
            );
        }
    }
    // Far from the fine layer the coarse data answer.
    let (x, y) = (45_000.0, 45_000.0);
    assert!((height(&pyramid, x, y) - terrain(x, y)).abs() < 20.0);
    // The coarse layer (10 x the fine spacing) is native at level 3: levels
    // 0 to 2 hold nodes only around the fine layer, level 3 everywhere.
    let coarse_level = 3;
    for lod in 0..layout.levels {
        let level = &info.levels[lod as usize];
        let all = layout.nodes_at_count(lod);
        if lod < coarse_level {
            assert!(level.present < all, "level {lod}: {} of {all} present", level.present);
        } else {
            assert_eq!(level.present, all, "level {lod}");
        }
    }
    let far = NodeId::new(0, 15, 15);
    let (x, y) = local(&pyramid, 20_000.0, 20_000.0);
    let near = layout.locate(0, x, y);
    assert!(!pyramid.has_node(far) && pyramid.node_summary(far).is_none());
    assert!(pyramid.record_range(far).is_none());
    let mut data = NodeData::default();
    assert!(matches!(pyramid.read_node(far, &mut data), Err(NodeError::Absent { .. })));
    let near = near.expect("inside the data").id;
    assert!(pyramid.has_node(near));
    pyramid.read_node(near, &mut data).expect("a present node reads");
    // Every present node's parent is present (the clipmap's fallback chain).
    for lod in 0..layout.levels - 1 {
        let [nx, ny] = layout.nodes_at(lod);
        for y in 0..ny {
            for x in 0..nx {
                let id = NodeId::new(lod, x, y);
                if pyramid.has_node(id) {
                    assert!(pyramid.has_node(id.parent().expect("a parent")), "{id:?}");
                }
            }
        }
    }
}

/// Heights along the east-west line at `y` from 5 km west of the fine
/// layer to its middle, every 30 m.
fn profile(pyramid: &Pyramid, y: f64) -> Vec<(f64, f64)> {
    (0..)
        .map(|k| FINE_ORIGIN[0] - 5000.0 + 30.0 * k as f64)
        .take_while(|&x| x < FINE_ORIGIN[0] + 0.5 * FINE_POSTS[0] as f64 * FINE[0])
        .map(|x| (x, height(pyramid, x, y)))
        .collect()
}

#[test]
fn the_seam_is_continuous_where_the_layers_agree() {
    // A plane: both layers' triangles reproduce it exactly.
    let plane = |x: f64, y: f64| 1000.0 + 0.02 * x - 0.01 * y;
    let pyramid = open(&[coarse(plane), fine(plane)], "agree");
    let y = FINE_ORIGIN[1] + 100.0 * FINE[1];
    for (x, h) in profile(&pyramid, y) {
        assert!((h - plane(x, y)).abs() < 1e-2, "at x = {x}: {h} against {}", plane(x, y));
    }
}

#[test]
fn the_seam_blends_over_the_margin_where_the_layers_disagree() {
    let plane = |x: f64, y: f64| 1000.0 + 0.02 * x - 0.01 * y;
    let offset = 100.0;
    let pyramid = open(&[coarse(plane), fine(move |x, y| plane(x, y) + offset)], "disagree");
    let y = FINE_ORIGIN[1] + 100.0 * FINE[1];
    let edge = FINE_ORIGIN[0];
    // The cosine ramp's steepest slope, plus the terrain's own.
    let steepest = std::f64::consts::FRAC_PI_2 * offset / BLEND_MARGIN_M + 0.03;
    let profile = profile(&pyramid, y);
    for pair in profile.windows(2) {
        let ((x0, h0), (x1, h1)) = (pair[0], pair[1]);
        // Between fine posts the surface is linear on 90 m cells: allow one
        // cell of chord error on top of the ramp.
        assert!(
            (h1 - h0).abs() <= steepest * (x1 - x0) * 1.1 + 1.0,
            "cliff between {x0} and {x1}: {h0} to {h1}"
        );
    }
    for &(x, h) in &profile {
        let blend = h - plane(x, y);
        if x <= edge {
            assert!(blend.abs() < 0.5, "outside the fine layer at {x}: {blend}");
        } else if x >= edge + BLEND_MARGIN_M + FINE[0] {
            assert!((blend - offset).abs() < 0.5, "past the margin at {x}: {blend}");
        } else {
            assert!((-0.5..=offset + 0.5).contains(&blend), "inside the margin at {x}: {blend}");
        }
    }
    // Halfway into the margin the ramp is at half.
    let mid = edge + BLEND_MARGIN_M / 2.0;
    let (x, h) = profile
        .iter()
        .copied()
        .min_by(|a, b| (a.0 - mid).abs().total_cmp(&(b.0 - mid).abs()))
        .expect("a sample");
    assert!((h - plane(x, y) - offset / 2.0).abs() < 0.1 * offset, "at {x}: {h}");
}

#[test]
fn stored_deltas_equal_brute_force_against_the_best_data() {
    let pyramid =
        open(&[coarse(terrain), fine(|x, y| terrain(x, y) + 25.0 * (x / 300.0).sin())], "delta");
    let layout = *pyramid.layout();
    let mut node = NodeData::default();
    let mut checked = 0;
    for lod in 1..layout.levels {
        let [nx, ny] = layout.nodes_at(lod);
        for (x, y) in [(0, 0), (nx / 2, ny / 2), (nx - 1, ny - 1), (nx / 3, ny / 2)] {
            let id = NodeId::new(lod, x, y);
            if !pyramid.has_node(id) {
                continue;
            }
            pyramid.read_node(id, &mut node).expect("read");
            // Every level-0 position under the node: the best data there are
            // linear between the finest present posts, so the maximum over
            // level-0 positions is the maximum over the area.
            let span = layout.span(lod);
            let step = (span / 64).max(1);
            let mut brute = 0.0f64;
            for j in (id.y as u64 * span..=(id.y as u64 + 1) * span).step_by(step as usize) {
                for i in (id.x as u64 * span..=(id.x as u64 + 1) * span).step_by(step as usize) {
                    if i >= layout.posts[0] as u64 || j >= layout.posts[1] as u64 {
                        continue;
                    }
                    // On the node's north and east edges the truth is read
                    // from inside the node: where the neighbour's finest
                    // present level differs, the best data along a shared
                    // edge are those of the side that is measured.
                    let inward = |k: u64, last: u64| if k == last { -1e-6 } else { 0.0 };
                    let xm = i as f64 * layout.spacing_m[0] + inward(i, (id.x as u64 + 1) * span);
                    let ym = j as f64 * layout.spacing_m[1] + inward(j, (id.y as u64 + 1) * span);
                    let truth = NodeSource::exact_height(&pyramid, xm, ym).expect("inside") as f64;
                    let posts = [
                        (i - id.x as u64 * span) as f64 / (1u64 << lod) as f64,
                        (j - id.y as u64 * span) as f64 / (1u64 << lod) as f64,
                    ];
                    let surface = node.interpolate(&layout, posts) as f64;
                    brute = brute.max((truth - surface).abs());
                }
            }
            let stored = node.delta as f64;
            assert!(stored >= brute - 1e-3, "{id:?}: stored {stored} below brute force {brute}");
            if step == 1 {
                assert!(
                    stored - brute <= 1e-3 * stored.max(1.0),
                    "{id:?}: stored {stored}, brute force {brute}"
                );
            }
            checked += 1;
        }
    }
    assert!(checked >= 6, "only {checked} nodes checked");
    // The fine layer's level 0 passes through its posts.
    assert_eq!(pyramid.info().levels[0].delta_max, 0.0);
}

/// A raw grid of `posts` with the posts `void(i, j)` marks as voids.
fn with_voids(grid: &ElevationGrid, void: impl Fn(u32, u32) -> bool) -> RawGrid {
    let mut raw =
        RawGrid::voids(std::path::Path::new("voids.tif"), grid.width, grid.height, grid.georef);
    for j in 0..grid.height {
        for i in 0..grid.width {
            if !void(i, j) {
                raw.heights[(j * grid.width + i) as usize] = grid.at(i, j);
            }
        }
    }
    raw
}

#[test]
fn small_voids_are_interpolated_large_ones_filled_from_the_base_or_left_without_data() {
    let small = |i: u32, j: u32| (20..23).contains(&i) && (30..33).contains(&j);
    let large = |i: u32, j: u32| (100..130).contains(&i) && (80..110).contains(&j);
    let raw = with_voids(&fine(terrain), |i, j| small(i, j) || large(i, j));
    let filled = voids::fill_small(raw).expect("fill");
    assert_eq!(filled.voids_filled, 9, "the 3 x 3 void is interpolated");
    assert!(filled.at(21, 31).is_finite());
    assert!(filled.at(115, 95).is_nan(), "the 30 x 30 void is not invented");
    // Alone: the large void is no data, in the pyramid too.
    let alone = open(std::slice::from_ref(&filled), "void-alone");
    let stats = alone.info().stats;
    assert_eq!((stats.voids_filled, stats.posts_from_layer, stats.posts_no_data), (9, 0, 900));
    let (x, y) = (FINE_ORIGIN[0] + 115.0 * FINE[0], FINE_ORIGIN[1] + 95.0 * FINE[1]);
    assert!(height(&alone, x, y).is_nan());
    // Over a base: filled from the base.
    let over = open(&[coarse(terrain), filled], "void-base");
    let stats = over.info().stats;
    assert_eq!((stats.voids_filled, stats.posts_from_layer, stats.posts_no_data), (9, 900, 0));
    assert!((height(&over, x, y) - terrain(x, y)).abs() < 20.0);
}

#[test]
fn a_partial_hgt_tile_is_not_invented_and_is_filled_from_a_base() {
    let dir = fresh_dir("layers-partial-hgt");
    let side = 1201usize;
    let void = |i: usize, j: usize| i >= side - 200 || j < 200;
    let heights: Vec<i16> = (0..side * side)
        .map(|k| (k % side, k / side))
        .map(|(i, j)| if void(i, j) { -32768 } else { 1500 + (i as i16 % 100) + (j as i16 % 50) })
        .collect();
    let hgt = dir.join("N39E040.hgt");
    testkit::dem::write_hgt(&hgt, side, &heights);
    let tile = ridgeline::dem::import_file(&hgt).expect("import the partial tile");
    let voids = heights.iter().filter(|&&h| h == -32768).count() as u64;
    assert_eq!(tile.voids_filled, 0);
    assert_eq!(tile.heights.iter().filter(|h| h.is_nan()).count() as u64, voids);
    let alone = open(std::slice::from_ref(&tile), "partial-alone");
    assert_eq!(alone.info().stats.posts_no_data, voids);
    // A 30" base in degrees under it.
    let spacing = 1.0 / 120.0;
    let base = ElevationGrid {
        width: 200,
        height: 200,
        heights: vec![1200.0; 200 * 200],
        georef: GeoRef { crs: Crs::Geographic, origin: [39.5, 38.5], spacing: [spacing; 2] },
        voids_filled: 0,
    };
    let layered = open(&[tile, base], "partial-base");
    let stats = layered.info().stats;
    assert_eq!((stats.posts_from_layer, stats.posts_no_data), (voids, 0));
    // The void corner (south-east of the tile) has the base's height.
    let georef = layered.info().georef;
    let spacing_m = layered.layout().spacing_m;
    let (lon, lat) = (40.95, 39.05);
    let x = (lon - georef.origin[0]) / georef.spacing[0] * spacing_m[0];
    let y = (lat - georef.origin[1]) / georef.spacing[1] * spacing_m[1];
    let h = NodeSource::exact_height(&layered, x, y).expect("inside");
    assert!((h - 1200.0).abs() < 1e-3, "{h}");
}

#[test]
fn layers_in_different_coordinate_systems_are_refused_naming_the_layer() {
    let mut degrees = fine(terrain);
    degrees.georef =
        GeoRef { crs: Crs::Geographic, origin: [40.0, 39.0], spacing: [1.0 / 1200.0; 2] };
    let Err(error) = build_layers(&[coarse(terrain), degrees], &BuildOptions::default(), &Silent)
    else {
        panic!("layers in metres and degrees were stacked");
    };
    let message = error.to_string();
    assert!(message.contains("layer 2") && message.contains("coordinate system"), "{message}");
    let Err(error) = build_layers(&[], &BuildOptions::default(), &Silent) else {
        panic!("no layers built");
    };
    assert!(error.to_string().contains("no layer"), "{error}");
}

#[test]
fn a_version_1_pyramid_is_refused_with_a_rebuild_hint() {
    let dir = fresh_dir("layers-version");
    let built = build_layers(&[fine(terrain)], &BuildOptions::default(), &Silent).expect("build");
    let path = dir.join(FILE_NAME);
    ridgeline::pyramid::write_atomic(&built, &path, &Silent).expect("write");
    let mut bytes = std::fs::read(&path).expect("read");
    bytes[8..12].copy_from_slice(&1u32.to_le_bytes());
    std::fs::write(&path, bytes).expect("write");
    let Err(error) = Pyramid::open(&path) else { panic!("a version 1 file opened") };
    let message = error.to_string();
    assert!(message.contains("version 1") && message.contains("rebuild"), "{message}");
    assert!(message.contains(&path.display().to_string()), "{message}");
}

#[test]
fn the_clipmap_never_asks_for_absent_nodes_and_answers_from_the_best_data() {
    use glam::{DVec2, DVec3};
    use ridgeline::clipmap::{Clipmap, ClipmapConfig, LoaderMode, ViewConfig};
    let pyramid = std::sync::Arc::new(open(&[coarse(terrain), fine(terrain)], "clipmap"));
    let config = ClipmapConfig {
        atlas_bytes: None,
        atlas_slots: 400,
        budget: 8,
        loader: LoaderMode::Inline,
    };
    let mut clipmap = Clipmap::new(pyramid.clone(), config).expect("a clipmap");
    let view_config = ViewConfig { node_count: 8, view_distance: 2.0, load_distance: 2.5 };
    // Over the coarse layer next to the fine one: views want level 0 there.
    let (x, y) = local(&pyramid, FINE_ORIGIN[0] - 1500.0, FINE_ORIGIN[1] + 9000.0);
    let view = clipmap.add_view(view_config, DVec3::new(x, y, 2000.0)).expect("a view");
    let mut settled = false;
    for _ in 0..500 {
        let stats = clipmap.update().expect("update");
        assert_eq!((stats.failed, stats.given_up), (0, 0), "{stats:?}");
        if stats.missing == 0 && stats.in_flight == 0 {
            settled = true;
            break;
        }
    }
    assert!(settled, "the clipmap never settled");
    let layout = *pyramid.layout();
    let [nx, ny] = layout.nodes_at(0);
    for id in (0..ny).flat_map(|y| (0..nx).map(move |x| NodeId::new(0, x, y))) {
        assert!(pyramid.has_node(id) || !clipmap.is_wanted(id), "{id:?} is absent but wanted");
    }
    assert!(clipmap.last_load_error().is_none());
    for (dx, dy) in [(0.0, 0.0), (2500.0, 0.0), (-800.0, 300.0)] {
        let point = DVec2::new(x + dx, y + dy);
        let sample = clipmap.height_at(view, point).expect("a height");
        let exact = NodeSource::exact_height(&*pyramid, point.x, point.y).expect("inside");
        assert!(
            (sample.height_m - exact).abs() <= 1e-3,
            "at {point}: {} against the best data {exact}",
            sample.height_m
        );
    }
}
