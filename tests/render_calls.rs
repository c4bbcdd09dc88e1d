//! One cost model: the default flight drawn by the GL renderer (its calls
//! counted as they are made) and by the null backend (its calls computed by
//! the cost model) must issue exactly the same calls, kind by kind, frame by
//! frame, depth slices included; on ES 3 and ES 2.0, with the sky and
//! without. A GL call added to a pass without its twin in
//! `render::cost` fails this test.

use std::sync::Arc;

use ridgeline::dem::ElevationGrid;
use ridgeline::display::{DisplayConfig, DisplayParts};
use ridgeline::earth::GridPlacement;
use ridgeline::flight::default_flight;
use ridgeline::geo::{Crs, GeoRef};
use ridgeline::gl::{GlBackend, GlesVersion};
use ridgeline::pipeline::FramePipeline;
use ridgeline::pyramid::{BuildOptions, Pyramid};
use ridgeline::render::{CallStats, NullBackend};
use ridgeline::scene::TerrainSummary;
use testkit::builtin_pyramid;
use testkit::flight::{along, fly, Frame, Settle};
use testkit::render::{config, SENTINEL, SIZE};

const FRAMES: u32 = 24;

/// Flies the built-in approach through both backends; returns the totals
/// and how many frames were cut into two depth slices.
fn fly_both(config: &DisplayConfig) -> (CallStats, u32) {
    fly_both_over(config, builtin_pyramid())
}

/// [`fly_both`] over `pyramid`, its own built-in approach.
fn fly_both_over(config: &DisplayConfig, pyramid: Arc<Pyramid>) -> (CallStats, u32) {
    let summary = TerrainSummary::from_pyramid(pyramid.info());
    let mut gl = DisplayParts::open(config, pyramid.clone(), summary.clone()).expect("EGL display");
    let mut null_pipeline =
        FramePipeline::new(&config.pipeline(), pyramid.clone(), summary).expect("pipeline");
    let mut null = NullBackend::new(&null_pipeline.buffer_plan(), gl.renderer.cost_model());
    let path = default_flight(&pyramid);
    let times: Vec<f64> = path.frame_times(FRAMES).collect();
    let (mut total, mut sliced) = (CallStats::default(), 0);
    let cameras = along(&path, FRAMES, 60.0, SIZE.into());
    fly(&mut gl, cameras, Settle::Every(1000), |Frame { k, camera, stats, flyer: gl }| {
        let (drawn, t) = (stats.calls, times[k]);
        null_pipeline.settle(camera, 1000).expect("settle");
        let counted = null_pipeline.frame(camera, &mut null).expect("null frame").calls;
        assert_eq!(
            gl.pipeline.draw_list().tiles,
            null_pipeline.draw_list().tiles,
            "frame {k}: both pipelines chose the same tiles"
        );
        assert_eq!(drawn, counted, "frame {k} at t = {t:.1} s: GL issued what the model counts");
        sliced += u32::from(gl.pipeline.draw_list().uniforms.and_then(|f| f.slices.far).is_some());
        total.add(&drawn);
    });
    (total, sliced)
}

#[test]
fn gl_and_null_backends_issue_the_same_calls_on_the_default_flight() {
    let (total, sliced) = fly_both(&config(GlBackend::Egl, GlesVersion::Es3));
    println!("ES 3, {FRAMES} frames ({sliced} in two depth slices): {total:?}");
    assert_eq!(total.frames, FRAMES as u64);
    assert!(total.draw_calls > 100 * FRAMES as u64 / 4, "the flight draws terrain");
    assert!(total.upload_calls > 0 && total.uniform_writes > total.draw_calls - 20);
    assert!(sliced > 0, "the flight includes frames drawn in two depth slices");
}

#[test]
fn the_counts_agree_on_es2_and_without_the_sky() {
    let es2 = fly_both(&config(GlBackend::Egl, GlesVersion::Es2)).0;
    let mut no_sky = config(GlBackend::Egl, GlesVersion::Es3);
    no_sky.sentinel = Some(SENTINEL);
    let sentinel = fly_both(&no_sky).0;
    assert!(sentinel.draw_calls < es2.draw_calls, "the sky is one draw a frame fewer");
}

