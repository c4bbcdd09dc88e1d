//! A pyramid damaged after it was opened still flies: opening checks only the
//! header, the bad node is caught when it is paged in, reported once, never
//! put in the atlas, and the views answer from its coarser ancestor.

use std::io::{Read, Seek, SeekFrom, Write};
use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::{DVec2, DVec3};
use ridgeline::clipmap::{Clipmap, ClipmapConfig, LoaderMode};
use ridgeline::node::{NodeData, NodeError, NodeId, NodeSource};
use ridgeline::pyramid::{BuildOptions, Pyramid, PyramidError};
use testkit::clipmap::{check_entries, check_height, VIEW};
use testkit::fresh_dir;
use testkit::pyramid::{build_and_write, random_grid};

/// Inverts `len` bytes of the file at `at`, in place, as a foreign program
/// (or a failing disk) would.
fn flip_bytes(path: &std::path::Path, at: u64, len: usize) {
    let mut file = std::fs::OpenOptions::new().read(true).write(true).open(path).expect("open");
    let mut bytes = vec![0u8; len];
    file.seek(SeekFrom::Start(at)).expect("seek");
    file.read_exact(&mut bytes).expect("read");
    bytes.iter_mut().for_each(|b| *b ^= 0xFF);
    file.seek(SeekFrom::Start(at)).expect("seek");
    file.write_all(&bytes).expect("write");
}

