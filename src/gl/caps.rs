//! What the current context can do, detected from its version and extension
//! strings rather than assumed, and clamped to the requested feature level so
//! that asking for ES 2.0 really exercises the ES 2.0 path (Mesa hands out an
//! ES 3.2 context even when 2.0 is asked for).

use std::collections::HashSet;

use glow::HasContext;

/// The OpenGL ES feature level a context is asked for. Code above the GL layer
/// branches on [`Capabilities`], never on this directly.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Default, clap::ValueEnum)]
pub enum GlesVersion {
    /// OpenGL ES 2.0 and GLSL ES 1.00: the low-end boards.
    #[value(name = "es2")]
    Es2,
    /// OpenGL ES 3.0 and later where present.
    #[default]
    #[value(name = "es3")]
    Es3,
}

/// Which GL the driver speaks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GlApi {
    /// OpenGL ES (EGL, the window backends).
    Es,
    /// Desktop OpenGL (OSMesa), running the GLSL ES shaders through
    /// GL_ARB_ES2_compatibility / GL_ARB_ES3_compatibility.
    Desktop,
}

/// The version the driver reports, parsed from GL_VERSION.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReportedVersion {
    /// OpenGL ES or desktop OpenGL.
    pub api: GlApi,
    /// Major version number.
    pub major: u32,
    /// Minor version number.
    pub minor: u32,
}

impl ReportedVersion {
    fn at_least(self, major: u32, minor: u32) -> bool {
        (self.major, self.minor) >= (major, minor)
    }
}

/// Features the renderer may use on this context. Each is true only when the
/// driver offers it through an entry point glow calls, at the requested level.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Capabilities {
    /// What the driver reported.
    pub reported: ReportedVersion,
    /// The level the code should target: the requested one, or ES 2.0 when
    /// the driver cannot do ES 3.0.
    pub level: GlesVersion,
    /// `#version 100` shaders compile (always on ES; desktop needs
    /// GL_ARB_ES2_compatibility or GL 4.1).
    pub glsl_es_100: bool,
    /// `#version 300 es` shaders compile.
    pub glsl_es_300: bool,
    /// Vertex array objects (ES 3.0, GL 3.0, OES/ARB_vertex_array_object).
    pub vertex_array_objects: bool,
    /// glDrawElementsBaseVertex (ES 3.2, GL 3.2, ARB_draw_elements_base_vertex).
    pub base_vertex: bool,
    /// GL_UNSIGNED_INT indices (ES 3.0, desktop, OES_element_index_uint).
    pub uint32_indices: bool,
    /// Instanced draws with attribute divisors (ES 3.0, GL 3.3).
    pub instancing: bool,
    /// GL_RGBA8 colour renderbuffers (ES 3.0, desktop, OES_rgb8_rgba8).
    pub rgba8_renderbuffer: bool,
    /// GL_DEPTH_COMPONENT24 renderbuffers (ES 3.0, desktop, OES_depth24).
    pub depth24_renderbuffer: bool,
    /// RGBA32F colour attachments one can draw to and read back as floats
    /// (core in ES 3.2 and GL 3.0, else `GL_EXT_color_buffer_float` on ES 3):
    /// what the accuracy tool's position pass needs.
    pub float_colour_buffer: bool,
    /// Implementation limits.
    pub limits: Limits,
}

/// Implementation limits read with glGetIntegerv.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Limits {
    /// GL_MAX_TEXTURE_SIZE: the widest texture side, texels.
    pub max_texture_size: i32,
    /// GL_MAX_RENDERBUFFER_SIZE: the widest renderbuffer side, pixels.
    pub max_renderbuffer_size: i32,
    /// GL_MAX_VERTEX_ATTRIBS: vertex attributes a program may use.
    pub max_vertex_attribs: i32,
    /// Zero on the target boards: no texture reads in the vertex shader.
    pub max_vertex_texture_units: i32,
    /// GL_MAX_VIEWPORT_DIMS: the largest viewport width and height, pixels.
    pub max_viewport: [i32; 2],
}

impl Capabilities {
    /// Detects the features from the version and extension strings, clamped
    /// to `requested`. Pure, so the rules are tested without a context.
    pub fn from_strings(
        reported: ReportedVersion,
        extensions: &HashSet<String>,
        requested: GlesVersion,
        limits: Limits,
    ) -> Capabilities {
        let has = |name: &str| extensions.contains(name);
        let es = reported.api == GlApi::Es;
        let es3_class = if es { reported.at_least(3, 0) } else { reported.at_least(3, 3) };
        // Core ES 3 features count only when ES 3 was asked for.
        let core3 = requested == GlesVersion::Es3 && es3_class;
        let core = |es_version: (u32, u32), gl_version: (u32, u32)| {
            let (major, minor) = if es { es_version } else { gl_version };
            core3 && reported.at_least(major, minor)
        };
        Capabilities {
            reported,
            level: if core3 { GlesVersion::Es3 } else { GlesVersion::Es2 },
            glsl_es_100: es || reported.at_least(4, 1) || has("GL_ARB_ES2_compatibility"),
            glsl_es_300: core3
                && (es || reported.at_least(4, 3) || has("GL_ARB_ES3_compatibility")),
            vertex_array_objects: core((3, 0), (3, 0))
                || has("GL_OES_vertex_array_object")
                || (!es && has("GL_ARB_vertex_array_object")),
            base_vertex: core((3, 2), (3, 2)) || (!es && has("GL_ARB_draw_elements_base_vertex")),
            uint32_indices: !es || core((3, 0), (3, 0)) || has("GL_OES_element_index_uint"),
            instancing: core((3, 0), (3, 3)),
            rgba8_renderbuffer: !es || core((3, 0), (3, 0)) || has("GL_OES_rgb8_rgba8"),
            depth24_renderbuffer: !es || core((3, 0), (3, 0)) || has("GL_OES_depth24"),
            float_colour_buffer: core((3, 2), (3, 0))
                || (core3 && has("GL_EXT_color_buffer_float")),
            limits,
        }
    }

