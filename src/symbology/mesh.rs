//! [`SymbolMesh`]: the symbols of one frame as coloured triangles in
//! pixels (origin at the top-left corner, y down, the way read-back
//! images are stored), and the painter that fills it with thick lines,
//! each over a dark outline so it reads on any terrain or sky.
//!
//! The mesh's storage is allocated once, [`MAX_SYMBOL_VERTICES`] vertices:
//! a frame's symbols never allocate. The painter collects strokes first
//! and writes every outline before every colour, so one draw call paints
//! them in the right order.

use glam::DVec2;

/// Vertices a frame's symbols may take (the most any frame needs is under
/// half of it: the horizon's 36 marks and 12 labels, the aircraft symbol,
/// the flight path marker, or the failure flag).
pub const MAX_SYMBOL_VERTICES: usize = 8192;
/// Strokes a frame may hold before they become vertices.
pub const MAX_STROKES: usize = MAX_SYMBOL_VERTICES / 12;

/// One vertex: a position in pixels and a colour.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SymbolVertex {
    /// Pixels from the top-left corner, x right, y down.
    pub position: [f32; 2],
    /// RGBA, 0-255.
    pub colour: [u8; 4],
}

/// Bytes of one vertex in the GPU buffer.
pub const VERTEX_BYTES: usize = std::mem::size_of::<SymbolVertex>();

/// A colour, RGBA 0-255.
pub type Rgba = [u8; 4];

/// White: the zero-pitch line, its marks and labels.
pub const WHITE: Rgba = [255, 255, 255, 255];
/// The dark outline under every stroke.
pub const OUTLINE: Rgba = [0, 0, 0, 255];
/// The aircraft reference symbol's yellow (Garmin's).
pub const YELLOW: Rgba = [255, 214, 0, 255];
/// The flight path marker's green (Garmin's).
pub const GREEN: Rgba = [40, 255, 80, 255];
/// The failure flag's red.
pub const RED: Rgba = [255, 32, 32, 255];
/// The failure flag's amber reason line.
pub const AMBER: Rgba = [255, 176, 0, 255];

#[derive(Clone, Copy, Debug)]
struct Stroke {
    a: DVec2,
    b: DVec2,
    half_width: f64,
    colour: Rgba,
}

/// A frame's symbols as triangles, with the strokes they are made from.
#[derive(Clone, Debug)]
pub struct SymbolMesh {
    vertices: Vec<SymbolVertex>,
    strokes: Vec<Stroke>,
    /// Solid quads drawn under everything (a flag's panel), as strokes
    /// without outline.
    panels: Vec<Stroke>,
    outline_px: f64,
    viewport: [u32; 2],
    /// Strokes refused for want of room (a bug: the budget is sized for
    /// the most symbols any frame draws).
    pub dropped: u32,
}

impl Default for SymbolMesh {
    fn default() -> Self {
        SymbolMesh::new()
    }
}

impl SymbolMesh {
    /// An empty mesh with its storage allocated.
    pub fn new() -> SymbolMesh {
        SymbolMesh {
            vertices: Vec::with_capacity(MAX_SYMBOL_VERTICES),
            strokes: Vec::with_capacity(MAX_STROKES),
            panels: Vec::with_capacity(16),
            outline_px: 1.0,
            viewport: [1, 1],
            dropped: 0,
        }
    }

    /// Empties the mesh for a frame of `viewport` pixels whose outlines are
    /// `outline_px` wide.
    pub fn begin(&mut self, viewport: [u32; 2], outline_px: f64) {
        self.vertices.clear();
        self.strokes.clear();
        self.panels.clear();
        self.viewport = viewport;
        self.outline_px = outline_px;
        self.dropped = 0;
    }

    /// The viewport the symbols were laid out for.
    pub fn viewport(&self) -> [u32; 2] {
        self.viewport
    }

    /// A line from `a` to `b`, `width` pixels wide, square ends, over an outline.
    pub fn line(&mut self, a: DVec2, b: DVec2, width: f64, colour: Rgba) {
        if self.strokes.len() + self.panels.len() >= MAX_STROKES {
            self.dropped += 1;
            debug_assert!(false, "symbol strokes beyond {MAX_STROKES}");
            return;
        }
        self.strokes.push(Stroke { a, b, half_width: width / 2.0, colour });
    }

