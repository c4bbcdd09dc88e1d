//! `ridgeline accuracy`: renders views of a flight with the LOD display and
//! with the full-resolution mesh in the same context, measures the per-pixel
//! screen-space geometric error ([`ridgeline::accuracy`] says exactly what
//! is measured), prints its percentiles and coverage mismatch, writes
//! `accuracy.json` and the worst view's heat map, and fails when the
//! measured p99.9 exceeds tau, or when a view shows terrain in one render
//! only over more than 0.01 % of its pixels: the bound is only a promise if
//! this confirms it.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::sync::Arc;

use anyhow::{bail, Context, Result};
use ridgeline::accuracy::RayGround;
use ridgeline::accuracy::{EarthGround, TrueCamera, Verdict, MISMATCH_PER_VIEW};
use ridgeline::camera::Camera;
use ridgeline::display::measure::{measure_flight_on_earth, AccuracyRun, EarthTruth, Truth};
use ridgeline::display::{DisplayConfig, DisplayParts};
use ridgeline::earth::GridPlacement;
use ridgeline::flight::FlightPath;
use ridgeline::gl::{GlBackend, TruthMesh, TruthPass, TruthRegion};
use serde_json::json;

use super::progress::Bar;
use super::terrain::Ground;

#[derive(clap::Args)]
pub struct AccuracyArgs {
    #[command(flatten)]
    pub view: super::ViewArgs,
    /// Views, evenly spaced in time along the path (first and last included).
    #[arg(long, default_value_t = 16)]
    pub views: u32,
    /// Headless contexts only: egl or osmesa (auto picks EGL).
    #[arg(long, value_enum, default_value_t = GlBackend::Auto)]
    pub backend: GlBackend,
    /// Print the report as one JSON object instead of tables.
    #[arg(long)]
    pub json: bool,
    /// Where accuracy.json, heat_map.png and picture.png (the worst view)
    /// and path.csv (the views' path) go.
    #[arg(long, default_value = "target/accuracy")]
    pub out: PathBuf,
    /// Against the geodetic truth, trace every N-th pixel across and down
    /// (1: every pixel; 0: do not measure against the earth).
    #[arg(long, default_value_t = 1)]
    pub earth_stride: u32,
}

pub fn run(args: &AccuracyArgs) -> Result<()> {
    check_args(args)?;
    let bar = Bar::new();
    let terrain = args.view.open_terrain(&bar)?;
    bar.finish();
    let path = terrain.flight_path(args.view.path.as_deref(), args.view.flight)?;
    let (mut display, config) = open_display(args, &terrain, &path)?;
    let views: Vec<(f64, Camera)> = path
        .frame_times(args.views.max(1))
        .map(|t| (t, path.sample(t).camera(args.view.fov, [args.view.size.x, args.view.size.y])))
        .collect();
    let run = measure(args, &terrain, &config, &mut display, &views)?;
    let report = report_json(args, &display, &run, &terrain.name);
    write_outputs(args, &run, &report)?;
    // The views flown, to edit or to measure one alone (`--path`).
    super::write_beside(&args.out.join("path.csv"), path.to_csv().as_bytes())?;
    if args.json {
        super::print(&(serde_json::to_string_pretty(&report)? + "\n"))?;
    } else {
        print_tables(&run)?;
    }
    verdict(&run).check()?;
    Ok(())
}

/// The headless display the views are drawn on, configured as `fly` would
/// draw `terrain` along `path`.
fn open_display(
    args: &AccuracyArgs,
    terrain: &super::terrain::Terrain,
    path: &FlightPath,
) -> Result<(DisplayParts, DisplayConfig)> {
    let mut config = DisplayConfig::new(headless(args.backend), args.view.size);
    args.view.configure_earth(&mut config, terrain);
    config.scene.lod.tau_px = args.view.tau;
    config.fov_x_deg = args.view.fov;
    // Views are far apart: each is a jump, so every view re-tests all tiles.
    args.view.configure(&mut config, path, 0.1);
    let display = DisplayParts::open(&config, Arc::clone(&terrain.source), terrain.summary.clone())
        .context("opening a headless display")?;
    Ok((display, config))
}

