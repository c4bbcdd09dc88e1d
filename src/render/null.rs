//! A backend that draws nothing and counts everything, by the cost model
//! ([`super::cost`]): exactly the calls the GL backend issues for the same
//! frames, so tests and benchmarks can check what a frame costs without any
//! GL context.

use super::{
    check_uploads, cost, BufferPlan, CallStats, CostModel, DrawList, FrameOutput, FrameUniforms,
    RenderBackend, RenderError, SymbolBackend,
};
use crate::symbology::SymbolMesh;

/// Counts what the GL backend would issue.
#[derive(Debug)]
pub struct NullBackend {
    calls: CallStats,
    model: CostModel,
    /// The GPU buffers it stands for; uploads past them are refused, and
    /// cluster indices without an index buffer, as the GL backend does.
    plan: BufferPlan,
}

impl NullBackend {
    /// A backend standing for the GPU buffers of `plan` (a pipeline's,
    /// `FramePipeline::buffer_plan`) on a context described by `model`.
    pub fn new(plan: &BufferPlan, model: CostModel) -> Self {
        NullBackend { calls: CallStats::default(), model, plan: *plan }
    }

    /// The calls counted so far.
    pub fn calls(&self) -> CallStats {
        self.calls
    }
}

impl RenderBackend for NullBackend {
    type Error = RenderError;

    fn upload_frame(&mut self, frame: &FrameOutput<'_>) -> Result<(), RenderError> {
        check_uploads(frame.staging, self.plan.buffer_bytes, frame.dirty)?;
        self.calls.add(&cost::upload(&self.model, frame.dirty));
        if let Some((staging, dirty)) = frame.indices {
            let capacity = self.plan.cluster_index_bytes.ok_or(RenderError::ClustersNotPlanned)?;
            check_uploads(staging, capacity, dirty)?;
            self.calls.add(&cost::upload(&self.model, dirty));
        }
        Ok(())
    }

    fn draw_frame(&mut self, list: &DrawList, uniforms: &FrameUniforms) -> Result<(), RenderError> {
        self.calls.add(&cost::frame(&self.model, list, uniforms));
        Ok(())
    }

    fn take_calls(&mut self) -> CallStats {
        std::mem::take(&mut self.calls)
    }
}

impl SymbolBackend for NullBackend {
    fn draw_symbols(&mut self, symbols: &SymbolMesh) -> Result<(), RenderError> {
        self.calls.add(&cost::symbols(&self.model, symbols));
        Ok(())
    }

    fn render_withdrawn(&mut self, flag: &SymbolMesh) -> Result<(), RenderError> {
        self.calls.add(&cost::withdrawn(&self.model, flag));
        Ok(())
    }
}
