//! The reference symbols drawn over the synthetic terrain, GL-free: their
//! geometry is computed here from the camera and the velocity, into a
//! [`SymbolMesh`] that a thin GL pass draws (`gl::symbol_pass`) and the
//! null backend counts.
//!
//! Following Garmin's synthetic vision (G1000 Pilot's Guide for the Cessna
//! Nav III, 190-00498-07 Rev. A, "Synthetic Vision"):
//! - the zero-pitch line, drawn completely across the display, with
//!   heading marks every 10° and labels every 30° (`N 3 6 E 12 ...`, the
//!   compass rose's);
//! - the aircraft reference symbol at the boresight (the screen's centre:
//!   the camera looks along the nose);
//! - the flight path marker where the velocity vector points, shown above
//!   30 kt of ground speed as Garmin's is, hidden when the velocity is
//!   unknown or off the screen;
//! - and, when the data are stale, the failure flag over a withdrawn
//!   terrain ([`flag`]).
//!
//! Conformal: every position comes from [`Projector`], the camera's own
//! projection (checked against the GL matrices in its tests).

pub mod flag;
pub mod font;
pub mod mesh;
pub mod projection;

pub use mesh::{SymbolMesh, SymbolVertex, MAX_SYMBOL_VERTICES, VERTEX_BYTES};
pub use projection::{heading_direction, Projector, ScreenLine};

use glam::{DVec2, DVec3};

use crate::camera::Camera;
use mesh::{GREEN, WHITE, YELLOW};

/// The ground speed below which no flight path marker is drawn, m/s (30
/// kt, Garmin's).
pub const FLIGHT_PATH_MIN_SPEED_MPS: f64 = 30.0 * 1852.0 / 3600.0;

/// Pixels per symbol unit for a viewport: symbols are sized for 540 rows
/// and scale with the height, never below 0.6 of that size.
pub fn scale(viewport: [u32; 2]) -> f64 {
    (viewport[1] as f64 / 540.0).clamp(0.6, 4.0)
}

/// Where the reference symbols went (for tests and stats).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Layout {
    /// The zero-pitch line's centreline, when on the screen.
    pub horizon: Option<ScreenLine>,
    /// Heading marks drawn.
    pub marks: u32,
    /// Heading labels drawn.
    pub labels: u32,
    /// The flight path marker's centre, when drawn.
    pub flight_path: Option<DVec2>,
}

/// Lays out the reference symbols for `camera` into `mesh`, with the flight
/// path marker for `velocity` (the display frame's x east, y north, z up;
/// m/s) when it is known.
pub fn reference_symbols(
    mesh: &mut SymbolMesh,
    camera: &Camera,
    velocity: Option<DVec3>,
) -> Layout {
    let s = scale(camera.viewport);
    mesh.begin(camera.viewport, s.max(1.0));
    let projector = Projector::new(camera);
    let mut layout = Layout { horizon: projector.zero_pitch_line(), ..Layout::default() };
    if let Some(line) = layout.horizon {
        let reach = projector.size().length();
        let (a, b) = (line.point - line.direction * reach, line.point + line.direction * reach);
        mesh.line(a, b, 2.0 * s, WHITE);
        heading_marks(mesh, &projector, s, &mut layout);
    }
    aircraft_symbol(mesh, projector.size() / 2.0, s);
    layout.flight_path = velocity.and_then(|v| flight_path_marker(mesh, &projector, v, s));
    mesh.finish();
    layout
}

/// Marks on the zero-pitch line every 10°, longer every 30° with the
/// heading's label above, each upright to the horizon.
fn heading_marks(mesh: &mut SymbolMesh, projector: &Projector, s: f64, layout: &mut Layout) {
    for step in 0..36 {
        let heading = step as f64 * 10.0;
        let Some(at) = projector.project(heading_direction(heading, 0.0)) else { continue };
        if !projector.on_screen(at, 20.0 * s) {
            continue;
        }
        // "Up" on the screen at this mark: toward the same heading raised.
        let Some(raised) = projector.project(heading_direction(heading, 1.0)) else { continue };
        let Some(up) = (raised - at).try_normalize() else { continue };
        let labelled = step % 3 == 0;
        let length = if labelled { 14.0 } else { 8.0 } * s;
        mesh.line(at, at + up * length, 2.0 * s, WHITE);
        layout.marks += 1;
        if labelled {
            let mut digits = [0u8; 2];
            text(
                mesh,
                heading_label(step / 3, &mut digits),
                at + up * (length + 5.0 * s),
                up,
                12.0 * s,
                WHITE,
            );
            layout.labels += 1;
        }
    }
}

/// The label of the `k`-th 30° heading: `N`, `3`, `6`, `E`, `12`, ... `33`.
fn heading_label(k: u32, digits: &mut [u8; 2]) -> &str {
    match k {
        0 => "N",
        3 => "E",
        6 => "S",
        9 => "W",
        _ => {
            let tens = k * 3;
            let n = if tens >= 10 { 2 } else { 1 };
            digits[0] = b'0' + (tens / 10 % 10) as u8;
            digits[1] = b'0' + (tens % 10) as u8;
            let text = &digits[2 - n..];
            std::str::from_utf8(text).unwrap_or("?")
        }
    }
}

