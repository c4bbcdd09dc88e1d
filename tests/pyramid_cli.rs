//! `ridgeline import` and `ridgeline info` as a user runs them.

use std::path::Path;

use ridgeline::pyramid::FILE_NAME;
use testkit::cli::Ridgeline;
use testkit::fresh_dir;

const RIDGELINE: Ridgeline = Ridgeline::new(env!("CARGO_BIN_EXE_ridgeline"));

#[test]
fn info_json_describes_an_imported_cache() {
    let cache = fresh_dir("cli-info");
    let imported = RIDGELINE
        .args(["import", "--synthetic", "257", "--node-size", "32", "--border", "1", "--out"])
        .arg(&cache)
        .ok();
    let said = imported.stderr();
    // Not a terminal: each phase's time on a line of the log.
    for phase in ["level 0: done in", "meshes: done in"] {
        assert!(said.contains(phase), "{said:?} lacks {phase:?}");
    }
    let info = RIDGELINE.args(["info", "--json"]).arg(&cache).ok();
    let json: serde_json::Value =
        serde_json::from_slice(&info.output.stdout).expect("info --json prints JSON");
    assert_eq!(json["levels"], 4, "256 cells need 32 << 3");
    assert_eq!(json["node_size"], 32);
    assert_eq!(json["posts"], serde_json::json!([257, 257]));
    assert_eq!(json["extent"]["east_m"], 256.0 * 90.0);
    assert!(json["georef"]["west"].is_null(), "a local grid has no degrees");
    let deltas = json["delta_per_level"].as_array().expect("deltas");
    assert_eq!(deltas.len(), 4);
    assert_eq!(deltas[0], 0.0);
    assert!(deltas[1..].iter().all(|d| d.as_f64().expect("number") > 0.0));
    let (lo, hi) =
        (json["height_min"].as_f64().expect("min"), json["height_max"].as_f64().expect("max"));
    assert!(lo < hi);
    assert_eq!(json["voids_filled"], 0);

    let text = RIDGELINE.args(["info"]).arg(&cache).ok().stdout();
    assert!(text.contains("257 x 257") && text.contains("4 levels"), "{text}");
    // One word per concept (DESIGN.md glossary): the grid's points are posts.
    assert!(text.contains("posts     257 x 257") && !text.contains("sample"), "{text}");
}

#[test]
fn info_refuses_a_damaged_cache_naming_the_file() {
    let cache = fresh_dir("cli-damaged");
    RIDGELINE.args(["import", "--synthetic", "100", "--out"]).arg(&cache).ok();
    let path = cache.join(FILE_NAME);
    let mut bytes = std::fs::read(&path).expect("read");
    let middle = bytes.len() / 2;
    bytes[middle] ^= 0x10;
    std::fs::write(&path, bytes).expect("damage");
    RIDGELINE.args(["info"]).arg(&cache).refused(&[&path.display().to_string(), "damaged"]);
}

#[test]
fn import_refuses_absurd_sizes_before_allocating() {
    let cache = fresh_dir("cli-absurd");
    RIDGELINE.args(["import", "--synthetic", "4000000000", "--out"]).arg(&cache).refused(&[]);
    let import = ["import", "--synthetic", "100", "--node-size", "0", "--out"];
    RIDGELINE.args(import).arg(&cache).refused(&["node size"]);
}

/// `--memory-mb` below the least an import needs is refused by name; an
/// import removes its own scratch directory and a killed import's stale one.
#[test]
fn import_bounds_its_memory_and_cleans_its_scratch() {
    let cache = fresh_dir("cli-memory");
    let import = ["import", "--synthetic", "100", "--memory-mb", "0", "--out"];
    RIDGELINE.args(import).arg(&cache).refused(&["--memory-mb 0"]);
    // No process has this id (Linux pids stop at 2^22).
    let stale = cache.join(".import-4999999");
    std::fs::create_dir_all(&stale).expect("a stale scratch directory");
    std::fs::write(stale.join("0000-layer"), b"left by a killed import").expect("stale spill");
    let import = ["import", "--synthetic", "100", "--memory-mb", "64", "--out"];
    RIDGELINE.args(import).arg(&cache).ok();
    let left: Vec<_> = std::fs::read_dir(&cache)
        .expect("the cache")
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".import-"))
        .collect();
    assert!(left.is_empty(), "scratch left behind: {left:?}");
}

