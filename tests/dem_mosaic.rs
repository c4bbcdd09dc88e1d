//! Mosaics: 2 x 2 one-degree tiles sharing their edge rows and columns
//! (three SRTM `.hgt` tiles and one DTED level 1 tile on the same 3" lattice)
//! join into one 2401 x 2401 grid; with a tile missing, the gap is filled
//! by the documented method and counted.

use std::path::PathBuf;

use ridgeline::dem::import_files;
use ridgeline::geo::Crs;
use testkit::dem::*;

const SIDE: u32 = 1201;
const MOSAIC: u32 = 2 * SIDE - 1;

/// Heights on the global lattice of the 2 x 2 block (post (0, 0) at 40 E, 39 N).
fn global(gi: u32, gj: u32) -> i16 {
    (100 + (gi + 2 * gj) % 4000) as i16
}

/// Heights of the tile whose south-west post is global post (`i0`, `j0`).
fn tile(i0: u32, j0: u32) -> Vec<i16> {
    (0..SIDE * SIDE).map(|k| global(i0 + k % SIDE, j0 + k / SIDE)).collect()
}

/// Writes the tiles named in `which` (of "sw", "se", "nw", "ne") and returns their paths.
fn write_tiles(dir: &TempDir, which: &[&str]) -> Vec<PathBuf> {
    let mut paths = Vec::new();
    for &name in which {
        let (i0, j0) = match name {
            "sw" => (0, 0),
            "se" => (SIDE - 1, 0),
            "nw" => (0, SIDE - 1),
            _ => (SIDE - 1, SIDE - 1),
        };
        let heights = tile(i0, j0);
        let (lon, lat) = (40 + i0 / (SIDE - 1), 39 + j0 / (SIDE - 1));
        let path = if name == "ne" {
            // The north-east tile comes as DTED level 1 (3" x 3" below 50 N).
            let spec = DtedSpec {
                level: 1,
                origin: [lon as i32, lat as i32],
                lon_tenths: 30,
                columns: SIDE,
                rows: SIDE,
            };
            let path = dir.path(&format!("e{lon:03}_n{lat:02}.dt1"));
            std::fs::write(
                &path,
                dted_bytes(spec, &heights.iter().map(|&h| i32::from(h)).collect::<Vec<_>>()),
            )
            .unwrap();
            path
        } else {
            let path = dir.path(&format!("N{lat:02}E{lon:03}.hgt"));
            write_hgt(&path, SIDE as usize, &heights);
            path
        };
        paths.push(path);
    }
    paths
}

#[test]
fn two_by_two_tiles_with_shared_edges_join_exactly() {
    let dir = TempDir::new("mosaic");
    // Any order: the lattice is the same for all of them.
    let paths = write_tiles(&dir, &["ne", "sw", "nw", "se"]);
    let grid = import_files(&paths).unwrap();
    assert_eq!((grid.width, grid.height), (MOSAIC, MOSAIC));
    assert_eq!(grid.georef.crs, Crs::Geographic);
    assert_close(grid.georef.origin[0], 40.0, 1e-9, "west");
    assert_close(grid.georef.origin[1], 39.0, 1e-9, "south");
    assert_close(grid.georef.spacing[1], 1.0 / 1200.0, 1e-15, "spacing");
    assert_eq!(grid.voids_filled, 0);
    for j in 0..MOSAIC {
        for i in 0..MOSAIC {
            assert_eq!(grid.at(i, j), f32::from(global(i, j)), "post ({i}, {j})");
        }
    }
}

#[test]
fn missing_tile_leaves_a_gap_of_no_data() {
    let dir = TempDir::new("mosaic-gap");
    let paths = write_tiles(&dir, &["sw", "se", "nw"]);
    let grid = import_files(&paths).unwrap();
    assert_eq!((grid.width, grid.height), (MOSAIC, MOSAIC));
    // The north-east quadrant beyond the shared edges had no data: a large
    // void, left as no-data (NaN), not invented.
    let edge = SIDE - 1;
    assert_eq!(grid.voids_filled, 0);
    for j in 0..MOSAIC {
        for i in 0..MOSAIC {
            let h = grid.at(i, j);
            if i <= edge || j <= edge {
                assert_eq!(f64::from(h), f64::from(global(i, j)), "post ({i}, {j})");
            } else {
                assert!(h.is_nan(), "post ({i}, {j}) was invented: {h}");
            }
        }
    }
}
