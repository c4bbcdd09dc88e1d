//! Where a direction of the world lands on the screen, in pixels (origin
//! top-left, y down), computed in f64 from the camera's attitude, field of
//! view and viewport: the same projection the GL matrices
//! ([`Camera::view`], [`Camera::projection`]) make, without their near
//! and far planes, which do not move a direction's pixel.
//!
//! The zero-pitch line is the image of every horizontal direction. With
//! `u` the world's up in eye coordinates, a pixel's eye direction
//! `(ndc_x / p00, ndc_y / p11, -1)` is horizontal when
//! `u.x ndc_x / p00 + u.y ndc_y / p11 = u.z`: a straight line on the
//! screen ([`Projector::zero_pitch_line`]).

use glam::{DMat3, DVec2, DVec3};

use crate::camera::Camera;

/// A straight line on the screen: a point and a unit direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScreenLine {
    /// The line's point nearest the screen's centre, pixels.
    pub point: DVec2,
    /// Unit direction along the line (x right, y down).
    pub direction: DVec2,
}

impl ScreenLine {
    /// Distance of `p` from the line, pixels.
    pub fn distance(&self, p: DVec2) -> f64 {
        (p - self.point).perp_dot(self.direction).abs()
    }
}

/// The camera's projection of world directions to pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Projector {
    /// World (local frame: x east, y north, z up) to eye (x right, y up, back).
    world_to_eye: DMat3,
    p00: f64,
    p11: f64,
    size: DVec2,
}

impl Projector {
    /// The projection of `camera`.
    pub fn new(camera: &Camera) -> Projector {
        let world_to_body = DMat3::from_quat(camera.attitude().inverse());
        let body_to_eye = DMat3::from_cols(DVec3::X, -DVec3::Z, DVec3::Y);
        let p11 = 1.0 / (camera.fov_y() / 2.0).tan();
        Projector {
            world_to_eye: body_to_eye * world_to_body,
            p00: p11 / camera.aspect(),
            p11,
            size: DVec2::new(camera.viewport[0] as f64, camera.viewport[1] as f64),
        }
    }

    /// The viewport, pixels.
    pub fn size(&self) -> DVec2 {
        self.size
    }

    /// The pixel `direction` (world) projects to; `None` when it points
    /// behind the camera or along its image plane.
    pub fn project(&self, direction: DVec3) -> Option<DVec2> {
        let eye = self.world_to_eye * direction;
        if eye.z > -1e-9 * eye.length().max(1e-300) {
            return None;
        }
        let ndc = DVec2::new(self.p00 * eye.x / -eye.z, self.p11 * eye.y / -eye.z);
        Some(DVec2::new((1.0 + ndc.x) * self.size.x / 2.0, (1.0 - ndc.y) * self.size.y / 2.0))
    }

    /// Whether `p` lies inside the viewport grown by `margin` pixels.
    pub fn on_screen(&self, p: DVec2, margin: f64) -> bool {
        p.cmpge(DVec2::splat(-margin)).all() && p.cmple(self.size + margin).all()
    }

    /// The zero-pitch line, or `None` when the camera looks straight up or
    /// down (every horizontal direction is then at the screen's edge or
    /// beyond) or the line misses the screen.
    pub fn zero_pitch_line(&self) -> Option<ScreenLine> {
        let up = self.world_to_eye * DVec3::Z;
        // a * px + b * py = c in pixels, from ndc_x = 2 px / w - 1 and
        // ndc_y = 1 - 2 py / h.
        let (kx, ky) = (up.x / self.p00, up.y / self.p11);
        let normal = DVec2::new(kx * 2.0 / self.size.x, -ky * 2.0 / self.size.y);
        let c = up.z + kx - ky;
        let length = normal.length();
        if length < 1e-12 {
            return None;
        }
        let (normal, offset) = (normal / length, c / length);
        let centre = self.size / 2.0;
        let point = centre - normal * (normal.dot(centre) - offset);
        if (point - centre).length() > self.size.length() {
            return None;
        }
        let mut direction = normal.perp();
        if direction.x < 0.0 {
            direction = -direction;
        }
        Some(ScreenLine { point, direction })
    }
}

/// The horizontal unit direction of heading `deg` (clockwise from north),
/// raised by `elevation_deg`.
pub fn heading_direction(deg: f64, elevation_deg: f64) -> DVec3 {
    let (h, e) = (deg.to_radians(), elevation_deg.to_radians());
    DVec3::new(h.sin() * e.cos(), h.cos() * e.cos(), e.sin())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera(pitch: f64, roll: f64) -> Camera {
        Camera {
            position: DVec3::new(0.0, 0.0, 1000.0),
            heading_deg: 30.0,
            pitch_deg: pitch,
            roll_deg: roll,
            fov_x_deg: 60.0,
            viewport: [640, 360],
        }
    }

    /// The same pixel through the f32 GL matrices the terrain is drawn with.
    fn through_gl(c: &Camera, direction: DVec3) -> DVec2 {
        let m = c.projection(1.0, 100_000.0) * c.view();
        let clip = m * (direction * 1000.0).as_vec3().extend(1.0);
        let ndc = clip.truncate() / clip.w;
        DVec2::new((1.0 + ndc.x as f64) * 320.0, (1.0 - ndc.y as f64) * 180.0)
    }

    #[test]
    fn directions_land_where_the_gl_matrices_put_them() {
        let c = camera(-7.0, 23.0);
        let p = Projector::new(&c);
        for (h, e) in [(30.0, 0.0), (10.0, -5.0), (55.0, 3.0)] {
            let d = heading_direction(h, e);
            let ours = p.project(d).unwrap();
            assert!((ours - through_gl(&c, d)).length() < 0.01, "{h} {e}: {ours}");
        }
        assert!(p.project(heading_direction(210.0, 0.0)).is_none(), "behind");
        let centre = p.project(c.forward()).unwrap();
        assert!((centre - DVec2::new(320.0, 180.0)).length() < 1e-9, "the nose is the centre");
    }

    #[test]
    fn the_zero_pitch_line_holds_every_horizontal_direction() {
        for (pitch, roll) in [(0.0, 0.0), (10.0, 0.0), (-15.0, 30.0), (5.0, -60.0), (20.0, 100.0)] {
            let c = camera(pitch, roll);
            let p = Projector::new(&c);
            let line = p.zero_pitch_line().unwrap();
            for h in [0.0, 15.0, 30.0, 45.0, 60.0] {
                if let Some(px) = p.project(heading_direction(h, 0.0)) {
                    assert!(line.distance(px) < 1e-6, "pitch {pitch} roll {roll} heading {h}");
                }
            }
        }
        let level = Projector::new(&camera(0.0, 0.0)).zero_pitch_line().unwrap();
        assert!((level.point.y - 180.0).abs() < 1e-9 && (level.direction.y).abs() < 1e-12);
        assert!(Projector::new(&camera(90.0, 0.0)).zero_pitch_line().is_none());
    }
}
