//! A mesh file, `meshes-12m.rlm` beside the pyramid (one per error): little-endian, versioned,
//! checksummed per record, memory-mapped, written atomically.
//!
//! ```text
//! header  magic "RIDGEMSH", version u32, levels u32, nodes u64,
//!         error_m f32, depth u32, tile_cells u32, pyramid u32 (see below),
//!         per level: delta_max f32, then crc32 of all of the above
//! table   per node of the pyramid's layout, in its node order (24 bytes):
//!         offset u64 (u64::MAX: absent), vertices u32, indices u32,
//!         delta f32, crc32 of (node index, record)
//! records post_level u32, the vertices (16 bytes each, [`MeshVertex`]),
//!         the indices (u16), zero padding to 4 bytes
//! ```
//!
//! `pyramid` is the CRC-32 of the first 64 KiB of the pyramid file (its
//! header and node table, or all of it): a mesh file built for another
//! pyramid, or for an earlier import of this one, is refused at open and
//! rebuilt by the caller.

use std::fs::File;
use std::io::{BufWriter, Read, Write};
use std::path::{Path, PathBuf};

use memmap2::Mmap;

use super::build::BuiltMeshes;
use super::MeshesError;
use crate::node::{MeshVertex, NodeError, NodeId, NodeLayout, NodeMesh};
use crate::pyramid::replace_file;

#[cfg(target_endian = "big")]
compile_error!("the mesh file is read by casting little-endian bytes");

/// The mesh file's name in a pyramid's cache directory, for meshes of
/// `error_m` at level 1 (files of several errors live side by side).
pub fn mesh_file_name(error_m: f32) -> String {
    format!("meshes-{error_m}m.rlm")
}
const MAGIC: [u8; 8] = *b"RIDGEMSH";
/// 6: vertex posts in half steps, cell centres of fans at odd ones.
const VERSION: u32 = 7;
const FIXED_LEN: usize = 40;
const ENTRY_LEN: usize = 24;
const ABSENT: u64 = u64::MAX;
/// Bytes of the pyramid file its identity covers.
const PYRAMID_ID_BYTES: u64 = 64 * 1024;

/// What the header says.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshHeader {
    /// The options the meshes were built with.
    pub options: super::MeshOptions,
    /// Largest mesh delta of each level, finest first.
    pub delta_per_level: Vec<f32>,
    /// Identity of the pyramid file the meshes belong to.
    pub pyramid: u32,
}

/// The identity of the pyramid file at `path` (see the module notes).
pub fn pyramid_identity(path: &Path) -> std::io::Result<u32> {
    let mut bytes = Vec::new();
    File::open(path)?.take(PYRAMID_ID_BYTES).read_to_end(&mut bytes)?;
    Ok(crc32fast::hash(&bytes))
}

/// Writes `meshes` (built for `layout`, the pyramid of identity `pyramid`)
/// to `path` atomically.
pub fn write_meshes(
    meshes: &BuiltMeshes,
    layout: &NodeLayout,
    pyramid: u32,
    path: &Path,
) -> Result<(), MeshesError> {
    let io = |path: &Path, source| MeshesError::Io { path: path.to_path_buf(), source };
    replace_file(
        path,
        |temporary| {
            let file = File::create(temporary).map_err(|e| io(temporary, e))?;
            let mut out = BufWriter::new(file);
            encode(meshes, layout, pyramid, &mut out).map_err(|e| io(temporary, e))?;
            let file = out.into_inner().map_err(|e| io(temporary, e.into_error()))?;
            file.sync_all().map_err(|e| io(temporary, e))
        },
        io,
    )
}

