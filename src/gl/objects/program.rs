//! [`Shader`] and [`Program`]: GLSL compiled and linked, with the driver's
//! info log in the error when it fails.

use std::rc::Rc;

use glow::HasContext;

use crate::gl::error::{GlError, ShaderStage};
use crate::gl::handle::Gl;
use crate::gl_check;

/// A compiled shader object. Usually short-lived: [`Program::build`] compiles,
/// links and drops its shaders.
#[derive(Debug)]
pub struct Shader {
    gl: Rc<Gl>,
    raw: glow::Shader,
    stage: ShaderStage,
}

impl Shader {
    /// Compiles `source`; `name` (a file name, say) labels errors.
    #[allow(unsafe_code)]
    pub fn compile(
        gl: &Rc<Gl>,
        stage: ShaderStage,
        name: &str,
        source: &str,
    ) -> Result<Shader, GlError> {
        let kind = match stage {
            ShaderStage::Vertex => glow::VERTEX_SHADER,
            ShaderStage::Fragment => glow::FRAGMENT_SHADER,
        };
        // SAFETY: creating a name needs only a current context.
        let raw = unsafe { gl.create_shader(kind) }
            .map_err(|reason| GlError::ObjectCreation { what: "shader", reason })?;
        let shader = Shader { gl: Rc::clone(gl), raw, stage };
        // SAFETY: `raw` is a live shader; glow passes the source's pointer and
        // length, and the status and log queries write glow-owned storage.
        let (compiled, log) = unsafe {
            gl.shader_source(raw, source);
            gl.compile_shader(raw);
            (gl.get_shader_compile_status(raw), gl.get_shader_info_log(raw))
        };
        if !compiled {
            return Err(GlError::ShaderCompile { name: name.to_owned(), stage, log });
        }
        gl_check!(gl)?;
        Ok(shader)
    }

    /// Vertex or fragment.
    pub fn stage(&self) -> ShaderStage {
        self.stage
    }
}

owns_gl_object!(Shader, glow::Shader, delete_shader);

/// A linked program.
#[derive(Debug)]
pub struct Program {
    gl: Rc<Gl>,
    raw: glow::Program,
    name: String,
}

impl Program {
    /// Compiles both stages and links them. `attributes` fixes attribute
    /// locations before linking, as GLSL ES 1.00 has no layout qualifiers.
    #[allow(unsafe_code)]
    pub fn build(
        gl: &Rc<Gl>,
        name: &str,
        vertex_source: &str,
        fragment_source: &str,
        attributes: &[(u32, &str)],
    ) -> Result<Program, GlError> {
        let vertex =
            Shader::compile(gl, ShaderStage::Vertex, &format!("{name}.vert"), vertex_source)?;
        let fragment =
            Shader::compile(gl, ShaderStage::Fragment, &format!("{name}.frag"), fragment_source)?;
        // SAFETY: creating a name needs only a current context.
        let raw = unsafe { gl.create_program() }
            .map_err(|reason| GlError::ObjectCreation { what: "program", reason })?;
        let program = Program { gl: Rc::clone(gl), raw, name: name.to_owned() };
        // SAFETY: `raw`, `vertex` and `fragment` are live objects of this
        // context; attribute names are passed as Rust strings glow converts.
        let (linked, log) = unsafe {
            gl.attach_shader(raw, vertex.raw());
            gl.attach_shader(raw, fragment.raw());
            for &(location, attribute) in attributes {
                gl.bind_attrib_location(raw, location, attribute);
            }
            gl.link_program(raw);
            let status = (gl.get_program_link_status(raw), gl.get_program_info_log(raw));
            // Detached, the shaders are freed when they drop below.
            gl.detach_shader(raw, vertex.raw());
            gl.detach_shader(raw, fragment.raw());
            status
        };
        if !linked {
            return Err(GlError::ProgramLink { name: name.to_owned(), log });
        }
        gl_check!(gl)?;
        Ok(program)
    }

    /// The name the program was built with (its shaders are `name.vert` and `name.frag`).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Makes this the current program (glUseProgram).
    #[allow(unsafe_code)]
    pub fn bind(&self) {
        // SAFETY: `raw` is a live, linked program of this context.
        unsafe { self.gl.use_program(Some(self.raw)) };
    }

    /// Where uniform `uniform` lives, or None when the program lacks it (or
    /// the compiler removed it as unused).
    #[allow(unsafe_code)]
    pub fn uniform_location(&self, uniform: &str) -> Option<glow::UniformLocation> {
        // SAFETY: `raw` is a live, linked program; glow converts the name.
        unsafe { self.gl.get_uniform_location(self.raw, uniform) }
    }
}

owns_gl_object!(Program, glow::Program, delete_program);
