//! The maps between what the i-HCCMesh stores and the input mesh's
//! numbering: [`IdMap`] (triangles: storage rank ↔ input id) and
//! [`VertexIds`] (each stored vertex's index in the input mesh).
//!
//! # Why a map at all
//!
//! Leaves hold triangles implicitly, in the order the templates lay the
//! tree out, so a triangle's place in storage (its *rank*: leaves in
//! node-word order, low-level tree by low-level tree) is not its input id,
//! and cannot be made so: the templates fix where a leaf sits, and a leaf
//! has no room for an id. The cursor contract asks for input ids (ties in
//! queries go to the smaller id, so every codec answers alike) and for a
//! cheap `triangle(id)`, so both directions are needed.
//!
//! # [`IdMap`]: a permutation with cycle shortcuts
//!
//! Rank → id (`π`) is a frame-of-reference array (`ForArray`): O(1), and
//! narrower than `log2 n` bits where nearby leaves hold nearby ids. Id →
//! rank (`π⁻¹`) is not stored as a second array (that would cost another
//! `log2 n` bits a triangle) but found by walking `π`'s cycle from `id`
//! with shortcuts (Munro, Raman, Raman and Rao, "Succinct representations
//! of permutations", ICALP 2003): on every cycle longer than
//! [`SHORTCUT`], every `SHORTCUT`-th element is marked (a bit per rank,
//! with a running count every 64) and stores the element `SHORTCUT` steps
//! before it. `π⁻¹(id)` walks forward from `id` to the first mark, jumps
//! back, and walks forward again to `id`'s predecessor: at most
//! `SHORTCUT + 2` reads of `π`, for `1 + 0.5 + w / SHORTCUT` bits a
//! triangle (`w` the back pointers' width) instead of `w`.
//!
//! # Layout of the `ids` section
//! `π` as a `ForArray`, then the back pointers as a `ForArray` (one per
//! mark, in rank order), then the marks, `⌈n / 64⌉` little-endian `u64`s.
//! The running counts are rebuilt on load.
//!
//! # [`VertexIds`]
//!
//! For each stored vertex (the low-level trees' arrays one after the
//! other) its input index, a `ForArray`; and the input vertices no
//! triangle uses, with their positions, so that the decoded mesh is the
//! input mesh. Layout of the `vertex ids` section: the `ForArray`, then
//! the unused vertices' count (`u64`) and per vertex its index (`u32`)
//! and position (3 × `f32`).

use crate::codec::common::FormatError;
use crate::codec::common::le::{f32x3_at, u32_at, u64_at};
use crate::codec::common::packed::ForVec;

/// Steps between marks on a cycle of `π` (see the module docs): `π⁻¹`
/// costs at most `SHORTCUT + 2` reads of `π`.
pub const SHORTCUT: u32 = 8;

/// Storage rank ↔ input triangle id (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct IdMap {
    fwd: ForVec,
    back: ForVec,
    marks: Vec<u64>,
    /// Marks before each word of `marks`.
    mark_rank: Vec<u32>,
}

impl Default for IdMap {
    fn default() -> Self {
        Self::new(&[])
    }
}

fn running_counts(words: &[u64]) -> Vec<u32> {
    let mut before = 0;
    words
        .iter()
        .map(|w| {
            let r = before;
            before += w.count_ones();
            r
        })
        .collect()
}

impl IdMap {
    /// The map whose `π(rank) = ids[rank]`; `ids` must be a permutation of
    /// `0..ids.len()`.
    pub fn new(ids: &[u32]) -> Self {
        let n = ids.len();
        let mut marks = vec![0u64; n.div_ceil(64)];
        let mut back_of = Vec::new();
        let mut visited = vec![false; n];
        let mut cycle = Vec::new();
        for start in 0..n {
            if visited[start] {
                continue;
            }
            cycle.clear();
            let mut x = start;
            while !visited[x] {
                visited[x] = true;
                cycle.push(x as u32);
                x = ids[x] as usize;
            }
            let len = cycle.len();
            let t = SHORTCUT as usize;
            if len > t {
                for j in (0..len).step_by(t) {
                    let x = cycle[j] as usize;
                    marks[x / 64] |= 1 << (x % 64);
                    back_of.push((x as u32, cycle[(j + len - t) % len]));
                }
            }
        }
        back_of.sort_unstable();
        let back: Vec<u32> = back_of.iter().map(|p| p.1).collect();
        let mark_rank = running_counts(&marks);
        Self {
            fwd: ForVec::new(ids),
            back: ForVec::new(&back),
            marks,
            mark_rank,
        }
    }

    /// Number of triangles.
    pub(super) fn len(&self) -> u32 {
        self.fwd.len() as u32
    }