#[test]
fn importing_the_shipped_srtm_tile_records_where_it_is() {
    let cache = fresh_dir("cli-srtm");
    let tile = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/dem/srtm3_n39e040_1000.tif");
    RIDGELINE.args(["import", tile, "--out"]).arg(&cache).ok();
    let info = RIDGELINE.args(["info", "--json"]).arg(&cache).ok();
    let json: serde_json::Value =
        serde_json::from_slice(&info.output.stdout).expect("info --json prints JSON");
    assert_eq!(json["posts"], serde_json::json!([1000, 1000]));
    assert_eq!(json["levels"], 5, "999 cells need 64 << 4");
    let degrees = |key: &str| json["georef"][key].as_f64().expect("geographic bounds");
    // Posts from 40 E + half a 3" cell to 40.8333 E - half a cell (see assets/dem/README.md).
    let half_cell = 0.5 / 1200.0;
    assert!((degrees("west") - (40.0 + half_cell)).abs() < 1e-9);
    assert!((degrees("north") - (40.0 - half_cell)).abs() < 1e-9);
    assert!((degrees("east") - (40.0 + 999.5 / 1200.0)).abs() < 1e-9);
    assert!((degrees("south") - (40.0 - 999.5 / 1200.0)).abs() < 1e-9);
    // A 3" cell is about 71.6 m east-west and 92.5 m north-south at 39.6 N.
    let spacing = json["spacing_m"].as_array().expect("spacing");
    assert!((spacing[0].as_f64().expect("east") - 71.6).abs() < 0.1);
    assert!((spacing[1].as_f64().expect("north") - 92.5).abs() < 0.1);
    assert_eq!(
        (json["height_min"].as_f64(), json["height_max"].as_f64()),
        (Some(1111.0), Some(3270.0))
    );
}

#[test]
fn importing_a_missing_file_names_it() {
    let cache = fresh_dir("cli-missing");
    RIDGELINE
        .args(["import", "no/such/tile.hgt", "--out"])
        .arg(&cache)
        .refused(&["no/such/tile.hgt"]);
    assert!(!cache.join(FILE_NAME).exists());
    // A first import that fails leaves no empty cache directory behind.
    let first = cache.join("first");
    RIDGELINE.args(["import", "no/such/tile.hgt", "--out"]).arg(&first).refused(&[]);
    assert!(!first.exists(), "{} was left behind", first.display());
}

/// A partial SRTM tile (its last 200 columns and southern 200 rows void)
/// over a 30" base imported as two layers: `info --json` counts the void
/// posts filled from the base, and the tile's interpolated and no-data
/// posts, separately; a file in another coordinate system is refused,
/// named.
#[test]
fn layered_import_counts_void_posts_by_what_became_of_them() {
    let dir = fresh_dir("cli-layers");
    let side = 1201usize;
    let large = |i: usize, j: usize| i >= side - 200 || j < 200;
    let small = |i: usize, j: usize| (500..502).contains(&i) && (600..602).contains(&j);
    let heights: Vec<i16> = (0..side * side)
        .map(|k| (k % side, k / side))
        .map(|(i, j)| if large(i, j) || small(i, j) { -32768 } else { 1500 + (i % 97) as i16 })
        .collect();
    let hgt = dir.join("N39E040.hgt");
    testkit::dem::write_hgt(&hgt, side, &heights);
    let voids = heights.iter().filter(|&&h| h == -32768).count() as u64;
    // The base: 30" posts over 39.5..41.5 E, 38.5..40.5 N, 1200 m.
    let base = dir.join("base.asc");
    let header =
        "NCOLS 241\nNROWS 241\nXLLCENTER 39.5\nYLLCENTER 38.5\nCELLSIZE 0.008333333333333333\n";
    let rows: Vec<Vec<String>> = (0..241).map(|_| vec!["1200".to_string(); 241]).collect();
    testkit::dem::write_ascii(&base, header, &rows);
    std::fs::write(dir.join("base.prj"), "GEOGCS[\"WGS 84\",DATUM[\"WGS_1984\"]]").unwrap();
    let cache = dir.join("cache");
    let hgt_arg = hgt.to_str().expect("a UTF-8 path");
    let base_arg = base.to_str().expect("a UTF-8 path");
    RIDGELINE.args(["import", hgt_arg, base_arg, "--out"]).arg(&cache).ok();
    let info = RIDGELINE.args(["info", "--json"]).arg(&cache).ok();
    let json: serde_json::Value = serde_json::from_slice(&info.output.stdout).expect("JSON");
    assert_eq!(json["format_version"], ridgeline::pyramid::format::VERSION);
    assert_eq!(json["layers"], 2);
    assert_eq!(json["posts_interpolated"], 4, "the 2 x 2 void");
    assert_eq!(json["posts_from_layer"], voids - 4);
    assert_eq!(json["posts_no_data"], 0);
    let present = json["nodes_present"].as_u64().expect("a count");
    assert!(present < json["node_count"].as_u64().expect("a count"), "level 0 is sparse");
    // Alone, the tile's large voids are no data.
    let alone = dir.join("alone");
    RIDGELINE.args(["import", hgt_arg, "--out"]).arg(&alone).ok();
    let info = RIDGELINE.args(["info", "--json"]).arg(&alone).ok();
    let json: serde_json::Value = serde_json::from_slice(&info.output.stdout).expect("JSON");
    assert_eq!(json["posts_no_data"], voids - 4);
    assert_eq!(json["posts_from_layer"], 0);
    // A base in metres (no .prj: a local grid) cannot go under degrees.
    let metres = dir.join("metres.asc");
    let header = "NCOLS 3\nNROWS 3\nXLLCENTER 1000\nYLLCENTER 1000\nCELLSIZE 500\n";
    let rows: Vec<Vec<String>> = (0..3).map(|_| vec!["10".to_string(); 3]).collect();
    testkit::dem::write_ascii(&metres, header, &rows);
    let metres_arg = metres.to_str().expect("a UTF-8 path");
    RIDGELINE
        .args(["import", hgt_arg, metres_arg, "--out"])
        .arg(dir.join("refused"))
        .refused(&["metres.asc", "coordinate system"]);
}

