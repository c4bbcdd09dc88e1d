//! The camera's clearance: the largest distance `c` such that every point
//! of the terrain within `c` of the camera's place on the ground lies at
//! least `c` below the camera. Every point of the terrain is then at least
//! `max(d, c)` from the eye, `d` its ground distance, so no leaf tile's
//! rule needs a ring finer than the one `c` away
//! ([`crate::tiles::errors::MeshErrors::set_clearance`]). Over a valley the
//! terrain's highest peak far off would give none: the clearance is found
//! from the resident nodes' height bounds around the camera.

use crate::node::NodeId;
use crate::tiles::{best_resident, ResidentNodes};

/// Candidate clearances step down by this ratio (a fourth of an octave:
/// the sub-levels the clearance picks are octaves).
const STEP: f64 = 1.189_207_115_002_721; // 2^(1/4)

/// Below this a clearance spares no ring, metres.
const LEAST_M: f64 = 1.0;

/// The camera's clearance at chart metres `eye_m` (east, north, height),
/// metres (0: none). `range_m` is the data's lowest and highest height: a
/// camera above the highest clears everything by the difference at least,
/// and none clears more than its height above the lowest.
pub fn clearance_m(nodes: &dyn ResidentNodes, eye_m: [f64; 3], range_m: (f64, f64)) -> f64 {
    let finite = eye_m.iter().all(|v| v.is_finite()) && range_m.0.is_finite();
    if !finite || !range_m.1.is_finite() {
        return 0.0;
    }
    let everywhere = (eye_m[2] - range_m.1).max(0.0);
    let mut c = eye_m[2] - range_m.0;
    while c > everywhere.max(LEAST_M) {
        if clears(nodes, eye_m, c) {
            return c;
        }
        c /= STEP;
    }
    everywhere
}

/// Whether every resident bound within `c` of the eye's ground place (its
/// square, conservatively) lies at least `c` below the eye. An area with no
/// resident node cannot be vouched for; outside the data there is no
/// terrain.
fn clears(nodes: &dyn ResidentNodes, eye_m: [f64; 3], c: f64) -> bool {
    let layout = nodes.layout();
    let ceiling = eye_m[2] - c;
    // The finest level whose nodes cover the square in a few per side.
    let level = (0..layout.levels)
        .find(|&l| layout.node_size_m(l).iter().all(|&s| s >= c / 2.0))
        .unwrap_or(layout.levels.saturating_sub(1));
    let size = layout.node_size_m(level);
    let count = layout.nodes_at(level);
    let range = |k: usize| {
        let lo = ((eye_m[k] - c) / size[k]).floor().max(0.0) as i64;
        let hi = ((eye_m[k] + c) / size[k]).floor().min(count[k] as f64 - 1.0) as i64;
        lo..=hi
    };
    let (xs, ys) = (range(0), range(1));
    ys.flat_map(|y| xs.clone().map(move |x| NodeId::new(level, x as u32, y as u32))).all(|id| {
        best_resident(nodes, id).is_some_and(|(_, data)| (data.max + data.delta) as f64 <= ceiling)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::procedural::{EarthParams, ProceduralEarth};
    use crate::scene::{PreloadedTerrain, TerrainData};

    /// 512 cells of 30 m a side.
    fn earth() -> (ProceduralEarth, PreloadedTerrain) {
        let params = EarthParams { node_size: 16, levels: 6, border: 1, spacing_m: 30.0, seed: 7 };
        let earth = ProceduralEarth::new(params).expect("small earth");
        let terrain = PreloadedTerrain::load(&earth).expect("loads");
        (earth, terrain)
    }

    /// Whether every level-0 sample within `c` of the eye's ground place
    /// lies at least `c` below the eye: the model, post by post.
    fn holds(earth: &ProceduralEarth, eye_m: [f64; 3], c: f64) -> bool {
        // Only the posts of the square around the disk can be within it.
        let posts = |k: usize| {
            let lo = ((eye_m[k] - c) / 30.0).floor().clamp(0.0, 512.0) as i64;
            lo..=((eye_m[k] + c) / 30.0).ceil().clamp(0.0, 512.0) as i64
        };
        posts(1).all(|j| {
            posts(0).all(|i| {
                let (x, y) = (i as f64 * 30.0 - eye_m[0], j as f64 * 30.0 - eye_m[1]);
                x.hypot(y) > c || earth.sample(i, j) as f64 <= eye_m[2] - c
            })
        })
    }

    #[test]
    fn the_clearance_holds_for_every_post_and_beats_the_highest_peak() {
        let (earth, terrain) = earth();
        let (lo, hi) = terrain.height_range();
        let range = (lo as f64, hi as f64);
        // Over the lowest post, at heights from below the highest peak to
        // far above it.
        let lowest = (0..=512i64 * 513 + 512)
            .map(|k| (k % 513, k / 513))
            .min_by(|a, b| earth.sample(a.0, a.1).total_cmp(&earth.sample(b.0, b.1)))
            .expect("posts");
        let place = [lowest.0 as f64 * 30.0, lowest.1 as f64 * 30.0];
        let mut beat_the_peak = false;
        for above in [-0.5, 0.0, 0.2, 1.0, 3.0] {
            let z = hi as f64 + above * (hi - lo) as f64;
            let eye = [place[0], place[1], z];
            let c = clearance_m(&terrain, eye, range);
            assert!(holds(&earth, eye, c), "{c} m at {eye:?}");
            assert!(c >= (z - hi as f64).max(0.0), "{c} m at {eye:?}");
            beat_the_peak |= c > (z - hi as f64).max(0.0) + 1.0;
        }
        assert!(beat_the_peak, "over the lowest post the terrain around clears more");
    }

    #[test]
    fn every_clearance_the_bounds_vouch_for_holds_post_by_post() {
        let (earth, terrain) = earth();
        let (lo, hi) = terrain.height_range();
        let mut vouched = 0;
        for (i, j) in [(40, 40), (256, 256), (470, 90), (128, 400), (0, 512)] {
            let ground = earth.sample(i, j) as f64;
            for above in [50.0, 300.0, 1_000.0] {
                let eye = [i as f64 * 30.0, j as f64 * 30.0, ground + above];
                // A ladder of clearances, a twentieth of an octave apart.
                let ladder = (0..200).map(|k| 5.0 * 2f64.powf(k as f64 / 20.0));
                for c in ladder.take_while(|&c| c < eye[2] - lo as f64) {
                    if clears(&terrain, eye, c) {
                        vouched += 1;
                        assert!(holds(&earth, eye, c), "{c} m vouched for at {eye:?}");
                    }
                }
            }
        }
        assert!(vouched > 50, "the bounds vouch for clearances: {vouched} (highest {hi} m)");
    }

    #[test]
    fn no_clearance_below_the_terrain_or_from_absurd_input() {
        let (_, terrain) = earth();
        let (lo, hi) = terrain.height_range();
        let range = (lo as f64, hi as f64);
        assert_eq!(clearance_m(&terrain, [7_000.0, 7_000.0, lo as f64 - 10.0], range), 0.0);
        for eye in [[f64::NAN, 0.0, 1e4], [0.0, 0.0, f64::INFINITY]] {
            assert_eq!(clearance_m(&terrain, eye, range), 0.0);
        }
        assert_eq!(clearance_m(&terrain, [0.0, 0.0, 1e4], (f64::NAN, hi as f64)), 0.0);
    }
}
