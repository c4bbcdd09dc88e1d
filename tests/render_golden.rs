//! Golden images: three fixed views of the built-in terrain rendered on
//! headless EGL and on OSMesa, each compared with the PNG in tests/golden/
//! and with each other under [`TOLERANCE`]; and proof that the tolerance is
//! tight enough to notice a camera moved 5 m, a coarser tau, a missing tile
//! and a wrong colour band.
//!
//! The goldens come from EGL. `RIDGELINE_UPDATE_GOLDEN=1 cargo test --test
//! render_golden` rewrites them (look at them before committing); a missing
//! golden is a failure that says so, never silently created.
//!
//! OSMesa skips loudly where libOSMesa is missing unless
//! RIDGELINE_REQUIRE_OSMESA=1 (CI sets it).

use image::RgbaImage;
use ridgeline::display::DisplayError;
use ridgeline::gl::{GlBackend, GlesVersion, OpenedBackend};
use std::path::PathBuf;
use std::sync::OnceLock;
use testkit::compare::{assert_similar, check_similar, Difference};
use testkit::gl::{skip_for_missing_osmesa, take_turn};
use testkit::render::{config, open, redraw, render, TOLERANCE, VIEWS};

fn golden_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/golden").join(format!("{name}.png"))
}

fn updating() -> bool {
    testkit::gl::required("RIDGELINE_UPDATE_GOLDEN")
}

/// The golden images in [`VIEWS`] order: read from tests/golden/, or, with
/// RIDGELINE_UPDATE_GOLDEN=1, rendered on EGL and written there first (once
/// per process, before any test compares against them). Call with the GL turn.
fn goldens() -> &'static [RgbaImage] {
    static GOLDENS: OnceLock<Vec<RgbaImage>> = OnceLock::new();
    GOLDENS.get_or_init(|| {
        if updating() {
            let mut display = open(&config(GlBackend::Egl, GlesVersion::Es3)).expect("EGL display");
            VIEWS
                .iter()
                .map(|view| write_golden(view.name, render(&mut display, &view.camera()).0))
                .collect()
        } else {
            VIEWS.iter().map(|view| read_golden(view.name)).collect()
        }
    })
}

fn read_golden(name: &str) -> RgbaImage {
    let path = golden_path(name);
    match image::open(&path) {
        Ok(image) => image.to_rgba8(),
        Err(e) => panic!(
            "golden image {} cannot be read ({e}).\n  Create it with `RIDGELINE_UPDATE_GOLDEN=1 cargo test --test \
             render_golden`, look at it, and commit it.",
            path.display()
        ),
    }
}

/// Writes beside the old file and renames into place.
fn write_golden(name: &str, image: RgbaImage) -> RgbaImage {
    let path = golden_path(name);
    let partial = path.with_extension(format!("png.tmp-{}", std::process::id()));
    std::fs::create_dir_all(path.parent().expect("golden directory")).expect("create tests/golden");
    image.save_with_format(&partial, image::ImageFormat::Png).expect("write golden image");
    std::fs::rename(&partial, &path).expect("rename golden image into place");
    eprintln!("*** RIDGELINE_UPDATE_GOLDEN: wrote {}", path.display());
    image
}

#[test]
fn egl_renders_the_golden_views() {
    let _turn = take_turn();
    let goldens = goldens();
    let mut display = open(&config(GlBackend::Egl, GlesVersion::Es3)).expect("EGL display");
    assert_eq!(display.context.info().backend, OpenedBackend::Egl);
    for (view, golden) in VIEWS.iter().zip(goldens) {
        let (image, stats) = render(&mut display, &view.camera());
        assert!(stats.scene.tiles > 50, "{}: only {} tiles drawn", view.name, stats.scene.tiles);
        let difference =
            assert_similar(&format!("golden-egl-{}", view.name), golden, &image, &TOLERANCE);
        println!("EGL {} vs golden: {difference} ({} tiles)", view.name, stats.scene.tiles);
    }
}

