//! The hasher of the crate's internal maps: foldhash's fast hasher with a
//! fixed seed. Their keys (integers, ids, vertex bits) come from no
//! adversary that matters, and std's default SipHash is several times
//! slower: it showed up in profiles of the mesh welder, the o-HCCMesh
//! encoder's dictionaries and the per-triangle-pair manifold bookkeeping.
//!
//! foldhash is already in every build through `hashbrown` (parry3d's and
//! lru's), so it costs no crate; it replaced a hand-written multiply-rotate
//! hasher after a benchmark showed no loss. The seed is fixed, not drawn
//! per process: no map's iteration order reaches an output today, and a
//! fixed seed keeps it that way if one ever does (the same file, byte for
//! byte, from every run).

use std::collections::HashMap;

/// A `HashMap` with foldhash's fast hasher under a fixed seed.
pub(crate) type FastMap<K, V> = HashMap<K, V, foldhash::fast::FixedState>;

#[cfg(test)]
mod tests {
    use super::*;
    use std::hash::BuildHasher;

    #[test]
    fn nearby_keys_spread_over_buckets() {
        // Consecutive ids and id pairs: the low bits of the hashes (which
        // pick hashbrown's buckets) take many values, and no two collide.
        let b = foldhash::fast::FixedState::default();
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
        // The seed is fixed: two maps (and two processes) hash alike.
        assert_eq!(
            b.hash_one(12345u64),
            foldhash::fast::FixedState::default().hash_one(12345u64)
        );
    }
}
