//! The tests' one flight loop: cameras flown one frame each on whatever
//! draws frames (a pipeline on its backend, or a GL display), with a
//! callback per frame that reads what the frame made. Paging before a
//! frame is the flight's choice ([`Settle`]), so a test flies either as
//! `ridgeline fly` does or with every frame complete.

use ridgeline::camera::Camera;
use ridgeline::display::DisplayParts;
use ridgeline::flight::FlightPath;
use ridgeline::pipeline::{FramePipeline, FrameStats};
use ridgeline::render::RenderBackend;

/// What draws one frame for a camera.
pub trait Flies {
    /// Pages in what `camera` wants, in at most `updates` paging updates.
    fn settle(&mut self, camera: &Camera, updates: u32);
    /// Draws one frame for `camera`.
    fn draw(&mut self, camera: &Camera) -> FrameStats;
}

/// A pipeline and the backend it draws on (the null backend, typically).
pub struct OnBackend<'a, B> {
    /// Paging, selection, tiles and the draw list.
    pub pipeline: &'a mut FramePipeline,
    /// What the frames are drawn on.
    pub backend: &'a mut B,
}

impl<B: RenderBackend> Flies for OnBackend<'_, B>
where
    B::Error: 'static,
{
    fn settle(&mut self, camera: &Camera, updates: u32) {
        self.pipeline.settle(camera, updates).expect("settle");
    }

    fn draw(&mut self, camera: &Camera) -> FrameStats {
        self.pipeline.frame(camera, self.backend).expect("frame")
    }
}

impl Flies for DisplayParts {
    fn settle(&mut self, camera: &Camera, updates: u32) {
        self.pipeline.settle(camera, updates).expect("settle");
    }

    fn draw(&mut self, camera: &Camera) -> FrameStats {
        self.frame(camera).expect("frame")
    }
}

/// When a flight pages in, with how many paging updates at most.
#[derive(Clone, Copy, Debug)]
pub enum Settle {
    /// Never: frames draw what has loaded, as `ridgeline fly` draws.
    Never,
    /// Before the first frame only (`ridgeline fly`'s start).
    First(u32),
    /// Before every frame: each frame complete and repeatable.
    Every(u32),
}

/// One frame of a flight, as the per-frame callback sees it.
pub struct Frame<'a, F> {
    /// The frame's number, from 0.
    pub k: usize,
    /// The camera it was drawn for.
    pub camera: &'a Camera,
    /// What drawing it took and made.
    pub stats: FrameStats,
    /// What drew it, to read its draw list or picture.
    pub flyer: &'a mut F,
}

/// Flies `cameras` on `flyer`, one frame each, paging in as `settle`
/// says; returns what `each` made of every frame.
pub fn fly<F: Flies, T>(
    flyer: &mut F,
    cameras: impl IntoIterator<Item = Camera>,
    settle: Settle,
    mut each: impl FnMut(Frame<'_, F>) -> T,
) -> Vec<T> {
    let mut made = Vec::new();
    for (k, camera) in cameras.into_iter().enumerate() {
        match settle {
            Settle::Every(updates) => flyer.settle(&camera, updates),
            Settle::First(updates) if k == 0 => flyer.settle(&camera, updates),
            Settle::First(_) | Settle::Never => {}
        }
        let stats = flyer.draw(&camera);
        made.push(each(Frame { k, camera: &camera, stats, flyer }));
    }
    made
}

/// The cameras of `frames` evenly spaced times along `path`, a
/// `fov_x_deg` field of view over `viewport` pixels.
pub fn along(
    path: &FlightPath,
    frames: u32,
    fov_x_deg: f64,
    viewport: [u32; 2],
) -> impl Iterator<Item = Camera> + '_ {
    path.frame_times(frames).map(move |t| path.sample(t).camera(fov_x_deg, viewport))
}