    /// The input id of the triangle at storage rank `rank` (`< len`).
    #[inline(always)]
    pub fn id(&self, rank: u32) -> u32 {
        self.fwd.get(u64::from(rank))
    }

    #[inline]
    fn marked(&self, x: u32) -> bool {
        self.marks[(x / 64) as usize] >> (x % 64) & 1 != 0
    }

    #[inline]
    fn back_of(&self, x: u32) -> u32 {
        let (w, b) = ((x / 64) as usize, x % 64);
        let k = self.mark_rank[w] + (self.marks[w] & ((1u64 << b) - 1)).count_ones();
        self.back.get(u64::from(k))
    }

    /// The storage rank of input triangle `id` (`< len`), or `None` when
    /// the map is not a permutation with sound shortcuts (a damaged file
    /// that `verify` has not seen).
    pub fn rank(&self, id: u32) -> Option<u32> {
        let n = self.len();
        if id >= n {
            return None;
        }
        let (mut x, mut jumped) = (id, false);
        for _ in 0..2 * SHORTCUT + 4 {
            let y = self.id(x);
            if y == id {
                return Some(x);
            }
            if !jumped && self.marked(x) {
                jumped = true;
                x = self.back_of(x);
            } else {
                x = y;
            }
            if x >= n {
                return None;
            }
        }
        None
    }

    /// Bytes in memory.
    pub fn bytes(&self) -> usize {
        self.fwd.bytes() + self.back.bytes() + self.marks.len() * 8 + self.mark_rank.len() * 4
    }

    /// The `ids` section (see the module docs).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.bytes());
        self.fwd.write(&mut out);
        self.back.write(&mut out);
        for w in &self.marks {
            out.extend_from_slice(&w.to_le_bytes());
        }
        out
    }

    /// Reads an `ids` section of `n` triangles; checks its frame (lengths,
    /// block heads), not the permutation ([`IdMap::verify`] does).
    pub fn parse(b: &[u8], n: u32) -> Result<Self, FormatError> {
        let (fwd, split) = ForVec::parse(b, 0, "ids")?;
        let (back, end) = ForVec::parse(b, split, "ids")?;
        let words = (n as usize).div_ceil(64);
        if fwd.len() != u64::from(n) || b.len() - end != words * 8 {
            return Err(FormatError::header(
                "ids",
                format!(
                    "{} ranks and {} bytes of marks for {n} triangles",
                    fwd.len(),
                    b.len() - end
                ),
            ));
        }
        let marks: Vec<u64> = (0..words).map(|k| u64_at(b, end + 8 * k)).collect();
        let total: u64 = marks.iter().map(|w| u64::from(w.count_ones())).sum();
        if total != back.len()
            || (!n.is_multiple_of(64) && marks.last().is_some_and(|w| w >> (n % 64) != 0))
        {
            return Err(FormatError::header(
                "ids",
                "the marks do not match the back pointers",
            ));
        }
        let mark_rank = running_counts(&marks);
        Ok(Self {
            fwd,
            back,
            marks,
            mark_rank,
        })
    }

    /// Proves that `π` is a permutation of `0..len` and that `π⁻¹` finds
    /// every id, in O(`len`): each cycle is walked once, checking that
    /// every mark's back pointer is the element `SHORTCUT` steps before it,
    /// that marks are at most `SHORTCUT` apart along a marked cycle, and
    /// that an unmarked cycle is short enough for `rank`'s walk.
    pub fn verify(&self) -> Result<(), &'static str> {
        let n = self.len();
        let mut seen = vec![false; n as usize];
        for r in 0..n {
            let id = self.id(r);
            if id >= n || std::mem::replace(&mut seen[id as usize], true) {
                return Err("the triangle ids are not a permutation");
            }
        }
        let t = SHORTCUT as usize;
        let mut visited = vec![false; n as usize];
        let mut cycle = Vec::new();
        for start in 0..n {
            if visited[start as usize] {
                continue;
            }
            cycle.clear();
            let mut x = start;
            while !std::mem::replace(&mut visited[x as usize], true) {
                cycle.push(x);
                x = self.id(x);
            }
            let len = cycle.len();
            let marks: Vec<usize> = (0..len).filter(|&j| self.marked(cycle[j])).collect();
            if marks.is_empty() {
                if len > 2 * t + 3 {
                    return Err("a long cycle of triangle ids has no shortcut");
                }
                continue;
            }
            for (k, &j) in marks.iter().enumerate() {
                let next = marks.get(k + 1).copied().unwrap_or(marks[0] + len);
                if next - j > t {
                    return Err("the triangle id shortcuts are too far apart");
                }
                if self.back_of(cycle[j]) != cycle[(j + len - t % len) % len] {
                    return Err("a triangle id shortcut points to the wrong place");
                }
            }
        }
        Ok(())
    }
}

