//! The pyramid file: what is written is what is read back, every node post is
//! the clamped level-0 sample (split, downsample, stitch), and damage of any
//! kind is refused with an error naming the file.

use std::io::{Seek, SeekFrom, Write};

use proptest::prelude::*;
use ridgeline::node::{NodeData, NodeError, NodeId, NodeSource};
use ridgeline::pyramid::{BuildOptions, Pyramid, PyramidError};
use testkit::fresh_dir;
use testkit::pyramid::{build_and_write, random_grid};

#[test]
fn every_node_reads_back_as_built_and_is_the_clamped_grid() {
    let dir = fresh_dir("file-roundtrip");
    let grid = random_grid(150, 97, 1);
    let (built, path) = build_and_write(&grid, BuildOptions { node_size: 16, border: 2 }, &dir);
    let pyramid = Pyramid::open(&dir).expect("open the cache directory");
    assert_eq!(pyramid.path(), path);
    assert_eq!(pyramid.info(), &built.info);
    let layout = *pyramid.layout();
    assert_eq!(layout.levels, 5, "97 x 150 samples need 16 << 4 = 256 >= 149 cells");
    let side = layout.stored_side() as i64;
    let mut node = NodeData::default();
    for lod in 0..layout.levels {
        let [nx, ny] = layout.nodes_at(lod);
        for (x, y) in (0..ny).flat_map(|y| (0..nx).map(move |x| (x, y))) {
            let id = NodeId::new(lod, x, y);
            pyramid.read_node(id, &mut node).expect("read");
            let (heights, summary) = built.node(id).expect("built node");
            assert_eq!(node.heights, heights);
            assert_eq!((node.min, node.max, node.delta), (summary.min, summary.max, summary.delta));
            assert_eq!(pyramid.node_summary(id), Some(summary));
            let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
            for q in 0..side {
                for p in 0..side {
                    let step = 1i64 << lod;
                    let to_sample = |node: u32, post: i64, last: u32| {
                        ((node as i64 * 16 + post - 2) * step).clamp(0, last as i64 - 1) as u32
                    };
                    let (i, j) = (to_sample(x, p, grid.width), to_sample(y, q, grid.height));
                    let h = node.heights[(q * side + p) as usize];
                    assert_eq!(h, grid.at(i, j), "{id:?} post ({p}, {q})");
                    if (2..=18).contains(&p) && (2..=18).contains(&q) {
                        (lo, hi) = (lo.min(h), hi.max(h));
                    }
                }
            }
            assert_eq!((node.min, node.max), (lo, hi), "{id:?}: min and max of the centre posts");
        }
    }
    let outside = NodeId::new(0, layout.nodes_at(0)[0], 0);
    assert!(matches!(pyramid.read_node(outside, &mut node), Err(NodeError::OutOfRange { .. })));
    assert!(matches!(
        pyramid.read_node(NodeId::new(200, 0, 0), &mut node),
        Err(NodeError::OutOfRange { .. })
    ));
}

#[test]
fn header_records_georeference_and_statistics() {
    let dir = fresh_dir("file-header");
    let grid = random_grid(70, 40, 2);
    build_and_write(&grid, BuildOptions::default(), &dir);
    let info = Pyramid::open(&dir).expect("open").info().clone();
    assert_eq!(info.georef, grid.georef);
    assert_eq!(info.layout.posts, [70, 40]);
    assert_eq!(info.layout.spacing_m, grid.georef.spacing_m([70, 40]));
    assert_eq!(info.stats.voids_filled, 3);
    let lo = grid.heights.iter().copied().fold(f32::INFINITY, f32::min);
    let hi = grid.heights.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    assert_eq!((info.stats.height_min, info.stats.height_max), (lo, hi));
}

#[test]
fn exact_height_interpolates_level0_on_its_triangles() {
    let dir = fresh_dir("file-exact-height");
    let grid = random_grid(90, 75, 3);
    build_and_write(&grid, BuildOptions { node_size: 16, border: 1 }, &dir);
    let pyramid = Pyramid::open(&dir).expect("open");
    let [dx, dy] = pyramid.layout().spacing_m;
    for (i, j) in [(0, 0), (89, 74), (16, 32), (17, 33), (45, 70)] {
        assert_eq!(pyramid.exact_height(i as f64 * dx, j as f64 * dy), Some(grid.at(i, j)));
    }
    // A quarter of the way into cell (10, 20), east of its diagonal: the
    // south-east triangle (SW, SE, NE).
    let (sw, se, ne) = (grid.at(10, 20) as f64, grid.at(11, 20) as f64, grid.at(11, 21) as f64);
    let expected = sw + 0.5 * (se - sw) + 0.25 * (ne - se);
    let got = pyramid.exact_height(10.5 * dx, 20.25 * dy).expect("finite");
    assert!((got as f64 - expected).abs() < 1e-3, "{got} vs {expected}");
    // Outside the data the edge extends.
    assert_eq!(pyramid.exact_height(-5.0 * dx, 200.0 * dy), Some(grid.at(0, 74)));
    assert_eq!(pyramid.exact_height(f64::NAN, 0.0), None);
}

/// Opening `bytes` written as a pyramid file and verifying it (open checks
/// the header, verify every node) must fail with an error naming it.
fn assert_refused(dir: &std::path::Path, bytes: &[u8], what: &str) -> PyramidError {
    let path = dir.join("damaged.rlp");
    std::fs::write(&path, bytes).expect("write damaged copy");
    let error = Pyramid::open(&path)
        .and_then(|pyramid| pyramid.verify())
        .err()
        .unwrap_or_else(|| panic!("{what}: a damaged file opened and verified"));
    assert!(
        error.to_string().contains(&path.display().to_string()),
        "{what}: {error} does not name the file"
    );
    error
}