/// `--sea-surface` raises a grid's sea floor to sea level and keeps its land
/// and its no data; without it the heights are kept as given.
#[test]
fn sea_surface_raises_the_sea_floor_and_keeps_land_and_no_data() {
    let dir = fresh_dir("cli-sea");
    let source = dir.join("coast.asc");
    // 64 x 64 posts 900 m apart: sea floor to -3000 m in the west, land to
    // 900 m in the east, a void too large to fill (no data) in each.
    let mut text = String::from(
        "ncols 64\nnrows 64\nxllcenter 0\nyllcenter 0\ncellsize 900\nnodata_value -9999\n",
    );
    for j in (0..64).rev() {
        let row: Vec<String> = (0..64)
            .map(|i| {
                let void = (20..36).contains(&j) && ((4..20).contains(&i) || (44..60).contains(&i));
                let h = -3000.0 + i as f64 * 62.0 + (j as f64 * 0.3).sin() * 40.0;
                if void {
                    "-9999".into()
                } else {
                    format!("{h:.1}")
                }
            })
            .collect();
        text.push_str(&row.join(" "));
        text.push('\n');
    }
    std::fs::write(&source, text).expect("write the grid");
    let lowest = |args: &[&str], out: &str| {
        let cache = dir.join(out);
        let mut all = vec!["import", source.to_str().expect("utf-8 path")];
        all.extend_from_slice(args);
        all.extend_from_slice(&["--node-size", "16", "--out"]);
        let imported = RIDGELINE.args(all).arg(&cache).ok();
        let info = RIDGELINE.args(["info", "--json"]).arg(&cache).ok();
        let json: serde_json::Value = serde_json::from_slice(&info.output.stdout).expect("JSON");
        let said = imported.stderr();
        let range =
            [&json["height_min"], &json["height_max"]].map(|v| v.as_f64().expect("a height"));
        (range[0], range[1], said, no_data_posts(&cache))
    };
    let (floor, top, _, holes) = lowest(&[], "as-given");
    assert!(holes >= 2 * 14 * 14, "both voids stay no data: {holes} posts");
    assert!(floor < -2900.0, "kept as given: lowest {floor}");
    let (sea, raised_top, said, raised_holes) = lowest(&["--sea-surface"], "sea");
    assert_eq!(sea, 0.0, "the sea floor is raised to sea level");
    assert_eq!(raised_top, top, "land is kept");
    assert_eq!(raised_holes, holes, "no data is never raised into terrain");
    assert!(said.contains("below sea level raised"), "{said}");
}

/// No-data posts of the level-0 nodes' centres in `cache`'s pyramid.
fn no_data_posts(cache: &Path) -> usize {
    use ridgeline::node::{NodeData, NodeId, NodeSource};
    let pyramid = ridgeline::pyramid::Pyramid::open(cache).expect("open the pyramid");
    let layout = *pyramid.layout();
    let (side, border, n) =
        (layout.stored_side() as usize, layout.border as usize, layout.node_size as usize);
    let mut data = NodeData::with_capacity(&layout);
    let [nx, ny] = layout.nodes_at(0);
    let mut holes = 0;
    for id in (0..ny).flat_map(|y| (0..nx).map(move |x| NodeId::new(0, x, y))) {
        if !pyramid.has_node(id) {
            continue;
        }
        pyramid.read_node(id, &mut data).expect("read a node");
        let centre = (0..n).flat_map(|j| (0..n).map(move |i| (j + border) * side + i + border));
        holes += centre.filter(|&k| data.heights[k].is_nan()).count();
    }
    holes
}
