//! A pyramid whose nodes come with their adaptive meshes: what `fly` and
//! `accuracy` page from. Opening builds the mesh file when it is missing or
//! belongs to another pyramid (an import, or an older cache).

use std::path::Path;
use std::sync::Arc;

use super::build::build_meshes;
use super::file::{mesh_file_name, pyramid_identity, write_meshes, MeshFile};
use super::{MeshOptions, MeshesError};
use crate::node::{NodeData, NodeError, NodeId, NodeLayout, NodeSource};
use crate::pyramid::{Progress, Pyramid};

/// The pyramid and its mesh file.
pub struct MeshedSource {
    pyramid: Arc<Pyramid>,
    file: MeshFile,
}

impl MeshedSource {
    /// Opens the mesh file beside `pyramid`, first building it with
    /// `options` when it is missing, damaged, or of another pyramid.
    pub fn open_or_build(
        pyramid: Arc<Pyramid>,
        options: MeshOptions,
        progress: &dyn Progress,
    ) -> Result<MeshedSource, MeshesError> {
        let path = mesh_path(pyramid.path(), &options);
        let layout = *pyramid.layout();
        let identity = pyramid_identity(pyramid.path())
            .map_err(|source| MeshesError::Io { path: pyramid.path().to_path_buf(), source })?;
        let file = match MeshFile::open(&path, &layout, identity) {
            Ok(file) if file.header().options == options => file,
            _ => {
                let built = build_meshes(pyramid.as_ref(), options, progress)?;
                write_meshes(&built, &layout, identity, &path)?;
                MeshFile::open(&path, &layout, identity)?
            }
        };
        Ok(MeshedSource { pyramid, file })
    }

    /// The pyramid the nodes' posts come from.
    pub fn pyramid(&self) -> &Arc<Pyramid> {
        &self.pyramid
    }

    /// The mesh file.
    pub fn file(&self) -> &MeshFile {
        &self.file
    }

    /// Largest mesh delta of each level, metres, finest first: what the
    /// distance rings are computed from.
    pub fn delta_per_level(&self) -> Vec<f64> {
        self.file.header().delta_per_level.iter().map(|&d| d as f64).collect()
    }
}

/// The file of meshes built with `options` beside the pyramid file at
/// `pyramid_file`.
pub fn mesh_path(pyramid_file: &Path, options: &MeshOptions) -> std::path::PathBuf {
    pyramid_file.with_file_name(mesh_file_name(options.error_m))
}

impl NodeSource for MeshedSource {
    fn layout(&self) -> &NodeLayout {
        self.pyramid.layout()
    }

    fn has_node(&self, id: NodeId) -> bool {
        self.pyramid.has_node(id)
    }

    /// The heights and the largest mesh of the file.
    fn node_bytes(&self) -> u64 {
        let side = self.pyramid.layout().stored_side() as u64;
        side * side * std::mem::size_of::<f32>() as u64 + self.file.largest_mesh_bytes()
    }

    /// The heights and the node's own mesh.
    fn node_bytes_of(&self, id: NodeId) -> u64 {
        let side = self.pyramid.layout().stored_side() as u64;
        let heights = side * side * std::mem::size_of::<f32>() as u64;
        heights + self.file.mesh_bytes(self.pyramid.layout(), id)
    }

    fn exact_height(&self, x_m: f64, y_m: f64) -> Result<f32, NodeError> {
        NodeSource::exact_height(self.pyramid.as_ref(), x_m, y_m)
    }

    /// The node's posts from the pyramid and its mesh from the mesh file;
    /// its delta is the mesh's, and its height range takes in every height
    /// and morph target of the mesh: a mesh takes posts finer than the
    /// node's own, whose peaks its posts' range does not hold, and the
    /// tiles' boxes (range widened by delta) must hold what is drawn, or a
    /// tile nearer than its box says is still morphing when it switches.
    fn read_node(&self, id: NodeId, out: &mut NodeData) -> Result<(), NodeError> {
        self.pyramid.read_node(id, out)?;
        debug_assert_eq!(out.grid_delta, out.delta, "the pyramid's posts");
        out.delta = self.file.read(self.pyramid.layout(), id, &mut out.mesh)?;
        for v in &out.mesh.vertices {
            for h in [v.height, v.target].into_iter().filter(|h| h.is_finite()) {
                out.min = out.min.min(h);
                out.max = out.max.max(h);
            }
        }
        Ok(())
    }
}
