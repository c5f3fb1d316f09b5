//! A fast hasher for the crate's internal maps, whose keys (integers, ids,
//! vertex bits) come from no adversary that matters: std's default SipHash
//! is several times slower and showed up in profiles of the mesh welder,
//! the RACBVH encoder's dictionaries and the per-triangle-pair manifold
//! bookkeeping.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// Multiply-rotate mixing of each word written, murmur3's finaliser on
/// [`Hasher::finish`] so every input bit reaches the high and low bits.
#[derive(Default, Clone, Copy)]
pub(crate) struct FastHasher(u64);

const K: u64 = 0x9e37_79b9_7f4a_7c15;

impl FastHasher {
    #[inline]
    fn mix(&mut self, w: u64) {
        self.0 = (self.0.rotate_left(23) ^ w).wrapping_mul(K);
    }
}

impl Hasher for FastHasher {
    #[inline]
    fn finish(&self) -> u64 {
        let mut h = self.0;
        h ^= h >> 33;
        h = h.wrapping_mul(0xff51_afd7_ed55_8ccd);
        h ^= h >> 33;
        h = h.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
        h ^ (h >> 33)
    }

    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        let mut chunks = bytes.chunks_exact(8);
        for c in &mut chunks {
            self.mix(u64::from_le_bytes(c.try_into().expect("8 bytes")));
        }
        for &b in chunks.remainder() {
            self.mix(u64::from(b));
        }
    }

    #[inline]
    fn write_u32(&mut self, x: u32) {
        self.mix(u64::from(x));
    }

    #[inline]
    fn write_u64(&mut self, x: u64) {
        self.mix(x);
    }

    #[inline]
    fn write_u128(&mut self, x: u128) {
        self.mix(x as u64);
        self.mix((x >> 64) as u64);
    }

    #[inline]
    fn write_usize(&mut self, x: usize) {
        self.mix(x as u64);
    }
}

/// A `HashMap` with [`FastHasher`].
pub(crate) type FastMap<K, V> = HashMap<K, V, BuildHasherDefault<FastHasher>>;

#[cfg(test)]
mod tests {
    use super::*;
    use std::hash::{BuildHasher, Hash};

    #[test]
    fn nearby_keys_spread_over_buckets() {
        // Consecutive ids and id pairs: the low bits of the hashes (which
        // pick hashbrown's buckets) take many values, and no two collide.
        let b = BuildHasherDefault::<FastHasher>::default();
        let mut seen = std::collections::HashSet::new();
        let mut low = std::collections::HashSet::new();
        for i in 0u32..64 {
            for j in 0u32..64 {
                let h = b.hash_one((i, j));
                assert!(seen.insert(h), "({i}, {j}) collides");
                low.insert(h & 1023);
            }
        }
        assert!(low.len() > 900, "{}", low.len());
        let mut m: FastMap<u128, u32> = FastMap::default();
        for k in 0..1000u128 {
            m.insert(k << 64 | k, k as u32);
        }
        assert!((0..1000u128).all(|k| m[&(k << 64 | k)] == k as u32));
        let mut h = FastHasher::default();
        [1u8, 2, 3].hash(&mut h);
        assert_ne!(h.finish(), FastHasher::default().finish());
    }
}
