//! Hashing for small integer keys (node ids, map posts): the tables that
//! look them up run thousands of times a frame and need no protection
//! against adversarial keys, so the default SipHash is replaced by a
//! rotate-xor accumulation finished with MurmurHash3's 64-bit mix, which
//! spreads neighbouring keys over all bits.

use std::hash::{BuildHasherDefault, Hasher};

#[derive(Default, Clone, Copy)]
/// The hasher; see the module.
pub(crate) struct IdHasher(u64);

impl Hasher for IdHasher {
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

/// Builds [`IdHasher`]s, for `HashMap`'s third parameter.
pub(crate) type BuildIdHasher = BuildHasherDefault<IdHasher>;
