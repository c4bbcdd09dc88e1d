//! Cluster batches (issue 12, Judnich & Ling): the default flight at tau 1,
//! 4 and 8 (tiles cut from node meshes, as `fly` draws them, and regular
//! grids) drawn once tile by tile and once as clusters must draw the same
//! triangles (skirts counted) and the same picture within the golden
//! tolerance, with at least 6 times fewer terrain draw calls; on EGL and
//! OSMesa, ES 3 and ES 2.0.
//!
//! Attribute-pointer changes: the issue asks for no more than draw calls,
//! and every frame is held to it (the sky's pointer and draw counted).
//! Per tile it is 3 per draw; with clusters a change of attribute base (a
//! window of 2^16 vertices) binds the window's vertex array, whose
//! pointers were set when the pass was made, so a frame sets only the
//! sky's. The test prints each tau's pointer changes and vertex array
//! binds per draw, frame by frame (min, mean, max).

use ridgeline::display::DisplayConfig;
use ridgeline::display::{DisplayError, DisplayParts};
use ridgeline::flight::default_flight;
use ridgeline::gl::{GlBackend, GlesVersion};
use testkit::builtin_pyramid;
use testkit::compare::assert_similar;
use testkit::flight::{along, fly, Settle};
use testkit::gl::{skip_for_missing_osmesa, take_turn};
use testkit::render::{config, open, open_grid, render, SIZE, TOLERANCE};

type Open = fn(&DisplayConfig) -> Result<DisplayParts, DisplayError>;

/// What a flight drew: tile draws, terrain draws with clusters, terrain
/// pointer changes, and per frame the clustered frame's pointer changes
/// and vertex array binds over its draw calls.
struct Flown {
    tiles: u64,
    draws: u64,
    pointers: u64,
    per_frame: Vec<(f64, f64)>,
}

/// Min, mean and max of `values`.
fn spread(values: impl Iterator<Item = f64> + Clone) -> (f64, f64, f64) {
    let n = values.clone().count() as f64;
    let min = values.clone().fold(f64::INFINITY, f64::min);
    let max = values.clone().fold(0.0, f64::max);
    (min, values.sum::<f64>() / n, max)
}

fn fly_both_ways(base: DisplayConfig, open: Open, tau: f64, frames: u32) -> Option<Flown> {
    let (backend, version) = (base.backend, base.version);
    let mut per_tile = base;
    per_tile.scene.lod.tau_px = tau;
    let mut clustered = per_tile.clone();
    clustered.scene.clusters = true;
    let mut tiles_display = match open(&per_tile) {
        Ok(display) => display,
        Err(DisplayError::Gl(error)) if skip_for_missing_osmesa("render_clusters", &error) => {
            return None
        }
        Err(error) => panic!("{error}"),
    };
    let mut clusters_display = open(&clustered).expect("the same backend opens twice");
    let path = default_flight(&builtin_pyramid());
    let mut flown = Flown { tiles: 0, draws: 0, pointers: 0, per_frame: Vec::new() };
    let cameras = along(&path, frames, 60.0, SIZE.into());
    fly(&mut tiles_display, cameras, Settle::Every(1000), |frame| {
        let (k, camera, one_by_one) = (frame.k, frame.camera, frame.stats);
        let expected = frame.flyer.context.read_pixels().expect("read back");
        let (actual, batched) = render(&mut clusters_display, camera);
        let name = format!("clusters-{:?}-{:?}-tau{tau}-{k}", backend, version);
        assert_eq!(
            batched.calls.triangles, one_by_one.calls.triangles,
            "{name}: the same triangles, skirts counted"
        );
        assert_similar(&name, &expected, &actual, &TOLERANCE);
        // The sky is one draw of each.
        let terrain_draws = batched.calls.draw_calls - 1;
        let calls = &batched.calls;
        assert!(
            calls.attribute_pointer_changes <= calls.draw_calls,
            "{name}: {} pointer changes for {} draws",
            calls.attribute_pointer_changes,
            calls.draw_calls
        );
        flown.tiles += one_by_one.calls.draw_calls - 1;
        flown.draws += terrain_draws;
        flown.pointers += calls.attribute_pointer_changes - 1;
        let per_draw = |n: u64| n as f64 / calls.draw_calls as f64;
        flown
            .per_frame
            .push((per_draw(calls.attribute_pointer_changes), per_draw(calls.vertex_array_binds)));
    });
    Some(flown)
}

fn check(backend: GlBackend, version: GlesVersion, taus: &[f64], frames: u32) {
    check_over(open, backend, version, taus, frames);
}

fn check_over(open: Open, backend: GlBackend, version: GlesVersion, taus: &[f64], frames: u32) {
    check_config(open, config(backend, version), taus, frames);
}

fn check_config(open: Open, base: DisplayConfig, taus: &[f64], frames: u32) {
    let _turn = take_turn();
    let (backend, version) = (base.backend, base.version);
    for &tau in taus {
        let Some(flown) = fly_both_ways(base.clone(), open, tau, frames) else {
            return;
        };
        let Flown { tiles, draws, pointers, per_frame } = flown;
        let ratio = tiles as f64 / draws as f64;
        let (p_min, p_mean, p_max) = spread(per_frame.iter().map(|f| f.0));
        let (v_min, v_mean, v_max) = spread(per_frame.iter().map(|f| f.1));
        println!(
            "{backend:?} {version:?} tau {tau}: {tiles} tile draws, {draws} cluster draws \
             ({ratio:.1}x fewer), {pointers} terrain pointer changes; per frame over its \
             draws (sky counted): pointer changes min {p_min:.2} mean {p_mean:.2} max \
             {p_max:.2}, vertex array binds min {v_min:.2} mean {v_mean:.2} max {v_max:.2}"
        );
        assert!(ratio >= 6.0, "tau {tau}: only {ratio:.2}x fewer draw calls");
    }
}

#[test]
fn clusters_draw_the_same_picture_with_six_times_fewer_calls_on_egl() {
    check(GlBackend::Egl, GlesVersion::Es3, &[1.0, 4.0, 8.0], 12);
}

/// Regular grids (`fly --regular-grid`): the same.
#[test]
fn clusters_of_regular_grids_draw_the_same_picture() {
    check_over(open_grid, GlBackend::Egl, GlesVersion::Es3, &[1.0, 4.0, 8.0], 8);
}

#[test]
fn clusters_draw_the_same_picture_on_es2() {
    check(GlBackend::Egl, GlesVersion::Es2, &[1.0, 4.0, 8.0], 6);
}

#[test]
fn clusters_draw_the_same_picture_on_osmesa() {
    check(GlBackend::OsMesa, GlesVersion::Es3, &[1.0, 4.0, 8.0], 6);
    check(GlBackend::OsMesa, GlesVersion::Es2, &[4.0], 4);
}

/// Bare ES 2.0 (no OES_vertex_array_object): a change of window sets the
/// three pointers.
#[test]
fn clusters_draw_the_same_picture_without_vertex_arrays() {
    let mut base = config(GlBackend::Egl, GlesVersion::Es2);
    base.vertex_arrays = false;
    check_config(open, base, &[1.0, 4.0, 8.0], 12);
}
