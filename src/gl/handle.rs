//! The shared GL handle every owner type holds: the loaded function table, the
//! context's capabilities, and whether the context is still alive.
//!
//! Owner types free their object on Drop only while the context lives; once
//! [`super::GlContext`] is dropped, destroying the context has freed them and
//! calling into GL would reach a context that no longer exists.

use std::cell::Cell;
use std::ops::Deref;

use super::caps::Capabilities;
use crate::render::CallStats;

/// One context's function table. Shared as `Rc<Gl>`: GL contexts are bound
/// to one thread, and so is this.
pub struct Gl {
    glow: glow::Context,
    caps: Capabilities,
    alive: Cell<bool>,
    /// Calls made through [`super::calls::Calls`] since the last take.
    calls: Cell<CallStats>,
}

impl Gl {
    pub(crate) fn new(glow: glow::Context, caps: Capabilities) -> Gl {
        Gl { glow, caps, alive: Cell::new(true), calls: Cell::new(CallStats::default()) }
    }

    /// Takes over a context the caller made and keeps current (an
    /// integrator's own window system or render loop): reads what it can do
    /// at `version` and refuses one that cannot compile GLSL ES 1.00. The
    /// caller keeps the context alive and current while any Ridgeline object
    /// made from it lives, and drops those objects before destroying it.
    pub fn adopt(
        glow: glow::Context,
        version: super::GlesVersion,
    ) -> Result<std::rc::Rc<Gl>, super::GlError> {
        let caps = Capabilities::detect(&glow, version);
        if !caps.glsl_es_100 {
            let why = "the context cannot compile GLSL ES 1.00 (no GL_ARB_ES2_compatibility)";
            return Err(super::GlError::InvalidRequest(why.to_owned()));
        }
        Ok(std::rc::Rc::new(Gl::new(glow, caps)))
    }

    /// What the context can do at the requested level.
    pub fn caps(&self) -> &Capabilities {
        &self.caps
    }

    /// False once the owning [`super::GlContext`] has been dropped.
    pub fn is_alive(&self) -> bool {
        self.alive.get()
    }

    /// The calls counted since the last take, and a new count from zero.
    pub fn take_calls(&self) -> CallStats {
        self.calls.take()
    }

    pub(crate) fn tally(&self, f: impl FnOnce(&mut CallStats)) {
        let mut calls = self.calls.get();
        f(&mut calls);
        self.calls.set(calls);
    }

    /// Called by the context just before it is destroyed.
    pub(crate) fn mark_dead(&self) {
        self.alive.set(false);
    }
}

impl Deref for Gl {
    type Target = glow::Context;

    fn deref(&self) -> &glow::Context {
        debug_assert!(self.is_alive(), "GL call after its context was dropped");
        &self.glow
    }
}

impl std::fmt::Debug for Gl {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Gl").field("caps", &self.caps).field("alive", &self.alive).finish()
    }
}
