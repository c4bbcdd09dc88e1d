//! The null backend counts what a scripted flight would cost a GPU: uploads
//! happen only when tiles change, a still camera uploads nothing, every tile
//! is one draw call, and a buffer too small for the view coarsens the tiles
//! instead of failing or leaving holes.

use ridgeline::render::{
    BufferPlan, CostModel, DrawList, FrameOutput, NullBackend, RenderBackend, RenderError, Slice,
};
use ridgeline::scene::{Scene, SceneConfig};
use ridgeline::tiles::grid::tile_bytes;
use ridgeline::tiles::TileGrid;
use testkit::scene::{fly, null_backend, pipeline, terrain, VIEWPORT};
use testkit::{camera, over_tile};

/// A scripted flight through the whole pipeline (clipmap paging included)
/// on the null backend.
#[test]
fn scripted_flight_counts_and_a_still_camera_uploads_nothing() {
    let config = SceneConfig { transfer_cap: None, ..SceneConfig::default() };
    let mut pipeline = pipeline(config);
    let mut backend = null_backend(&pipeline);
    let mut uploaded = 0;
    for k in 0..20 {
        let cam = camera(
            VIEWPORT,
            over_tile(10_000.0 + 1_500.0 * k as f64, 20_000.0, 3_500.0),
            60.0,
            -6.0,
        );
        let stats = fly(&mut pipeline, &mut backend, &cam).unwrap();
        let (calls, scene) = (stats.calls, stats.scene);
        let slices =
            if pipeline.draw_list().uniforms.unwrap().slices.far.is_some() { 2 } else { 1 };
        let tiles: usize = [Slice::Near, Slice::Far]
            .iter()
            .map(|&slice| pipeline.draw_list().tiles_in(slice).count())
            .sum();
        assert!(tiles >= scene.tiles && tiles <= slices * scene.tiles);
        assert_eq!(calls.draw_calls as usize, tiles + 1, "a draw per tile and slice, and the sky");
        assert_eq!(calls.bytes_uploaded, scene.bytes_uploaded);
        assert!(calls.upload_calls as usize <= 1, "one transfer per frame without a cap");
        assert_eq!(calls.frames, 1);
        uploaded += calls.bytes_uploaded;
    }
    assert!(uploaded > 0, "moving uploads new tiles");
    let still = camera(VIEWPORT, over_tile(40_000.0, 20_000.0, 3_500.0), 60.0, -6.0);
    fly(&mut pipeline, &mut backend, &still).unwrap();
    for _ in 0..5 {
        let stats = fly(&mut pipeline, &mut backend, &still).unwrap();
        let calls = stats.calls;
        assert_eq!(
            (
                calls.bytes_uploaded,
                calls.upload_calls,
                stats.scene.tiles_generated,
                stats.nodes_loaded
            ),
            (0, 0, 0, 0),
            "a still camera pages and uploads nothing"
        );
        assert!(calls.draw_calls > 1);
    }
}

/// The null backend refuses an upload past its buffer with the error the
/// GL backend gives.
#[test]
fn an_upload_past_the_buffer_is_refused() {
    let plan = BufferPlan { buffer_bytes: 64, cluster_index_bytes: None };
    let mut backend = NullBackend::new(&plan, CostModel { vertex_arrays: true, sky: true });
    let staging = [0u8; 128];
    let list = DrawList::default();
    let dirty = std::slice::from_ref(&(32..96));
    let frame = FrameOutput { list: &list, staging: &staging, dirty, indices: None };
    let error = backend.render(&frame).unwrap_err();
    assert_eq!(
        error,
        RenderError::UploadPastBuffer { start: 32, end: 96, capacity: 64, staging: 128 }
    );
}

/// A draw list built for no frame (no uniforms) draws nothing, but the
/// frame's uploads still go: `RenderBackend::render` decides it for every
/// backend.
#[test]
fn a_list_without_uniforms_uploads_and_draws_nothing() {
    let plan = BufferPlan::new(128, false);
    let mut backend = NullBackend::new(&plan, CostModel { vertex_arrays: true, sky: true });
    let (staging, list) = ([0u8; 128], DrawList::default());
    let dirty = std::slice::from_ref(&(0..64u32));
    let frame = FrameOutput { list: &list, staging: &staging, dirty, indices: None };
    backend.render(&frame).expect("an upload within the buffer");
    let calls = backend.take_calls();
    assert_eq!((calls.upload_calls, calls.bytes_uploaded), (1, 64));
    assert_eq!((calls.frames, calls.clears, calls.draw_calls), (0, 0, 0));
}

