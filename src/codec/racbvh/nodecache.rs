//! The decoded-node cache: complete node words by global node index, in a
//! fixed table shared by all threads, consulted before the cluster cache
//! when the budget cannot hold every cluster (see the module docs of
//! [`super`], "Node cache").
//!
//! A set-associative table of [`WAYS`]-way sets, each behind a sequence
//! lock made of atomics: readers never wait and never write (a set being
//! written reads as a miss), a writer that finds its set being written by
//! another thread skips its insert. Entries are never stale: a node's
//! complete words are the same however often its cluster is decoded.

use std::sync::atomic::{AtomicU32, AtomicU64, Ordering, fence};

use crate::codec::common::page_cache::LiveToken;

/// Ways per set.
pub const WAYS: usize = 8;

/// The most triangle ids an entry holds: a leaf with more triangles is
/// cached without them (its ids come from its cluster).
pub const MAX_LEAF_IDS: usize = 16;

// A set, in `u32` words: the sequence word (odd while written), the ways'
// reference bits (not-recently-used replacement), the ways' keys (node
// index + 1; 0 is empty), then per way the node's 8 words and, in a tree
// whose leaves hold several triangles, room for a leaf's ids.
const SEQ: usize = 0;
const USED: usize = 1;
const KEYS: usize = 2;
const ENTRIES: usize = KEYS + WAYS;

/// The table.
pub(super) struct NodeCache {
    words: Box<[AtomicU32]>,
    sets: usize,
    /// Triangle-id words per entry (0 when every leaf holds one triangle).
    ids: usize,
    /// Look-ups that missed (counted only on misses: a hit writes nothing
    /// unless it sets its way's reference bit).
    misses: AtomicU64,
    /// The table's bytes, counted with the cluster cache's live bytes.
    live: LiveToken,
}

impl NodeCache {
    /// Bytes of a set whose entries hold `ids` triangle ids.
    pub(super) const fn set_bytes(ids: usize) -> usize {
        4 * (ENTRIES + WAYS * (8 + ids))
    }

    /// The triangle-id words an entry gets in a tree whose leaves hold up
    /// to `max_leaf` triangles.
    pub(super) fn ids_for(max_leaf: u32) -> usize {
        if max_leaf > 1 {
            (max_leaf as usize).min(MAX_LEAF_IDS)
        } else {
            0
        }
    }

    /// A table of `sets` sets (at least one) with `ids` triangle-id words
    /// an entry, its bytes counted by `live`.
    pub(super) fn new(sets: usize, ids: usize, live: LiveToken) -> Self {
        let sets = sets.max(1);
        let n = sets * Self::set_bytes(ids) / 4;
        Self {
            words: (0..n).map(|_| AtomicU32::new(0)).collect(),
            sets,
            ids,
            misses: AtomicU64::new(0),
            live,
        }
    }

    /// Bytes of the table.
    pub(super) fn bytes(&self) -> usize {
        self.live.bytes()
    }

    /// Look-ups that missed.
    pub(super) fn misses(&self) -> u64 {
        self.misses.load(Ordering::Relaxed)
    }

    /// How many nodes the table holds.
    pub(super) fn capacity(&self) -> usize {
        self.sets * WAYS
    }

    /// The triangle ids an entry holds.
    pub(super) fn leaf_ids(&self) -> usize {
        self.ids
    }

    /// The words of the set node `g` maps to.
    #[inline]
    fn set(&self, g: u32) -> &[AtomicU32] {
        // Fibonacci hashing, then multiply-shift onto the set count.
        let h = u64::from(g.wrapping_mul(0x9E37_79B1));
        let set = ((h * self.sets as u64) >> 32) as usize;
        let len = Self::set_bytes(self.ids) / 4;
        &self.words[set * len..(set + 1) * len]
    }

