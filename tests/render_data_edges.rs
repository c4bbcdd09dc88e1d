//! Real DEMs of different roughness flown along, across and past each of
//! their four edges at 300 m above the ground (`flight::builtin_edges`:
//! inside along the edge, inside looking out, outside looking back in, and
//! outside diagonally), at tau 1, 2, 4 and 8, through the node meshes `fly`
//! draws, measured by the accuracy tool with skirt pixels counted; and a
//! grid whose data end along a ragged no-data outline (the Rhine basin)
//! flown along it (`flight::builtin_outline`).
//!
//! Issue 25's promises, per view, and what this test holds:
//! - p99.9 within tau (the bound the view achieved), skirts included: held;
//! - skirt pixels at most 0.05 % of the terrain pixels: held (0.0004 %
//!   at most, the Grenoble DSM at tau 8; the SRTM tile at tau 4 held
//!   0.070 % while node edges were shared only inside level-3 squares);
//!   none erring by more than 2 tau: held;
//! - the coverage mismatch at most 0.01 % of the pixels: held (0.0027 %
//!   in the Rhine outline's worst view, 0 past the rectangles' edges);
//! - no hole pixel: held along the outline; one past the Grenoble DSM's
//!   north edge.
//!
//! The outline's mismatch (0.0298 %) and holes (up to 10 a view, 20 under
//! a budget) were the horizon's: it culled tiles behind a hill the
//! drawn surface does not hold where the data have no-data posts. The
//! horizon culls now only over data without a no-data post
//! (`TerrainData::gapless`).
//!
//! The views above tau (up to 7 of 16 at tau 8, a skirt pixel 2.6 tau)
//! were skirts seen from beneath the data's cut face, from beyond an edge:
//! rays below the terrain's cut edge travelled under the surface and met
//! the skirts hung under tile edges further in, as deep as the two sides'
//! errors. The cut face is now drawn solid (`tiles::curtain`), in the
//! display and in the truth: on the code before it this test breaks 74 of
//! its limits. `docs/edges.md` has the numbers.
//!
//! Before skirts hung only as deep as a crack can open this frame, every
//! edge DEM failed at tau 4 (the Grenoble DSM 46 px p99.9 in its worst
//! view at 1280x720, SRTM 81 px, Jacksboro 89 px): skirts between exact
//! level-0 tiles of different node meshes hung 97 m (twice the level-1
//! meshes' error) and showed under the data's cut face seen from beyond it.
//! Before a post with data beside one without read as itself, the Rhine's
//! outline lost 2.6 % of the pixels at tau 1 (23 % in one view). The views
//! here are the render tests' small viewport with one tile of view distance
//! (the rings closest to the camera); `ridgeline accuracy --flight edges`
//! (or `outline`) flies the same views at full size.

use std::sync::Arc;

use ridgeline::camera::Camera;
use ridgeline::display::measure::AccuracyRun;
use ridgeline::flight::{builtin_edges, builtin_outline, FlightPath};
use ridgeline::pyramid::Pyramid;
use testkit::asset_pyramid;
use testkit::compare::save_evidence;
use testkit::gl::take_turn;
use testkit::render::{measure_accuracy_budgeted, SIZE};

const TAUS: [f64; 4] = [1.0, 2.0, 4.0, 8.0];

/// The steep DSM, the mountains, the gentle ridges: (cache name, asset).
const EDGE_DEMS: [(&str, &str); 3] = [
    ("grenoble-dsm", "copernicus_grenoble_n45e005_500.tif"),
    ("srtm-tile", "srtm3_n39e040_1000.tif"),
    ("jacksboro", "jacksboro_fault_3s.asc"),
];

/// The views of `path` at the render tests' size.
fn views(path: &FlightPath) -> Vec<(f64, Camera)> {
    let size = [SIZE.x, SIZE.y];
    path.waypoints().iter().map(|w| (w.t, w.pose.camera(60.0, size))).collect()
}

/// The edge views over `pyramid`'s data.
fn edge_views(pyramid: &Pyramid) -> Vec<(f64, Camera)> {
    let (origin, extent) = pyramid.finest_area_m();
    views(&builtin_edges(origin, extent, &|x, y| pyramid.exact_height(x, y)))
}

