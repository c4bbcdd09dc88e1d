//! Headless desktop OpenGL through OSMesa, loaded at run time from
//! `libOSMesa.so.8` (or `.so`), for regression tests that must not depend on
//! EGL. OSMesa gives desktop GL, so the GLSL ES shaders run through
//! GL_ARB_ES2_compatibility; the compatibility profile is asked for because
//! it keeps vertex array object 0 usable, as ES 2.0 code expects.

use std::ffi::{c_char, c_int, c_void, CStr};
use std::ptr::NonNull;
use std::sync::OnceLock;

use super::error::GlError;

const BACKEND: &str = "OSMesa";
/// Tried in order; the versioned name first, as Debian ships the bare name
/// only with the -dev package.
const LIBRARY_NAMES: [&str; 3] = ["libOSMesa.so.8", "libOSMesa.so", "libOSMesa.so.6"];

// From GL/osmesa.h.
const OSMESA_RGBA: c_int = 0x1908;
const OSMESA_FORMAT: c_int = 0x22;
const OSMESA_DEPTH_BITS: c_int = 0x30;
const OSMESA_STENCIL_BITS: c_int = 0x31;
const OSMESA_ACCUM_BITS: c_int = 0x32;
const OSMESA_PROFILE: c_int = 0x33;
const OSMESA_COMPAT_PROFILE: c_int = 0x35;
const GL_UNSIGNED_BYTE: u32 = 0x1401;

type CreateContextAttribs = unsafe extern "C" fn(*const c_int, *mut c_void) -> *mut c_void;
type CreateContextExt = unsafe extern "C" fn(u32, c_int, c_int, c_int, *mut c_void) -> *mut c_void;
type MakeCurrent = unsafe extern "C" fn(*mut c_void, *mut c_void, u32, c_int, c_int) -> u8;
type DestroyContext = unsafe extern "C" fn(*mut c_void);
type GetProcAddress = unsafe extern "C" fn(*const c_char) -> *const c_void;

/// The entry points, resolved once per process. The library is never
/// unloaded: llvmpipe keeps worker threads running inside it.
struct OsMesaApi {
    create_attribs: Option<CreateContextAttribs>,
    create_ext: CreateContextExt,
    make_current: MakeCurrent,
    destroy: DestroyContext,
    get_proc_address: GetProcAddress,
    /// The file name that loaded, for reports.
    name: &'static str,
    _library: libloading::Library,
}

static API: OnceLock<Result<OsMesaApi, (String, String)>> = OnceLock::new();

fn api() -> Result<&'static OsMesaApi, GlError> {
    API.get_or_init(|| load(&LIBRARY_NAMES)).as_ref().map_err(|(library, reason)| {
        GlError::LibraryMissing { library: library.clone(), reason: reason.clone() }
    })
}

