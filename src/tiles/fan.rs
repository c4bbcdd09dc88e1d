//! Cells split four ways so that a node's mesh, fully morphed, is its
//! parent's very surface.
//!
//! Where a mesh refines down to single cells of its lattice it draws them
//! along the data's diagonal (south-west to north-east, as the regular
//! grids and the truth pass do), so that a mesh of error 0 is the data
//! exactly. The parent's mesh is a right-triangulated irregular network:
//! half of its long edges run north-west to south-east, straight through
//! such cells. Fully morphed, a cell drawn along the other diagonal folds
//! where the parent does not, and the tile pops when the parent takes over
//! (measured: 8 to 13 m at tau 32 px on the built-in terrain, 5 % of the
//! pixels of a 256 × 144 view).
//!
//! Such a cell is drawn as a fan of four triangles around a vertex at its
//! centre. Unmorphed, the centre lies on the cell's own diagonal (halfway
//! between its two ends), so the fan draws the same two planes as before
//! and the mesh's error is unchanged; its target is the parent's height at
//! the centre, on the parent's edge, so fully morphed each of the four
//! triangles lies on one side of that edge. A cell needs a fan exactly when
//! the parent's height at its centre differs from the midpoint of its
//! diagonal's targets: the four corners' targets lie on the parent's surface,
//! and two triangulations of four points agree only where they are planar.

use crate::node::MeshVertex;

/// Metres by which the parent's height at a cell's centre may differ from
/// the cell's own morphed centre before the cell is fanned: the f32
/// rounding of targets near 9 000 m, well under a millimetre of view.
const NESTED_M: f64 = 2e-3;

/// Splits every cell of `vertices`/`indices` drawn as two half-cell
/// triangles whose fully morphed surface is not the parent's (see the
/// module). Vertex posts are in half steps of the mesh's lattice, so a
/// cell's centre is a whole post (odd, odd). `parent_at(x, y)` is the
/// parent's height and normal (x and y, as stored) at `(x, y)` in the same
/// half steps, `None` where it has none. Returns how many cells were fanned.
pub fn fan_unnested_cells(
    vertices: &mut Vec<MeshVertex>,
    indices: &mut Vec<u16>,
    parent_at: impl Fn(f64, f64) -> Option<(f64, [f64; 2])>,
) -> usize {
    fan_with(&mut FanScratch::default(), vertices, indices, &mut Vec::new(), parent_at)
}

/// What [`fan_with`] works in, reused from tile to tile (tiles are made in
/// frames: no allocation once the largest has been fanned).
#[derive(Default)]
pub struct FanScratch {
    by_cell: Vec<([u16; 2], usize)>,
    fanned: Vec<bool>,
    fans: Vec<[u16; 12]>,
    kept: Vec<u16>,
}

/// [`fan_unnested_cells`] in `scratch`; `bands` (the vertices' morph
/// bands, or empty) gives a cell's centre the band of its south-west
/// corner.
pub fn fan_with(
    scratch: &mut FanScratch,
    vertices: &mut Vec<MeshVertex>,
    indices: &mut Vec<u16>,
    bands: &mut Vec<u8>,
    parent_at: impl Fn(f64, f64) -> Option<(f64, [f64; 2])>,
) -> usize {
    half_cell_pairs(vertices, indices, &mut scratch.by_cell);
    let FanScratch { by_cell, fanned, fans, kept } = scratch;
    fanned.clear();
    fanned.resize(indices.len() / 3, false);
    fans.clear();
    let pairs = by_cell.windows(2).filter(|w| w[0].0 == w[1].0).map(|w| [w[0].1, w[1].1]);
    for pair in pairs {
        if pair.iter().any(|&t| fanned[t]) {
            continue;
        }
        let Some(corners) = cell_corners(vertices, indices, pair) else { continue };
        let [sw, se, ne, nw] = corners.map(|v| vertices[v as usize]);
        if [sw, se, ne, nw].iter().any(|v| !v.height.is_finite() || !v.target.is_finite()) {
            continue;
        }
        let centre = [sw.post[0] + 1, sw.post[1] + 1];
        let Some((parent, normal)) = parent_at(centre[0] as f64, centre[1] as f64) else {
            continue;
        };
        let along_sw_ne = shares_diagonal(indices, pair, corners[0], corners[2]);
        let (a, b) = if along_sw_ne { (sw, ne) } else { (se, nw) };
        let morphed = (a.target as f64 + b.target as f64) / 2.0;
        if !parent.is_finite() || (parent - morphed).abs() <= NESTED_M {
            continue;
        }
        let c = vertices.len() as u16;
        if !bands.is_empty() {
            bands.push(bands[corners[0] as usize]);
        }
        vertices.push(MeshVertex {
            post: centre,
            height: ((a.height as f64 + b.height as f64) / 2.0) as f32,
            target: parent as f32,
            // Gouraud along the cell's own diagonal, then the parent's.
            normal: {
                let own = mean_normal(a, b);
                [own[0], own[1], normal[0].round() as i8, normal[1].round() as i8]
            },
        });
        let [sw, se, ne, nw] = corners;
        fans.push([sw, se, c, se, ne, c, ne, nw, c, nw, sw, c]);
        fanned[pair[0]] = true;
        fanned[pair[1]] = true;
    }
    if fans.is_empty() {
        return 0;
    }
    let ccw = first_is_ccw(vertices, indices);
    kept.clear();
    let unfanned = indices.chunks_exact(3).zip(fanned.iter()).filter(|(_, &f)| !f);
    kept.extend(unfanned.flat_map(|(t, _)| t.iter().copied()));
    std::mem::swap(indices, kept);
    for fan in fans.iter() {
        for tri in fan.chunks_exact(3) {
            let t = if ccw { [tri[0], tri[1], tri[2]] } else { [tri[0], tri[2], tri[1]] };
            indices.extend_from_slice(&t);
        }
    }
    fans.len()
}

