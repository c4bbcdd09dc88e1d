//! Comparing two renders of the same view, and keeping the evidence when
//! they differ.
//!
//! The metric: per pixel, the largest absolute difference of its R, G and B
//! channels (alpha is always opaque). Two images match under a [`Tolerance`]
//! when the share of pixels whose largest difference exceeds
//! `channel_threshold` is at most `max_share_over`, and the mean over all
//! pixels of that largest difference is at most `max_mean`. The share catches
//! a missing tile or a wrong colour in one region; the mean catches a small
//! shift or a changed shade spread over the whole picture.

use crate::target_tmp;
use image::{Rgba, RgbaImage};
use std::path::PathBuf;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerance {
    pub channel_threshold: u8,
    pub max_share_over: f64,
    pub max_mean: f64,
}

/// How two images of one size differ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Difference {
    /// Share of pixels whose largest channel difference exceeds the threshold.
    pub share_over: f64,
    /// Mean over all pixels of the largest channel difference.
    pub mean: f64,
    /// The largest channel difference anywhere.
    pub largest: u8,
}

impl Difference {
    pub fn between(a: &RgbaImage, b: &RgbaImage, channel_threshold: u8) -> Difference {
        assert_eq!(a.dimensions(), b.dimensions(), "images of different sizes");
        let (mut over, mut sum, mut largest) = (0usize, 0u64, 0u8);
        for (p, q) in a.pixels().zip(b.pixels()) {
            let d = pixel_difference(p, q);
            over += usize::from(d > channel_threshold);
            sum += d as u64;
            largest = largest.max(d);
        }
        let count = (a.width() * a.height()).max(1) as f64;
        Difference { share_over: over as f64 / count, mean: sum as f64 / count, largest }
    }

    pub fn within(&self, tolerance: &Tolerance) -> bool {
        self.share_over <= tolerance.max_share_over && self.mean <= tolerance.max_mean
    }
}

impl std::fmt::Display for Difference {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{:.3}% of pixels over threshold, mean {:.3}, largest {}",
            self.share_over * 100.0,
            self.mean,
            self.largest
        )
    }
}

fn pixel_difference(p: &Rgba<u8>, q: &Rgba<u8>) -> u8 {
    (0..3).map(|c| p.0[c].abs_diff(q.0[c])).max().unwrap_or(0)
}

/// The largest channel difference per pixel, as grey scaled by 4 (so
/// small differences show), red where it exceeds `channel_threshold`.
pub fn difference_image(a: &RgbaImage, b: &RgbaImage, channel_threshold: u8) -> RgbaImage {
    RgbaImage::from_fn(a.width(), a.height(), |x, y| {
        let d = pixel_difference(a.get_pixel(x, y), b.get_pixel(x, y));
        if d > channel_threshold {
            Rgba([255, 0, 0, 255])
        } else {
            let grey = d.saturating_mul(4);
            Rgba([grey, grey, grey, 255])
        }
    })
}

/// Saves `image` as `CARGO_TARGET_TMPDIR/render-failures/NAME.png` and
/// returns the path (or why it could not be saved) for a panic message.
pub fn save_evidence(image: &RgbaImage, name: &str) -> String {
    let dir = target_tmp().join("render-failures");
    let path: PathBuf = dir.join(format!("{name}.png"));
    let saved = std::fs::create_dir_all(&dir)
        .map_err(|e| e.to_string())
        .and_then(|()| image.save(&path).map_err(|e| e.to_string()));
    match saved {
        Ok(()) => path.display().to_string(),
        Err(e) => format!("{} (not saved: {e})", path.display()),
    }
}

/// Compares `actual` against `expected`; on a mismatch saves both and their
/// difference image and says where. Returns the difference either way.
pub fn check_similar(
    name: &str,
    expected: &RgbaImage,
    actual: &RgbaImage,
    tolerance: &Tolerance,
) -> Result<Difference, String> {
    if expected.dimensions() != actual.dimensions() {
        let saved = save_evidence(actual, &format!("{name}-actual"));
        return Err(format!(
            "{name}: size {:?}, expected {:?}; actual at {saved}",
            actual.dimensions(),
            expected.dimensions()
        ));
    }
    let difference = Difference::between(expected, actual, tolerance.channel_threshold);
    if difference.within(tolerance) {
        return Ok(difference);
    }
    let expected_at = save_evidence(expected, &format!("{name}-expected"));
    let actual_at = save_evidence(actual, &format!("{name}-actual"));
    let diff_at = save_evidence(
        &difference_image(expected, actual, tolerance.channel_threshold),
        &format!("{name}-diff"),
    );
    Err(format!(
        "{name}: {difference} exceeds {tolerance:?}\n  expected: {expected_at}\n  actual:   {actual_at}\n  diff:     {diff_at}"
    ))
}

/// [`check_similar`] that panics on a mismatch.
pub fn assert_similar(
    name: &str,
    expected: &RgbaImage,
    actual: &RgbaImage,
    tolerance: &Tolerance,
) -> Difference {
    check_similar(name, expected, actual, tolerance).unwrap_or_else(|problem| panic!("{problem}"))
}