#[test]
fn truncated_empty_foreign_and_newer_files_are_refused() {
    let dir = fresh_dir("file-refused");
    let (_, path) =
        build_and_write(&random_grid(40, 40, 4), BuildOptions { node_size: 8, border: 1 }, &dir);
    let good = std::fs::read(&path).expect("read");
    assert!(matches!(assert_refused(&dir, &[], "empty"), PyramidError::Truncated { .. }));
    assert!(matches!(
        assert_refused(&dir, &good[..good.len() - 1], "short"),
        PyramidError::Truncated { .. }
    ));
    assert!(matches!(
        assert_refused(&dir, &good[..100], "header only"),
        PyramidError::Truncated { .. }
    ));
    let mut longer = good.clone();
    longer.push(0);
    assert!(matches!(assert_refused(&dir, &longer, "longer"), PyramidError::Corrupt { .. }));
    assert!(matches!(
        assert_refused(&dir, b"GIF89a and more bytes", "foreign"),
        PyramidError::NotAPyramid { .. }
    ));
    let mut newer = good.clone();
    newer[8] = 4;
    assert!(matches!(
        assert_refused(&dir, &newer, "newer"),
        PyramidError::Version { found: 4, .. }
    ));
    let missing = Pyramid::open(dir.join("missing")).err().expect("missing file");
    assert!(matches!(missing, PyramidError::Io { .. }) && missing.to_string().contains("missing"));
}

#[test]
fn a_node_damaged_after_opening_is_refused_when_read() {
    let dir = fresh_dir("file-damaged-later");
    let (_, path) =
        build_and_write(&random_grid(40, 40, 5), BuildOptions { node_size: 8, border: 1 }, &dir);
    let pyramid = Pyramid::open(&path).expect("open");
    let mut node = NodeData::default();
    pyramid.read_node(NodeId::new(0, 0, 0), &mut node).expect("intact");
    // Another program writes into the file in place (Ridgeline never does).
    let len = std::fs::metadata(&path).expect("len").len();
    let mut file = std::fs::OpenOptions::new().write(true).open(&path).expect("open for writing");
    file.seek(SeekFrom::Start(len - 40)).expect("seek");
    file.write_all(&[0xAB]).expect("write");
    drop(file);
    let last = NodeId::new(pyramid.layout().levels - 1, 0, 0);
    match pyramid.read_node(last, &mut node) {
        Err(NodeError::Corrupt { path: named, id, .. }) => assert_eq!((named, id), (path, last)),
        other => panic!("expected a corrupt node, got {other:?}"),
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// CRC-32 catches every single-byte change, and every byte is covered.
    #[test]
    fn any_flipped_byte_is_refused_by_open_and_verify(position in 0.0f64..1.0, flip in 1u8..=255) {
        let dir = fresh_dir("file-flip");
        let (_, path) = build_and_write(&random_grid(30, 20, 6), BuildOptions { node_size: 8, border: 2 }, &dir);
        let mut bytes = std::fs::read(&path).expect("read");
        let at = ((bytes.len() as f64 * position) as usize).min(bytes.len() - 1);
        bytes[at] ^= flip;
        assert_refused(&dir, &bytes, &format!("byte {at} ^ {flip:#x}"));
    }
}

#[test]
fn every_header_byte_is_covered() {
    let dir = fresh_dir("file-header-bytes");
    let (_, path) =
        build_and_write(&random_grid(30, 20, 7), BuildOptions { node_size: 8, border: 2 }, &dir);
    let good = std::fs::read(&path).expect("read");
    let header_len = u64::from_le_bytes(good[12..20].try_into().expect("8 bytes")) as usize;
    assert_eq!(header_len % 16, 0);
    for at in 0..header_len {
        let mut bytes = good.clone();
        bytes[at] ^= 0xFF;
        assert_refused(&dir, &bytes, &format!("header byte {at}"));
    }
}

/// Opening reads no node table entry (so it costs the same at any size):
/// a damaged entry opens, and surfaces when its node is read, naming the
/// node and the file; the other nodes read as before; verify finds it.
#[test]
fn a_damaged_table_entry_is_found_when_its_node_is_read() {
    let dir = fresh_dir("file-entry");
    let (_, path) =
        build_and_write(&random_grid(40, 40, 8), BuildOptions { node_size: 8, border: 1 }, &dir);
    let mut bytes = std::fs::read(&path).expect("read");
    // The table follows the fixed header (176 bytes), the level table (28
    // bytes a level) and the header checksum; entries are 24 bytes.
    let levels = u32::from_le_bytes(bytes[36..40].try_into().expect("4 bytes")) as usize;
    let table = 176 + 28 * levels + 4;
    let bad = NodeId::new(0, 1, 0);
    bytes[table + 24 + 9] ^= 0x40; // node index 1: its min
    let damaged = dir.join("entry.rlp");
    std::fs::write(&damaged, &bytes).expect("write");
    let pyramid = Pyramid::open(&damaged).expect("opening reads no entry");
    assert!(pyramid.is_present(bad), "a damaged entry is read, and reported, not skipped");
    let mut node = NodeData::default();
    match pyramid.read_node(bad, &mut node) {
        Err(NodeError::Corrupt { path: named, id, problem }) => {
            assert_eq!((named, id), (damaged.clone(), bad));
            assert!(problem.contains("entry 1"), "{problem}");
        }
        other => panic!("expected a corrupt node, got {other:?}"),
    }
    pyramid.read_node(NodeId::new(0, 0, 0), &mut node).expect("its neighbour reads");
    assert!(pyramid.verify().is_err(), "verify checks every entry");
}