/// Measures `views` on `display` against the truth `terrain` gives: the
/// full-resolution mesh drawn on the GPU, or for a procedural earth each
/// pixel's ray; and against the ellipsoid's geodetic truth.
fn measure(
    args: &AccuracyArgs,
    terrain: &super::terrain::Terrain,
    config: &DisplayConfig,
    display: &mut DisplayParts,
    views: &[(f64, Camera)],
) -> Result<AccuracyRun> {
    let layout = *terrain.source.layout();
    let exact = |x: f64, y: f64| terrain.exact_height(x, y);
    let placement = GridPlacement::new(&terrain.georef(), layout.posts, layout.spacing_m);
    let ground = earth_ground(args, terrain, placement, views)?;
    let on_earth = ground.as_ref().map(|(ground, reach_m)| EarthTruth {
        placement,
        ground,
        stride: args.earth_stride,
        reach_m: *reach_m,
    });
    let on_earth = on_earth.as_ref();
    let spacing = layout.spacing_m;
    match &terrain.ground {
        Ground::Procedural(earth) => {
            // Out to the horizon the full-resolution mesh is 10^8 triangles
            // and more: follow each pixel's ray on the CPU instead.
            let ground = RayGround {
                exact: &exact,
                slope: earth.slope_bound(),
                top_m: earth.height_bounds()[1],
                spacing_m: spacing[0].min(spacing[1]),
            };
            let truth = Truth::Rays(ground);
            measure_flight_on_earth(display, truth, on_earth, &exact, spacing, views)
        }
        Ground::Pyramid(_) => {
            let mesh = truth_mesh(terrain, config, views)?;
            let truth = TruthPass::new(display.context.gl(), &mesh)
                .context("uploading the full-resolution mesh")?;
            let truth = Truth::Mesh(&truth);
            measure_flight_on_earth(display, truth, on_earth, &exact, spacing, views)
        }
    }
    .context("measuring the views")
}

/// The full-resolution mesh around the flight: all of a single tile, a
/// window of a layered pyramid's level 0 (which spans its whole base).
fn truth_mesh(
    terrain: &super::terrain::Terrain,
    config: &DisplayConfig,
    views: &[(f64, Camera)],
) -> Result<TruthMesh> {
    let layout = *terrain.source.layout();
    let grid_size = config.scene.lod.grid_size;
    let positions = views.iter().map(|(_, c)| [c.position.x, c.position.y]);
    // On the ellipsoid a global grid's truth is not cut at its seam.
    let period = config.scene.earth.and_then(|p| p.period_posts()).map(|p| p as u32);
    let region = match period {
        Some(period) => {
            TruthRegion::around_positions_wrapping(&layout, grid_size, positions, period)
        }
        None => TruthRegion::around_positions(&layout, grid_size, positions),
    };
    TruthMesh::load_wrapped(terrain.source.as_ref(), region, period)
        .with_context(|| format!("{}: the full-resolution mesh", terrain.name))
}

/// `accuracy.json`: the run's settings, its summary and every view.
fn report_json(
    args: &AccuracyArgs,
    display: &DisplayParts,
    run: &AccuracyRun,
    dataset_name: &str,
) -> serde_json::Value {
    let info = display.context.info();
    json!({
        "dataset": dataset_name,
        "backend": info.backend.name(),
        "gl_renderer": info.renderer,
        "size": [args.view.size.x, args.view.size.y],
        "fov_x_deg": args.view.fov,
        "tau_px": run.tau_px,
        "flight": format!("{:?}", args.view.flight).to_lowercase(),
        "truth": run.truth,
        "horizon_culled": mean(run, |v| v.horizon_culled as f64),
        "tau_achieved_max_px": run.tau_achieved_max_px,
        "tau_loosened_views": run.tau_loosened_views,
        "triangle_budget": args.view.triangle_budget,
        "frame_ms_target": args.view.frame_ms,
        "p50_px": run.summary.p50_px,
        "p99_px": run.summary.p99_px,
        "p999_px": run.summary.p999_px,
        "max_px": run.summary.max_px,
        "mean_px": run.summary.mean_px,
        "terrain_pixels": run.summary.pixels,
        "coverage_mismatch": run.coverage_mismatch,
        "coverage_mismatch_worst_view": run.views.iter().map(|v| v.coverage_mismatch).fold(0.0, f64::max),
        "holes": run.holes,
        "skirt_pixels": run.skirt_pixels,
        "max_surface_px": run.max_surface_px,
        "triangles_lod": mean(run, |v| v.triangles_lod as f64),
        "triangles_truth": mean(run, |v| v.triangles_truth as f64),
        "lod_frame_ms": mean(run, |v| v.lod_frame_ms),
        "truth_frame_ms": mean(run, |v| v.truth_frame_ms),
        "views": run.views.len(),
        "worst_view": run.worst.as_ref().map(|w| w.index),
        "earth": run.earth,
        "per_view": run.views,
    })
}