#[test]
fn osmesa_renders_the_golden_views_and_matches_egl() {
    let _turn = take_turn();
    let goldens = goldens();
    let mut osmesa = match open(&config(GlBackend::OsMesa, GlesVersion::Es2)) {
        Err(DisplayError::Gl(error))
            if skip_for_missing_osmesa(
                "osmesa_renders_the_golden_views_and_matches_egl",
                &error,
            ) =>
        {
            return;
        }
        other => other.expect("OSMesa display"),
    };
    assert_eq!(osmesa.context.info().backend, OpenedBackend::OsMesa);
    assert!(
        !osmesa.context.info().is_es(),
        "OSMesa runs the ES shaders on desktop GL: {}",
        osmesa.context.info().version
    );
    let mut egl = open(&config(GlBackend::Egl, GlesVersion::Es3)).expect("EGL display");
    for (view, golden) in VIEWS.iter().zip(goldens) {
        let (from_osmesa, _) = render(&mut osmesa, &view.camera());
        let (from_egl, _) = render(&mut egl, &view.camera());
        let to_golden = assert_similar(
            &format!("golden-osmesa-{}", view.name),
            golden,
            &from_osmesa,
            &TOLERANCE,
        );
        let to_egl = assert_similar(
            &format!("osmesa-vs-egl-{}", view.name),
            &from_egl,
            &from_osmesa,
            &TOLERANCE,
        );
        println!("OSMesa {}: vs golden {to_golden}; vs EGL {to_egl}", view.name);
    }
}

/// Each of these changes must fail the comparison with the golden image,
/// or the tolerance would let such a fault through: the camera 5 m east,
/// tau 2 px instead of 1, the tile under the middle of the picture left out
/// of the draw list, the caution band widened from 152 m to 1000 m (where it
/// reaches the terrain), red and blue swapped (a read-back bug).
#[test]
fn the_tolerance_rejects_a_moved_camera_a_coarser_tau_a_missing_tile_and_wrong_colours() {
    let _turn = take_turn();
    let goldens = goldens();
    let mut display = open(&config(GlBackend::Egl, GlesVersion::Es3)).expect("EGL display");
    let mut coarser = config(GlBackend::Egl, GlesVersion::Es3);
    coarser.scene.lod.tau_px = 2.0;
    let mut coarser = open(&coarser).expect("EGL display, tau 2 px");
    let mut banded = config(GlBackend::Egl, GlesVersion::Es3);
    let banded_caution_m = 1000.0;
    banded.scene.caution_below_m = banded_caution_m as f32;
    let highest_m = testkit::builtin_pyramid().info().stats.height_max as f64;
    let mut banded = open(&banded).expect("EGL display, caution band 1000 m");
    for (view, golden) in VIEWS.iter().zip(goldens) {
        let mut moved = view.camera();
        moved.position.x += 5.0;
        let (image, _) = render(&mut display, &moved);
        must_differ(&format!("{}-moved-5m", view.name), golden, &image);
        must_differ(
            &format!("{}-tau-2px", view.name),
            golden,
            &render(&mut coarser, &view.camera()).0,
        );
        // The band can only colour terrain within 1000 m below the aircraft.
        if view.altitude - banded_caution_m < highest_m {
            must_differ(
                &format!("{}-caution-1000m", view.name),
                golden,
                &render(&mut banded, &view.camera()).0,
            );
        }
        let (mut swapped, _) = render(&mut display, &view.camera());
        for pixel in swapped.pixels_mut() {
            pixel.0.swap(0, 2);
        }
        must_differ(&format!("{}-red-blue-swapped", view.name), golden, &swapped);
        render(&mut display, &view.camera());
        let centre = centre_tile(&display, &view.camera());
        let image = redraw(&mut display, |list| {
            list.tiles.remove(centre);
        });
        must_differ(&format!("{}-centre-tile-missing", view.name), golden, &image);
    }
}

fn must_differ(name: &str, golden: &RgbaImage, image: &RgbaImage) {
    let difference = Difference::between(golden, image, TOLERANCE.channel_threshold);
    println!("{name}: {difference}");
    assert!(!difference.within(&TOLERANCE), "{name} passed as the golden image: {difference}");
}