/// Cluster indices reach only a backend whose buffer plan has an index
/// buffer, within it: the null backend refuses them otherwise, as the GL
/// renderer does.
#[test]
fn cluster_indices_need_a_planned_index_buffer() {
    let model = CostModel { vertex_arrays: true, sky: true };
    let (staging, list) = ([0u8; 128], DrawList::default());
    let indices = std::slice::from_ref(&(0..64u32));
    let frame = FrameOutput {
        list: &list,
        staging: &staging,
        dirty: &[],
        indices: Some((&staging, indices)),
    };
    let without = NullBackend::new(&BufferPlan::new(128, false), model).render(&frame);
    assert_eq!(without.unwrap_err(), RenderError::ClustersNotPlanned);
    let with = BufferPlan::new(128, true);
    assert_eq!(with.cluster_index_bytes, Some(64));
    NullBackend::new(&with, model).render(&frame).expect("indices within the planned buffer");
    let past = std::slice::from_ref(&(0..96u32));
    let frame = FrameOutput { indices: Some((&staging, past)), ..frame };
    let error = NullBackend::new(&with, model).render(&frame).unwrap_err();
    assert!(matches!(error, RenderError::UploadPastBuffer { capacity: 64, .. }), "{error}");
}

#[test]
fn the_default_transfer_cap_bounds_every_upload() {
    let config = SceneConfig::default();
    let cap = config.transfer_cap.expect("the default caps transfers");
    let mut scene = Scene::new(config, terrain()).unwrap();
    let mut pieces = 0;
    for k in 0..10 {
        let cam = camera(
            VIEWPORT,
            over_tile(10_000.0 + 3_000.0 * k as f64, 25_000.0, 3_200.0),
            70.0,
            -6.0,
        );
        scene.frame(&cam, terrain()).unwrap();
        let (_, ranges) = scene.uploads();
        pieces += ranges.len();
        let tile = tile_bytes(config.lod.grid_size);
        assert!(
            ranges.iter().all(|r| r.end - r.start <= cap.max(tile)),
            "a transfer exceeds the cap: {ranges:?}"
        );
    }
    assert!(pieces > 10, "a moving camera's uploads are cut into several transfers");
}

#[test]
fn a_small_buffer_coarsens_instead_of_failing() {
    let roomy = SceneConfig::default();
    // The view wants about 8 MB of tiles; coarsened twice, 3 MB.
    let tight = SceneConfig { buffer_bytes: 1 << 22, ..roomy };
    let cam = camera(VIEWPORT, over_tile(30_000.0, 30_000.0, 2_600.0), 10.0, -10.0);
    let mut full = Scene::new(roomy, terrain()).unwrap();
    let wanted = full.frame(&cam, terrain()).unwrap();
    let mut scene = Scene::new(tight, terrain()).unwrap();
    let report = scene.frame(&cam, terrain()).unwrap();
    assert!(report.coarsened > 0, "4 MB cannot hold {} tiles", wanted.tiles);
    assert!(report.tiles > 0 && report.tiles < wanted.tiles);
    assert!(report.allocator_used_bytes <= 1 << 22);
}

/// The near plane follows the nearest tile drawn, not the highest peak of
/// the data: below the highest summit but high above the valley, a 0.5 m
/// near plane would leave a 24-bit depth buffer blind to hundreds of metres
/// at the horizon. Low over the ground it comes back in front of it.
#[test]
fn the_near_plane_follows_the_nearest_tile() {
    let terrain = terrain();
    let mut scene = Scene::new(SceneConfig::default(), terrain).expect("scene");
    let near = |scene: &mut Scene, cam: &ridgeline::camera::Camera| {
        scene.frame(cam, terrain).expect("frame");
        let frame = scene.draw_list().uniforms.expect("frame uniforms");
        let m = frame.view_projection.to_cols_array();
        // Perspective: near = m[14] / (m[10] - 1) for glam's right-handed GL projection.
        let (c, d) = (m[10] as f64, m[14] as f64);
        d / (c - 1.0)
    };
    // The lowest ground on a 5 km lattice, away from the data's edges.
    let pyramid = testkit::builtin_pyramid();
    let lattice =
        (2..14).flat_map(|i| (2..18).map(move |j| (i as f64 * 5000.0, j as f64 * 5000.0)));
    let origin = testkit::builtin_origin();
    let height = |&(x, y): &(f64, f64)| {
        pyramid.exact_height(origin.x + x, origin.y + y).expect("inside the data") as f64
    };
    let (x, y) = lattice.min_by(|a, b| height(a).total_cmp(&height(b))).expect("points");
    let ground = height(&(x, y));
    let summit = pyramid.info().stats.height_max as f64;
    let high = camera(VIEWPORT, over_tile(x, y, ground + 1000.0), 0.0, -5.0);
    assert!(high.position.z < summit, "the view is below the highest summit ({summit} m)");
    let high_near = near(&mut scene, &high);
    let low = camera(VIEWPORT, over_tile(x, y, ground + 20.0), 0.0, -5.0);
    let low_near = near(&mut scene, &low);
    println!(
        "near plane {high_near:.1} m at {:.0} m above the ground, {low_near:.2} m at 20 m",
        high.position.z - ground
    );
    assert!(high_near > 100.0, "near plane {high_near} m");
    assert!(
        (0.5..16.0).contains(&low_near),
        "near plane {low_near} m must stay in front of the ground 20 m below"
    );
}