    /// Runs `read` on the entry of node `g` (the set's words and the
    /// entry's first word) if it is cached, and returns its answer if no
    /// writer touched the set meanwhile.
    #[inline]
    fn read<R>(&self, g: u32, read: impl FnOnce(&[AtomicU32]) -> R) -> Option<R> {
        let s = self.set(g);
        let key = g.wrapping_add(1);
        let seq = s[SEQ].load(Ordering::Acquire);
        let way = (seq & 1 == 0)
            .then(|| (0..WAYS).find(|&w| s[KEYS + w].load(Ordering::Relaxed) == key))
            .flatten();
        let got = way.map(|w| read(&s[ENTRIES + w * (8 + self.ids)..][..8 + self.ids]));
        fence(Ordering::Acquire);
        match (got, way) {
            (Some(r), Some(w)) if s[SEQ].load(Ordering::Relaxed) == seq => {
                let bit = 1 << w;
                if s[USED].load(Ordering::Relaxed) & bit == 0 {
                    s[USED].fetch_or(bit, Ordering::Relaxed);
                }
                Some(r)
            }
            _ => {
                self.misses.fetch_add(1, Ordering::Relaxed);
                None
            }
        }
    }

    /// The complete words of node `g`, if cached.
    #[inline]
    pub(super) fn get(&self, g: u32) -> Option<[u32; 8]> {
        self.read(g, |e| std::array::from_fn(|k| e[k].load(Ordering::Relaxed)))
    }

    /// The `count` triangle ids of leaf `g`, if cached with them.
    pub(super) fn get_ids(&self, g: u32, count: usize) -> Option<[u32; MAX_LEAF_IDS]> {
        if count > self.ids {
            return None;
        }
        let (w7, ids) = self.read(g, |e| {
            let ids: [u32; MAX_LEAF_IDS] =
                std::array::from_fn(|k| e.get(8 + k).map_or(0, |x| x.load(Ordering::Relaxed)));
            (e[7].load(Ordering::Relaxed), ids)
        })?;
        (w7 == crate::build::LEAF_FLAG | count as u32).then_some(ids)
    }

    /// Caches the complete words of node `g` (and, for a leaf, its
    /// triangle ids, if the entry has room for them: else none), replacing
    /// an empty way, else one not used since the set's reference bits were
    /// last cleared.
    pub(super) fn insert(&self, g: u32, words: &[u32; 8], ids: &[u32]) {
        let s = self.set(g);
        let Some(seq) = begin_write(s) else {
            return;
        };
        let key = g.wrapping_add(1);
        let keys: [u32; WAYS] = std::array::from_fn(|w| s[KEYS + w].load(Ordering::Relaxed));
        let used = s[USED].load(Ordering::Relaxed);
        let way = if let Some(w) = keys.iter().position(|&k| k == key || k == 0) {
            w
        } else if let Some(w) = (0..WAYS).find(|&w| used & (1 << w) == 0) {
            w
        } else {
            // Every way used since the last clearing: start a new round.
            s[USED].store(0, Ordering::Relaxed);
            0
        };
        s[KEYS + way].store(key, Ordering::Relaxed);
        let e = &s[ENTRIES + way * (8 + self.ids)..][..8 + self.ids];
        for (slot, &w) in e.iter().zip(words.iter().chain(ids.iter().take(self.ids))) {
            slot.store(w, Ordering::Relaxed);
        }
        s[USED].fetch_or(1 << way, Ordering::Relaxed);
        s[SEQ].store(seq.wrapping_add(2), Ordering::Release);
    }

    /// Empties the table (sets being written by another thread at the same
    /// time may keep their entry).
    pub(super) fn clear(&self) {
        for s in self.words.chunks(Self::set_bytes(self.ids) / 4) {
            let Some(seq) = begin_write(s) else {
                continue;
            };
            s[USED..ENTRIES]
                .iter()
                .for_each(|k| k.store(0, Ordering::Relaxed));
            s[SEQ].store(seq.wrapping_add(2), Ordering::Release);
        }
    }
}

