//! [`PlaceCache`]: what placing a projected grid's nodes and tiles costs
//! that does not depend on the eye, kept across frames: each node's
//! [`Expansion`] (five exact inverse projections) and each tile's patch
//! sampled on the ellipsoid ([`PatchSamples`], nine or more), with each
//! node centre's surface point and axes ([`NodeSeries`]). Both are
//! functions of the grid's lattice and the node or tile alone, so a frame
//! only turns them into the camera's axes. Before this cache the draw list
//! made a node's series once per tile and the selector sampled every
//! tile's patch every frame (on a UTM grid 1.4 ms a frame more than the
//! chart, dev profile).
//!
//! Entries live two frames: one a frame does not use is kept for the next
//! and then dropped, so the cache holds about what two frames use and a
//! still view recomputes nothing. A frame of another lattice (another
//! grid) clears it.

use std::collections::HashMap;
use std::hash::Hash;

use glam::{DMat3, DVec3};

use super::ellipsoid;
use super::expansion::Expansion;
use super::placement::ProjectedLattice;

/// A patch of a projected grid sampled on an `n` x `n` lattice of posts:
/// each sample's surface point (ECEF) and geodetic up. Eye-independent.
#[derive(Clone, Debug, PartialEq)]
pub struct PatchSamples {
    /// Lattice cells a side.
    pub n: usize,
    /// The distance between the patch's first and last corner posts on the
    /// ellipsoid, metres.
    pub span: f64,
    /// `(n + 1)^2` samples, row by row: surface point and unit up.
    pub points: Box<[[DVec3; 2]]>,
}

impl PatchSamples {
    /// Level-0 posts `[p0, p1]` of `lattice`, sampled so that neighbouring
    /// samples are at most about 55 km apart (`n` from 2 to 32).
    pub fn new(lattice: &ProjectedLattice, p0: [f64; 2], p1: [f64; 2]) -> PatchSamples {
        let surface = |post: [f64; 2]| {
            let (lat, lon) = lattice.geodetic(post);
            ellipsoid::to_ecef(lat, lon, 0.0)
        };
        let span = surface(p0).distance(surface(p1));
        let n = ((span / 55_000.0).ceil() as usize).clamp(2, 32);
        let mut points = Vec::with_capacity((n + 1) * (n + 1));
        for j in 0..=n {
            for i in 0..=n {
                let (fu, fv) = (i as f64 / n as f64, j as f64 / n as f64);
                let post = [p0[0] + (p1[0] - p0[0]) * fu, p0[1] + (p1[1] - p0[1]) * fv];
                let (lat, lon) = lattice.geodetic(post);
                points.push([ellipsoid::to_ecef(lat, lon, 0.0), ellipsoid::normal(lat, lon)]);
            }
        }
        debug_assert_eq!(points.len(), (n + 1) * (n + 1));
        PatchSamples { n, span, points: points.into_boxed_slice() }
    }
}

/// What placing a projected grid's node takes that does not depend on the
/// eye: its centre's surface point and axes, and its series.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeSeries {
    /// The centre's surface point, ECEF metres.
    pub surface: DVec3,
    /// East, north and up at the centre, ECEF, as columns.
    pub enu: DMat3,
    /// The node's [`Expansion::uniforms`].
    pub uniforms: [f32; 8],
}

impl NodeSeries {
    /// The node of `lattice` centred on level-0 post `centre`.
    pub fn new(lattice: &ProjectedLattice, centre: [i64; 2]) -> NodeSeries {
        let post = centre.map(|c| c as f64);
        let (lat, lon) = lattice.geodetic(post);
        NodeSeries {
            surface: ellipsoid::to_ecef(lat, lon, 0.0),
            enu: ellipsoid::enu_to_ecef(lat, lon),
            uniforms: Expansion::new(lattice, post).uniforms(),
        }
    }
}

/// A map whose entries live while a frame or the next uses them.
#[derive(Clone, Debug)]
struct TwoFrames<K, V> {
    current: HashMap<K, V>,
    previous: HashMap<K, V>,
}

impl<K, V> Default for TwoFrames<K, V> {
    fn default() -> Self {
        TwoFrames { current: HashMap::new(), previous: HashMap::new() }
    }
}

impl<K: Eq + Hash + Copy, V> TwoFrames<K, V> {
    /// `key`'s value, made by `make` when neither this frame nor the last
    /// used it.
    fn get_or_make(&mut self, key: K, make: impl FnOnce() -> V) -> &V {
        if !self.current.contains_key(&key) {
            let value = self.previous.remove(&key).unwrap_or_else(make);
            self.current.insert(key, value);
        }
        &self.current[&key]
    }

    /// Starts a frame: what the last frame did not use is dropped (keeping
    /// both maps' room, so a steady flight allocates only for new keys).
    fn next_frame(&mut self) {
        std::mem::swap(&mut self.current, &mut self.previous);
        self.current.clear();
    }

    fn clear(&mut self) {
        self.current.clear();
        self.previous.clear();
    }

    fn len(&self) -> usize {
        self.current.len() + self.previous.len()
    }
}

/// A projected grid's node series and tile samples, kept across frames
/// (see the module doc). Geographic grids need neither: their nodes have
/// no series and their patches' samples cost a sine and cosine a row and
/// a column.
#[derive(Clone, Debug, Default)]
pub struct PlaceCache {
    lattice: Option<ProjectedLattice>,
    nodes: TwoFrames<[i64; 2], NodeSeries>,
    patches: TwoFrames<[u64; 4], PatchSamples>,
}

impl PlaceCache {
    /// Starts a frame of the projected grid `lattice` (`None`: a
    /// geographic grid, or the chart; [`super::EarthFrame::projected_lattice`]).
    pub fn next_frame(&mut self, lattice: Option<ProjectedLattice>) {
        if lattice != self.lattice {
            self.nodes.clear();
            self.patches.clear();
            self.lattice = lattice;
        }
        self.nodes.next_frame();
        self.patches.next_frame();
    }

    /// Whether it was started ([`Self::next_frame`]) for `lattice`.
    pub fn serves(&self, lattice: Option<ProjectedLattice>) -> bool {
        self.lattice == lattice
    }

    /// The node centred on level-0 post `centre` (`None` but for a
    /// projected grid's frame).
    pub fn node(&mut self, centre: [i64; 2]) -> Option<NodeSeries> {
        let lattice = self.lattice?;
        Some(*self.nodes.get_or_make(centre, || NodeSeries::new(&lattice, centre)))
    }

    /// The samples of level-0 posts `[p0, p1]` (`None` but for a projected
    /// grid's frame).
    pub fn patch(&mut self, p0: [f64; 2], p1: [f64; 2]) -> Option<&PatchSamples> {
        let lattice = self.lattice?;
        let key = [p0[0], p0[1], p1[0], p1[1]].map(f64::to_bits);
        Some(self.patches.get_or_make(key, || PatchSamples::new(&lattice, p0, p1)))
    }

    /// Entries held (both frames'), nodes and patches.
    pub fn len(&self) -> (usize, usize) {
        (self.nodes.len(), self.patches.len())
    }
}
