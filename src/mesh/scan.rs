//! One triangle's posts scanned row by row: the largest vertical distance
//! from its plane, how many posts have data, their height range.
//!
//! The error map visits every post once per depth of the hierarchy (about
//! 22 times for a 2049-post node), so this loop is the cost of building
//! meshes. Each row's posts inside the triangle are a span found from the
//! three edge functions, and the plane is stepped along the row by one
//! addition, instead of three cross products per post of the bounding box.

use super::HeightGrid;

/// What one scan found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleScan {
    /// Largest `|height - plane|` over the posts with data, metres.
    pub worst: f64,
    /// Posts with data.
    pub with_data: u32,
    /// Posts without data (NaN).
    pub without: u32,
    /// Lowest and highest height with data.
    pub z: [f32; 2],
}

/// Scans every post of the triangle `corners` (counter-clockwise seen from
/// above, edges and corners included; a triangle of the RTIN hierarchy, so
/// its edges run along the axes or the diagonals) against the plane through
/// its corner heights `h`.
pub fn scan_triangle(grid: &HeightGrid, corners: [[u32; 2]; 3], h: [f64; 3]) -> TriangleScan {
    // Coordinates relative to the triangle's south-west bound: the same
    // triangle anywhere in any grid scans with the same arithmetic, so a
    // block's scan and a node's own scan round alike (issue 21: a shard
    // builds a node alone that one process cuts from its block, and both
    // must write the same bytes).
    let sw = [0, 1].map(|a| corners.iter().map(|c| c[a]).min().unwrap_or(0));
    let v = corners.map(|c| [(c[0] - sw[0]) as i64, (c[1] - sw[1]) as i64]);
    let (x_lo, y0) = (0, 0);
    let x_hi = v.iter().map(|p| p[0]).max().unwrap_or(0);
    let y1 = v.iter().map(|p| p[1]).max().unwrap_or(0);
    if x_hi - x_lo <= 2 && y1 - y0 <= 2 {
        return scan_small(grid, corners, h);
    }
    // Edge k runs from v[k+1] to v[k+2]; its function w_k(p) = a x + b y + c
    // is positive inside and proportional to corner k's barycentric weight.
    // Along the axes and the diagonals a and b are -1, 0 or 1 once divided
    // by the edge's length in steps, so each row's span needs no division.
    let edge = |k: usize| {
        let (p, q) = (v[(k + 1) % 3], v[(k + 2) % 3]);
        let steps = (q[0] - p[0]).abs().max((q[1] - p[1]).abs()).max(1);
        let (a, b) = (-(q[1] - p[1]) / steps, (q[0] - p[0]) / steps);
        (a, b, -(a * p[0] + b * p[1]), steps as f64)
    };
    let edges = [edge(0), edge(1), edge(2)];
    // w_k scaled back by its length: the plane is sum_k w_k len_k h_k / area2.
    let weight = |k: usize, x: i64, y: i64| {
        let (a, b, c, len) = edges[k];
        (a * x + b * y + c) as f64 * len
    };
    let area2 = weight(0, v[0][0], v[0][1]);
    debug_assert!(area2 > 0.0, "corners counter-clockwise");
    let slope_x = (0..3).map(|k| edges[k].0 as f64 * edges[k].3 * h[k]).sum::<f64>() / area2;
    let side = grid.side() as usize;
    let heights = grid.heights();
    let mut scan = TriangleScan {
        worst: 0.0,
        with_data: 0,
        without: 0,
        z: [f32::INFINITY, f32::NEG_INFINITY],
    };
    for y in y0..=y1 {
        let Some((first, last)) = row_span(&edges, y, x_lo, x_hi) else { continue };
        let plane = (0..3).map(|k| weight(k, first, y) * h[k]).sum::<f64>() / area2;
        let (first_x, row_y) = (first as usize + sw[0] as usize, y as usize + sw[1] as usize);
        let row = &heights[row_y * side..][first_x..=first_x + (last - first) as usize];
        scan_row(row, plane, slope_x, &mut scan);
    }
    scan
}

/// The posts `x` of row `y` with every edge function at least 0, within
/// `[x_lo, x_hi]` (edge coefficients `a`, `b` in -1..=1).
fn row_span(edges: &[(i64, i64, i64, f64); 3], y: i64, x_lo: i64, x_hi: i64) -> Option<(i64, i64)> {
    let (mut first, mut last) = (x_lo, x_hi);
    for &(a, b, c, _) in edges {
        // a x + (b y + c) >= 0.
        let rest = b * y + c;
        match a {
            1 => first = first.max(-rest),
            -1 => last = last.min(rest),
            _ if rest < 0 => return None,
            _ => {}
        }
    }
    (first <= last).then_some((first, last))
}

/// A triangle at most two posts across: its posts are its corners and the
/// midpoints of its edges that fall on posts, where the plane is the mean
/// of the edge's ends. Most triangles of a hierarchy are this small.
fn scan_small(grid: &HeightGrid, corners: [[u32; 2]; 3], h: [f64; 3]) -> TriangleScan {
    let mut scan = TriangleScan {
        worst: 0.0,
        with_data: 0,
        without: 0,
        z: [f32::INFINITY, f32::NEG_INFINITY],
    };
    let mut count = |post: f32, plane: f64| {
        if post.is_nan() {
            scan.without += 1;
        } else {
            scan.with_data += 1;
            scan.worst = scan.worst.max((post as f64 - plane).abs());
            scan.z = [scan.z[0].min(post), scan.z[1].max(post)];
        }
    };
    for &corner in &h[..3] {
        count(corner as f32, corner);
    }
    for (p, q) in [(0, 1), (1, 2), (2, 0)] {
        let (a, b) = (corners[p], corners[q]);
        if (a[0] + b[0]) % 2 == 0 && (a[1] + b[1]) % 2 == 0 {
            let m = grid.at((a[0] + b[0]) / 2, (a[1] + b[1]) / 2);
            count(m, (h[p] + h[q]) / 2.0);
        }
    }
    scan
}

/// One row's posts against the plane starting at `plane` and rising by
/// `slope` a post.
fn scan_row(row: &[f32], mut plane: f64, slope: f64, scan: &mut TriangleScan) {
    let mut worst = scan.worst;
    let [mut lo, mut hi] = scan.z;
    let mut without = 0u32;
    for &post in row {
        if post.is_nan() {
            without += 1;
        } else {
            worst = worst.max((post as f64 - plane).abs());
            lo = lo.min(post);
            hi = hi.max(post);
        }
        plane += slope;
    }
    scan.worst = worst;
    scan.z = [lo, hi];
    scan.without += without;
    scan.with_data += row.len() as u32 - without;
}
