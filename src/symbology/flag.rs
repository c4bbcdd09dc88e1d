//! The failure flag drawn instead of the synthetic terrain when its data
//! are stale or invalid: a red cross from corner to corner (the way an
//! electronic flight instrument flags a failed display) and, in a black
//! panel at the centre, `SVS FAIL` in red with the reason in amber below.
//! Nothing in it can be taken for terrain, sky or a live symbol.

use glam::DVec2;

use super::mesh::{SymbolMesh, AMBER, OUTLINE, RED};
use super::{scale, text};

/// The colour the target is cleared to under the flag: a dark grey no
/// terrain tint, sky or haze produces.
pub const WITHDRAWN_CLEAR: [f32; 4] = [0.06, 0.06, 0.07, 1.0];
/// The flag's title.
pub const TITLE: &str = "SVS FAIL";

/// Lays out the failure flag for a `viewport`, with `reason` (upper-case
/// words, see [`crate::input::StaleReason::flag_text`]) under the title.
pub fn failure_flag(mesh: &mut SymbolMesh, viewport: [u32; 2], reason: &str) {
    let s = scale(viewport);
    mesh.begin(viewport, s.max(1.0));
    let size = DVec2::new(viewport[0] as f64, viewport[1] as f64);
    let width = 6.0 * s;
    let centre = size / 2.0;
    // Sized for the viewport's height, narrowed to fit its width.
    let fit = |preferred: f64, words: &str| {
        preferred.min(0.75 * size.x * super::font::HEIGHT / super::font::width(words).max(1.0))
    };
    let (title_height, reason_height) = (fit(36.0 * s, TITLE), fit(16.0 * s, reason));
    let inked = |height: f64, words: &str| super::font::width(words) * height / super::font::HEIGHT;
    let half = DVec2::new(
        inked(title_height, TITLE).max(inked(reason_height, reason)) / 2.0 + 8.0 * s,
        (title_height + reason_height) / 2.0 + 20.0 * s,
    );
    // The cross stops at the panel, so the words stay clear.
    let gap = (half.x / size.x).min(half.y / size.y) + 2.0 * s / size.length();
    for (from, to) in [(DVec2::ZERO, size), (DVec2::new(0.0, size.y), DVec2::new(size.x, 0.0))] {
        let at = |t: f64| from + (to - from) * t;
        mesh.line(at(0.0), at(0.5 - gap), width, RED);
        mesh.line(at(0.5 + gap), at(1.0), width, RED);
    }
    mesh.panel(centre - half, centre + half, OUTLINE);
    let (corners, border) = (box_corners(centre - half, centre + half), 3.0 * s);
    mesh.polyline(&corners, border, RED);
    let up = DVec2::new(0.0, -1.0);
    let title_base = centre.y + half.y - 14.0 * s - reason_height - 10.0 * s;
    text(mesh, TITLE, DVec2::new(centre.x, title_base), up, title_height, RED);
    text(
        mesh,
        reason,
        DVec2::new(centre.x, centre.y + half.y - 12.0 * s),
        up,
        reason_height,
        AMBER,
    );
    mesh.finish();
}

fn box_corners(min: DVec2, max: DVec2) -> [DVec2; 5] {
    [min, DVec2::new(max.x, min.y), max, DVec2::new(min.x, max.y), min]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_flag_fits_the_screen_at_every_size() {
        let mut mesh = SymbolMesh::new();
        for viewport in [[160, 90], [256, 144], [1280, 720], [3840, 2160]] {
            failure_flag(&mut mesh, viewport, "ATTITUDE INVALID");
            assert_eq!(mesh.dropped, 0);
            let (w, h) = (viewport[0] as f32, viewport[1] as f32);
            // The cross's outline may pass the corners; the panel stays inside.
            let panel = &mesh.vertices()[..6];
            assert!(panel.iter().all(|v| v.position[0] > 0.0 && v.position[0] < w), "{viewport:?}");
            assert!(panel.iter().all(|v| v.position[1] > 0.0 && v.position[1] < h), "{viewport:?}");
        }
    }
}