/// Over a layered pyramid the LOD never splits a tile whose children have
/// no data of their own (absent nodes): looking from the SRTM tile out over
/// the 5' base, every drawn tile is drawn from its own level's node once the
/// view has settled, and tiles over the base stop at the base's levels.
/// Before this rule the default flight drew about 2000 tiles a frame, most
/// of them resampling the base; now about 550.
#[test]
fn tiles_stop_where_finer_data_stop() {
    let config = SceneConfig::default();
    let mut pipeline = pipeline(config);
    let mut backend = null_backend(&pipeline);
    // 5 km inside the tile's west edge, looking west over the base.
    let cam = camera(VIEWPORT, over_tile(5_000.0, 45_000.0, 4_000.0), 270.0, -4.0);
    let stats = fly(&mut pipeline, &mut backend, &cam).unwrap();
    let drawn = &pipeline.draw_list().drawn;
    let resampled: Vec<_> = drawn.iter().filter(|d| d.source_level != d.key.level).collect();
    assert!(resampled.is_empty(), "tiles drawn from coarser nodes: {resampled:?}");
    let levels: std::collections::BTreeSet<u8> = drawn.iter().map(|d| d.key.level).collect();
    assert!(levels.contains(&0), "the SRTM tile near the camera at level 0: {levels:?}");
    let base_native = 6;
    assert!(
        drawn.iter().any(|d| d.key.level >= base_native),
        "the base beyond at its own levels: {levels:?}"
    );
    println!("{} tiles at levels {levels:?}", stats.scene.tiles);
}

/// Every drawn tile's block holds its whole mesh: vertices on the tile's
/// square, indices right after them naming only its own vertices, surface
/// triangles counter-clockwise from above, blocks apart; tiles cut from node
/// meshes have fewer triangles than the regular grid, and the frame's
/// triangles are the tiles' indices.
#[test]
fn every_tile_carries_its_mesh_in_its_block() {
    let config = SceneConfig::default();
    let terrain = testkit::scene::terrain_meshed();
    let mut scene = Scene::new(config, terrain).unwrap();
    let cam = camera(VIEWPORT, over_tile(30_000.0, 30_000.0, 2_600.0), 10.0, -10.0);
    let report = scene.frame(&cam, terrain).unwrap();
    let (staging, _) = scene.uploads();
    let list = scene.draw_list();
    let grid = TileGrid::new(config.lod.grid_size);
    let mut blocks: Vec<_> = list.tiles.iter().map(|t| t.block_range()).collect();
    blocks.sort_unstable_by_key(|r| r.start);
    assert!(blocks.windows(2).all(|w| w[0].end <= w[1].start), "blocks do not overlap");
    assert!(blocks.iter().all(|r| r.start % 4 == 0 && r.len() % 4 == 0));
    let (mut cut, mut cut_triangles) = (0, 0);
    for tile in &list.tiles {
        let block = tile.block(staging);
        let vertices = block.vertex_count();
        assert_eq!(tile.index_byte_offset, tile.byte_offset + 20 * vertices as u32);
        let side = (config.lod.grid_size as f32 * tile.post_step / tile.vertex_step) as u16;
        assert!(block.vertices().all(|v| v.post[0] <= side && v.post[1] <= side), "{:?}", tile.key);
        for t in 0..block.triangle_count() {
            let corners = block.triangle(t);
            assert!(corners.iter().all(|&v| (v as usize) < vertices));
            if block.is_skirt(t) {
                continue;
            }
            let p = corners.map(|v| block.vertex(v as usize).post.map(|c| c as i64));
            let area = (p[1][0] - p[0][0]) * (p[2][1] - p[0][1])
                - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0]);
            assert!(area > 0, "tile {:?} triangle {t} faces up", tile.key);
        }
        if tile.vertex_step != tile.post_step || vertices != grid.vertices.len() {
            cut += 1;
            cut_triangles += block.triangle_count();
        }
    }
    assert!(cut > list.tiles.len() / 2, "{cut} of {} tiles cut from node meshes", list.tiles.len());
    // A mesh is at most its level's grid with every cell a fan of four
    // (meshes::fan); near the camera, at level 0, it is about the grid
    // plus the fans (15 % more over this view), coarser further out.
    assert!(cut_triangles < 2 * cut * grid.indices.len() / 3, "{cut_triangles} triangles");
    assert_eq!(report.triangles, list.triangles());
}