#[test]
fn a_mismatch_names_and_keeps_the_images() {
    let grey = RgbaImage::from_pixel(8, 4, image::Rgba([100, 100, 100, 255]));
    let mut spotted = grey.clone();
    spotted.put_pixel(3, 2, image::Rgba([100, 180, 100, 255]));
    let problem = check_similar("self-test-spot", &grey, &spotted, &TOLERANCE)
        .expect_err("a spot on 1 of 32 pixels passed");
    for kind in ["expected", "actual", "diff"] {
        let path = testkit::target_tmp().join(format!("render-failures/self-test-spot-{kind}.png"));
        assert!(problem.contains(&path.display().to_string()), "{problem}");
        assert_eq!(image::open(&path).expect("evidence saved").to_rgba8().dimensions(), (8, 4));
    }
    let diff = image::open(testkit::target_tmp().join("render-failures/self-test-spot-diff.png"))
        .unwrap()
        .to_rgba8();
    assert_eq!(diff.get_pixel(3, 2).0, [255, 0, 0, 255], "the differing pixel is marked red");
    assert_eq!(check_similar("self-test-same", &grey, &grey, &TOLERANCE).map(|d| d.largest), Ok(0));
}

/// Index in the last draw list of the tile under the middle of the picture:
/// the one holding the first point where the camera's forward ray meets the
/// terrain (marched in 10 m steps over the exact heights).
fn centre_tile(
    display: &ridgeline::display::DisplayParts,
    camera: &ridgeline::camera::Camera,
) -> usize {
    let forward = camera.forward();
    let hit = (1..20_000)
        .map(|step| camera.position + forward * (10.0 * step as f64))
        .find(|p| p.z <= testkit::render::ground(p.x, p.y))
        .expect("the forward ray meets the terrain");
    let relative = (hit - camera.position).truncate().as_vec2();
    let side = display.pipeline.scene().config().lod.grid_size as f32;
    let list = display.pipeline.scene().draw_list();
    // Tile corners are relative to the camera.
    let posts = list.uniforms.expect("a drawn frame").posts;
    list.tiles
        .iter()
        .position(|t| {
            let min = glam::Vec2::from(t.post_position(&posts, 0.0, 0.0));
            let max = glam::Vec2::from(t.post_position(&posts, side, side));
            relative.cmpge(min).all() && relative.cmplt(max).all()
        })
        .expect("a drawn tile holds the centre of the picture")
}

/// The "no data" treatment, kept in a golden image (`edge.png`): the
/// built-in SRTM tile alone, seen from 8 km beyond its east edge, looking
/// back west. The terrain ends at the data's last post, with no shelf and
/// no skirt curtain, and below it the sky pass's grey diagonal hatching
/// fills what no terrain covers (a fifth of the picture and more).
#[test]
fn the_no_data_hatching_at_the_coverage_edge_matches_its_golden() {
    let _turn = take_turn();
    let pyramid = testkit::srtm_tile_pyramid();
    let [east, north] = ridgeline::node::NodeSource::layout(&*pyramid).extent_m();
    let size = testkit::render::SIZE;
    let camera = testkit::camera(
        [size.x, size.y],
        glam::DVec3::new(east + 8_000.0, north / 2.0, 4_500.0),
        270.0,
        -10.0,
    );
    let config = config(GlBackend::Egl, GlesVersion::Es3);
    let mut display = testkit::render::open_over(&config, pyramid).expect("EGL display");
    let (image, _) = render(&mut display, &camera);
    let hatching = image.pixels().filter(|p| testkit::render::is_hatching(p.0)).count();
    let share = hatching as f64 / (size.x * size.y) as f64;
    assert!(share > 0.2, "only {:.1} % of the picture shows the no-data hatching", share * 100.0);
    let golden = if updating() { write_golden("edge", image.clone()) } else { read_golden("edge") };
    let difference = assert_similar("golden-egl-edge", &golden, &image, &TOLERANCE);
    println!("EGL edge vs golden: {difference}; hatching {:.1} % of the picture", share * 100.0);
}