    /// Detects the capabilities of the context current on this thread.
    pub(crate) fn detect(gl: &glow::Context, requested: GlesVersion) -> Capabilities {
        let version = gl.version();
        let reported = ReportedVersion {
            api: if version.is_embedded { GlApi::Es } else { GlApi::Desktop },
            major: version.major,
            minor: version.minor,
        };
        Capabilities::from_strings(reported, gl.supported_extensions(), requested, read_limits(gl))
    }
}

#[allow(unsafe_code)]
fn read_limits(gl: &glow::Context) -> Limits {
    // SAFETY: plain glGetIntegerv queries of enums valid in ES 2.0 and GL 2.0,
    // writing into glow-managed storage of the right length.
    unsafe {
        let mut viewport = [0; 2];
        gl.get_parameter_i32_slice(glow::MAX_VIEWPORT_DIMS, &mut viewport);
        Limits {
            max_texture_size: gl.get_parameter_i32(glow::MAX_TEXTURE_SIZE),
            max_renderbuffer_size: gl.get_parameter_i32(glow::MAX_RENDERBUFFER_SIZE),
            max_vertex_attribs: gl.get_parameter_i32(glow::MAX_VERTEX_ATTRIBS),
            max_vertex_texture_units: gl.get_parameter_i32(glow::MAX_VERTEX_TEXTURE_IMAGE_UNITS),
            max_viewport: viewport,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn caps(
        api: GlApi,
        major: u32,
        minor: u32,
        exts: &[&str],
        requested: GlesVersion,
    ) -> Capabilities {
        let extensions = exts.iter().map(|s| s.to_string()).collect();
        let reported = ReportedVersion { api, major, minor };
        Capabilities::from_strings(reported, &extensions, requested, Limits::default())
    }

    #[test]
    fn bare_es2_has_only_the_es2_core() {
        let c = caps(GlApi::Es, 2, 0, &[], GlesVersion::Es3);
        assert_eq!(c.level, GlesVersion::Es2);
        assert!(c.glsl_es_100 && !c.glsl_es_300);
        assert!(!c.vertex_array_objects && !c.base_vertex && !c.uint32_indices);
        assert!(!c.instancing && !c.rgba8_renderbuffer && !c.depth24_renderbuffer);
        assert!(!c.float_colour_buffer);
    }

    #[test]
    fn es2_extensions_add_their_features() {
        let exts = [
            "GL_OES_vertex_array_object",
            "GL_OES_element_index_uint",
            "GL_OES_rgb8_rgba8",
            "GL_OES_depth24",
        ];
        let c = caps(GlApi::Es, 2, 0, &exts, GlesVersion::Es2);
        assert!(c.vertex_array_objects && c.uint32_indices);
        assert!(c.rgba8_renderbuffer && c.depth24_renderbuffer);
        assert!(!c.base_vertex && !c.instancing);
    }

    #[test]
    fn es32_asked_for_es2_stays_at_es2() {
        let c = caps(GlApi::Es, 3, 2, &[], GlesVersion::Es2);
        assert_eq!(c.level, GlesVersion::Es2);
        assert!(!c.glsl_es_300 && !c.vertex_array_objects && !c.base_vertex);
        assert!(!c.instancing && !c.uint32_indices);
    }

    #[test]
    fn es30_has_es3_core_but_not_base_vertex() {
        let c = caps(GlApi::Es, 3, 0, &[], GlesVersion::Es3);
        assert_eq!(c.level, GlesVersion::Es3);
        assert!(c.glsl_es_300 && c.vertex_array_objects && c.instancing && c.uint32_indices);
        assert!(!c.base_vertex && !c.float_colour_buffer);
        assert!(
            caps(GlApi::Es, 3, 0, &["GL_EXT_color_buffer_float"], GlesVersion::Es3)
                .float_colour_buffer
        );
        let es32 = caps(GlApi::Es, 3, 2, &[], GlesVersion::Es3);
        assert!(es32.base_vertex && es32.float_colour_buffer);
    }

    #[test]
    fn desktop_needs_es_compatibility_for_glsl_es() {
        let old = caps(GlApi::Desktop, 3, 3, &[], GlesVersion::Es3);
        assert!(!old.glsl_es_100 && !old.glsl_es_300);
        let compat = caps(
            GlApi::Desktop,
            3,
            3,
            &["GL_ARB_ES2_compatibility", "GL_ARB_ES3_compatibility"],
            GlesVersion::Es3,
        );
        assert!(compat.glsl_es_100 && compat.glsl_es_300 && compat.instancing);
        let gl45 = caps(GlApi::Desktop, 4, 5, &[], GlesVersion::Es2);
        assert!(gl45.glsl_es_100 && !gl45.glsl_es_300 && !gl45.instancing);
        assert!(gl45.uint32_indices && gl45.rgba8_renderbuffer);
    }
}
