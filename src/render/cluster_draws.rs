//! How the terrain pass walks a frame's clusters ([`super::cluster`]):
//! which clusters each part of the pass draws and in which order, the runs
//! of members each draws per depth slice, and the members' uniform array.
//! The GL terrain pass and the cost model both walk these.

#[cfg(feature = "test-support")]
use super::cluster::ClusterMorph;
use super::cluster::{Cluster, ClusterRun, Member, MAX_MEMBERS, MEMBER_FLOATS};
use super::draw_list::{DrawList, Slice, TileUniforms};

/// The bit of the terrain pass's part that draws depth slice `slice` with
/// the plain program or the no-data one. The parts are drawn in bit order.
pub fn part_bit(slice: Slice, no_data: bool) -> u8 {
    let slice = match slice {
        Slice::Far => 0,
        Slice::Near => 2,
    };
    1 << (slice + no_data as u8)
}

impl TileUniforms {
    /// The tile's six uniform vectors, as `u_members[6 slot]` to
    /// `u_members[6 slot + 5]` take them: south-west post, vertex step and
    /// skirt shares (four bits per edge); morph start, end, the deepest
    /// skirt's depth and its node centre's row; on the ellipsoid, the node
    /// centre's camera-relative offset and column, and its rotation
    /// ([`crate::earth::NodePlace::vectors`]; zero in the chart); a
    /// projected grid's node series ([`crate::earth::Expansion::uniforms`]).
    pub fn member_uniforms(&self) -> [f32; MEMBER_FLOATS] {
        let [x, y] = self.first_post;
        let [start, end] = self.morph;
        let shares = self.packed_skirt_shares();
        let [ox, oy, oz, cx, qx, qy, qz, qw] = self.place.vectors();
        let cy = self.place.centre[1];
        let e = self.place.expansion;
        [
            x,
            y,
            self.vertex_step,
            shares,
            start,
            end,
            self.skirt_depth,
            cy,
            ox,
            oy,
            oz,
            cx,
            qx,
            qy,
            qz,
            qw,
            e[0],
            e[1],
            e[2],
            e[3],
            e[4],
            e[5],
            e[6],
            // The expansion's last float is free: the shader's
            // `u_members[6 slot + 5].w`.
            self.sub_morph_end,
        ]
    }
}

impl DrawList {
    /// Whether the frame is drawn as clusters (else one draw per tile).
    pub fn clustered(&self) -> bool {
        self.clustered
    }

    /// Whether some tile or cluster drawn in `slice` has no data (then the
    /// pass switches to the no-data program after the others).
    pub fn has_no_data_in(&self, slice: Slice) -> bool {
        if self.clustered {
            self.clusters_with(slice, true, None).next().is_some()
        } else {
            self.tiles_with(slice, true).next().is_some()
        }
    }

    /// Whether tile `tile` reaches into depth slice `slice`.
    pub fn tile_in(&self, tile: &TileUniforms, slice: Slice) -> bool {
        let Some(frame) = self.uniforms else { return false };
        let (near, far) = frame.slices.tile_slices(tile, &frame, self.grid_size as f32);
        match slice {
            Slice::Near => near,
            Slice::Far => far,
        }
    }

    /// The clusters with a member in `slice`, with or without no data, in
    /// draw order: those of attribute base `bound` (the one last set)
    /// first, then the other bases, those that the next part also draws
    /// last (so it can start with the base this part ends with); within a
    /// base, list order. The GL terrain pass and the cost model both walk
    /// this.
    pub fn clusters_with(
        &self,
        slice: Slice,
        no_data: bool,
        bound: Option<u32>,
    ) -> impl Iterator<Item = &Cluster> + '_ {
        let part = part_bit(slice, no_data);
        // The next part with clusters, in drawing order.
        let later = self.clusters.iter().fold(0u8, |all, c| all | c.parts) & !(2 * part - 1);
        let next = later & later.wrapping_neg();
        let in_next = move |base: u32| {
            next != 0 && self.clusters.iter().any(|c| c.base == base && c.parts & next != 0)
        };
        let phase = move |k: u8| {
            self.clusters.iter().filter(move |c| {
                c.parts & part != 0
                    && match k {
                        0 => Some(c.base) == bound,
                        1 => Some(c.base) != bound && !in_next(c.base),
                        _ => Some(c.base) != bound && in_next(c.base),
                    }
            })
        };
        phase(0).chain(phase(1)).chain(phase(2))
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
            #[cfg_attr(not(feature = "test-support"), allow(unused_mut))]
            let mut uniforms = tile.member_uniforms();
            #[cfg(feature = "test-support")]
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