/// The best data on the ellipsoid for the geodetic truth, loaded as far as
/// the views can see (the horizon of the highest view over the lowest
/// ground, and that of the highest ground), and that reach; `None` with
/// `--earth-stride 0`.
fn earth_ground(
    args: &AccuracyArgs,
    terrain: &super::terrain::Terrain,
    placement: GridPlacement,
    views: &[(f64, Camera)],
) -> Result<Option<(EarthGround, f64)>> {
    if args.earth_stride == 0 {
        return Ok(None);
    }
    let (low, high) = terrain.summary.height_range;
    let eyes: Vec<_> = views.iter().map(|(_, c)| TrueCamera::new(c, &placement).eye).collect();
    let highest = views.iter().map(|(_, c)| c.position.z).fold(high as f64, f64::max);
    let horizon = |h: f64| (2.0 * 6_400_000.0 * (h - low as f64).max(1.0)).sqrt();
    let reach_m = 1.1 * (horizon(highest) + horizon(high as f64)) + 10_000.0;
    // Heights only: the pyramid itself, not the source with its meshes.
    let source: &dyn ridgeline::node::NodeSource = match &terrain.ground {
        super::terrain::Ground::Pyramid(pyramid) => pyramid.as_ref(),
        super::terrain::Ground::Procedural(earth) => earth.as_ref(),
    };
    let ground = EarthGround::load(source, placement, &eyes, reach_m)
        .with_context(|| format!("{}: the best data for the geodetic truth", terrain.name))?;
    Ok(Some((ground, reach_m)))
}

/// The run's verdict: p99.9 within the largest tau a view achieved, and
/// every view's coverage mismatch within [`MISMATCH_PER_VIEW`].
fn verdict(run: &AccuracyRun) -> Verdict {
    let mismatch = run.views.iter().map(|v| (v.t, v.coverage_mismatch));
    Verdict::of(&run.summary, run.tau_achieved_max_px, mismatch)
}

fn check_args(args: &AccuracyArgs) -> Result<()> {
    args.view.check()?;
    if args.backend == GlBackend::Window {
        bail!("--backend window: the accuracy tool renders off screen; use egl or osmesa");
    }
    Ok(())
}

/// The accuracy tool draws off screen: `auto` means headless EGL.
fn headless(backend: GlBackend) -> GlBackend {
    if backend == GlBackend::Auto {
        GlBackend::Egl
    } else {
        backend
    }
}

fn mean(run: &AccuracyRun, f: impl Fn(&ridgeline::display::measure::ViewRow) -> f64) -> f64 {
    run.views.iter().map(f).sum::<f64>() / run.views.len().max(1) as f64
}

fn write_outputs(args: &AccuracyArgs, run: &AccuracyRun, report: &serde_json::Value) -> Result<()> {
    let out = &args.out;
    std::fs::create_dir_all(out)
        .with_context(|| format!("{}: cannot create the output folder", out.display()))?;
    super::write_beside(
        &out.join("accuracy.json"),
        serde_json::to_string_pretty(report)?.as_bytes(),
    )?;
    if let Some(worst) = &run.worst {
        super::save_png(&worst.heat_map, &out.join("heat_map.png"))?;
        super::save_png(&worst.picture, &out.join("picture.png"))?;
    }
    Ok(())
}

/// Prints the per-view table, the run's summary and the verdicts.
fn print_tables(run: &AccuracyRun) -> Result<()> {
    let mut out = String::new();
    view_table(&mut out, run)?;
    writeln!(out)?;
    error_lines(&mut out, run)?;
    cost_lines(&mut out, run)?;
    let verdict = verdict(run);
    let said = |held: bool| if held { "confirmed" } else { "NOT confirmed" };
    // Two decimals at most: a budget's tau is any number.
    let bound = (run.tau_achieved_max_px * 100.0).round() / 100.0;
    let held = said(verdict.bound_held());
    writeln!(out, "  bound             p99.9 {:.3} px <= tau {bound} px: {held}", verdict.p999_px)?;
    if let Some(earth) = &run.earth {
        let p999 = earth.errors.p999_px;
        let held = said(p999 <= run.tau_achieved_max_px);
        writeln!(out, "  bound on earth    p99.9 {p999:.3} px <= tau {bound} px: {held}")?;
    }
    let worst = match verdict.mismatched {
        Some(view) => format!(" (view {} at t = {:.1} s)", view.index, view.t),
        None => String::new(),
    };
    writeln!(
        out,
        "  coverage          worst view {:.4} %{worst} <= {:.2} % of its pixels: {}",
        100.0 * verdict.worst_mismatch,
        100.0 * MISMATCH_PER_VIEW,
        said(verdict.coverage_held())
    )?;
    super::print(&out)
}