/// Clusters (Judnich & Ling): the pass draws runs of a cluster's members
/// and changes attribute base (a window's vertex array, or three pointers
/// without vertex arrays) only where the base changes; the model must
/// count the same, on ES 3, on ES 2.0 and on ES 2.0 without vertex arrays.
#[test]
fn the_counts_agree_with_clusters() {
    for (version, vertex_arrays) in
        [(GlesVersion::Es3, true), (GlesVersion::Es2, true), (GlesVersion::Es2, false)]
    {
        let mut clustered = config(GlBackend::Egl, version);
        clustered.scene.clusters = true;
        clustered.vertex_arrays = vertex_arrays;
        let (total, sliced) = fly_both(&clustered);
        println!(
            "clusters, {version:?}, vertex arrays {vertex_arrays}, {FRAMES} frames ({sliced} \
             sliced): {total:?}"
        );
        assert!(sliced > 0, "the flight includes frames drawn in two depth slices");
        assert!(
            total.attribute_pointer_changes <= total.draw_calls,
            "no more pointer changes than draws: {total:?}"
        );
    }
}

/// On the ellipsoid (`fly`'s default since issue 26's phase B) the pass
/// writes `u_earth` with the frame's uniforms and six vectors a member:
/// the model counts the same, tile by tile on ES 3 and clustered on ES 2.0.
#[test]
fn the_counts_agree_on_the_ellipsoid() {
    let pyramid = builtin_pyramid();
    let info = pyramid.info();
    let placement = GridPlacement::new(&info.georef, info.layout.posts, info.layout.spacing_m);
    for (version, clusters) in [(GlesVersion::Es3, false), (GlesVersion::Es2, true)] {
        let mut earth = config(GlBackend::Egl, version);
        earth.scene.earth = Some(placement);
        earth.scene.clusters = clusters;
        let (total, sliced) = fly_both(&earth);
        println!("ellipsoid, {version:?}, clusters {clusters}, {FRAMES} frames ({sliced} sliced): {total:?}");
        assert!(total.draw_calls > 0, "the flight draws terrain");
    }
}

/// A projected grid (UTM zone 37 N, 60 m posts, hills) drawn on the
/// ellipsoid by its nodes' series: the same calls as the model counts.
#[test]
fn the_counts_agree_on_a_utm_grid_on_the_ellipsoid() {
    let posts = [513, 513];
    let georef = GeoRef {
        crs: Crs::Projected { epsg: Some(32637) },
        origin: [600_000.0, 4_350_000.0],
        spacing: [60.0; 2],
    };
    let heights = (0..posts[1])
        .flat_map(|j| (0..posts[0]).map(move |i| (i as f32, j as f32)))
        .map(|(i, j)| 1500.0 + 400.0 * (i / 37.0).sin() * (j / 53.0).cos())
        .collect();
    let grid =
        ElevationGrid { width: posts[0], height: posts[1], heights, georef, voids_filled: 0 };
    let dir = testkit::fresh_dir("calls-utm37n");
    testkit::pyramid::build_and_write(&grid, BuildOptions::default(), &dir);
    let pyramid = Arc::new(Pyramid::open(&dir).expect("the UTM pyramid"));
    let info = pyramid.info();
    let placement = GridPlacement::new(&info.georef, info.layout.posts, info.layout.spacing_m);
    assert!(placement.projected_lattice().is_some(), "placed by its projection");
    for (version, clusters) in [(GlesVersion::Es3, false), (GlesVersion::Es2, true)] {
        let mut earth = config(GlBackend::Egl, version);
        earth.scene.earth = Some(placement);
        earth.scene.clusters = clusters;
        let (total, sliced) = fly_both_over(&earth, pyramid.clone());
        println!(
            "UTM, {version:?}, clusters {clusters}, {FRAMES} frames ({sliced} sliced): {total:?}"
        );
        assert!(total.draw_calls > 0, "the flight draws terrain");
    }
}
