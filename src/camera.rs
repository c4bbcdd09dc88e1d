//! The viewer: where the aircraft is, how it is turned, and what it sees.
//!
//! Positions are f64 metres in the local frame (x east, y north, z up, origin
//! at the dataset's south-west sample; see [`crate::geo`]). Everything drawn is
//! expressed relative to the camera before it becomes f32, so precision does
//! not depend on how far the aircraft is from the origin. The view matrix
//! therefore only rotates.
//!
//! Attitude follows aviation conventions: heading clockwise from true north,
//! pitch positive nose up, roll positive right wing down, all in degrees.

use glam::{DMat3, DQuat, DVec3, Mat4, Vec3, Vec4};

/// Mean earth radius in metres (IUGG), for the curvature drop.
pub const EARTH_RADIUS_M: f64 = 6_371_008.8;

/// Everything that defines one view of the terrain.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Position in the local frame: east, north, altitude above mean sea level.
    pub position: DVec3,
    /// Heading, degrees clockwise from true north.
    pub heading_deg: f64,
    /// Pitch, degrees, positive nose up.
    pub pitch_deg: f64,
    /// Roll, degrees, positive right wing down.
    pub roll_deg: f64,
    /// Horizontal field of view.
    pub fov_x_deg: f64,
    /// Viewport in pixels.
    pub viewport: [u32; 2],
}

/// Why a camera cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CameraError {
    /// A position or angle is NaN or infinite.
    #[error("camera {field} is {value}, not a finite number")]
    NotFinite {
        /// Which value: `x`, `y`, `altitude`, `heading`, `pitch`, `roll` or `field of view`.
        field: &'static str,
        /// The value found.
        value: f64,
    },
    /// The horizontal field of view, degrees, is not in (0, 179].
    #[error("field of view {0} degrees is outside (0, 179]")]
    FieldOfView(f64),
    /// The viewport, pixels wide and high, has a zero side.
    #[error("viewport {0}x{1} has no pixels")]
    EmptyViewport(u32, u32),
}

impl Camera {
    /// Refuses NaN, infinities and degenerate projections before anything is drawn.
    pub fn validate(&self) -> Result<(), CameraError> {
        let fields = [
            ("x", self.position.x),
            ("y", self.position.y),
            ("altitude", self.position.z),
            ("heading", self.heading_deg),
            ("pitch", self.pitch_deg),
            ("roll", self.roll_deg),
            ("field of view", self.fov_x_deg),
        ];
        for (field, value) in fields {
            if !value.is_finite() {
                return Err(CameraError::NotFinite { field, value });
            }
        }
        if !(self.fov_x_deg > 0.0 && self.fov_x_deg <= 179.0) {
            return Err(CameraError::FieldOfView(self.fov_x_deg));
        }
        if self.viewport[0] == 0 || self.viewport[1] == 0 {
            return Err(CameraError::EmptyViewport(self.viewport[0], self.viewport[1]));
        }
        Ok(())
    }

    /// Rotation from body axes (x right wing, y nose, z up through the canopy)
    /// to the local frame.
    pub fn attitude(&self) -> DQuat {
        let heading = DQuat::from_rotation_z(-self.heading_deg.to_radians());
        let pitch = DQuat::from_rotation_x(self.pitch_deg.to_radians());
        let roll = DQuat::from_rotation_y(self.roll_deg.to_radians());
        heading * pitch * roll
    }

    /// Unit vector along the nose, in the local frame.
    pub fn forward(&self) -> DVec3 {
        self.attitude() * DVec3::Y
    }

    /// Viewport width over height.
    pub fn aspect(&self) -> f64 {
        self.viewport[0] as f64 / self.viewport[1] as f64
    }

    /// Vertical field of view in radians, from the horizontal one and the aspect.
    pub fn fov_y(&self) -> f64 {
        let half_x = (self.fov_x_deg.to_radians() / 2.0).tan();
        2.0 * (half_x / self.aspect()).atan()
    }

    /// Ulrich's perspective factor K = viewport width / (2 tan(fov_x / 2)):
    /// a length `delta` at distance `D` spans `delta / D * K` pixels.
    pub fn perspective_scale(&self) -> f64 {
        self.viewport[0] as f64 / (2.0 * (self.fov_x_deg.to_radians() / 2.0).tan())
    }

