//! A pyramid whose nodes come with their error maps: what `fly` and
//! `accuracy` page from. Opening builds the map file when it is missing or
//! belongs to another pyramid (an import, or an older cache).

use std::path::Path;
use std::sync::Arc;

use super::file::{build_store, pyramid_identity, MapFile, StoreInfo, MAP_FILE_NAME};
use super::{MeshOptions, MeshesError};
use crate::node::{NodeData, NodeError, NodeId, NodeLayout, NodeSource};
use crate::pyramid::{Progress, Pyramid};

/// The pyramid and its map file.
pub struct MeshedSource {
    pyramid: Arc<Pyramid>,
    file: MapFile,
}

impl MeshedSource {
    /// Opens the map file beside `pyramid`, first building it with
    /// `options` when it is missing, damaged, incomplete, or of another
    /// pyramid or other options.
    pub fn open_or_build(
        pyramid: Arc<Pyramid>,
        options: MeshOptions,
        progress: &dyn Progress,
    ) -> Result<MeshedSource, MeshesError> {
        let path = map_path(pyramid.path());
        let layout = *pyramid.layout();
        let identity = pyramid_identity(pyramid.path())
            .map_err(|source| MeshesError::Io { path: pyramid.path().to_path_buf(), source })?;
        let file = match MapFile::open(&path, &layout, identity) {
            Ok(file) if file.info().options == options && file.is_complete() => file,
            _ => {
                let nodes = stored_nodes(pyramid.as_ref());
                build_store(pyramid.as_ref(), identity, &nodes, options, &path, progress)?;
                MapFile::open(&path, &layout, identity)?
            }
        };
        Ok(MeshedSource { pyramid, file })
    }

    /// The pyramid the nodes' posts come from.
    pub fn pyramid(&self) -> &Arc<Pyramid> {
        &self.pyramid
    }

    /// The map file.
    pub fn file(&self) -> &MapFile {
        &self.file
    }

    /// What the map file's header says.
    pub fn info(&self) -> &StoreInfo {
        self.file.info()
    }

    /// The error of each level's finest mesh, metres, finest level first:
    /// what the rings' Ulrich rule is computed from.
    pub fn delta_per_level(&self) -> Vec<f64> {
        self.file.info().finest_error_per_level()
    }
}

/// Every node `source` stores, in the layout's node order.
pub fn stored_nodes(source: &dyn NodeSource) -> Vec<NodeId> {
    let layout = source.layout();
    let mut nodes = Vec::new();
    for level in 0..layout.levels {
        let [nx, ny] = layout.nodes_at(level);
        for y in 0..ny {
            for x in 0..nx {
                let id = NodeId::new(level, x, y);
                if source.has_node(id) {
                    nodes.push(id);
                }
            }
        }
    }
    nodes
}

/// The map file beside the pyramid file at `pyramid_file`.
pub fn map_path(pyramid_file: &Path) -> std::path::PathBuf {
    pyramid_file.with_file_name(MAP_FILE_NAME)
}

impl NodeSource for MeshedSource {
    fn layout(&self) -> &NodeLayout {
        self.pyramid.layout()
    }

    fn has_node(&self, id: NodeId) -> bool {
        self.pyramid.has_node(id)
    }

    /// The heights and the largest map of the file.
    fn node_bytes(&self) -> u64 {
        let side = self.pyramid.layout().stored_side() as u64;
        side * side * std::mem::size_of::<f32>() as u64 + self.file.largest_map_bytes()
    }

    /// The heights and the node's own map.
    fn node_bytes_of(&self, id: NodeId) -> u64 {
        let side = self.pyramid.layout().stored_side() as u64;
        let heights = side * side * std::mem::size_of::<f32>() as u64;
        heights + self.file.map_bytes(self.pyramid.layout(), id)
    }

    fn exact_height(&self, x_m: f64, y_m: f64) -> Result<f32, NodeError> {
        NodeSource::exact_height(self.pyramid.as_ref(), x_m, y_m)
    }

    /// The node's posts from the pyramid and its map from the map file;
    /// its delta is its finest mesh's, and its height range takes in every
    /// height its map keeps: a map takes posts finer than the node's own,
    /// whose peaks its posts' range does not hold, and the tiles' boxes
    /// must hold what is drawn.
    fn read_node(&self, id: NodeId, out: &mut NodeData) -> Result<(), NodeError> {
        self.pyramid.read_node(id, out)?;
        self.file.read(self.pyramid.as_ref(), id, &mut out.map)?;
        out.delta = out.map.floor_m + out.map.reference_delta;
        for &h in out.map.heights.iter().filter(|h| h.is_finite()) {
            out.min = out.min.min(h);
            out.max = out.max.max(h);
        }
        Ok(())
    }
}