/// Takes set `s` for writing: its sequence word made odd (the value it had
/// is returned, to be stored plus two when the write is done), with a
/// release fence so that no write to the set is seen before it; `None`
/// when another thread is writing the set (the caller skips its write).
fn begin_write(s: &[AtomicU32]) -> Option<u32> {
    let seq = s[SEQ].load(Ordering::Relaxed);
    if seq & 1 != 0
        || s[SEQ]
            .compare_exchange(
                seq,
                seq.wrapping_add(1),
                Ordering::Relaxed,
                Ordering::Relaxed,
            )
            .is_err()
    {
        return None;
    }
    fence(Ordering::Release);
    Some(seq)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::codec::common::page_cache::Live;
    use std::sync::Arc;

    fn table(sets: usize, ids: usize) -> NodeCache {
        let live = Arc::new(Live::default());
        NodeCache::new(sets, ids, live.token(sets * NodeCache::set_bytes(ids)))
    }

    fn w(g: u32) -> [u32; 8] {
        std::array::from_fn(|k| g * 8 + k as u32)
    }

    #[test]
    fn a_set_keeps_its_recently_used_ways() {
        let c = table(1, 0);
        for g in 0..WAYS as u32 {
            c.insert(g, &w(g), &[]);
        }
        for g in 0..WAYS as u32 {
            assert_eq!(c.get(g), Some(w(g)));
        }
        // All ways used: a new round starts with way 0.
        c.insert(100, &w(100), &[]);
        assert_eq!(c.get(100), Some(w(100)));
        assert_eq!(c.get(0), None);
        // Node 1 is used again; the next insert takes a way not used since.
        assert_eq!(c.get(1), Some(w(1)));
        c.insert(101, &w(101), &[]);
        assert_eq!(c.get(1), Some(w(1)));
        assert_eq!(c.get(100), Some(w(100)));
        assert_eq!(
            c.get(2),
            None,
            "the first way not used since the round began"
        );
        // Node u32::MAX - 1 is the largest a tree has: its key is not 0
        // (empty).
        c.insert(u32::MAX - 1, &w(7), &[]);
        assert_eq!(c.get(u32::MAX - 1), Some(w(7)));
        let misses = c.misses();
        c.clear();
        assert_eq!(c.get(u32::MAX - 1), None);
        assert_eq!(c.get(1), None);
        assert_eq!(c.misses(), misses + 2);
    }

    #[test]
    fn a_leaf_keeps_its_triangle_ids_if_they_fit() {
        use crate::build::LEAF_FLAG;
        let c = table(3, NodeCache::ids_for(4));
        assert_eq!(NodeCache::ids_for(1), 0);
        assert_eq!(NodeCache::ids_for(100), MAX_LEAF_IDS);
        let mut leaf = w(5);
        leaf[7] = LEAF_FLAG | 3;
        c.insert(5, &leaf, &[9, 8, 7]);
        assert_eq!(c.get(5), Some(leaf));
        assert_eq!(
            c.get_ids(5, 3).map(|x| x[..3].to_vec()),
            Some(vec![9, 8, 7])
        );
        // A count the entry does not hold, or a node that is not that leaf.
        assert_eq!(c.get_ids(5, 2), None);
        assert_eq!(c.get_ids(5, 5), None);
        c.insert(6, &w(6), &[]);
        assert_eq!(c.get_ids(6, 3), None);
        assert_eq!(c.get_ids(7, 3), None);
    }

    #[test]
    fn threads_never_read_a_mixed_entry() {
        use crate::build::LEAF_FLAG;
        let c = table(2, 2);
        let entry = |g: u32| {
            let mut e = w(g);
            e[7] = LEAF_FLAG | 2;
            (e, [g * 3, g * 5])
        };
        std::thread::scope(|s| {
            for t in 0..4u32 {
                let c = &c;
                s.spawn(move || {
                    for k in 0..20_000u32 {
                        let g = (k * 7 + t) % 23;
                        let (e, ids) = entry(g);
                        if k % 3 == 0 {
                            c.insert(g, &e, &ids);
                        } else if let Some(got) = c.get(g) {
                            assert_eq!(got, e);
                        } else if let Some(got) = c.get_ids(g, 2) {
                            assert_eq!(got[..2], ids);
                        }
                    }
                });
            }
        });
    }
}
