//! Cluster draws (Judnich & Ling's batches): what the GL terrain pass and the
//! cost model need to draw a frame's clusters, each of up to 16 tiles, with
//! one glDrawElements per cluster and depth slice.
//!
//! A cluster's block (made by `crate::clusters`) holds its member tiles'
//! vertices one after another, each vertex carrying its member's slot, then
//! one list of 16-bit indices numbered from the cluster's attribute base
//! ([`Cluster::base`]). Clusters whose bases agree share their attribute
//! pointers, so the pass sets them only when the base changes. The vertex
//! shader takes the member's placement, morph and skirts from
//! `u_members[2 slot]` and `u_members[2 slot + 1]` (a uniform array indexed
//! by a vertex attribute: GLSL ES 1.00 allows it in vertex shaders).

use super::draw_list::{DrawList, Slice, TileUniforms};

/// Most tiles a cluster holds: the 16 of a two-level cluster.
pub const MAX_MEMBERS: usize = 16;

/// Floats of one member's uniforms: two vec4.
pub const MEMBER_FLOATS: usize = 8;

/// Which morph range each member of a cluster takes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub enum ClusterMorph {
    /// Its own tile's (what per-tile drawing does): the right one.
    #[default]
    PerMember,
    /// The first member's, for every member: deliberately broken, so
    /// tests can show that the crack and pop tests catch a wrong cluster
    /// morph (members of two levels then morph over one level's range).
    FirstMember,
}

/// In which order a frame's clusters are drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub enum ClusterOrder {
    /// Grouped by attribute base (each base's pointers set once a part),
    /// the groups by their nearest cluster, nearest first within a group.
    #[default]
    ByBase,
    /// Nearest first (by each cluster's nearest member), as tiles are:
    /// early depth rejection, at the price of more pointer changes.
    NearestFirst,
}

/// One cluster of the frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cluster {
    /// Byte offset, in the GPU buffer, of vertex 0 of its indices: where
    /// its attribute pointers point (a multiple of the vertex size).
    pub base: u32,
    /// Byte offset of its first index.
    pub index_byte_offset: u32,
    /// Its first member in [`DrawList::members`] (its members follow in
    /// block order).
    pub first_member: u32,
    /// How many members it has (1 to [`MAX_MEMBERS`]).
    pub member_count: u32,
    /// Some member has posts without data: drawn by the voids program.
    pub voids: bool,
}

/// One member tile of a cluster.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Member {
    /// The tile, an index into [`DrawList::tiles`].
    pub tile: u32,
    /// Its slot in the cluster (0..16): which `u_members` entries its
    /// vertices read.
    pub slot: u8,
    /// Its first index, counted from the cluster's first index.
    pub first_index: u32,
    /// Its indices (its tile's, rebased).
    pub index_count: u32,
}

/// One glDrawElements of a cluster: consecutive members in one depth slice.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ClusterRun {
    /// Byte offset of its first index.
    pub index_byte_offset: u32,
    /// Indices drawn.
    pub index_count: u32,
}

impl TileUniforms {
    /// The tile's two uniform vectors, as `u_members[2 slot]` and
    /// `u_members[2 slot + 1]` take them: south-west post, vertex step and
    /// skirt edges; morph start, end and skirt depth.
    pub fn member_uniforms(&self) -> [f32; MEMBER_FLOATS] {
        let [x, y] = self.first_post;
        let [start, end] = self.morph;
        [x, y, self.vertex_step, self.skirt_edges as f32, start, end, self.skirt_depth, 0.0]
    }
}

impl DrawList {
    /// Whether the frame is drawn as clusters (else one draw per tile).
    pub fn clustered(&self) -> bool {
        self.clustered
    }

    /// Whether some tile or cluster drawn in `slice` has voids (then the
    /// pass switches to the voids program after the others).
    pub fn has_voids_in(&self, slice: Slice) -> bool {
        if self.clustered {
            self.clusters_with(slice, true, None).next().is_some()
        } else {
            self.tiles_with(slice, true).next().is_some()
        }
    }

    /// Whether tile `tile` reaches into depth slice `slice`.
    pub fn tile_in(&self, tile: &TileUniforms, slice: Slice) -> bool {
        let Some(frame) = self.uniforms else { return false };
        let (near, far) = frame.slices.tile_slices(tile, &frame.posts, self.grid_size as f32);
        match slice {
            Slice::Near => near,
            Slice::Far => far,
        }
    }

    /// The clusters with a member in `slice`, with or without voids, in
    /// draw order: those of attribute base `bound` (the one last set)
    /// first, then the rest in list order (grouped by base, nearest group
    /// first). The GL terrain pass and the cost model both walk this.
    pub fn clusters_with(
        &self,
        slice: Slice,
        voids: bool,
        bound: Option<u32>,
    ) -> impl Iterator<Item = &Cluster> + '_ {
        let wanted = move |c: &&Cluster| c.voids == voids && self.runs(c, slice).next().is_some();
        let first = self.clusters.iter().filter(move |c| Some(c.base) == bound).filter(wanted);
        let rest = self.clusters.iter().filter(move |c| Some(c.base) != bound).filter(wanted);
        first.chain(rest)
    }

    /// The members of `cluster`.
    pub fn members_of(&self, cluster: &Cluster) -> &[Member] {
        let first = cluster.first_member as usize;
        &self.members[first..first + cluster.member_count as usize]
    }

    /// The draws of `cluster` in `slice`: each run of consecutive members
    /// that reach into it (one run when the range is not cut).
    pub fn runs<'a>(
        &'a self,
        cluster: &'a Cluster,
        slice: Slice,
    ) -> impl Iterator<Item = ClusterRun> + 'a {
        let members = self.members_of(cluster);
        let inside = move |k: usize| self.tile_in(&self.tiles[members[k].tile as usize], slice);
        let mut k = 0;
        std::iter::from_fn(move || {
            while k < members.len() && !inside(k) {
                k += 1;
            }
            if k == members.len() {
                return None;
            }
            let first = members[k];
            let mut count = 0;
            while k < members.len() && inside(k) {
                count += members[k].index_count;
                k += 1;
            }
            Some(ClusterRun {
                index_byte_offset: cluster.index_byte_offset
                    + first.first_index * crate::tiles::block::INDEX_BYTES,
                index_count: count,
            })
        })
    }

    /// The uniform array of `cluster`: each member's [`TileUniforms::member_uniforms`]
    /// at its slot, written into `out`; returns how many floats to send
    /// (up to the highest slot used).
    pub fn cluster_uniforms(
        &self,
        cluster: &Cluster,
        out: &mut [f32; MAX_MEMBERS * MEMBER_FLOATS],
    ) -> usize {
        let mut used = 0;
        let members = self.members_of(cluster);
        for member in members {
            let at = member.slot as usize * MEMBER_FLOATS;
            let tile = &self.tiles[member.tile as usize];
            let mut uniforms = tile.member_uniforms();
            if self.cluster_morph == ClusterMorph::FirstMember {
                let first = &self.tiles[members[0].tile as usize];
                uniforms[4..6].copy_from_slice(&first.morph);
            }
            out[at..at + MEMBER_FLOATS].copy_from_slice(&uniforms);
            used = used.max(at + MEMBER_FLOATS);
        }
        used
    }
}