    /// Lines through `points` in order.
    pub fn polyline(&mut self, points: &[DVec2], width: f64, colour: Rgba) {
        for pair in points.windows(2) {
            self.line(pair[0], pair[1], width, colour);
        }
    }

    /// A solid rectangle from `min` to `max`, drawn under every stroke.
    pub fn panel(&mut self, min: DVec2, max: DVec2, colour: Rgba) {
        if self.panels.len() == self.panels.capacity() {
            self.dropped += 1;
            debug_assert!(false, "symbol panels beyond their capacity");
            return;
        }
        let y = (min.y + max.y) / 2.0;
        let half = (max.y - min.y).abs() / 2.0;
        self.panels.push(Stroke {
            a: DVec2::new(min.x + half, y),
            b: DVec2::new(max.x - half, y),
            half_width: half,
            colour,
        });
    }

    /// Turns the strokes into triangles: panels, then every outline, then
    /// every colour.
    pub fn finish(&mut self) {
        self.vertices.clear();
        let outline = self.outline_px;
        for k in 0..self.panels.len() {
            let s = self.panels[k];
            self.quad(&s, 0.0, s.colour);
        }
        for k in 0..self.strokes.len() {
            let s = self.strokes[k];
            self.quad(&s, outline, OUTLINE);
        }
        for k in 0..self.strokes.len() {
            let s = self.strokes[k];
            self.quad(&s, 0.0, s.colour);
        }
    }

    /// The stroke `s`, widened by `grow` pixels on every side, as two triangles.
    fn quad(&mut self, s: &Stroke, grow: f64, colour: Rgba) {
        let along = (s.b - s.a).try_normalize().unwrap_or(DVec2::X);
        let across = along.perp();
        let (h, l) = (s.half_width + grow, s.half_width + grow);
        let corners = [
            s.a - along * l - across * h,
            s.b + along * l - across * h,
            s.b + along * l + across * h,
            s.a - along * l + across * h,
        ];
        for k in [0, 1, 2, 0, 2, 3] {
            let p = corners[k];
            self.vertices.push(SymbolVertex { position: [p.x as f32, p.y as f32], colour });
        }
    }

    /// The triangles' vertices (after [`SymbolMesh::finish`]).
    pub fn vertices(&self) -> &[SymbolVertex] {
        &self.vertices
    }

    /// The vertices as the bytes the GPU buffer receives.
    pub fn bytes(&self) -> &[u8] {
        bytemuck::cast_slice(&self.vertices)
    }

    /// Whether there is nothing to draw.
    pub fn is_empty(&self) -> bool {
        self.vertices.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outlines_come_before_colours_and_storage_is_never_regrown() {
        let mut mesh = SymbolMesh::new();
        let capacity = mesh.vertices.capacity();
        mesh.begin([100, 100], 1.0);
        mesh.panel(DVec2::new(10.0, 10.0), DVec2::new(90.0, 30.0), RED);
        mesh.line(DVec2::new(0.0, 50.0), DVec2::new(100.0, 50.0), 2.0, WHITE);
        mesh.line(DVec2::new(50.0, 0.0), DVec2::new(50.0, 100.0), 2.0, GREEN);
        mesh.finish();
        let colours: Vec<Rgba> = mesh.vertices().chunks(6).map(|q| q[0].colour).collect();
        assert_eq!(colours, vec![RED, OUTLINE, OUTLINE, WHITE, GREEN]);
        // The white line covers y 49..51 and its outline 48..52.
        let ys: Vec<f32> = mesh.vertices()[18..24].iter().map(|v| v.position[1]).collect();
        assert!(ys.iter().all(|&y| y == 49.0 || y == 51.0), "{ys:?}");
        assert_eq!(mesh.bytes().len(), 30 * VERTEX_BYTES);
        assert_eq!(mesh.vertices.capacity(), capacity);
    }
}
