//! [`PositionImage`]: what a position render read back: per pixel, the
//! surface point drawn there relative to the camera (metres, x east, y north,
//! z up, the curvature drop included), or nothing.

use glam::{UVec2, Vec3};

/// One RGBA32F read-back, row 0 at the top; alpha 1 marks terrain, 0 sky.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PositionImage {
    /// Width and height, pixels.
    pub size: UVec2,
    /// One RGBA32F texel per pixel, row-major from the top left: the camera-relative
    /// point in metres (x, y, z) and the terrain flag (alpha).
    pub texels: Vec<[f32; 4]>,
}

impl PositionImage {
    /// The camera-relative point at pixel `index` (row-major from the top
    /// left), if terrain was drawn there.
    pub fn point(&self, index: usize) -> Option<Vec3> {
        let [x, y, z, w] = self.texels[index];
        (w > 0.5).then_some(Vec3::new(x, y, z))
    }

    /// Pixels in the image: width times height.
    pub fn pixel_count(&self) -> usize {
        self.size.x as usize * self.size.y as usize
    }
}
