//! Global grids wrap: a grid whose columns span 360 degrees gets its
//! closing column at import, its posts one turn apart are one place, and a
//! camera path given in latitude and longitude crosses its seam (Greenwich
//! for a grid stored 0 to 360 degrees, the antimeridian for one stored
//! -180 to 180) without jumping back over the earth, whichever way the
//! file writes its longitudes; the reader says what it did.

use std::path::Path;

use ridgeline::dem::{close_global, ElevationGrid};
use ridgeline::earth::GridPlacement;
use ridgeline::flight::FlightPath;
use ridgeline::geo::{Crs, GeoRef};

fn global(west: f64, spacing: f64) -> GeoRef {
    GeoRef { crs: Crs::Geographic, origin: [west, -90.0], spacing: [spacing, spacing] }
}

#[test]
fn a_global_grid_gets_its_closing_column_and_wraps() {
    let georef = global(0.0, 30.0);
    let heights: Vec<f32> = (0..7 * 12).map(|k| k as f32).collect();
    let grid = ElevationGrid { width: 12, height: 7, heights, georef, voids_filled: 0 };
    let closed = close_global(grid.clone());
    assert_eq!((closed.width, closed.height), (13, 7));
    for j in 0..7 {
        assert_eq!(closed.at(12, j), closed.at(0, j), "row {j}: the seam column repeats the first");
        assert_eq!(closed.at(11, j), grid.at(11, j));
    }
    let placement = GridPlacement::new(&closed.georef, [13, 7], closed.georef.spacing_m([13, 7]));
    assert_eq!(placement.period_posts(), Some(12.0));
    let regional = ElevationGrid { width: 11, ..grid };
    assert_eq!(close_global(regional.clone()), regional, "a regional grid is left as it is");
}

fn path_over(georef: &GeoRef, posts: [u32; 2], rows: &str) -> FlightPath {
    let text = format!("t,lat,lon,alt,heading,pitch,roll\n{rows}");
    FlightPath::parse_csv(Path::new("path.csv"), &text, georef, posts).expect("a valid path")
}

/// Chart x of each waypoint, and the reader's note.
fn chart_x(path: &FlightPath) -> (Vec<f64>, Option<String>) {
    let xs = path.waypoints().iter().map(|w| w.pose.position.x).collect();
    (xs, path.longitude_note().map(str::to_string))
}

#[test]
fn a_path_across_greenwich_over_a_0_to_360_grid_is_followed_across_the_seam() {
    let (georef, posts) = (global(0.0, 5.0 / 60.0), [4321, 2161]);
    let spacing = georef.spacing_m(posts)[0];
    for lons in [["-0.5", "-0.1", "0.3", "0.7"], ["359.5", "359.9", "0.3", "0.7"]] {
        let rows: String =
            (0..4).map(|k| format!("{},51.5,{},3000,90,0,0\n", 10 * k, lons[k])).collect();
        let (xs, note) = chart_x(&path_over(&georef, posts, &rows));
        // 359.5 degrees is post 4314: the grid's east end, then on past it.
        assert!((xs[0] / spacing - 4314.0).abs() < 1e-6, "{lons:?}: {xs:?}");
        let steps: Vec<f64> = xs.windows(2).map(|w| (w[1] - w[0]) / spacing).collect();
        assert!(steps.iter().all(|s| (s - 4.8).abs() < 1e-6), "{lons:?}: {steps:?} posts a row");
        let note = note.expect("the reader says what it did");
        assert!(note.contains("seam") && note.contains("wrap"), "{note}");
    }
}

#[test]
fn a_path_across_the_antimeridian_over_a_minus_180_grid_and_longitudes_stored_0_to_360() {
    let (georef, posts) = (global(-180.0, 0.5), [721, 361]);
    let spacing = georef.spacing_m(posts)[0];
    let rows = "0,60,179.5,3000,90,0,0\n10,60,180.5,3000,90,0,0\n20,60,-179,3000,90,0,0\n";
    let (xs, note) = chart_x(&path_over(&georef, posts, rows));
    let posts_at: Vec<f64> = xs.iter().map(|x| x / spacing).collect();
    assert!((posts_at[0] - 719.0).abs() < 1e-6, "{posts_at:?}");
    assert!((posts_at[1] - 721.0).abs() < 1e-6 && (posts_at[2] - 722.0).abs() < 1e-6);
    assert!(note.is_some());
    // A regional grid stored in -180..180 reads 359.5 as -0.5, and says so.
    let regional = GeoRef { crs: Crs::Geographic, origin: [-2.0, 50.0], spacing: [0.01, 0.01] };
    let (xs, note) = chart_x(&path_over(&regional, [401, 301], "0,51,359.5,900,0,0,0\n"));
    assert!((xs[0] / regional.spacing_m([401, 301])[0] - 150.0).abs() < 1e-6, "{xs:?}");
    assert!(note.expect("said").contains("1 of 1 rows normalised"));
    let (_, note) = chart_x(&path_over(&regional, [401, 301], "0,51,-0.5,900,0,0,0\n"));
    assert_eq!(note, None, "longitudes already in the grid's turn need no note");
}
