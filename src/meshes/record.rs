//! One node's record in the map file (format 2, issue 21: about a fifth
//! of format 1's bytes), little-endian:
//!
//! ```text
//! head  kind u8 (0 dense, 1 sparse with its heights, 2 sparse with the
//!       pyramid's heights), post_level u8, edges u8 (bit 0
//!       hierarchy_leaves, bits 4 to 7 shared_edges: 0 in maps built
//!       before them, whose edges are all their own), key
//!       coding u8 (0 gaps, 1 bitmask), cells u32, floor_m f32,
//!       reference_delta f32, count u32, key_bytes u32, height_base f32,
//!       height_step f32 (kind 1; else 0)
//! body  dense: count codes (u8)
//!       sparse: keys (key_bytes: LEB128 of each key less the previous
//!       one less 1, the first less -1; or one bit per post of the
//!       lattice, row-major, whichever is shorter), count codes (u8);
//!       kind 1: count heights (u16 steps of height_step above
//!       height_base, 65535 for no data), count normals ([i8; 2])
//!       zero padding to 4 bytes
//! ```
//!
//! Kind 2's heights and normals are the pyramid's at its keys: page-in
//! reads them from the nodes under the map's node ([`super::pagein`]).
//! Kind 1's heights were rounded to their steps at build (the map's
//! reference delta holds the half step), so they read back bit for bit.

use super::build::{dequantise, quantise};
use crate::node::ErrorMap;

/// Bytes of a record's head.
pub const RECORD_HEAD: usize = 32;
/// A map with a code for every post.
pub const DENSE: u32 = 0;
/// A sparse map storing its heights and normals.
pub const STORED: u32 = 1;
/// A sparse map whose heights and normals are the pyramid's.
pub const FROM_PYRAMID: u32 = 2;
const GAPS: u8 = 0;
const BITMASK: u8 = 1;
/// The height step code of a post without data.
const NO_DATA: u16 = u16::MAX;

/// The record's kind for `map`.
pub fn kind_of(map: &ErrorMap) -> u32 {
    match (map.is_dense(), map.height_step > 0.0) {
        (true, _) => DENSE,
        (false, true) => STORED,
        (false, false) => FROM_PYRAMID,
    }
}

/// Encodes `map`'s record: its bytes (padded to 4) and its post count.
pub fn encode(map: &ErrorMap) -> (Vec<u8>, u32) {
    let kind = kind_of(map);
    let count = if kind == DENSE { map.codes.len() } else { map.keys.len() };
    let (coding, keys) = if kind == DENSE { (GAPS, Vec::new()) } else { encode_keys(map) };
    let base = match kind {
        STORED => {
            map.heights.iter().copied().filter(|h| h.is_finite()).fold(f32::INFINITY, f32::min)
        }
        _ => 0.0,
    };
    let base = if base.is_finite() { base } else { 0.0 };
    let mut bytes = Vec::with_capacity(RECORD_HEAD + keys.len() + 5 * count + 3);
    let edges = map.hierarchy_leaves as u8 | map.shared_edges << 4;
    bytes.extend_from_slice(&[kind as u8, map.post_level, edges, coding]);
    for word in [map.cells, map.floor_m.to_bits(), map.reference_delta.to_bits(), count as u32] {
        bytes.extend_from_slice(&word.to_le_bytes());
    }
    for word in [keys.len() as u32, base.to_bits(), map.height_step.to_bits()] {
        bytes.extend_from_slice(&word.to_le_bytes());
    }
    bytes.extend_from_slice(&keys);
    bytes.extend_from_slice(&map.codes);
    if kind == STORED {
        for &h in &map.heights {
            let q = if h.is_finite() { quantise(base, map.height_step, h) } else { NO_DATA };
            bytes.extend_from_slice(&q.to_le_bytes());
        }
        bytes.extend_from_slice(bytemuck::cast_slice(&map.normals));
    }
    bytes.resize(bytes.len().next_multiple_of(4), 0);
    (bytes, count as u32)
}

/// The shorter of the two key codings.
fn encode_keys(map: &ErrorMap) -> (u8, Vec<u8>) {
    let mut gaps = Vec::with_capacity(map.keys.len() + 8);
    let mut next = 0u32;
    for &key in &map.keys {
        let mut gap = key - next;
        while gap >= 0x80 {
            gaps.push(0x80 | (gap & 0x7f) as u8);
            gap >>= 7;
        }
        gaps.push(gap as u8);
        next = key + 1;
    }
    let posts = map.side() as usize * map.side() as usize;
    if gaps.len() <= posts.div_ceil(8) {
        return (GAPS, gaps);
    }
    let mut bits = vec![0u8; posts.div_ceil(8)];
    for &key in &map.keys {
        bits[key as usize / 8] |= 1 << (key % 8);
    }
    (BITMASK, bits)
}

/// What a record's head says.
pub struct Head {
    /// [`DENSE`], [`STORED`] or [`FROM_PYRAMID`].
    pub kind: u32,
    /// Reference-lattice cells a side.
    pub cells: u32,
    /// Posts the record keeps.
    pub count: usize,
}

/// Reads a record's head (at least [`RECORD_HEAD`] bytes, checked by the
/// caller).
pub fn head(record: &[u8]) -> Head {
    let u32_at = |k: usize| u32::from_le_bytes(record[k..k + 4].try_into().expect("4 bytes"));
    Head { kind: record[0] as u32, cells: u32_at(4), count: u32_at(16) as usize }
}