/// The outline views over `pyramid`'s data.
fn outline_views(pyramid: &Pyramid) -> Vec<(f64, Camera)> {
    let (origin, extent) = pyramid.finest_area_m();
    let path = builtin_outline(origin, extent, &|x, y| pyramid.exact_height(x, y));
    views(&path.expect("the data have a no-data outline"))
}

fn measure(
    pyramid: &Arc<Pyramid>,
    views: &[(f64, Camera)],
    tau_px: f64,
    budget: Option<u64>,
) -> AccuracyRun {
    let _turn = take_turn();
    measure_accuracy_budgeted(pyramid.clone(), views, tau_px, true, budget)
}

/// Issue 25's limits, and what this test holds where it is not met yet:
/// skirt pixels and one hole pixel. Since the cut face is drawn solid
/// (`tiles::curtain`) no skirt is seen from beneath it, and a skirt pixel
/// is a crack seen from above, erring less than the two sides do. Since
/// every vertex of a leaf tile follows its own morph band
/// (`tiles::by_distance`), leaf tiles of other sub-levels meet without a
/// crack, and the skirts left hung along the share squares' edges
/// (`docs/edges.md`, "Morph bands"): 0.070 % of the terrain on the SRTM
/// tile at tau 4, at most 0.02 % on every other flight, where they were
/// 0.06 % at tau 1 and up to 0.58 % at tau 8 before. Since the share
/// squares are level 5 (`node::SHARE_LEVEL`) none of these DEMs has a
/// share square's edge inside it, and no flight holds more than 0.0004 %.
/// One hole pixel shows on the Grenoble DSM's view
/// 7 at tau 2 to 8 (the same before the curtains): the truth's point on a
/// ray grazing the west cut face lands 1.1 m past the first post, where no
/// LOD tile is.
struct Limits {
    p999_taus: f64,
    skirt_taus: f64,
    skirt_share: f64,
    holes: usize,
}

const LIMITS: Limits = Limits { p999_taus: 1.0, skirt_taus: 2.0, skirt_share: 0.0005, holes: 1 };

/// Every limit of the module doc, per view; every broken one listed. The
/// views above the strict targets are counted and printed.
fn check(name: &str, tau_px: f64, run: &AccuracyRun, coverage: Coverage) -> Vec<String> {
    let mut broken = Vec::new();
    let (mut skirt, mut terrain, mut above_tau, mut triangles) = (0, 0, 0, 0);
    for (k, view) in run.views.iter().enumerate() {
        let e = &view.errors;
        let tau = view.tau_px;
        let limit = &LIMITS;
        let worst_skirt = view.worst_skirt.as_ref().map_or(0.0, |p| p.error_px as f64);
        println!(
            "  {name} tau {tau_px} view {k}: bound {tau:.2}, p99.9 {:.3} max {:.2} px, skirt pixels {} \
             (worst {worst_skirt:.2} px), mismatch {:.4} %, holes {}, mirror {:.4} m, tiles {:?}, triangles {}",
            e.p999_px,
            e.max_px,
            view.skirt_pixels,
            100.0 * view.coverage_mismatch,
            view.holes,
            view.mirror_p99_m,
            view.tiles_per_level,
            view.triangles_lod
        );
        if e.p999_px > tau {
            above_tau += 1;
            println!("    above tau; its worst skirt pixel: {:?}", view.worst_skirt);
        }
        let mut fail = |what: String| broken.push(format!("{name} tau {tau_px} view {k}: {what}"));
        if e.p999_px > limit.p999_taus * tau {
            let over = limit.p999_taus;
            fail(format!(
                "p99.9 {:.3} px over {over} tau {tau}: {:?}",
                e.p999_px, view.worst_skirt
            ));
        }
        if worst_skirt > limit.skirt_taus * tau {
            fail(format!("a skirt pixel errs by {worst_skirt:.2} px: {:?}", view.worst_skirt));
        }
        if view.coverage_mismatch > coverage.mismatch {
            let share = 100.0 * view.coverage_mismatch;
            fail(format!("coverage mismatch {share:.4} %: {:?}", view.truth_only_probe));
        }
        if view.holes > limit.holes.min(coverage.holes) {
            fail(format!("{} hole pixels", view.holes));
        }
        skirt += view.skirt_pixels;
        terrain += e.pixels;
        triangles += view.triangles_lod;
    }
    println!(
        "{name} tau {tau_px}: {above_tau} views above tau, skirt pixels {:.4} % of {terrain} terrain pixels, \
         {triangles} triangles over the views",
        100.0 * skirt as f64 / terrain.max(1) as f64
    );
    if skirt as f64 > LIMITS.skirt_share * terrain as f64 {
        broken
            .push(format!("{name} tau {tau_px}: {skirt} skirt pixels of {terrain} terrain pixels"));
    }
    assert!(terrain > 20_000, "{name} tau {tau_px}: the views see terrain ({terrain} pixels)");
    if let (Some(worst), false) = (&run.worst, broken.is_empty()) {
        let file = format!("data-edges-{name}-tau{tau_px}-view{}", worst.index);
        println!("  worst view's picture: {}", save_evidence(&worst.picture, &file));
        println!("  its heat map: {}", save_evidence(&worst.heat_map, &format!("{file}-heat")));
    }
    broken
}