/// Each stored vertex's input index, and the input vertices no triangle
/// uses (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct VertexIds {
    map: ForVec,
    /// Input vertices no triangle uses: index and position.
    pub unused: Vec<(u32, [f32; 3])>,
}

impl VertexIds {
    /// The map of stored vertex `s` to input vertex `ids[s]`, and the
    /// unused input vertices.
    pub fn new(ids: &[u32], unused: Vec<(u32, [f32; 3])>) -> Self {
        Self {
            map: ForVec::new(ids),
            unused,
        }
    }

    /// Number of stored vertices mapped.
    pub(super) fn len(&self) -> u32 {
        self.map.len() as u32
    }

    /// The input index of stored vertex `s` (`< len`).
    #[inline]
    pub fn get(&self, s: u32) -> u32 {
        self.map.get(u64::from(s))
    }

    /// Bytes in memory.
    pub fn bytes(&self) -> usize {
        self.map.bytes() + 8 + self.unused.len() * 16
    }

    /// The `vertex ids` section.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.bytes());
        self.map.write(&mut out);
        out.extend_from_slice(&(self.unused.len() as u64).to_le_bytes());
        for (i, p) in &self.unused {
            out.extend_from_slice(&i.to_le_bytes());
            for c in p {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
        out
    }

    /// Reads a `vertex ids` section for `stored` stored vertices.
    pub fn parse(b: &[u8], stored: u32) -> Result<Self, FormatError> {
        let (map, end) = ForVec::parse(b, 0, "vertex ids")?;
        let bad = |why: String| FormatError::header("vertex ids", why);
        if map.len() != u64::from(stored) {
            return Err(bad(format!(
                "{} entries for {stored} stored vertices",
                map.len()
            )));
        }
        if b.len() < end + 8 {
            return Err(FormatError::Truncated {
                section: "vertex ids",
                need: end as u64 + 8,
                have: b.len() as u64,
            });
        }
        let count = u64_at(b, end);
        if Some(b.len() as u64)
            != count
                .checked_mul(16)
                .and_then(|c| c.checked_add(end as u64 + 8))
        {
            return Err(bad(format!(
                "{count} unused vertices in {} bytes",
                b.len() - end - 8
            )));
        }
        let unused = (0..count as usize)
            .map(|k| {
                let at = end + 8 + 16 * k;
                (u32_at(b, at), f32x3_at(b, at + 4))
            })
            .collect();
        Ok(Self { map, unused })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn perm(n: u32, seed: u64) -> Vec<u32> {
        let mut p: Vec<u32> = (0..n).collect();
        let mut s = seed | 1;
        for i in (1..p.len()).rev() {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            p.swap(i, (s % (i as u64 + 1)) as usize);
        }
        p
    }

    #[test]
    fn inverse_by_shortcuts_finds_every_id() {
        for (n, seed) in [(0, 1), (1, 1), (2, 3), (9, 4), (100, 5), (5000, 6)] {
            let ids = perm(n, seed);
            let m = IdMap::new(&ids);
            m.verify().unwrap();
            for (r, &id) in ids.iter().enumerate() {
                assert_eq!(m.id(r as u32), id);
                assert_eq!(m.rank(id), Some(r as u32));
            }
            let back = IdMap::parse(&m.to_bytes(), n).unwrap();
            assert_eq!(back, m);
        }
        // One long cycle and the identity (cycles of length one).
        let n = 1000u32;
        for ids in [
            (0..n).map(|i| (i + 1) % n).collect::<Vec<_>>(),
            (0..n).collect(),
        ] {
            let m = IdMap::new(&ids);
            m.verify().unwrap();
            assert!(m.bytes() < 4 * n as usize);
        }
    }

    #[test]
    fn damaged_maps_are_caught() {
        let ids = perm(300, 9);
        let m = IdMap::new(&ids);
        let bytes = m.to_bytes();
        let mut rejected = 0;
        for k in 0..bytes.len() * 8 {
            let mut b = bytes.clone();
            b[k / 8] ^= 1 << (k % 8);
            match IdMap::parse(&b, 300) {
                Err(_) => rejected += 1,
                Ok(bad) => {
                    if bad.verify().is_err() {
                        rejected += 1;
                    } else {
                        // Accepted: still a sound map (a flip in padding).
                        for id in 0..300 {
                            assert_eq!(bad.id(bad.rank(id).unwrap()), id);
                        }
                    }
                }
            }
        }
        assert!(rejected > bytes.len() * 4, "{rejected} rejected");
    }

    /// `rank` finds every id: what `verify` has to guarantee.
    fn sound(m: &IdMap) -> bool {
        (0..m.len()).all(|id| m.rank(id).is_some_and(|r| m.id(r) == id))
    }

    /// A map from raw parts, bypassing `new`'s construction.
    fn raw(ids: &[u32], back: &[u32], marked: &[u32]) -> IdMap {
        let mut marks = vec![0u64; ids.len().div_ceil(64)];
        for &x in marked {
            marks[x as usize / 64] |= 1 << (x % 64);
        }
        let mark_rank = running_counts(&marks);
        IdMap {
            fwd: ForVec::new(ids),
            back: ForVec::new(back),
            marks,
            mark_rank,
        }
    }

    #[test]
    fn verify_rejects_bad_shortcuts_and_permutations() {
        let n = 100u32;
        // One cycle 0 → 1 → … → 99 → 0: marks every SHORTCUT-th element,
        // each pointing SHORTCUT steps back.
        let ids: Vec<u32> = (0..n).map(|i| (i + 1) % n).collect();
        let good = IdMap::new(&ids);
        good.verify().unwrap();
        assert!(sound(&good));
        let t = SHORTCUT;
        let marked: Vec<u32> = (0..n).step_by(t as usize).collect();
        let back: Vec<u32> = marked.iter().map(|&x| (x + n - t) % n).collect();
        assert_eq!(raw(&ids, &back, &marked), good);

        // A back pointer one step off.
        let mut off = back.clone();
        off[3] = (off[3] + 1) % n;
        assert!(raw(&ids, &off, &marked).verify().is_err());
        // A mark dropped (its back pointer with it): a gap of 2·SHORTCUT.
        let (mut m2, mut b2) = (marked.clone(), back.clone());
        m2.remove(5);
        b2.remove(5);
        let gap = raw(&ids, &b2, &m2);
        assert!(gap.verify().is_err());
        // No marks at all on a long cycle: `rank` gives up, `verify` says so.
        let bare = raw(&ids, &[], &[]);
        assert!(!sound(&bare));
        assert!(bare.verify().is_err());
        // Not a permutation: two ranks map to one id.
        let mut dup = ids.clone();
        dup[7] = dup[8];
        assert!(raw(&dup, &back, &marked).verify().is_err());
        // Out of range.
        let mut far = ids.clone();
        far[7] = n;
        assert!(raw(&far, &back, &marked).verify().is_err());

        // A short cycle needs no marks; the longest `rank` walks is accepted.
        let short = 2 * SHORTCUT + 3;
        let ids: Vec<u32> = (0..short).map(|i| (i + 1) % short).collect();
        let m = raw(&ids, &[], &[]);
        assert!(sound(&m));
        m.verify().unwrap();
    }

    #[test]
    fn verify_accepts_exactly_what_rank_can_walk() {
        // Random damage to π, the back pointers and the marks: whatever
        // `verify` accepts, `rank` must invert (the property the old
        // O(len · SHORTCUT) check tested directly).
        let mut s = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        let (mut accepted, mut rejected) = (0, 0);
        for round in 0..400u64 {
            let n = 1 + (next() % 120) as u32;
            let ids = perm(n, round + 1);
            let m = IdMap::new(&ids);
            assert!(m.verify().is_ok() && sound(&m));
            let mut back: Vec<u32> = (0..m.back.len()).map(|k| m.back.get(k)).collect();
            let mut marked: Vec<u32> = (0..n).filter(|&x| m.marked(x)).collect();
            let mut fwd = ids.clone();
            match next() % 4 {
                0 if !back.is_empty() => {
                    let k = (next() % back.len() as u64) as usize;
                    back[k] = (next() % u64::from(n)) as u32;
                }
                1 if !marked.is_empty() => {
                    let k = (next() % marked.len() as u64) as usize;
                    marked.remove(k);
                    back.remove(k);
                }
                2 => {
                    let x = (next() % u64::from(n)) as u32;
                    if let Err(k) = marked.binary_search(&x) {
                        marked.insert(k, x);
                        back.insert(k, (next() % u64::from(n)) as u32);
                    }
                }
                _ => {
                    let (a, b) = (next() % u64::from(n), next() % u64::from(n));
                    fwd.swap(a as usize, b as usize);
                }
            }
            let bad = raw(&fwd, &back, &marked);
            if bad.verify().is_ok() {
                accepted += 1;
                assert!(sound(&bad), "round {round}: verify accepted an unsound map");
            } else {
                rejected += 1;
            }
        }
        assert!(accepted > 0 && rejected > 0, "{accepted} / {rejected}");
    }

    #[test]
    fn vertex_ids_round_trip() {
        let v = VertexIds::new(&[5, 3, 5, 0], vec![(1, [1.0, 2.0, 3.0]), (2, [0.0; 3])]);
        let b = v.to_bytes();
        assert_eq!(VertexIds::parse(&b, 4).unwrap(), v);
        assert!(VertexIds::parse(&b, 3).is_err());
        assert!(VertexIds::parse(&b[..b.len() - 1], 4).is_err());
        assert_eq!(v.get(2), 5);
    }
}
