//! The reference symbols and the failure flag on screen: golden images on
//! EGL and OSMesa, ES 3 and ES 2.0 (`symbols.png`: the medium golden view
//! banked and climbing, with the zero-pitch line, heading marks and
//! labels, the aircraft symbol and the flight path marker over the
//! terrain; `stale.png`: the withdrawn frame with the failure flag), the
//! symbols conformal in the drawn pixels (the zero-pitch line within 1 px
//! of where the GL matrices put horizontal directions, at several roll and
//! pitch angles; the flight path marker's ring centred within 1 px of the
//! projected velocity), and the null backend counting the symbol pass and
//! the withdrawn frame call for call.
//!
//! `RIDGELINE_UPDATE_GOLDEN=1 cargo test --test render_symbols` rewrites
//! the two goldens (look at them before committing).

use glam::{DVec2, DVec3, Vec4Swizzles};
use image::RgbaImage;
use ridgeline::camera::Camera;
use ridgeline::display::{DisplayError, DisplayParts};
use ridgeline::gl::{GlBackend, GlesVersion};
use ridgeline::pipeline::FramePipeline;
use ridgeline::render::NullBackend;
use ridgeline::symbology::{flag, heading_direction, reference_symbols, SymbolMesh};
use std::path::PathBuf;
use testkit::compare::assert_similar;
use testkit::gl::{skip_for_missing_osmesa, take_turn};
use testkit::render::{config, open, TOLERANCE, VIEWS};

/// The medium golden view, banked 20° right and pitched up 2°, descending
/// at 60 m/s a little right of the nose.
fn banked() -> (Camera, DVec3) {
    let mut camera = VIEWS[0].camera();
    camera.roll_deg = 20.0;
    camera.pitch_deg = 2.0;
    let velocity = heading_direction(camera.heading_deg + 4.0, -3.0) * 60.0;
    (camera, velocity)
}

fn golden(name: &str, image: &RgbaImage) -> RgbaImage {
    let path =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/golden").join(format!("{name}.png"));
    if testkit::gl::required("RIDGELINE_UPDATE_GOLDEN") {
        let partial = path.with_extension("png.tmp");
        image.save_with_format(&partial, image::ImageFormat::Png).expect("write golden");
        std::fs::rename(&partial, &path).expect("rename golden");
        eprintln!("*** RIDGELINE_UPDATE_GOLDEN: wrote {}", path.display());
    }
    image::open(&path)
        .unwrap_or_else(|e| {
            panic!("golden {} ({e}): RIDGELINE_UPDATE_GOLDEN=1 makes it", path.display())
        })
        .to_rgba8()
}

/// The two pictures on one display: symbols over the terrain, the flag.
fn pictures(display: &mut DisplayParts) -> (RgbaImage, RgbaImage) {
    let (camera, velocity) = banked();
    let mut mesh = SymbolMesh::new();
    reference_symbols(&mut mesh, &camera, Some(velocity));
    display.pipeline.settle(&camera, 1000).expect("settle");
    display.frame_with_symbols(&camera, &mesh).expect("frame with symbols");
    let symbols = display.context.read_pixels().expect("read back");
    flag::failure_flag(&mut mesh, camera.viewport, "STALE DATA");
    let stats = display.withdrawn_frame(&mesh).expect("withdrawn frame");
    assert_eq!(stats.scene.tiles, 0, "the terrain is withdrawn");
    (symbols, display.context.read_pixels().expect("read back"))
}

#[test]
fn symbols_and_flag_match_their_goldens_on_egl_and_osmesa_es3_and_es2() {
    let _turn = take_turn();
    let mut reference = open(&config(GlBackend::Egl, GlesVersion::Es3)).expect("EGL display");
    let (symbols, stale) = pictures(&mut reference);
    let (golden_symbols, golden_stale) = (golden("symbols", &symbols), golden("stale", &stale));
    for (backend, version) in [
        (GlBackend::Egl, GlesVersion::Es3),
        (GlBackend::Egl, GlesVersion::Es2),
        (GlBackend::OsMesa, GlesVersion::Es3),
        (GlBackend::OsMesa, GlesVersion::Es2),
    ] {
        let name = format!("{backend:?}-{version:?}").to_lowercase();
        let mut display = match open(&config(backend, version)) {
            Err(DisplayError::Gl(e))
                if skip_for_missing_osmesa(&format!("symbols on {name}"), &e) =>
            {
                continue
            }
            other => other.expect("display"),
        };
        let (symbols, stale) = pictures(&mut display);
        let a = assert_similar(&format!("symbols-{name}"), &golden_symbols, &symbols, &TOLERANCE);
        let b = assert_similar(&format!("stale-{name}"), &golden_stale, &stale, &TOLERANCE);
        println!("{name}: symbols {a}; stale {b}");
    }
}

/// Pixels of exactly `colour`.
fn pixels_of(image: &RgbaImage, colour: [u8; 3]) -> Vec<DVec2> {
    image
        .enumerate_pixels()
        .filter(|(_, _, p)| p.0[..3] == colour)
        .map(|(x, y, _)| DVec2::new(x as f64 + 0.5, y as f64 + 0.5))
        .collect()
}

/// Where the f32 GL matrices the terrain is drawn with put `direction`.
fn through_gl(camera: &Camera, direction: DVec3) -> DVec2 {
    let m = camera.projection(1.0, 100_000.0) * camera.view();
    let clip = m * (direction * 1000.0).as_vec3().extend(1.0);
    let ndc = clip.xy() / clip.w;
    let size = DVec2::new(camera.viewport[0] as f64, camera.viewport[1] as f64);
    DVec2::new((1.0 + ndc.x as f64) * size.x / 2.0, (1.0 - ndc.y as f64) * size.y / 2.0)
}

