//! The owner types on a real (headless EGL, llvmpipe) context: range checks,
//! typed compile and link errors with the driver's log, GL errors naming file
//! and line, refusals before the GL is asked, and objects outliving their
//! context.

use std::rc::Rc;
use std::sync::Mutex;

use glam::UVec2;
use ridgeline::gl::{
    Buffer, BufferTarget, BufferUsage, ContextRequest, GlBackend, GlContext, GlError, GlesVersion,
    Program, Renderbuffer, ShaderStage, VertexArray,
};

/// llvmpipe already uses every core; contexts take turns.
static SERIAL: Mutex<()> = Mutex::new(());

fn egl(version: GlesVersion) -> GlContext {
    GlContext::new(&ContextRequest::new(GlBackend::Egl, version, UVec2::new(16, 16)))
        .expect("headless EGL context")
}

const VERTEX: &str =
    "#version 100\nattribute vec2 a_position;\nvoid main() { gl_Position = vec4(a_position, 0.0, 1.0); }\n";

#[test]
fn buffer_writes_ranges_inside_and_refuses_past_the_end() {
    let _turn = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let context = egl(GlesVersion::Es2);
    for target in [BufferTarget::Vertices, BufferTarget::Indices] {
        let buffer = Buffer::new(context.gl(), target, 64, BufferUsage::Dynamic).expect("buffer");
        assert_eq!(buffer.size(), 64);
        buffer.upload_range(0, &[1; 64]).expect("whole buffer");
        buffer.upload_range(60, &[2; 4]).expect("last four bytes");
        buffer.upload_range(64, &[]).expect("empty write at the end");
        for (offset, len) in [(61, 4), (65, 0), (0, 65), (usize::MAX, 1)] {
            match buffer.upload_range(offset, &vec![0; len]) {
                Err(GlError::InvalidRequest(message)) => {
                    assert!(message.contains("overruns"), "{message}")
                }
                other => panic!("offset {offset} len {len}: expected a refusal, got {other:?}"),
            }
        }
    }
    let too_big = Buffer::new(context.gl(), BufferTarget::Vertices, 1 << 31, BufferUsage::Static);
    assert!(matches!(too_big, Err(GlError::InvalidRequest(_))), "{too_big:?}");
}

#[test]
fn compile_and_link_errors_carry_the_driver_log() {
    let _turn = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let context = egl(GlesVersion::Es2);
    let broken =
        "#version 100\nprecision mediump float;\nvoid main() { gl_FragColor = undeclared; }\n";
    match Program::build(context.gl(), "broken", VERTEX, broken, &[(0, "a_position")]) {
        Err(GlError::ShaderCompile { name, stage, log }) => {
            assert_eq!((name.as_str(), stage), ("broken.frag", ShaderStage::Fragment));
            assert!(log.contains("undeclared"), "log: {log}");
        }
        other => panic!("expected a compile error, got {other:?}"),
    }
    // The fragment shader reads a varying the vertex shader never declares.
    let unmatched = "#version 100\nprecision mediump float;\nvarying vec4 v_missing;\nvoid main() { gl_FragColor = v_missing; }\n";
    match Program::build(context.gl(), "unmatched", VERTEX, unmatched, &[]) {
        Err(GlError::ProgramLink { name, log }) => {
            assert_eq!(name, "unmatched");
            assert!(log.contains("v_missing"), "log: {log}");
        }
        other => panic!("expected a link error, got {other:?}"),
    }
    let error = GlError::ShaderCompile {
        name: "x.frag".into(),
        stage: ShaderStage::Fragment,
        log: "L".into(),
    };
    assert_eq!(error.to_string(), "fragment shader `x.frag` failed to compile:\nL");
}

#[test]
fn es3_shaders_compile_where_the_level_allows() {
    let _turn = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let context = egl(GlesVersion::Es3);
    assert!(context.caps().glsl_es_300);
    let vertex = "#version 300 es\nlayout(location = 0) in vec2 a_position;\nvoid main() { gl_Position = vec4(a_position, 0.0, 1.0); }\n";
    let fragment =
        "#version 300 es\nprecision mediump float;\nout vec4 colour;\nvoid main() { colour = vec4(1.0); }\n";
    let program =
        Program::build(context.gl(), "es3", vertex, fragment, &[]).expect("GLSL ES 3.00 program");
    assert!(program.uniform_location("absent").is_none());
    VertexArray::new(context.gl()).expect("ES 3 has vertex arrays").bind();
}

#[cfg(debug_assertions)]
#[test]
fn gl_errors_name_the_file_and_line() {
    let _turn = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let context = egl(GlesVersion::Es3);
    // 0x1234 is no internal format: glRenderbufferStorage raises GL_INVALID_ENUM.
    match Renderbuffer::new(context.gl(), 0x1234, UVec2::new(4, 4)) {
        Err(GlError::Gl { code, name, file, line }) => {
            assert_eq!((code, name), (0x0500, "GL_INVALID_ENUM"));
            assert!(file.ends_with("framebuffer.rs"), "{file}");
            assert!(line > 0);
        }
        other => panic!("expected a GL error, got {other:?}"),
    }
}

#[test]
fn render_targets_refuse_sizes_before_the_gl() {
    let _turn = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let context = egl(GlesVersion::Es3);
    let max = context.caps().limits.max_renderbuffer_size as u32;
    assert!(max >= 2048, "GL_MAX_RENDERBUFFER_SIZE {max}");
    for size in [UVec2::new(0, 4), UVec2::new(4, 0), UVec2::new(max + 1, 4)] {
        let refused = Renderbuffer::new(context.gl(), glow::RGBA8, size);
        assert!(matches!(refused, Err(GlError::InvalidRequest(_))), "{size}: {refused:?}");
    }
    let zero =
        GlContext::new(&ContextRequest::new(GlBackend::Egl, GlesVersion::Es3, UVec2::new(0, 8)));
    assert!(matches!(zero, Err(GlError::InvalidRequest(_))), "zero-sized headless target accepted");
}

#[test]
fn objects_outliving_their_context_are_not_freed_twice() {
    let _turn = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let context = egl(GlesVersion::Es3);
    let gl = Rc::clone(context.gl());
    let buffer = Buffer::new(&gl, BufferTarget::Vertices, 16, BufferUsage::Static).expect("buffer");
    let program = Program::build(
        &gl,
        "kept",
        VERTEX,
        "#version 100\nvoid main() { gl_FragColor = vec4(1.0); }\n",
        &[],
    )
    .expect("program");
    assert!(gl.is_alive());
    drop(context);
    assert!(!gl.is_alive(), "the handle must know its context is gone");
    // Dropping now must not call into the destroyed context.
    drop(buffer);
    drop(program);
}
