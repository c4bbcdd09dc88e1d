//! [`Verdict`]: whether a measured run keeps the promise the accuracy tool
//! checks, the error bound over all views and the coverage per view. The
//! accuracy tool prints it and exits non-zero on it, so both read it here.

use super::ErrorSummary;

/// The coverage mismatch a view may show, a share of its pixels: where the
/// data end the display draws what they hold and nothing beyond, at the
/// truth's line within rounding (issue 25).
pub const MISMATCH_PER_VIEW: f64 = 1e-4;

/// A view whose coverage mismatch is above [`MISMATCH_PER_VIEW`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MismatchedView {
    /// Position of the view among the measured views, from 0.
    pub index: usize,
    /// The view's time on the flight path, seconds.
    pub t: f64,
    /// Share of the view's pixels with terrain in one render only.
    pub share: f64,
}

/// Why a run is not confirmed.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum VerdictError {
    /// The p99.9 error over all views is above the bound.
    #[error("measured p99.9 error {p999_px:.3} px exceeds tau {bound_px} px")]
    Bound {
        /// The measured p99.9, pixels.
        p999_px: f64,
        /// The bound it is held to, pixels.
        bound_px: f64,
    },
    /// A view draws terrain in one render only over too many pixels.
    #[error(
        "view {} at t = {:.1} s shows terrain in one render only over {:.4} % of its pixels, \
         above {:.2} %",
        .0.index, .0.t, 100.0 * .0.share, 100.0 * MISMATCH_PER_VIEW
    )]
    Coverage(MismatchedView),
}

/// What the accuracy tool decides from a run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Verdict {
    /// p99.9 over every terrain pixel of every view, pixels.
    pub p999_px: f64,
    /// The bound the error is held to (the largest tau a view achieved).
    pub bound_px: f64,
    /// The largest coverage mismatch of any view (0 for no views).
    pub worst_mismatch: f64,
    /// The view with the largest mismatch, when it is above the limit.
    pub mismatched: Option<MismatchedView>,
}

impl Verdict {
    /// The verdict on `summary` held to `bound_px`, with each view's `(t,
    /// coverage mismatch)` in the order measured.
    pub fn of(
        summary: &ErrorSummary,
        bound_px: f64,
        mismatch_per_view: impl IntoIterator<Item = (f64, f64)>,
    ) -> Verdict {
        let mut worst: Option<MismatchedView> = None;
        for (index, (t, share)) in mismatch_per_view.into_iter().enumerate() {
            if worst.is_none_or(|w| share > w.share) {
                worst = Some(MismatchedView { index, t, share });
            }
        }
        let worst_mismatch = worst.map_or(0.0, |w| w.share);
        let mismatched = worst.filter(|w| w.share > MISMATCH_PER_VIEW);
        Verdict { p999_px: summary.p999_px, bound_px, worst_mismatch, mismatched }
    }

    /// Whether p99.9 is within the bound.
    pub fn bound_held(&self) -> bool {
        self.p999_px <= self.bound_px
    }

    /// Whether every view's coverage mismatch is within the limit.
    pub fn coverage_held(&self) -> bool {
        self.mismatched.is_none()
    }

    /// Ok when both hold; else the first broken promise.
    pub fn check(&self) -> Result<(), VerdictError> {
        if !self.bound_held() {
            return Err(VerdictError::Bound { p999_px: self.p999_px, bound_px: self.bound_px });
        }
        match self.mismatched {
            Some(view) => Err(VerdictError::Coverage(view)),
            None => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn summary(p999_px: f64) -> ErrorSummary {
        ErrorSummary { p999_px, ..ErrorSummary::default() }
    }

    /// A run within its bound fails when one view's mismatch is above 0.01
    /// %, and the error names that view and its share.
    #[test]
    fn a_view_above_the_mismatch_limit_fails_a_run_within_its_bound() {
        let views = [(0.0, 0.0), (2.5, 2.98e-4), (5.0, 0.5e-4)];
        let verdict = Verdict::of(&summary(0.4), 1.0, views);
        assert!(verdict.bound_held());
        assert!(!verdict.coverage_held());
        let error = verdict.check().expect_err("the mismatch fails the verdict");
        assert_eq!(
            error,
            VerdictError::Coverage(MismatchedView { index: 1, t: 2.5, share: 2.98e-4 })
        );
        let text = error.to_string();
        assert!(text.contains("view 1 at t = 2.5 s") && text.contains("0.0298 %"), "{text}");
    }

    #[test]
    fn mismatch_at_the_limit_and_the_bound_confirm() {
        let verdict = Verdict::of(&summary(1.0), 1.0, [(0.0, MISMATCH_PER_VIEW), (1.0, 0.0)]);
        assert_eq!(verdict.check(), Ok(()));
        assert_eq!(verdict.worst_mismatch, MISMATCH_PER_VIEW);
        assert_eq!(Verdict::of(&summary(0.0), 1.0, []).check(), Ok(()));
    }

    #[test]
    fn the_bound_is_checked_first() {
        let verdict = Verdict::of(&summary(1.5), 1.0, [(0.0, 0.5)]);
        assert!(matches!(verdict.check(), Err(VerdictError::Bound { .. })));
    }
}