/// `label`, its baseline centred on `at`, upright along `up` (unit, in
/// pixels), `height` pixels high.
pub fn text(
    mesh: &mut SymbolMesh,
    label: &str,
    at: DVec2,
    up: DVec2,
    height: f64,
    colour: mesh::Rgba,
) {
    let unit = height / font::HEIGHT;
    // Screen y grows down: "along" is `up` turned a quarter clockwise on screen.
    let along = DVec2::new(-up.y, up.x);
    let left = at - along * (font::width(label) * unit / 2.0);
    let width = (unit * 0.9).max(1.2);
    font::segments(label, |a, b| {
        let point = |[x, y]: [f64; 2]| left + along * (x * unit) + up * (y * unit);
        mesh.line(point(a), point(b), width, colour);
    });
}

/// Garmin's yellow aircraft symbol at the boresight: two wing bars with
/// down-turned inner ends and a centre square.
fn aircraft_symbol(mesh: &mut SymbolMesh, centre: DVec2, s: f64) {
    let width = 4.0 * s;
    for side in [-1.0, 1.0] {
        let p = |x: f64, y: f64| centre + DVec2::new(side * x * s, y * s);
        mesh.polyline(&[p(70.0, 0.0), p(24.0, 0.0), p(24.0, 10.0)], width, YELLOW);
    }
    mesh.line(
        centre - DVec2::new(2.5 * s, 0.0),
        centre + DVec2::new(2.5 * s, 0.0),
        5.0 * s,
        YELLOW,
    );
}

/// The flight path marker where `velocity` points: a circle with wings
/// level with the horizon and a tail up. `None` (not drawn) below
/// [`FLIGHT_PATH_MIN_SPEED_MPS`] or when the direction is off the screen.
fn flight_path_marker(
    mesh: &mut SymbolMesh,
    projector: &Projector,
    velocity: DVec3,
    s: f64,
) -> Option<DVec2> {
    if !velocity.is_finite() || velocity.truncate().length() < FLIGHT_PATH_MIN_SPEED_MPS {
        return None;
    }
    let centre = projector.project(velocity.normalize())?;
    let radius = 8.0 * s;
    if !projector.on_screen(centre, -radius) {
        return None;
    }
    let level = projector.zero_pitch_line().map_or(DVec2::X, |line| line.direction);
    let up = DVec2::new(level.y, -level.x);
    let width = 2.5 * s;
    const SIDES: usize = 12;
    let mut ring = [DVec2::ZERO; SIDES + 1];
    for (k, p) in ring.iter_mut().enumerate() {
        let angle = k as f64 / SIDES as f64 * std::f64::consts::TAU;
        *p = centre + DVec2::new(angle.cos(), angle.sin()) * radius;
    }
    mesh.polyline(&ring, width, GREEN);
    for side in [-1.0, 1.0] {
        mesh.line(
            centre + level * side * radius,
            centre + level * side * (radius + 12.0 * s),
            width,
            GREEN,
        );
    }
    mesh.line(centre + up * radius, centre + up * (radius + 8.0 * s), width, GREEN);
    Some(centre)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera(pitch: f64, roll: f64) -> Camera {
        Camera {
            position: DVec3::new(0.0, 0.0, 1000.0),
            heading_deg: 95.0,
            pitch_deg: pitch,
            roll_deg: roll,
            fov_x_deg: 60.0,
            viewport: [960, 540],
        }
    }

    #[test]
    fn labels_follow_the_compass_rose() {
        let mut digits = [0; 2];
        let labels: Vec<String> =
            (0..12).map(|k| heading_label(k, &mut digits).to_owned()).collect();
        assert_eq!(labels, ["N", "3", "6", "E", "12", "15", "S", "21", "24", "W", "30", "33"]);
    }

    #[test]
    fn a_level_view_shows_the_line_marks_labels_and_marker() {
        let mut mesh = SymbolMesh::new();
        let velocity = heading_direction(100.0, -3.0) * 60.0;
        let layout = reference_symbols(&mut mesh, &camera(0.0, 0.0), Some(velocity));
        let line = layout.horizon.unwrap();
        assert!((line.point.y - 270.0).abs() < 1e-9);
        // 60 degrees of view: headings 70..120, with the margin 60..130.
        assert!((6..=8).contains(&layout.marks), "{layout:?}");
        assert!(layout.labels >= 2, "{layout:?}");
        assert!(layout.flight_path.unwrap().x > 480.0, "right of the nose, heading 100 from 95");
        assert!(layout.flight_path.unwrap().y > 270.0, "below the horizon, descending");
        assert_eq!(mesh.dropped, 0);
        assert!(mesh.vertices().len() < MAX_SYMBOL_VERTICES / 2);
    }

    #[test]
    fn the_marker_hides_when_slow_or_unknown() {
        let mut mesh = SymbolMesh::new();
        let slow = heading_direction(95.0, 0.0) * 10.0;
        assert_eq!(reference_symbols(&mut mesh, &camera(0.0, 0.0), Some(slow)).flight_path, None);
        assert_eq!(reference_symbols(&mut mesh, &camera(0.0, 0.0), None).flight_path, None);
        let behind = heading_direction(275.0, 0.0) * 100.0;
        assert_eq!(reference_symbols(&mut mesh, &camera(0.0, 0.0), Some(behind)).flight_path, None);
    }
}
