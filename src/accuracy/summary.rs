//! [`ErrorSummary`]: the distribution of per-pixel errors over all views,
//! as the percentiles the accuracy tool reports.

/// Percentiles of the per-pixel error, pixels.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct ErrorSummary {
    /// Median error (nearest rank), pixels.
    pub p50_px: f64,
    /// 99th percentile error, pixels.
    pub p99_px: f64,
    /// 99.9th percentile error, pixels.
    pub p999_px: f64,
    /// Largest error, pixels.
    pub max_px: f64,
    /// Mean error, pixels.
    pub mean_px: f64,
    /// How many pixel errors these are taken over.
    pub pixels: usize,
}

impl ErrorSummary {
    /// Summarises `errors` (sorted in place; NaN entries must have been left
    /// out). All zero for no pixels.
    pub fn of(errors: &mut [f32]) -> ErrorSummary {
        debug_assert!(errors.iter().all(|e| !e.is_nan()));
        if errors.is_empty() {
            return ErrorSummary::default();
        }
        errors.sort_unstable_by(f32::total_cmp);
        let sum: f64 = errors.iter().map(|&e| e as f64).sum();
        ErrorSummary {
            p50_px: percentile(errors, 0.5),
            p99_px: percentile(errors, 0.99),
            p999_px: percentile(errors, 0.999),
            max_px: percentile(errors, 1.0),
            mean_px: sum / errors.len() as f64,
            pixels: errors.len(),
        }
    }
}

/// The `q` quantile of ascending `sorted` by the nearest-rank rule: the
/// smallest value with at least a share `q` of the values at or below it.
pub fn percentile(sorted: &[f32], q: f64) -> f64 {
    debug_assert!(!sorted.is_empty() && (0.0..=1.0).contains(&q));
    let rank = (q * sorted.len() as f64).ceil() as usize;
    sorted[rank.clamp(1, sorted.len()) - 1] as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_rank_percentiles() {
        let mut values: Vec<f32> = (1..=1000).rev().map(|v| v as f32).collect();
        let summary = ErrorSummary::of(&mut values);
        assert_eq!(
            (summary.p50_px, summary.p99_px, summary.p999_px, summary.max_px),
            (500.0, 990.0, 999.0, 1000.0)
        );
        assert_eq!(summary.mean_px, 500.5);
        assert_eq!(ErrorSummary::of(&mut []), ErrorSummary::default());
        assert_eq!(percentile(&[3.0], 0.0), 3.0);
    }
}
