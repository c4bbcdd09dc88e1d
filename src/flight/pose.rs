//! Where the aircraft is and how it is turned at one instant, and how two such
//! instants blend.

use glam::DVec3;

use crate::camera::Camera;

/// The aircraft's state at one instant, in the camera's conventions (see
/// [`crate::camera`]): local metres east/north, altitude above mean sea level,
/// heading clockwise from true north, pitch nose up, roll right wing down.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Local frame, metres: east, north, altitude above mean sea level.
    pub position: DVec3,
    /// Heading, degrees clockwise from true north.
    pub heading_deg: f64,
    /// Pitch, degrees, positive nose up.
    pub pitch_deg: f64,
    /// Roll, degrees, positive right wing down.
    pub roll_deg: f64,
}

impl Pose {
    /// The camera looking from this pose. The caller validates it
    /// ([`Camera::validate`]) along with its own field of view and viewport.
    pub fn camera(&self, fov_x_deg: f64, viewport: [u32; 2]) -> Camera {
        Camera {
            position: self.position,
            heading_deg: self.heading_deg,
            pitch_deg: self.pitch_deg,
            roll_deg: self.roll_deg,
            fov_x_deg,
            viewport,
        }
    }

    /// The pose a fraction `s` (0 = `self`, 1 = `to`) of the way to `to`:
    /// position, pitch and roll linearly, heading along the shorter arc, so
    /// 359 to 1 passes through 0 rather than swinging round through 180.
    /// The heading comes back in [0, 360).
    pub fn lerp(&self, to: &Pose, s: f64) -> Pose {
        let lerp = |a: f64, b: f64| a + (b - a) * s;
        Pose {
            position: self.position.lerp(to.position, s),
            heading_deg: normalize_heading(
                self.heading_deg + heading_difference(self.heading_deg, to.heading_deg) * s,
            ),
            pitch_deg: lerp(self.pitch_deg, to.pitch_deg),
            roll_deg: lerp(self.roll_deg, to.roll_deg),
        }
    }
}

/// The signed turn in [-180, 180) from heading `from` to heading `to`
/// (positive clockwise, i.e. to the right).
pub fn heading_difference(from: f64, to: f64) -> f64 {
    (to - from + 180.0).rem_euclid(360.0) - 180.0
}

/// `heading` in degrees brought into [0, 360).
pub fn normalize_heading(heading: f64) -> f64 {
    let wrapped = heading.rem_euclid(360.0);
    // rem_euclid of a tiny negative number rounds up to exactly 360.
    if wrapped >= 360.0 {
        0.0
    } else {
        wrapped
    }
}