/// What a flight holds of its coverage, per view: the share of pixels with
/// terrain in one render only, and hole pixels.
#[derive(Clone, Copy)]
struct Coverage {
    mismatch: f64,
    holes: usize,
}

/// Past the rectangle's edges: issue 25's limit; holes as `limits` says.
const EDGE_COVERAGE: Coverage = Coverage { mismatch: 1e-4, holes: usize::MAX };

/// Along a ragged outline: issue 25's limit, and no hole.
const OUTLINE_COVERAGE: Coverage = Coverage { mismatch: 1e-4, holes: 0 };

#[test]
fn real_dems_flown_past_their_edges_hold_tau_with_skirts_counted() {
    let mut broken = Vec::new();
    for (name, file) in EDGE_DEMS {
        let pyramid = asset_pyramid(name, file);
        let views = edge_views(&pyramid);
        for tau_px in TAUS {
            let run = measure(&pyramid, &views, tau_px, None);
            broken.extend(check(name, tau_px, &run, EDGE_COVERAGE));
        }
    }
    assert!(broken.is_empty(), "{} broken promises:\n{}", broken.len(), broken.join("\n"));
}

#[test]
fn a_ragged_no_data_outline_is_drawn_to_the_last_post_with_data() {
    let pyramid = asset_pyramid("rhine-basin", "rhine_basin_30s.tif");
    let views = outline_views(&pyramid);
    let mut broken = Vec::new();
    for tau_px in TAUS {
        let run = measure(&pyramid, &views, tau_px, None);
        broken.extend(check("rhine", tau_px, &run, OUTLINE_COVERAGE));
    }
    assert!(broken.is_empty(), "{} broken promises:\n{}", broken.len(), broken.join("\n"));
}

/// A triangle budget of half what tau 1 draws raises tau; the promises
/// hold at the tau each view achieved, past the steep DSM's edges and
/// along the Rhine's outline.
#[test]
fn a_triangle_budget_that_raises_tau_keeps_the_promises_at_the_edges() {
    let mut broken = Vec::new();
    let flights = [
        ("grenoble-dsm", asset_pyramid("grenoble-dsm", EDGE_DEMS[0].1), false),
        ("rhine", asset_pyramid("rhine-basin", "rhine_basin_30s.tif"), true),
    ];
    for (name, pyramid, outline) in flights {
        let views = if outline { outline_views(&pyramid) } else { edge_views(&pyramid) };
        let free = measure(&pyramid, &views, 1.0, None);
        let mean = free.views.iter().map(|v| v.triangles_lod).sum::<u64>() / views.len() as u64;
        let budget = (mean / 2).max(1);
        let run = measure(&pyramid, &views, 1.0, Some(budget));
        println!(
            "{name}: budget {budget} triangles (half of tau 1's mean), tau raised on {} of {} views, up to {:.2} px",
            run.tau_loosened_views,
            run.views.len(),
            run.tau_achieved_max_px
        );
        assert!(run.tau_loosened_views > 0, "{name}: the budget raised tau on no view");
        let coverage = if outline { OUTLINE_COVERAGE } else { EDGE_COVERAGE };
        broken.extend(check(&format!("{name}-budget"), 1.0, &run, coverage));
    }
    assert!(broken.is_empty(), "{} broken promises:\n{}", broken.len(), broken.join("\n"));
}
