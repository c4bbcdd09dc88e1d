//! Error codes: an error map's bounds stored in one byte each.
//!
//! Code `c` in `1..=254` stands for `ERROR_UNIT_M * 2^(c / 8)` metres, a
//! step of 9 %; a bound is always coded up (the code's error is at least
//! the bound), so a triangle left unsplit at error `e` still errs by at
//! most `e`, and coding keeps the map's order (a split set closed before
//! coding stays closed). Code 0 is an exact zero (the triangle is planar
//! over its posts), 255 a split that is always made (a triangle mixing
//! posts with and without data). The codes span 1 mm to about 3 600 km.

/// The error of code 1's step base, metres.
pub const ERROR_UNIT_M: f64 = 1e-3;
/// Codes a doubling of the error spans.
pub const CODES_PER_OCTAVE: f64 = 8.0;
/// The code of a split always made.
pub const ALWAYS: u8 = 255;

/// The smallest code whose error is at least `error_m` (a bound coded up).
pub fn error_code(error_m: f64) -> u8 {
    if error_m.is_nan() || error_m == f64::INFINITY {
        return ALWAYS;
    }
    if error_m <= 0.0 {
        return 0;
    }
    let steps = (CODES_PER_OCTAVE * (error_m / ERROR_UNIT_M).log2()).ceil();
    let mut code = steps.clamp(1.0, 254.0) as u8;
    // log2 rounds: make sure the code's error is not below the bound (from
    // a table: the maps code every triangle, and exp2 was a tenth of it).
    let errors = code_errors();
    while code < 254 && errors[code as usize] < error_m {
        code += 1;
    }
    code
}

/// [`code_error`] of every code, computed once.
fn code_errors() -> &'static [f64; 256] {
    static TABLE: std::sync::OnceLock<[f64; 256]> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| std::array::from_fn(|c| code_error(c as u8)))
}

/// The error a code stands for, metres (infinite for [`ALWAYS`]).
pub fn code_error(code: u8) -> f64 {
    match code {
        0 => 0.0,
        ALWAYS => f64::INFINITY,
        c => ERROR_UNIT_M * (c as f64 / CODES_PER_OCTAVE).exp2(),
    }
}

/// The largest code a mesh of error `error_m` leaves unsplit: a split is
/// made where the code is above it.
pub fn threshold_code(error_m: f64) -> u8 {
    if error_m.is_nan() || error_m < 0.0 {
        return 0;
    }
    if error_m == f64::INFINITY {
        return 254;
    }
    // The largest code whose error is at most `error_m`.
    let mut code = error_code(error_m);
    let errors = code_errors();
    while code > 0 && errors[code as usize] > error_m {
        code -= 1;
    }
    code.min(254)
}

/// Whether a mesh of error `error_m` splits where the code is `code`:
/// `code > threshold_code(error_m)`, from the code's error (one table read,
/// where the threshold takes a logarithm: extraction asks it per post).
pub fn splits(code: u8, error_m: f64) -> bool {
    if code == ALWAYS {
        return true;
    }
    if error_m.is_nan() {
        return code > 0;
    }
    // Codes' errors rise with the code, so the largest at most the error
    // is the threshold: a code is above it exactly when its error is.
    code_errors()[code as usize] > error_m.max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_split_is_made_exactly_where_the_code_is_above_the_threshold() {
        let mut errors: Vec<f64> = (0..256).map(|c| code_error(c as u8)).collect();
        errors.extend((0..4000).map(|k| 1e-5 * 1.01f64.powi(k)));
        errors.extend(errors.clone().iter().flat_map(|&e| [e.next_up(), e.next_down()]));
        errors.extend([0.0, -1.0, f64::NAN, f64::INFINITY, f64::MAX, f64::MIN_POSITIVE]);
        for e in errors {
            for code in 0..=255u8 {
                assert_eq!(splits(code, e), code > threshold_code(e), "code {code} at {e}");
            }
        }
    }

    #[test]
    fn codes_bound_their_errors_from_above_and_keep_order() {
        let mut last = 0;
        for k in 0..2000 {
            let e = 1e-4 * 1.013f64.powi(k);
            let code = error_code(e);
            assert!(code_error(code) >= e || code == 254, "{e} coded {code}");
            assert!(code >= last, "order kept");
            last = code;
            let t = threshold_code(e);
            assert!(code_error(t) <= e, "threshold {t} of {e}");
            assert!(t == 254 || code_error(t + 1) > e);
        }
        assert_eq!((error_code(0.0), error_code(f64::INFINITY)), (0, ALWAYS));
        assert_eq!(threshold_code(0.0), 0);
    }
}