/// Decodes a record into `out` (a fresh map). A [`FROM_PYRAMID`] record
/// leaves the heights and normals to the caller.
pub fn decode(record: &[u8], out: &mut ErrorMap) -> Result<(), String> {
    let u32_at = |k: usize| u32::from_le_bytes(record[k..k + 4].try_into().expect("4 bytes"));
    let Head { kind, cells, count } = head(record);
    let side = cells as u64 + 1;
    if !(kind <= FROM_PYRAMID && cells.is_power_of_two() && cells <= 1 << 15) {
        return Err(format!("map record of kind {kind} and {cells} cells"));
    }
    out.post_level = record[1];
    if record[2] & 0x0e != 0 {
        return Err(format!("map record's edge byte {:#04x} sets unknown bits", record[2]));
    }
    out.hierarchy_leaves = record[2] & 1 != 0;
    out.shared_edges = record[2] >> 4;
    out.cells = cells;
    out.floor_m = f32::from_bits(u32_at(8));
    out.reference_delta = f32::from_bits(u32_at(12));
    if !(out.floor_m >= 0.0 && out.reference_delta >= 0.0) {
        return Err("map record's floor or reference delta is not a distance".into());
    }
    let body = &record[RECORD_HEAD..];
    if kind == DENSE {
        if count as u64 != side * side || body.len() < count {
            return Err("dense map record does not hold a code per post".into());
        }
        out.codes = body[..count].to_vec();
        return Ok(());
    }
    let key_bytes = u32_at(20) as usize;
    let per_post = if kind == STORED { 5 } else { 1 };
    if key_bytes.checked_add(per_post * count).is_none_or(|end| end > body.len()) {
        return Err("map record is shorter than its posts".into());
    }
    let (keys, rest) = body.split_at(key_bytes);
    out.keys = decode_keys(record[3], keys, count, side * side)?;
    let (codes, rest) = rest.split_at(count);
    out.codes = codes.to_vec();
    if kind == STORED {
        let (base, step) = (f32::from_bits(u32_at(24)), f32::from_bits(u32_at(28)));
        if !(base.is_finite() && step.is_finite() && step > 0.0) {
            return Err("map record's height steps are not finite".into());
        }
        out.height_step = step;
        let (heights, normals) = rest.split_at(2 * count);
        out.heights = heights
            .chunks_exact(2)
            .map(|q| match u16::from_le_bytes([q[0], q[1]]) {
                NO_DATA => f32::NAN,
                q => dequantise(base, step, q),
            })
            .collect();
        out.normals = bytemuck::pod_collect_to_vec(&normals[..2 * count]);
    }
    Ok(())
}

/// The keys of `count` posts of a lattice of `posts` posts, ascending.
fn decode_keys(coding: u8, bytes: &[u8], count: usize, posts: u64) -> Result<Vec<u32>, String> {
    let mut keys = Vec::with_capacity(count);
    match coding {
        GAPS => {
            let (mut next, mut gap, mut shift) = (0u64, 0u64, 0u32);
            for &b in bytes {
                if shift > 28 {
                    return Err("map record's key gap is too long".into());
                }
                gap |= ((b & 0x7f) as u64) << shift;
                shift += 7;
                if b & 0x80 == 0 {
                    let key = next + gap;
                    if key >= posts {
                        return Err("map record's posts are not inside the node".into());
                    }
                    keys.push(key as u32);
                    (next, gap, shift) = (key + 1, 0, 0);
                }
            }
            if shift != 0 {
                return Err("map record's keys end inside a gap".into());
            }
        }
        BITMASK if bytes.len() as u64 == posts.div_ceil(8) => {
            for (k, &b) in bytes.iter().enumerate() {
                let mut b = b;
                while b != 0 {
                    let key = (8 * k) as u64 + b.trailing_zeros() as u64;
                    if key >= posts {
                        return Err("map record's posts are not inside the node".into());
                    }
                    keys.push(key as u32);
                    b &= b - 1;
                }
            }
        }
        _ => return Err(format!("map record's key coding {coding} is not known")),
    }
    if keys.len() != count {
        return Err(format!("map record has {} keys, its head says {count}", keys.len()));
    }
    Ok(keys)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dense(shared_edges: u8, hierarchy_leaves: bool) -> ErrorMap {
        ErrorMap {
            cells: 2,
            codes: (0..9).collect(),
            shared_edges,
            hierarchy_leaves,
            ..ErrorMap::default()
        }
    }

    #[test]
    fn the_edge_byte_keeps_both_fields_and_rejects_unknown_bits() {
        for (shared, leaves) in [(0, false), (ErrorMap::WEST | ErrorMap::NORTH, true), (15, false)]
        {
            let (bytes, _) = encode(&dense(shared, leaves));
            let mut out = ErrorMap::default();
            decode(&bytes, &mut out).unwrap();
            assert_eq!((out.shared_edges, out.hierarchy_leaves), (shared, leaves));
        }
        let (mut bytes, _) = encode(&dense(0, false));
        bytes[2] = 2;
        let err = decode(&bytes, &mut ErrorMap::default()).unwrap_err();
        assert!(err.contains("edge byte 0x02"), "{err}");
    }
}
