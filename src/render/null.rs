//! A backend that draws nothing and counts everything: uploads, draw calls,
//! uniform writes, attribute pointer changes. Tests use it to check what a
//! frame would cost on a GPU without any GL context.

use super::{DrawList, RenderBackend};
use std::ops::Range;

/// Running totals since creation (or the last [`NullBackend::take`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct CallCounts {
    pub frames: u64,
    pub upload_calls: u64,
    pub bytes_uploaded: u64,
    pub draw_calls: u64,
    pub uniform_writes: u64,
    pub attribute_pointer_changes: u64,
    pub triangles: u64,
}

#[derive(Debug, Default)]
pub struct NullBackend {
    counts: CallCounts,
    /// Size of the GPU buffer it pretends to hold; uploads past it are bugs.
    capacity: u32,
}

impl NullBackend {
    pub fn new(capacity: u32) -> Self {
        NullBackend { counts: CallCounts::default(), capacity }
    }

    pub fn counts(&self) -> CallCounts {
        self.counts
    }

    /// Returns the counts and starts again from zero.
    pub fn take(&mut self) -> CallCounts {
        std::mem::take(&mut self.counts)
    }
}

impl RenderBackend for NullBackend {
    type Error = std::convert::Infallible;

    fn upload(&mut self, staging: &[u8], ranges: &[Range<u32>]) -> Result<(), Self::Error> {
        for range in ranges {
            assert!(
                range.end <= self.capacity && range.end as usize <= staging.len(),
                "upload past the buffer"
            );
            self.counts.upload_calls += 1;
            self.counts.bytes_uploaded += (range.end - range.start) as u64;
        }
        Ok(())
    }

    fn draw(&mut self, list: &DrawList) -> Result<(), Self::Error> {
        self.counts.frames += 1;
        // The GL backend writes three per-tile uniforms (origin with spacing,
        // morph range, skirt depth) and points the tile's attributes at its bytes.
        let mut last_offset = None;
        for tile in &list.tiles {
            self.counts.draw_calls += 1;
            self.counts.uniform_writes += 3;
            if last_offset != Some(tile.byte_offset) {
                self.counts.attribute_pointer_changes += 1;
                last_offset = Some(tile.byte_offset);
            }
            self.counts.triangles += list.indices_per_tile as u64 / 3;
        }
        Ok(())
    }
}
