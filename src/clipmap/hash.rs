//! Tables of node ids: the clipmap looks up thousands of ids per frame,
//! hashed by [`crate::hash::IdHasher`].

use std::collections::{HashMap, HashSet};

use crate::hash::BuildIdHasher;
use crate::node::NodeId;

pub(crate) type NodeMap<V> = HashMap<NodeId, V, BuildIdHasher>;
pub(crate) type NodeSet = HashSet<NodeId, BuildIdHasher>;

pub(crate) fn node_map<V>(capacity: usize) -> NodeMap<V> {
    NodeMap::with_capacity_and_hasher(capacity, BuildIdHasher::default())
}

pub(crate) fn node_set(capacity: usize) -> NodeSet {
    NodeSet::with_capacity_and_hasher(capacity, BuildIdHasher::default())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::hash::BuildHasher;

    #[test]
    fn neighbouring_ids_spread_over_the_buckets() {
        // 4096 neighbouring ids into 8192 buckets by the low bits, as the
        // hash table does: nearly all distinct, like a random hash.
        let build = BuildIdHasher::default();
        let mut buckets = std::collections::HashSet::new();
        for y in 0..64 {
            for x in 0..64 {
                buckets.insert(build.hash_one(NodeId::new(3, 1000 + x, 2000 + y)) & 8191);
            }
        }
        assert!(buckets.len() > 3000, "{} distinct buckets", buckets.len());
    }
}