/// Loads the first of `names` that exists; on failure, the names tried and
/// why each failed.
#[allow(unsafe_code)]
fn load(names: &[&'static str]) -> Result<OsMesaApi, (String, String)> {
    let mut failures = Vec::new();
    for &name in names {
        // SAFETY: loading libOSMesa runs Mesa's initialisers, which have no
        // preconditions on the caller.
        match unsafe { libloading::Library::new(name) } {
            Ok(library) => {
                return resolve(library, name).map_err(|reason| (name.to_owned(), reason))
            }
            Err(e) => failures.push(e.to_string()),
        }
    }
    Err((names.join(" or "), failures.join("; ")))
}

#[allow(unsafe_code)]
fn resolve(library: libloading::Library, name: &'static str) -> Result<OsMesaApi, String> {
    // SAFETY: each symbol is read with the signature GL/osmesa.h gives it;
    // the copied pointers stay valid because the library is never unloaded.
    unsafe {
        Ok(OsMesaApi {
            create_attribs: symbol(&library, b"OSMesaCreateContextAttribs\0").ok(),
            create_ext: symbol(&library, b"OSMesaCreateContextExt\0")?,
            make_current: symbol(&library, b"OSMesaMakeCurrent\0")?,
            destroy: symbol(&library, b"OSMesaDestroyContext\0")?,
            get_proc_address: symbol(&library, b"OSMesaGetProcAddress\0")?,
            name,
            _library: library,
        })
    }
}

/// Copies a function pointer out of the library.
///
/// # Safety
/// `T` must be the symbol's true type, and the library must outlive the copy.
#[allow(unsafe_code)]
unsafe fn symbol<T: Copy>(library: &libloading::Library, name: &[u8]) -> Result<T, String> {
    // SAFETY: forwarded to the caller (see above).
    unsafe { library.get::<T>(name) }
        .map(|found| *found)
        .map_err(|e| format!("{}: {e}", String::from_utf8_lossy(&name[..name.len() - 1])))
}

/// An OSMesa context bound to a 1x1 colour buffer of its own; drawing goes
/// to an offscreen framebuffer, so the buffer only has to exist.
pub(crate) struct OsMesaContext {
    api: &'static OsMesaApi,
    raw: NonNull<c_void>,
    /// Handed to OSMesaMakeCurrent; boxed so it never moves.
    buffer: Box<[u8; 4]>,
}

impl OsMesaContext {
    pub(crate) fn open() -> Result<(OsMesaContext, glow::Context), GlError> {
        let api = api()?;
        let raw = create(api).ok_or_else(|| {
            creation("OSMesaCreateContextAttribs/Ext returned NULL for an RGBA compatibility-profile context")
        })?;
        let context = OsMesaContext { api, raw, buffer: Box::new([0; 4]) };
        context.make_current()?;
        let glow = context.load_glow();
        Ok((context, glow))
    }

    /// Which library runs it, for reports.
    pub(crate) fn platform(&self) -> String {
        format!("OSMesa from {}", self.api.name)
    }

    #[allow(unsafe_code)]
    pub(crate) fn make_current(&self) -> Result<(), GlError> {
        // SAFETY: `raw` is a live context, and `buffer` is a 1x1 RGBA
        // UNSIGNED_BYTE image that lives (without moving) as long as it does.
        let ok = unsafe {
            (self.api.make_current)(
                self.raw.as_ptr(),
                self.buffer.as_ptr() as *mut c_void,
                GL_UNSIGNED_BYTE,
                1,
                1,
            )
        };
        if ok == 0 {
            return Err(creation("OSMesaMakeCurrent failed"));
        }
        Ok(())
    }

    #[allow(unsafe_code)]
    fn load_glow(&self) -> glow::Context {
        let get = self.api.get_proc_address;
        // SAFETY: the context is current; OSMesaGetProcAddress returns entry
        // points of the library, which stays loaded, or null.
        unsafe { glow::Context::from_loader_function_cstr(|name: &CStr| get(name.as_ptr())) }
    }
}

/// Asks for RGBA, no depth or stencil in the OSMesa buffer (the offscreen
/// framebuffer has its own) and the compatibility profile; falls back to
/// OSMesaCreateContextExt on libraries older than 11.2.
#[allow(unsafe_code)]
fn create(api: &OsMesaApi) -> Option<NonNull<c_void>> {
    let attributes = [
        OSMESA_FORMAT,
        OSMESA_RGBA,
        OSMESA_DEPTH_BITS,
        0,
        OSMESA_STENCIL_BITS,
        0,
        OSMESA_ACCUM_BITS,
        0,
        OSMESA_PROFILE,
        OSMESA_COMPAT_PROFILE,
        0,
    ];
    // SAFETY: the attribute list is zero-terminated as OSMesa requires and
    // outlives the call; no context is shared.
    let raw = unsafe {
        match api.create_attribs {
            Some(create) => create(attributes.as_ptr(), std::ptr::null_mut()),
            None => (api.create_ext)(OSMESA_RGBA as u32, 0, 0, 0, std::ptr::null_mut()),
        }
    };
    NonNull::new(raw)
}

impl Drop for OsMesaContext {
    #[allow(unsafe_code)]
    fn drop(&mut self) {
        // SAFETY: `raw` is a live context destroyed exactly once; the buffer
        // is freed only after this, when the fields drop.
        unsafe { (self.api.destroy)(self.raw.as_ptr()) };
    }
}

fn creation(reason: &str) -> GlError {
    GlError::ContextCreation { backend: BACKEND, reason: reason.to_owned() }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_library_is_named() {
        let Err((library, reason)) = load(&["libRidgelineAbsent.so.1", "libRidgelineAbsent.so"])
        else {
            panic!("a library that does not exist loaded");
        };
        assert_eq!(library, "libRidgelineAbsent.so.1 or libRidgelineAbsent.so");
        assert!(reason.contains("libRidgelineAbsent.so.1"), "{reason}");
    }
}
