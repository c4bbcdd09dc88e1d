//! The timing protocol: blocks of frames timed one by one around glFinish,
//! each operation's block paired with a baseline block just before it so
//! drift on the shared machine cancels, and the spread of all baseline
//! blocks as the significance level (Polok's standard deviation).

use super::scene::{Operation, Scene};
use ridgeline::gl::GlError;
use std::time::Instant;

/// How long each measurement runs.
#[derive(Clone, Copy, Debug)]
pub struct RunLength {
    /// Timed frames per block (one more, untimed, warms the block up).
    pub frames: u32,
    /// Baseline/operation block pairs per operation.
    pub pairs: u32,
}

/// One block: mean frame time and mean time inside glBufferSubData.
#[derive(Clone, Copy, Debug)]
pub struct Block {
    pub frame_secs: f64,
    pub upload_secs: f64,
}

/// One operation's paired blocks.
#[derive(Clone, Debug)]
pub struct Pairs {
    pub baseline: Vec<Block>,
    pub measured: Vec<Block>,
}

impl Pairs {
    /// Mean frame time added by the operation (operation minus its
    /// baselines), in seconds.
    pub fn cost_secs(&self) -> f64 {
        mean(self.measured.iter().map(|b| b.frame_secs))
            - mean(self.baseline.iter().map(|b| b.frame_secs))
    }

    /// Mean seconds per frame inside glBufferSubData.
    pub fn upload_secs(&self) -> f64 {
        mean(self.measured.iter().map(|b| b.upload_secs))
    }

    /// Sample variance of the blocks' seconds inside glBufferSubData.
    pub fn upload_variance(&self) -> f64 {
        let m = self.upload_secs();
        let n = self.measured.len();
        self.measured.iter().map(|b| (b.upload_secs - m).powi(2)).sum::<f64>()
            / n.saturating_sub(1).max(1) as f64
    }
}

fn mean(values: impl Iterator<Item = f64>) -> f64 {
    let (sum, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    sum / n.max(1) as f64
}

/// Times `frames` frames of `operation` after one warm-up frame; `frames` is
/// rounded up to whole upload periods so every block sends the same
/// average traffic.
pub fn block(scene: &mut Scene, operation: Operation, frames: u32) -> Result<Block, GlError> {
    let period = match operation {
        Operation::TileUpload { batch } => scene.upload_period(batch),
        _ => 1,
    };
    let frames = frames.div_ceil(period) * period;
    scene.frame(operation)?;
    let (mut total, mut upload) = (0.0, 0.0);
    for _ in 0..frames {
        let start = Instant::now();
        upload += scene.frame(operation)?;
        total += start.elapsed().as_secs_f64();
    }
    Ok(Block { frame_secs: total / frames as f64, upload_secs: upload / frames as f64 })
}

/// Measures `operation` as `length.pairs` (baseline, operation) block pairs.
pub fn pairs(scene: &mut Scene, operation: Operation, length: RunLength) -> Result<Pairs, GlError> {
    let mut result = Pairs { baseline: Vec::new(), measured: Vec::new() };
    for _ in 0..length.pairs {
        result.baseline.push(block(scene, Operation::Baseline, length.frames)?);
        result.measured.push(block(scene, operation, length.frames)?);
    }
    Ok(result)
}
