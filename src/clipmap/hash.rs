//! Hashing for node ids: the clipmap looks up thousands of ids per frame and
//! needs no protection against adversarial keys, so the default SipHash is
//! replaced by a rotate-xor accumulation finished with MurmurHash3's 64-bit
//! mix, which spreads the grid coordinates over all bits.

use std::collections::{HashMap, HashSet};
use std::hash::{BuildHasherDefault, Hasher};

use crate::node::NodeId;

#[derive(Default, Clone, Copy)]
pub(crate) struct NodeIdHasher(u64);

impl Hasher for NodeIdHasher {
    fn write(&mut self, bytes: &[u8]) {
        for &byte in bytes {
            self.write_u64(byte as u64);
        }
    }

    fn write_u8(&mut self, value: u8) {
        self.write_u64(value as u64);
    }

    fn write_u32(&mut self, value: u32) {
        self.write_u64(value as u64);
    }

    fn write_u64(&mut self, value: u64) {
        self.0 = self.0.rotate_left(26) ^ value;
    }

    fn finish(&self) -> u64 {
        let mut h = self.0;
        h ^= h >> 33;
        h = h.wrapping_mul(0xff51_afd7_ed55_8ccd);
        h ^= h >> 33;
        h = h.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
        h ^ (h >> 33)
    }
}

type BuildNodeIdHasher = BuildHasherDefault<NodeIdHasher>;
pub(crate) type NodeMap<V> = HashMap<NodeId, V, BuildNodeIdHasher>;
pub(crate) type NodeSet = HashSet<NodeId, BuildNodeIdHasher>;

pub(crate) fn node_map<V>(capacity: usize) -> NodeMap<V> {
    NodeMap::with_capacity_and_hasher(capacity, BuildNodeIdHasher::default())
}

pub(crate) fn node_set(capacity: usize) -> NodeSet {
    NodeSet::with_capacity_and_hasher(capacity, BuildNodeIdHasher::default())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::hash::BuildHasher;

    #[test]
    fn neighbouring_ids_spread_over_the_buckets() {
        // 4096 neighbouring ids into 8192 buckets by the low bits, as the
        // hash table does: nearly all distinct, like a random hash.
        let build = BuildNodeIdHasher::default();
        let mut buckets = std::collections::HashSet::new();
        for y in 0..64 {
            for x in 0..64 {
                buckets.insert(build.hash_one(NodeId::new(3, 1000 + x, 2000 + y)) & 8191);
            }
        }
        assert!(buckets.len() > 3000, "{} distinct buckets", buckets.len());
    }
}