#[test]
fn a_node_damaged_after_opening_is_reported_once_and_replaced_by_its_ancestor() {
    let dir = fresh_dir("corrupt-flies");
    let grid = random_grid(300, 300, 31);
    let (_, path) = build_and_write(&grid, BuildOptions { node_size: 16, border: 2 }, &dir);
    let pyramid = Arc::new(Pyramid::open(&path).expect("open"));
    let layout = *pyramid.layout();
    assert_eq!((layout.levels, layout.nodes_at(0)), (6, [19, 19]));
    let bad = NodeId::new(0, 9, 9);
    let parent = bad.parent().unwrap();
    let mut node = NodeData::with_capacity(&layout);
    pyramid.read_node(bad, &mut node).expect("intact before the damage");

    // Damage the middle of the node's heights on disk, after opening.
    let record = pyramid.record_range(bad).expect("a node of the pyramid");
    flip_bytes(&path, record.start + (record.end - record.start) / 2, 16);

    // The map is shared (MAP_SHARED): the mapped bytes changed with the file.
    match pyramid.read_node(bad, &mut node) {
        Err(NodeError::Corrupt { path: named, id, .. }) => {
            assert_eq!((named, id), (path.clone(), bad))
        }
        other => panic!("the flipped bytes were not seen through the map: {other:?}"),
    }
    let [sx, sy] = layout.spacing_m;
    let centre = DVec2::new(9.5 * 16.0 * sx, 9.5 * 16.0 * sy);
    assert_eq!(pyramid.exact_height(centre.x, centre.y), None, "no height from damaged posts");
    assert!(
        pyramid.exact_height(centre.x + 16.0 * sx, centre.y).is_some(),
        "the neighbour is fine"
    );
    // Opening again still succeeds (header only); verifying finds the node.
    let reopened = Pyramid::open(&path).expect("open checks the header only");
    match reopened.verify() {
        Err(error @ PyramidError::Corrupt { .. }) => {
            let text = error.to_string();
            assert!(
                text.contains(&path.display().to_string()) && text.contains("level: 0, x: 9, y: 9"),
                "{text}"
            );
        }
        other => panic!("verify missed the damage: {other:?}"),
    }
    let mut ancestor = NodeData::with_capacity(&layout);
    pyramid.read_node(parent, &mut ancestor).expect("the parent is intact");

    let ground = grid.at(152, 152) as f64;
    for loader in [LoaderMode::Inline, LoaderMode::Thread { queue: 4 }] {
        let config = ClipmapConfig { atlas_bytes: None, atlas_slots: 600, budget: 50, loader };
        let mut clipmap = Clipmap::new(pyramid.clone(), config).expect("clipmap");
        let view = clipmap.add_view(VIEW, DVec3::new(centre.x, centre.y, ground + 60.0)).unwrap();
        let (mut failed, mut given_up, start) = (0, 0, Instant::now());
        loop {
            let stats = clipmap.update().unwrap();
            (failed, given_up) = (failed + stats.failed, given_up + stats.given_up);
            assert_eq!(
                clipmap.atlas().slot_of(bad),
                None,
                "{loader:?}: the bad node is in the atlas"
            );
            check_entries(&clipmap, view).unwrap();
            if stats.missing == 1 && stats.in_flight == 0 && clipmap.frame() > 3 {
                break;
            }
            assert!(
                start.elapsed() < Duration::from_secs(30),
                "{loader:?} never settled: {stats:?}"
            );
            std::thread::sleep(Duration::from_millis(1));
        }
        assert!(clipmap.is_wanted(bad), "the view wants the bad node");
        assert_eq!(
            (failed, given_up, clipmap.corrupt_nodes()),
            (1, 1, 1),
            "{loader:?}: reported once"
        );
        assert_eq!(clipmap.unreadable_nodes(), 0);
        assert!(clipmap.has_given_up(bad));
        match clipmap.last_load_error() {
            Some(NodeError::Corrupt { path: named, id, .. }) => {
                assert_eq!((named, *id), (&path, bad))
            }
            other => panic!("{loader:?}: last error {other:?}"),
        }
        // Not requested again, however long it stays wanted.
        for _ in 0..30 {
            let stats = clipmap.update().unwrap();
            assert_eq!((stats.failed, stats.requested, stats.missing), (0, 0, 1), "{loader:?}");
        }
        assert_eq!(clipmap.corrupt_nodes(), 1);

        // Inside the bad node, heights and lookups come from its parent.
        for (fx, fy) in [(0.5, 0.5), (0.1, 0.8), (0.9, 0.2), (0.33, 0.61)] {
            let point = DVec2::new((9.0 + fx) * 16.0 * sx, (9.0 + fy) * 16.0 * sy);
            let sample = clipmap.height_at(view, point).expect("a height inside the data");
            assert_eq!(sample.node, parent, "{loader:?}: {point} answered from {:?}", sample.node);
            let posts = layout.locate(1, point.x, point.y).unwrap().posts;
            assert_eq!(sample.height_m, ancestor.interpolate(&layout, posts));
            assert_eq!(sample.error_bound_m, ancestor.delta);
            assert_eq!(clipmap.lookup(view, point, 0).unwrap().node, parent);
        }
        // Beside it, level 0 answers as usual.
        let beside = centre + DVec2::new(16.0 * sx, 0.0);
        assert_eq!(check_height(&clipmap, view, beside).unwrap(), 0);
    }
}

#[test]
fn a_file_truncated_after_opening_is_an_io_error_not_a_crash() {
    let dir = fresh_dir("corrupt-truncated");
    let grid = random_grid(100, 100, 32);
    let (_, path) = build_and_write(&grid, BuildOptions { node_size: 16, border: 2 }, &dir);
    let pyramid = Pyramid::open(&path).expect("open");
    let len = std::fs::metadata(&path).expect("len").len();
    let file = std::fs::OpenOptions::new().write(true).open(&path).expect("open for writing");
    file.set_len(len / 2).expect("truncate");
    drop(file);
    // Reading pages past the new end through the map would raise SIGBUS;
    // every record read asks for the file's length first.
    let mut node = NodeData::with_capacity(pyramid.layout());
    let last = NodeId::new(pyramid.layout().levels - 1, 0, 0);
    match pyramid.read_node(last, &mut node) {
        Err(NodeError::Io { path: named, source }) => {
            assert_eq!(named, path);
            assert!(source.to_string().contains("shrank"), "{source}");
        }
        other => panic!("expected an I/O error, got {other:?}"),
    }
    assert_eq!(pyramid.exact_height(10.0, 10.0), None);
    assert!(matches!(pyramid.verify(), Err(PyramidError::Corrupt { .. })));
}