fn encode(
    meshes: &BuiltMeshes,
    layout: &NodeLayout,
    pyramid: u32,
    out: &mut impl Write,
) -> std::io::Result<()> {
    let deltas = meshes.delta_per_level();
    let mut header = Vec::with_capacity(FIXED_LEN + 4 * deltas.len() + 4);
    header.extend_from_slice(&MAGIC);
    header.extend_from_slice(&VERSION.to_le_bytes());
    header.extend_from_slice(&(layout.levels as u32).to_le_bytes());
    header.extend_from_slice(&layout.node_count().to_le_bytes());
    header.extend_from_slice(&meshes.options.error_m.to_le_bytes());
    header.extend_from_slice(&(meshes.options.depth as u32).to_le_bytes());
    header.extend_from_slice(&meshes.options.tile_cells.to_le_bytes());
    header.extend_from_slice(&pyramid.to_le_bytes());
    for delta in &deltas {
        header.extend_from_slice(&delta.to_le_bytes());
    }
    header.extend_from_slice(&crc32fast::hash(&header).to_le_bytes());
    out.write_all(&header)?;
    let table_end = header.len() + ENTRY_LEN * layout.node_count() as usize;
    let mut offset = table_end as u64;
    let mut index = 0u64;
    let mut records = Vec::new();
    for level in 0..layout.levels {
        let [nx, ny] = layout.nodes_at(level);
        for y in 0..ny {
            for x in 0..nx {
                let id = NodeId::new(level, x, y);
                let entry = match meshes.mesh(layout, id) {
                    Some(built) => {
                        let record = record_bytes(&built.mesh);
                        let crc = record_crc(index, &record);
                        let entry = Entry {
                            offset,
                            vertices: built.mesh.vertices.len() as u32,
                            indices: built.mesh.indices.len() as u32,
                            delta: built.delta,
                            crc,
                        };
                        offset += record.len() as u64;
                        records.push(record);
                        entry
                    }
                    None => Entry { offset: ABSENT, vertices: 0, indices: 0, delta: 0.0, crc: 0 },
                };
                out.write_all(&entry.encode())?;
                index += 1;
            }
        }
    }
    for record in records {
        out.write_all(&record)?;
    }
    Ok(())
}

fn record_bytes(mesh: &NodeMesh) -> Vec<u8> {
    let mut bytes = Vec::with_capacity(4 + 16 * mesh.vertices.len() + 2 * mesh.indices.len() + 2);
    bytes.extend_from_slice(&(mesh.post_level as u32).to_le_bytes());
    bytes.extend_from_slice(bytemuck::cast_slice(&mesh.vertices));
    bytes.extend_from_slice(bytemuck::cast_slice(&mesh.indices));
    bytes.resize(bytes.len().next_multiple_of(4), 0);
    bytes
}

fn record_crc(index: u64, record: &[u8]) -> u32 {
    let mut hasher = crc32fast::Hasher::new();
    hasher.update(&index.to_le_bytes());
    hasher.update(record);
    hasher.finalize()
}

/// One node's table entry.
#[derive(Clone, Copy, Debug)]
struct Entry {
    offset: u64,
    vertices: u32,
    indices: u32,
    delta: f32,
    crc: u32,
}

impl Entry {
    fn encode(&self) -> [u8; ENTRY_LEN] {
        let mut out = [0u8; ENTRY_LEN];
        out[0..8].copy_from_slice(&self.offset.to_le_bytes());
        out[8..12].copy_from_slice(&self.vertices.to_le_bytes());
        out[12..16].copy_from_slice(&self.indices.to_le_bytes());
        out[16..20].copy_from_slice(&self.delta.to_le_bytes());
        out[20..24].copy_from_slice(&self.crc.to_le_bytes());
        out
    }

    fn decode(bytes: &[u8]) -> Entry {
        let u32_at = |k: usize| u32::from_le_bytes(bytes[k..k + 4].try_into().expect("4 bytes"));
        Entry {
            offset: u64::from_le_bytes(bytes[0..8].try_into().expect("8 bytes")),
            vertices: u32_at(8),
            indices: u32_at(12),
            delta: f32::from_bits(u32_at(16)),
            crc: u32_at(20),
        }
    }

