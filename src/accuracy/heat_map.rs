//! The error image of one view as colours, for a person to find where the
//! error is: terrain pixels on a dark-blue to yellow ramp up to tau, red
//! above tau (brighter the further above, saturating at 4 tau); pixels where
//! only one image shows terrain magenta; sky in both dark grey.

use image::{Rgba, RgbaImage};

use super::PositionImage;

/// Sky in both images.
pub const HEAT_SKY: [u8; 4] = [32, 32, 32, 255];
/// Terrain in one image, sky in the other.
pub const HEAT_MISMATCH: [u8; 4] = [255, 0, 255, 255];

/// Ramp stops from 0 to tau: dark blue, teal, green, yellow.
const RAMP: [[f64; 3]; 4] =
    [[20.0, 30.0, 110.0], [20.0, 140.0, 150.0], [60.0, 190.0, 60.0], [250.0, 230.0, 40.0]];

/// Colours one view's per-pixel `errors_px` (NaN where not measured)
/// against `tau_px`; `lod` and `truth` are the view's position images.
pub fn heat_map(
    errors_px: &[f32],
    lod: &PositionImage,
    truth: &PositionImage,
    tau_px: f64,
) -> RgbaImage {
    debug_assert_eq!(errors_px.len(), lod.pixel_count());
    RgbaImage::from_fn(lod.size.x, lod.size.y, |x, y| {
        let k = y as usize * lod.size.x as usize + x as usize;
        let colour = match (lod.point(k).is_some(), truth.point(k).is_some()) {
            (false, false) => HEAT_SKY,
            // Both, or a silhouette pixel whose error was measured.
            _ if !errors_px[k].is_nan() => ramp(errors_px[k] as f64 / tau_px),
            _ => HEAT_MISMATCH,
        };
        Rgba(colour)
    })
}

/// The colour of an error of `ratio` times tau.
fn ramp(ratio: f64) -> [u8; 4] {
    if ratio.is_nan() {
        return HEAT_SKY;
    }
    if ratio > 1.0 {
        let red = 140.0 + 115.0 * ((ratio - 1.0) / 3.0).min(1.0);
        return [red as u8, 0, 0, 255];
    }
    let position = ratio.max(0.0) * (RAMP.len() - 1) as f64;
    let stop = (position.floor() as usize).min(RAMP.len() - 2);
    let f = position - stop as f64;
    let (a, b) = (RAMP[stop], RAMP[stop + 1]);
    let channel = |c: usize| (a[c] + (b[c] - a[c]) * f).round() as u8;
    [channel(0), channel(1), channel(2), 255]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramp_ends_at_yellow_and_turns_red_above_tau() {
        assert_eq!(ramp(0.0), [20, 30, 110, 255]);
        assert_eq!(ramp(1.0), [250, 230, 40, 255]);
        assert_eq!(ramp(1.0 + 1e-9)[1], 0);
        assert_eq!(ramp(10.0), [255, 0, 0, 255]);
    }
}