/// The whole frame pipeline flies over a node damaged after opening: a copy
/// of the built-in terrain, the level-0 node under a low camera flipped on
/// disk. Every frame is drawn (null backend, counting what GL would issue);
/// the damage is reported once, naming node and file; the tiles over the
/// node draw its parent's data; the tiles beside it draw their own.
#[test]
fn the_pipeline_flies_over_a_damaged_node_on_its_ancestor() {
    let dir = fresh_dir("corrupt-pipeline");
    let original = testkit::builtin_pyramid();
    std::fs::copy(original.path(), dir.join(ridgeline::pyramid::FILE_NAME)).expect("copy");
    let pyramid = Arc::new(Pyramid::open(&dir).expect("open the copy"));
    let path = pyramid.path().to_path_buf();
    let layout = *pyramid.layout();
    let origin = testkit::builtin_origin();
    let ground = origin + DVec2::new(30_000.0, 40_000.0);
    let span_m = [0, 1].map(|a| layout.node_size as f64 * layout.spacing_m[a]);
    let bad = NodeId::new(0, (ground.x / span_m[0]) as u32, (ground.y / span_m[1]) as u32);
    assert!(pyramid.is_present(bad), "level 0 is stored over the SRTM tile");
    let record = pyramid.record_range(bad).expect("a node of the pyramid");
    flip_bytes(&path, record.start + (record.end - record.start) / 3, 64);

    let config = ridgeline::scene::SceneConfig::default();
    let summary = ridgeline::scene::TerrainSummary::from_pyramid(pyramid.info());
    let mut pipeline = testkit::scene::pipeline_over(pyramid.clone(), summary, config);
    let mut backend = testkit::scene::null_backend(&pipeline);
    let centre = DVec2::new((bad.x as f64 + 0.5) * span_m[0], (bad.y as f64 + 0.5) * span_m[1]);
    let height = original.exact_height(centre.x, centre.y).expect("the original has data") as f64;
    let grid = config.lod.grid_size;
    let (mut over, mut beside) = (0, 0);
    for k in 0..6 {
        let x = centre.x - 3_000.0 + 1_000.0 * k as f64;
        let camera = testkit::camera(
            testkit::scene::VIEWPORT,
            glam::DVec3::new(x, centre.y - 2_000.0, height + 400.0),
            20.0,
            -25.0,
        );
        let stats = testkit::scene::fly(&mut pipeline, &mut backend, &camera).expect("a frame");
        assert!(stats.calls.draw_calls > 1, "frame {k} draws terrain");
        for drawn in &pipeline.draw_list().drawn {
            let (key, source_level) = (drawn.key, drawn.source_level);
            if key.level != 0 {
                continue;
            }
            let (node, _) = ridgeline::tiles::vertex::tile_node(key, grid, layout.node_size);
            if node == bad {
                assert!(source_level >= 1, "frame {k}: tile {key:?} drew the damaged node");
                over += 1;
            } else if pyramid.is_present(node) {
                beside += usize::from(source_level == 0);
            }
        }
    }
    assert!(over > 0 && beside > 0, "tiles over the node {over}, level-0 tiles beside it {beside}");
    let clipmap = pipeline.clipmap();
    assert_eq!(clipmap.corrupt_nodes(), 1, "reported once");
    match clipmap.last_load_error() {
        Some(NodeError::Corrupt { path: named, id, .. }) => assert_eq!((named, *id), (&path, bad)),
        other => panic!("last error {other:?}"),
    }
    println!("{over} tile draws over the damaged node came from its ancestors; {beside} beside it from level 0");
}