/// The triangles (by number) that fill one cell, each spanning exactly one
/// cell (two half steps) in both directions, sorted by cell: two in a row
/// with the same cell are a pair.
fn half_cell_pairs(vertices: &[MeshVertex], indices: &[u16], by_cell: &mut Vec<([u16; 2], usize)>) {
    by_cell.clear();
    by_cell.extend(indices.chunks_exact(3).enumerate().filter_map(|(t, tri)| {
        let p = [0, 1, 2].map(|k| vertices[tri[k] as usize].post);
        let lo = [0, 1].map(|a| p.iter().map(|q| q[a]).min().unwrap_or(0));
        let hi = [0, 1].map(|a| p.iter().map(|q| q[a]).max().unwrap_or(0));
        let one_cell = (0..2).all(|a| hi[a] - lo[a] == 2) && lo.iter().all(|c| c % 2 == 0);
        one_cell.then_some((lo, t))
    }));
    by_cell.sort_unstable();
}

/// The cell's corners (south-west, south-east, north-east, north-west) as
/// vertex numbers, if the pair's vertices are exactly those four.
fn cell_corners(vertices: &[MeshVertex], indices: &[u16], pair: [usize; 2]) -> Option<[u16; 4]> {
    let mut corners: [Option<u16>; 4] = [None; 4];
    let sw = pair
        .iter()
        .flat_map(|&t| &indices[3 * t..3 * t + 3])
        .map(|&v| vertices[v as usize].post)
        .min()?;
    for &t in &pair {
        for &v in &indices[3 * t..3 * t + 3] {
            let p = vertices[v as usize].post;
            let corner = match (p[0].checked_sub(sw[0])?, p[1].checked_sub(sw[1])?) {
                (0, 0) => 0,
                (2, 0) => 1,
                (2, 2) => 2,
                (0, 2) => 3,
                _ => return None,
            };
            corners[corner] = Some(v);
        }
    }
    let [a, b, c, d] = corners;
    Some([a?, b?, c?, d?])
}

/// Whether both triangles of `pair` hold vertices `a` and `b`: their
/// shared edge, the cell's drawn diagonal.
fn shares_diagonal(indices: &[u16], pair: [usize; 2], a: u16, b: u16) -> bool {
    pair.iter().all(|&t| {
        let tri = &indices[3 * t..3 * t + 3];
        tri.contains(&a) && tri.contains(&b)
    })
}

/// The mean of two vertices' own normals (x, y).
fn mean_normal(a: MeshVertex, b: MeshVertex) -> [i8; 2] {
    [0, 1].map(|k| ((a.normal[k] as i32 + b.normal[k] as i32) / 2) as i8)
}

/// Whether the mesh's triangles wind counter-clockwise (east x, north y).
fn first_is_ccw(vertices: &[MeshVertex], indices: &[u16]) -> bool {
    let Some(tri) = indices.chunks_exact(3).next() else { return true };
    let p = [0, 1, 2].map(|k| vertices[tri[k] as usize].post.map(|c| c as i64));
    let area =
        (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0]);
    area > 0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vertex(i: u16, j: u16, height: f32, target: f32) -> MeshVertex {
        MeshVertex { post: [2 * i, 2 * j], height, target, normal: [0; 4] }
    }

    /// One cell drawn along its south-west to north-east diagonal, counter-clockwise.
    fn cell(targets: [f32; 4]) -> (Vec<MeshVertex>, Vec<u16>) {
        let [a, b, c, d] = targets;
        let vertices = vec![
            vertex(0, 0, 10.0, a),
            vertex(1, 0, 20.0, b),
            vertex(1, 1, 30.0, c),
            vertex(0, 1, 40.0, d),
        ];
        (vertices, vec![0, 1, 2, 0, 2, 3])
    }

    #[test]
    fn a_cell_across_a_parent_fold_becomes_a_fan_on_its_own_diagonal() {
        // The parent folds along the other diagonal: its centre is the mean of b and d.
        let (mut vertices, mut indices) = cell([0.0, 8.0, 0.0, 8.0]);
        let fanned = fan_unnested_cells(&mut vertices, &mut indices, |_, _| Some((8.0, [0.0; 2])));
        assert_eq!(fanned, 1);
        assert_eq!(indices.len(), 12);
        let centre = vertices[4];
        assert_eq!(centre.post, [1, 1]);
        assert_eq!(centre.height, 20.0, "unmorphed, on the cell's own diagonal");
        assert_eq!(centre.target, 8.0, "fully morphed, on the parent's fold");
        assert!(first_is_ccw(&vertices, &indices[9..]), "the fan keeps the winding");
    }

    #[test]
    fn a_cell_inside_one_parent_triangle_is_left_alone() {
        let (mut vertices, mut indices) = cell([0.0, 8.0, 4.0, -4.0]);
        // Planar targets: the parent's height at the centre is their mean.
        assert_eq!(
            fan_unnested_cells(&mut vertices, &mut indices, |_, _| Some((2.0, [0.0; 2]))),
            0
        );
        assert_eq!((vertices.len(), indices.len()), (4, 6));
    }

    #[test]
    fn cells_without_data_or_parent_are_left_alone() {
        let (mut vertices, mut indices) = cell([0.0, 8.0, 0.0, 8.0]);
        assert_eq!(fan_unnested_cells(&mut vertices, &mut indices, |_, _| None), 0);
        vertices[1].height = f32::NAN;
        assert_eq!(
            fan_unnested_cells(&mut vertices, &mut indices, |_, _| Some((8.0, [0.0; 2]))),
            0
        );
    }
}
