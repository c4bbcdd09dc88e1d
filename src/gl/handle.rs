//! The shared GL handle every owner type holds: the loaded function table, the
//! context's capabilities, and whether the context is still alive.
//!
//! Owner types free their object on Drop only while the context lives; once
//! [`super::GlContext`] is dropped, destroying the context has freed them and
//! calling into GL would reach a context that no longer exists.

use std::cell::Cell;
use std::ops::Deref;

use super::caps::Capabilities;

/// One context's function table. Shared as `Rc<Gl>`: GL contexts are bound
/// to one thread, and so is this.
pub struct Gl {
    glow: glow::Context,
    caps: Capabilities,
    alive: Cell<bool>,
}

impl Gl {
    pub(crate) fn new(glow: glow::Context, caps: Capabilities) -> Gl {
        Gl { glow, caps, alive: Cell::new(true) }
    }

    /// What the context can do at the requested level.
    pub fn caps(&self) -> &Capabilities {
        &self.caps
    }

    /// False once the owning [`super::GlContext`] has been dropped.
    pub fn is_alive(&self) -> bool {
        self.alive.get()
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