    /// Bytes of the record the entry describes.
    fn record_len(&self) -> u64 {
        (4 + 16 * self.vertices as u64 + 2 * self.indices as u64).next_multiple_of(4)
    }
}

/// An open mesh file.
pub struct MeshFile {
    path: PathBuf,
    map: Mmap,
    header: MeshHeader,
    table: usize,
    nodes: u64,
}

impl MeshFile {
    /// Opens and checks the header of the mesh file at `path`, which must
    /// belong to the pyramid of `layout` and identity `pyramid`.
    pub fn open(path: &Path, layout: &NodeLayout, pyramid: u32) -> Result<MeshFile, MeshesError> {
        let io = |source| MeshesError::Io { path: path.to_path_buf(), source };
        let file = File::open(path).map_err(io)?;
        let map = map_file(&file).map_err(io)?;
        let corrupt = |problem: String| MeshesError::Corrupt { path: path.to_path_buf(), problem };
        let (header, table) = decode_header(&map, layout).map_err(corrupt)?;
        if header.pyramid != pyramid {
            return Err(corrupt("built for another pyramid (or an earlier import)".into()));
        }
        let nodes = layout.node_count();
        let end = table as u64 + nodes * ENTRY_LEN as u64;
        if (map.len() as u64) < end {
            return Err(corrupt(format!(
                "truncated: {} bytes, the table ends at {end}",
                map.len()
            )));
        }
        Ok(MeshFile { path: path.to_path_buf(), map, header, table, nodes })
    }

    /// The heap, bytes, the largest mesh of the file takes once read
    /// (its vertices and indices; [`MeshFile::read`] reserves exactly).
    pub fn largest_mesh_bytes(&self) -> u64 {
        (0..self.nodes as usize).map(|index| self.entry_bytes(index)).max().unwrap_or(0)
    }

    /// The heap, bytes, node `id`'s mesh takes once read; 0 when the file
    /// has none for it.
    pub fn mesh_bytes(&self, layout: &NodeLayout, id: NodeId) -> u64 {
        match layout.node_index(id) {
            Some(index) if index < self.nodes => self.entry_bytes(index as usize),
            _ => 0,
        }
    }

    fn entry_bytes(&self, index: usize) -> u64 {
        let at = self.table + index * ENTRY_LEN;
        let entry = Entry::decode(&self.map[at..at + ENTRY_LEN]);
        if entry.offset == ABSENT {
            return 0;
        }
        let vertex = std::mem::size_of::<MeshVertex>() as u64;
        vertex * entry.vertices as u64 + 2 * entry.indices as u64
    }

    /// What the header says.
    pub fn header(&self) -> &MeshHeader {
        &self.header
    }

    /// The path the file was opened from.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Reads node `id`'s mesh into `out`, reusing its buffers, and returns
    /// its delta; a damaged record is [`NodeError::Corrupt`] and leaves
    /// `out` as it was. An absent node has an empty mesh.
    pub fn read(
        &self,
        layout: &NodeLayout,
        id: NodeId,
        out: &mut NodeMesh,
    ) -> Result<f32, NodeError> {
        let index = layout.node_index(id).ok_or(NodeError::OutOfRange { id })?;
        let corrupt = |problem: String| NodeError::Corrupt { path: self.path.clone(), id, problem };
        debug_assert!(index < self.nodes);
        let at = self.table + index as usize * ENTRY_LEN;
        let entry = Entry::decode(&self.map[at..at + ENTRY_LEN]);
        if entry.offset == ABSENT {
            return Err(NodeError::Absent { id });
        }
        let end =
            entry.offset.checked_add(entry.record_len()).filter(|&e| e <= self.map.len() as u64);
        let Some(end) = end else {
            return Err(corrupt(format!("mesh record past the end of the file ({entry:?})")));
        };
        let record = &self.map[entry.offset as usize..end as usize];
        if record_crc(index, record) != entry.crc {
            return Err(corrupt("mesh record checksum mismatch".into()));
        }
        decode_record(record, &entry, out).map_err(corrupt)?;
        Ok(entry.delta)
    }
}

