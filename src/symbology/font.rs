//! A built-in stroke font: each glyph a few polylines on a grid 4 units
//! wide and 6 high (y up), drawn as thick lines like every other symbol,
//! so labels need no texture and scale, rotate with the horizon and stay
//! sharp at any size. Upper-case letters, digits, space, `-` and `.`;
//! any other character is drawn as a box, never dropped silently.

/// A glyph: polylines of grid points (x 0..=4, y 0..=6).
pub type Glyph = &'static [&'static [(i8, i8)]];

/// Grid units a glyph advances by (4 of ink, 2 of space).
pub const ADVANCE: f64 = 6.0;
/// Grid units of a glyph's height.
pub const HEIGHT: f64 = 6.0;

const BOX: Glyph = &[&[(0, 0), (4, 0), (4, 6), (0, 6), (0, 0)]];
const O: &[(i8, i8)] = &[(1, 0), (0, 1), (0, 5), (1, 6), (3, 6), (4, 5), (4, 1), (3, 0), (1, 0)];
const P: &[(i8, i8)] = &[(0, 0), (0, 6), (3, 6), (4, 5), (4, 4), (3, 3), (0, 3)];
/// The S, whose twelve points would stand one a line in the table.
#[rustfmt::skip]
const S: &[(i8, i8)] =
    &[(4, 5), (3, 6), (1, 6), (0, 5), (0, 4), (1, 3), (3, 3), (4, 2), (4, 1), (3, 0), (1, 0), (0, 1)];

/// The polylines of `c` (lower case drawn as upper case).
pub fn glyph(c: char) -> Glyph {
    match c.to_ascii_uppercase() {
        ' ' => &[],
        '-' => &[&[(1, 3), (3, 3)]],
        '.' => &[&[(2, 0), (2, 1)]],
        '0' => &[O, &[(0, 1), (4, 5)]],
        '1' => &[&[(1, 5), (2, 6), (2, 0)], &[(1, 0), (3, 0)]],
        '2' => &[&[(0, 5), (1, 6), (3, 6), (4, 5), (4, 4), (0, 0), (4, 0)]],
        '3' => &[
            &[(0, 5), (1, 6), (3, 6), (4, 5), (4, 4), (3, 3), (1, 3)],
            &[(3, 3), (4, 2), (4, 1), (3, 0), (1, 0), (0, 1)],
        ],
        '4' => &[&[(3, 0), (3, 6), (0, 2), (4, 2)]],
        '5' => &[&[(4, 6), (0, 6), (0, 3), (3, 3), (4, 2), (4, 1), (3, 0), (0, 0)]],
        '6' => &[&[(4, 6), (1, 6), (0, 5), (0, 1), (1, 0), (3, 0), (4, 1), (4, 2), (3, 3), (0, 3)]],
        '7' => &[&[(0, 6), (4, 6), (1, 0)]],
        '8' => &[
            &[(1, 3), (0, 4), (0, 5), (1, 6), (3, 6), (4, 5), (4, 4), (3, 3), (1, 3)],
            &[(1, 3), (0, 2), (0, 1), (1, 0), (3, 0), (4, 1), (4, 2), (3, 3)],
        ],
        '9' => &[&[(4, 3), (1, 3), (0, 4), (0, 5), (1, 6), (3, 6), (4, 5), (4, 1), (3, 0), (0, 0)]],
        'A' => &[&[(0, 0), (0, 4), (2, 6), (4, 4), (4, 0)], &[(0, 3), (4, 3)]],
        'B' => &[P, &[(3, 3), (4, 2), (4, 1), (3, 0), (0, 0)]],
        'C' => &[&[(4, 6), (1, 6), (0, 5), (0, 1), (1, 0), (4, 0)]],
        'D' => &[&[(0, 0), (0, 6), (3, 6), (4, 5), (4, 1), (3, 0), (0, 0)]],
        'E' => &[&[(4, 6), (0, 6), (0, 0), (4, 0)], &[(0, 3), (3, 3)]],
        'F' => &[&[(4, 6), (0, 6), (0, 0)], &[(0, 3), (3, 3)]],
        'G' => &[&[(4, 5), (3, 6), (1, 6), (0, 5), (0, 1), (1, 0), (3, 0), (4, 1), (4, 3), (2, 3)]],
        'H' => &[&[(0, 0), (0, 6)], &[(4, 0), (4, 6)], &[(0, 3), (4, 3)]],
        'I' => &[&[(1, 6), (3, 6)], &[(2, 6), (2, 0)], &[(1, 0), (3, 0)]],
        'J' => &[&[(4, 6), (4, 1), (3, 0), (1, 0), (0, 1)]],
        'K' => &[&[(0, 0), (0, 6)], &[(4, 6), (0, 2)], &[(1, 3), (4, 0)]],
        'L' => &[&[(0, 6), (0, 0), (4, 0)]],
        'M' => &[&[(0, 0), (0, 6), (2, 3), (4, 6), (4, 0)]],
        'N' => &[&[(0, 0), (0, 6), (4, 0), (4, 6)]],
        'O' => &[O],
        'P' => &[P],
        'Q' => &[O, &[(2, 2), (4, 0)]],
        'R' => &[P, &[(2, 3), (4, 0)]],
        'S' => &[S],
        'T' => &[&[(0, 6), (4, 6)], &[(2, 6), (2, 0)]],
        'U' => &[&[(0, 6), (0, 1), (1, 0), (3, 0), (4, 1), (4, 6)]],
        'V' => &[&[(0, 6), (2, 0), (4, 6)]],
        'W' => &[&[(0, 6), (1, 0), (2, 3), (3, 0), (4, 6)]],
        'X' => &[&[(0, 0), (4, 6)], &[(0, 6), (4, 0)]],
        'Y' => &[&[(0, 6), (2, 3), (4, 6)], &[(2, 3), (2, 0)]],
        'Z' => &[&[(0, 6), (4, 6), (0, 0), (4, 0)]],
        _ => BOX,
    }
}

/// Line segments of `text`'s glyphs in grid units, the text's left end at
/// x = 0 and its baseline at y = 0, each handed to `each` as two points.
pub fn segments(text: &str, mut each: impl FnMut([f64; 2], [f64; 2])) {
    for (k, c) in text.chars().enumerate() {
        let x0 = k as f64 * ADVANCE;
        for line in glyph(c) {
            for pair in line.windows(2) {
                let point = |(x, y): (i8, i8)| [x0 + x as f64, y as f64];
                each(point(pair[0]), point(pair[1]));
            }
        }
    }
}

/// Width of `text` in grid units (no trailing space).
pub fn width(text: &str) -> f64 {
    let n = text.chars().count() as f64;
    (n * ADVANCE - (ADVANCE - 4.0)).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_glyph_stays_on_its_grid_and_unknowns_are_boxes() {
        for c in ('A'..='Z').chain('0'..='9').chain([' ', '-', '.']) {
            for line in glyph(c) {
                assert!(line.len() >= 2, "{c}: a polyline of one point");
                assert!(
                    line.iter().all(|&(x, y)| (0..=4).contains(&x) && (0..=6).contains(&y)),
                    "{c}"
                );
            }
        }
        assert_eq!(glyph('%'), BOX);
        assert_eq!(glyph('n'), glyph('N'));
        let mut n = 0;
        segments("N 3", |_, _| n += 1);
        assert_eq!(n, 3 + 11, "N has three strokes, 3 eleven");
        assert_eq!(width("12"), 10.0);
    }
}