/// The drawn zero-pitch line, found column by column as the white run
/// nearest the GL projection of the horizontal, lies within 1 px of it at
/// several roll and pitch angles; the drawn flight path marker's ring is
/// centred within 1 px of the GL projection of the velocity.
#[test]
fn the_drawn_symbols_are_conformal() {
    let _turn = take_turn();
    let mut display = open(&config(GlBackend::Egl, GlesVersion::Es3)).expect("EGL display");
    let mut mesh = SymbolMesh::new();
    let mut checked = 0;
    for (pitch, roll) in [(0.0, 0.0), (-6.0, 15.0), (4.0, -30.0), (8.0, 45.0), (-10.0, -60.0)] {
        let mut camera = VIEWS[0].camera();
        (camera.pitch_deg, camera.roll_deg) = (pitch, roll);
        let velocity = heading_direction(camera.heading_deg - 5.0, pitch - 2.0) * 50.0;
        reference_symbols(&mut mesh, &camera, Some(velocity));
        // Drawn alone, over the withdrawn frame's plain clear: nothing else is white or green.
        display.withdrawn_frame(&mesh).expect("symbols drawn");
        let image = display.context.read_pixels().expect("read back");
        let a = through_gl(&camera, heading_direction(camera.heading_deg - 20.0, 0.0));
        let b = through_gl(&camera, heading_direction(camera.heading_deg + 20.0, 0.0));
        let across = (b - a).normalize().perp();
        let white = pixels_of(&image, [255, 255, 255]);
        // Columns away from the heading marks (a mark's foot joins the line).
        let marks: Vec<f64> = (0..36)
            .map(|k| heading_direction(k as f64 * 10.0, 0.0))
            .filter(|d| camera.forward().dot(*d) > 0.0)
            .map(|d| through_gl(&camera, d).x)
            .collect();
        for x in (20..camera.viewport[0] - 20).step_by(13) {
            if marks.iter().any(|m| (m - x as f64).abs() < 8.0) {
                continue;
            }
            let t = (x as f64 + 0.5 - a.x) / (b.x - a.x);
            let expected = a + (b - a) * t;
            // The white pixels of this column within 4 px of the line; their mean offset.
            let near: Vec<f64> = white
                .iter()
                .filter(|p| (p.x - expected.x).abs() < 0.6)
                .map(|p| (*p - expected).dot(across))
                .filter(|d| d.abs() < 4.0)
                .collect();
            if near.is_empty() {
                continue; // under the aircraft symbol, or off the screen
            }
            let offset = near.iter().sum::<f64>() / near.len() as f64;
            assert!(
                offset.abs() <= 1.0,
                "pitch {pitch}, roll {roll}, x {x}: the line is {offset:.2} px off"
            );
            checked += 1;
        }
        let green = pixels_of(&image, [40, 255, 80]);
        let ring: Vec<&DVec2> = green
            .iter()
            .filter(|p| (**p - through_gl(&camera, velocity.normalize())).length() < 8.0)
            .collect();
        let centre = ring.iter().fold(DVec2::ZERO, |s, p| s + **p) / ring.len() as f64;
        let expected = through_gl(&camera, velocity.normalize());
        assert!(
            (centre - expected).length() <= 1.0,
            "pitch {pitch}, roll {roll}: marker at {centre}, velocity at {expected}"
        );
    }
    assert!(checked >= 20, "only {checked} columns showed the line");
}

/// The symbol pass and the withdrawn frame cost what the null backend
/// counts, on ES 3 and on ES 2.0 without vertex array objects.
#[test]
fn the_null_backend_counts_the_symbol_pass_and_the_withdrawn_frame() {
    let _turn = take_turn();
    for (version, vertex_arrays) in [(GlesVersion::Es3, true), (GlesVersion::Es2, false)] {
        let mut config = config(GlBackend::Egl, version);
        config.vertex_arrays = vertex_arrays;
        let mut gl = open(&config).expect("EGL display");
        let terrain = testkit::builtin_terrain();
        let summary = testkit::summary_of(&terrain);
        let mut pipeline =
            FramePipeline::new(&config.pipeline(), terrain, summary).expect("pipeline");
        let mut null = NullBackend::new(&pipeline.buffer_plan(), gl.renderer.cost_model());
        let (camera, velocity) = banked();
        let mut mesh = SymbolMesh::new();
        reference_symbols(&mut mesh, &camera, Some(velocity));
        gl.pipeline.settle(&camera, 1000).unwrap();
        pipeline.settle(&camera, 1000).unwrap();
        let drawn = gl.frame_with_symbols(&camera, &mesh).unwrap().calls;
        let counted = pipeline.frame_with_symbols(&camera, &mesh, &mut null).unwrap().calls;
        assert_eq!(drawn, counted, "{version:?}: a frame with symbols");
        flag::failure_flag(&mut mesh, camera.viewport, "NO DATA");
        let drawn = gl.withdrawn_frame(&mesh).unwrap().calls;
        let counted = pipeline.withdrawn_frame(&mesh, &mut null).unwrap().calls;
        assert_eq!(drawn, counted, "{version:?}: a withdrawn frame");
        assert_eq!(drawn.draw_calls, 1, "the flag is one draw");
    }
}