fn decode_record(record: &[u8], entry: &Entry, out: &mut NodeMesh) -> Result<(), String> {
    let post_level = u32::from_le_bytes(record[0..4].try_into().expect("4 bytes"));
    let vertex_end = 4 + 16 * entry.vertices as usize;
    let vertices: &[MeshVertex] = bytemuck::try_cast_slice(&record[4..vertex_end])
        .map_err(|e| format!("mesh vertices: {e}"))?;
    let index_bytes = &record[vertex_end..vertex_end + 2 * entry.indices as usize];
    let indices: &[u16] =
        bytemuck::try_cast_slice(index_bytes).map_err(|e| format!("mesh indices: {e}"))?;
    let bad_index = indices.iter().any(|&i| i as u32 >= entry.vertices);
    if post_level > 255 || entry.indices % 3 != 0 || bad_index || entry.vertices > 65_536 {
        return Err(format!("mesh record is not a mesh ({entry:?})"));
    }
    out.post_level = post_level as u8;
    // Exactly: a buffer grows to the largest mesh read into it, no further
    // (what a memory budget counts a slot at).
    out.vertices.clear();
    out.vertices.reserve_exact(vertices.len());
    out.vertices.extend_from_slice(vertices);
    out.indices.clear();
    out.indices.reserve_exact(indices.len());
    out.indices.extend_from_slice(indices);
    Ok(())
}

fn decode_header(bytes: &[u8], layout: &NodeLayout) -> Result<(MeshHeader, usize), String> {
    if bytes.len() < FIXED_LEN || bytes[0..8] != MAGIC {
        return Err("not a Ridgeline mesh file".into());
    }
    let u32_at = |k: usize| u32::from_le_bytes(bytes[k..k + 4].try_into().expect("4 bytes"));
    let version = u32_at(8);
    if version != VERSION {
        return Err(format!("mesh file version {version}, this build reads {VERSION}"));
    }
    let levels = u32_at(12) as usize;
    let nodes = u64::from_le_bytes(bytes[16..24].try_into().expect("8 bytes"));
    if levels != layout.levels as usize || nodes != layout.node_count() {
        return Err(format!("{levels} levels and {nodes} nodes, the pyramid has other"));
    }
    let crc_at = FIXED_LEN + 4 * levels;
    if bytes.len() < crc_at + 4 {
        return Err("truncated header".into());
    }
    if crc32fast::hash(&bytes[..crc_at]) != u32_at(crc_at) {
        return Err("header checksum mismatch".into());
    }
    let options = super::MeshOptions {
        error_m: f32::from_bits(u32_at(24)),
        depth: u32_at(28).min(255) as u8,
        tile_cells: u32_at(32),
    };
    options.validate(layout).map_err(|e| e.to_string())?;
    let delta_per_level: Vec<f32> =
        (0..levels).map(|l| f32::from_bits(u32_at(FIXED_LEN + 4 * l))).collect();
    if delta_per_level.iter().any(|d| !(d.is_finite() && *d >= 0.0)) {
        return Err(format!("level deltas {delta_per_level:?} are not distances"));
    }
    let header = MeshHeader { options, delta_per_level, pyramid: u32_at(36) };
    Ok((header, crc_at + 4))
}

#[allow(unsafe_code)]
fn map_file(file: &File) -> std::io::Result<Mmap> {
    // SAFETY: as for the pyramid (see `pyramid::open::map_file`): the file
    // is only ever replaced by rename, never written in place by us; every
    // record read checks its checksum, so a foreign writer surfaces as
    // NodeError::Corrupt; no slice of the map outlives the call that made it.
    unsafe { Mmap::map(file) }
}