/// A row per view: its tau, errors, mismatch and triangles.
fn view_table(out: &mut String, run: &AccuracyRun) -> Result<()> {
    writeln!(
        out,
        "{:>8} {:>7} {:>8} {:>8} {:>8} {:>8} {:>9} {:>9} {:>9} {:>9}",
        "t s",
        "tau px",
        "p50 px",
        "p99 px",
        "p99.9 px",
        "max px",
        "mismatch",
        "lod tris",
        "truth tris",
        "mirror m"
    )?;
    for v in &run.views {
        let e = &v.errors;
        writeln!(
            out,
            "{:>8.1} {:>7.2} {:>8.3} {:>8.3} {:>8.3} {:>8.3} {:>8.4}% {:>9} {:>9} {:>9.4}",
            v.t,
            v.tau_px,
            e.p50_px,
            e.p99_px,
            e.p999_px,
            e.max_px,
            100.0 * v.coverage_mismatch,
            v.triangles_lod,
            v.triangles_truth,
            v.mirror_p99_m
        )?;
    }
    Ok(())
}

/// The run's tau, errors, skirts, coverage and triangles.
fn error_lines(out: &mut String, run: &AccuracyRun) -> Result<()> {
    let s = &run.summary;
    if run.tau_loosened_views == 0 {
        writeln!(out, "  tau               {} px", run.tau_px)?;
    } else {
        writeln!(
            out,
            "  tau               LOOSENED by the frame budget on {} of {} views: requested {} px, \
             achieved up to {:.2} px (the bound checked below)",
            run.tau_loosened_views,
            run.views.len(),
            run.tau_px,
            run.tau_achieved_max_px
        )?;
    }
    writeln!(out, "  error             p50 {:.3}, p99 {:.3}, p99.9 {:.3}, max {:.3} px over {} terrain pixels", s.p50_px, s.p99_px, s.p999_px, s.max_px, s.pixels)?;
    writeln!(
        out,
        "  skirts            {} terrain pixels show one; max error off skirts {:.3} px",
        run.skirt_pixels, run.max_surface_px
    )?;
    writeln!(
        out,
        "  coverage mismatch {:.4}% of pixels, {} holes; {} silhouette pixels (terrain in one \
         render only, over ground both cover) measured as error",
        100.0 * run.coverage_mismatch,
        run.holes,
        run.views.iter().map(|v| v.silhouette).sum::<usize>()
    )?;
    let ratio =
        mean(run, |v| v.triangles_truth as f64) / mean(run, |v| v.triangles_lod as f64).max(1.0);
    let counted = if run.truth == "cpu_rays" { ", counted in the frustum" } else { "" };
    writeln!(
        out,
        "  triangles         LOD {:.0}, full resolution {:.0}{counted} ({ratio:.2}x)",
        mean(run, |v| v.triangles_lod as f64),
        mean(run, |v| v.triangles_truth as f64)
    )?;
    if run.truth == "cpu_rays" {
        writeln!(out, "  truth             each pixel's ray on the CPU against the exact heights")?;
    }
    Ok(())
}

/// Against the earth, horizon culling, frame times and the worst view.
fn cost_lines(out: &mut String, run: &AccuracyRun) -> Result<()> {
    if let Some(earth) = &run.earth {
        let e = &earth.errors;
        writeln!(
            out,
            "  against the earth p50 {:.3}, p99 {:.3}, p99.9 {:.3}, max {:.3} px over {} traced pixels \
             ({}; {:.4}% coverage mismatch, {} holes; rays {:.0} ms a view)",
            e.p50_px,
            e.p99_px,
            e.p999_px,
            e.max_px,
            e.pixels,
            match earth.stride {
                1 => "every pixel".to_string(),
                n => format!("one pixel in {n} across and down"),
            },
            100.0 * earth.coverage_mismatch,
            earth.holes,
            earth.truth_ms
        )?;
    }
    writeln!(
        out,
        "  horizon culled    {:.0} tiles a view (in the frustum, below the horizon)",
        mean(run, |v| v.horizon_culled as f64)
    )?;
    let (lod_ms, truth_ms) = (mean(run, |v| v.lod_frame_ms), mean(run, |v| v.truth_frame_ms));
    writeln!(
        out,
        "  frame ms          LOD {lod_ms:.1}, full resolution {truth_ms:.1} ({:.2}x)",
        truth_ms / lod_ms.max(1e-9)
    )?;
    if let Some(worst) = &run.worst {
        writeln!(
            out,
            "  worst view        t = {:.1} s (heat_map.png, picture.png)",
            run.views[worst.index].t
        )?;
    }
    Ok(())
}