    /// Rotation-only view matrix: camera-relative local coordinates to eye space
    /// (GL convention: x right, y up, looking down -z).
    pub fn view(&self) -> Mat4 {
        let world_to_body = DMat3::from_quat(self.attitude().inverse());
        // Body (right, nose, up) to eye (right, up, back).
        let body_to_eye = DMat3::from_cols(DVec3::X, -DVec3::Z, DVec3::Y);
        let m = (body_to_eye * world_to_body).as_mat3();
        Mat4::from_mat3(m)
    }

    /// Perspective projection between `near` and `far` metres.
    pub fn projection(&self, near: f32, far: f32) -> Mat4 {
        Mat4::perspective_rh_gl(self.fov_y() as f32, self.aspect() as f32, near, far)
    }
}

/// The six planes of a view frustum in camera-relative local coordinates, each
/// `(n, d)` with `n . p + d >= 0` inside.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frustum {
    /// Left, right, bottom, top, near and far planes, each `(n, d)` with `n . p + d >= 0` inside.
    pub planes: [Vec4; 6],
}

impl Frustum {
    /// Extracts the planes of `view_projection` (Gribb and Hartmann).
    pub fn from_view_projection(m: Mat4) -> Self {
        let rows = [m.row(0), m.row(1), m.row(2), m.row(3)];
        let mut planes = [
            rows[3] + rows[0],
            rows[3] - rows[0],
            rows[3] + rows[1],
            rows[3] - rows[1],
            rows[3] + rows[2],
            rows[3] - rows[2],
        ];
        for plane in &mut planes {
            let length = plane.truncate().length();
            if length > 0.0 {
                *plane /= length;
            }
        }
        Frustum { planes }
    }

    /// Whether the box `[min, max]` may be visible (conservative: a box that
    /// straddles a corner outside may be kept).
    pub fn intersects_box(&self, min: Vec3, max: Vec3) -> bool {
        self.planes.iter().all(|plane| {
            let normal = plane.truncate();
            let corner = Vec3::select(normal.cmpge(Vec3::ZERO), max, min);
            normal.dot(corner) + plane.w >= 0.0
        })
    }
}

/// How far a point at horizontal distance `distance` metres lies below the
/// camera's tangent plane on a spherical earth.
pub fn curvature_drop(distance: f64) -> f64 {
    distance * distance / (2.0 * EARTH_RADIUS_M)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Camera {
        Camera {
            position: DVec3::new(0.0, 0.0, 1000.0),
            heading_deg: 0.0,
            pitch_deg: 0.0,
            roll_deg: 0.0,
            fov_x_deg: 60.0,
            viewport: [800, 600],
        }
    }

    #[test]
    fn attitude_follows_aviation_conventions() {
        let mut c = camera();
        assert!((c.forward() - DVec3::Y).length() < 1e-12, "heading 0 looks north");
        c.heading_deg = 90.0;
        assert!((c.forward() - DVec3::X).length() < 1e-12, "heading 90 looks east");
        c.heading_deg = 0.0;
        c.pitch_deg = 30.0;
        assert!(c.forward().z > 0.49, "pitch up raises the nose");
        c.pitch_deg = 0.0;
        c.roll_deg = 30.0;
        let right_wing = c.attitude() * DVec3::X;
        assert!(right_wing.z < -0.49, "roll right lowers the right wing");
    }

    #[test]
    fn view_looks_down_minus_z_along_the_nose() {
        let mut c = camera();
        c.heading_deg = 37.0;
        c.pitch_deg = -12.0;
        let eye = c.view().transform_vector3(c.forward().as_vec3());
        assert!((eye - Vec3::NEG_Z).length() < 1e-5, "{eye}");
    }

    #[test]
    fn curvature_drop_at_100_km_is_about_785_m() {
        assert!((curvature_drop(100_000.0) - 784.8).abs() < 0.5);
    }

    #[test]
    fn frustum_keeps_what_is_ahead_and_drops_what_is_behind() {
        let c = camera();
        let f = Frustum::from_view_projection(c.projection(1.0, 10_000.0) * c.view());
        assert!(f.intersects_box(Vec3::new(-10.0, 100.0, -10.0), Vec3::new(10.0, 120.0, 10.0)));
        assert!(!f.intersects_box(Vec3::new(-10.0, -120.0, -10.0), Vec3::new(10.0, -100.0, 10.0)));
    }

    #[test]
    fn bad_numbers_are_refused() {
        let mut c = camera();
        c.pitch_deg = f64::NAN;
        assert!(matches!(c.validate(), Err(CameraError::NotFinite { field: "pitch", .. })));
        let mut c = camera();
        c.fov_x_deg = 0.0;
        assert!(c.validate().is_err());
    }
}
