//! Which pixels must show terrain when the mesh has no hole, worked out from
//! the camera alone.
//!
//! A pixel's ray starts above the terrain (the flights keep the camera
//! hundreds of metres above it). If, still over the data, the ray has gone
//! below the lowest height the drawn surface can have there, it has crossed
//! the surface: the terrain is a height field over the whole data rectangle,
//! so a watertight mesh has a front face somewhere along that segment. The
//! lowest drawn height at horizontal distance `d` is the data's minimum less
//! the shader's earth-curvature drop, `d^2 / 2R`, taken at `d` plus a tile
//! diagonal (a triangle's vertices may lie that much farther) and a metre
//! for rounding. Any pixel so marked that still shows the clear colour is a
//! hole: a crack between tiles, a missing tile, a dropped skirt.

use glam::{DVec2, DVec3};
use ridgeline::camera::{Camera, EARTH_RADIUS_M};

/// The data rectangle and its lowest height.
#[derive(Clone, Copy, Debug)]
pub struct TerrainBounds {
    /// South-west and north-east corners kept, local metres.
    pub min: DVec2,
    pub max: DVec2,
    pub lowest_m: f64,
    /// How much farther than the ray's crossing a triangle's vertex may lie.
    pub reach_slack_m: f64,
}

/// Row-major, row 0 at the top: true where the pixel's ray must meet the terrain.
pub fn terrain_guaranteed(camera: &Camera, bounds: &TerrainBounds) -> Vec<bool> {
    let [width, height] = camera.viewport;
    let half_x = (camera.fov_x_deg.to_radians() / 2.0).tan();
    let half_y = (camera.fov_y() / 2.0).tan();
    let attitude = camera.attitude();
    let mut mask = Vec::with_capacity((width * height) as usize);
    for row in 0..height {
        let ndc_y = 1.0 - 2.0 * (row as f64 + 0.5) / height as f64;
        for column in 0..width {
            let ndc_x = 2.0 * (column as f64 + 0.5) / width as f64 - 1.0;
            // Body axes: x right, y nose, z up.
            let ray = attitude * DVec3::new(ndc_x * half_x, 1.0, ndc_y * half_y);
            mask.push(ray_meets_terrain(camera.position, ray, bounds));
        }
    }
    mask
}

fn ray_meets_terrain(eye: DVec3, ray: DVec3, bounds: &TerrainBounds) -> bool {
    let horizontal = ray.truncate().length();
    if ray.z >= 0.0 || horizontal == 0.0 {
        return false;
    }
    // Along the ray, at horizontal distance d, its height is eye.z - d t; the
    // surface is at least lowest - a (d + c)^2 - 1. The ray is below it from
    // the smaller root of a d^2 + (2ac - t) d + (a c^2 + eye.z - lowest + 1) = 0.
    let t = -ray.z / horizontal;
    let a = 1.0 / (2.0 * EARTH_RADIUS_M);
    let c = bounds.reach_slack_m;
    let b = 2.0 * a * c - t;
    let k = a * c * c + eye.z - bounds.lowest_m + 1.0;
    let discriminant = b * b - 4.0 * a * k;
    if k <= 0.0 || b >= 0.0 || discriminant < 0.0 {
        return false;
    }
    // The stable form of the smaller root (b is negative, a tiny).
    let distance = 2.0 * k / (-b + discriminant.sqrt());
    let end = eye.truncate() + ray.truncate() / horizontal * distance;
    end.cmpge(bounds.min).all() && end.cmple(bounds.max).all()
}
