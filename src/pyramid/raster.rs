//! One level of the pyramid held as a whole raster of posts, the form in which
//! a level is downsampled and then cut into nodes.

use std::borrow::Cow;

use rayon::prelude::*;

use crate::dem::ElevationGrid;

/// The posts of level `lod`: post `(k, m)` is level-0 sample
/// `(min(k << lod, width - 1), min(m << lod, height - 1))`.
///
/// Invariant: `cols = ceil((width - 1) / 2^lod) + 1` (likewise `rows`), so the
/// last post lies on or past the data's last sample and every node post past
/// it clamps to it; `heights.len() == cols * rows`, row 0 southern.
pub(crate) struct LevelRaster<'a> {
    pub level: u8,
    pub cols: u32,
    pub rows: u32,
    heights: Cow<'a, [f32]>,
}

impl<'a> LevelRaster<'a> {
    /// Level 0: the grid itself, borrowed.
    pub fn finest(grid: &'a ElevationGrid) -> Self {
        debug_assert_eq!(grid.heights.len(), grid.width as usize * grid.height as usize);
        LevelRaster {
            level: 0,
            cols: grid.width,
            rows: grid.height,
            heights: Cow::Borrowed(&grid.heights),
        }
    }

    /// Row `m` of posts, west to east.
    pub fn row(&self, m: u32) -> &[f32] {
        let start = m as usize * self.cols as usize;
        &self.heights[start..start + self.cols as usize]
    }

    /// Level `lod + 1`: every other post of this level (subsampling, see the
    /// module notes in [`super`]), rows in parallel.
    pub fn downsample(&self) -> LevelRaster<'static> {
        let cols = (self.cols - 1).div_ceil(2) + 1;
        let rows = (self.rows - 1).div_ceil(2) + 1;
        let mut heights = vec![0.0f32; cols as usize * rows as usize];
        heights.par_chunks_mut(cols as usize).enumerate().for_each(|(m, out)| {
            let src = self.row((2 * m as u32).min(self.rows - 1));
            for (k, post) in out.iter_mut().enumerate() {
                *post = src[(2 * k).min(src.len() - 1)];
            }
        });
        debug_assert_eq!(heights.len(), cols as usize * rows as usize);
        LevelRaster { level: self.level + 1, cols, rows, heights: Cow::Owned(heights) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geo::GeoRef;

    fn grid(width: u32, height: u32) -> ElevationGrid {
        let heights = (0..width * height).map(|n| n as f32).collect();
        ElevationGrid { width, height, heights, georef: GeoRef::local([1.0, 1.0]), voids_filled: 0 }
    }

    /// The post at `(k, m)`, indices past either edge clamped to it.
    fn clamped(raster: &LevelRaster, k: i64, m: i64) -> f32 {
        let m = m.clamp(0, raster.rows as i64 - 1) as u32;
        raster.row(m)[k.clamp(0, raster.cols as i64 - 1) as usize]
    }

    #[test]
    fn every_post_of_every_level_is_the_clamped_level0_sample() {
        for (width, height) in [(1, 1), (2, 7), (10, 9), (33, 17), (64, 65)] {
            let grid = grid(width, height);
            let mut raster = LevelRaster::finest(&grid).downsample();
            for lod in 1..7u8 {
                let step = 1i64 << lod;
                assert_eq!(raster.cols as i64, (width as i64 - 1 + step - 1) / step + 1);
                for m in -2..raster.rows as i64 + 2 {
                    for k in -2..raster.cols as i64 + 2 {
                        let i = (k * step).clamp(0, width as i64 - 1) as u32;
                        let j = (m * step).clamp(0, height as i64 - 1) as u32;
                        assert_eq!(
                            clamped(&raster, k, m),
                            grid.at(i, j),
                            "lod {lod} post ({k}, {m})"
                        );
                    }
                }
                raster = raster.downsample();
            }
        }
    }
}
