//! What the o-HCCMesh encoder and decoder compute alike, so that they stay
//! symmetric: the contexts, the template layout of a low-level tree (the
//! i-HCCMesh's own, rebuilt from template symbols), the corner cache of the
//! streaming vertex indices, the edge look-up for parallelogram prediction
//! and the predictor itself.

use super::super::node::{
    INDEX_BITS, MAX_TREE_INTERCONNECTIONS, MAX_TREE_NODES, MAX_TREE_VERTICES, TYPE_INNER,
    TYPE_LEAF, TYPE_TEMPLATE_LEAF,
};
use super::super::template::{MAX_HEIGHT, MAX_TEMPLATE_NODES, TEMPLATE_COUNT, TEMPLATES};

/// Context of the template symbols.
pub const CTX_TEMPLATE: usize = 0;
/// Contexts of the corner symbols, by corner slot (0, 1, 2).
pub const CTX_CORNER: usize = 1;
/// Contexts of parallelogram residuals, by axis.
pub const CTX_PARA: usize = 4;
/// Contexts of residuals against a neighbour (one or two corners known,
/// no parallelogram), by axis.
pub const CTX_NEAR: usize = 7;
/// Contexts of residuals against the tree's last decoded vertex (no corner
/// of the triangle known yet), by axis.
pub const CTX_FAR: usize = 10;
/// Context of a multi-triangle leaf's triangle count − 1.
pub const CTX_LEAF: usize = 13;
/// Number of contexts.
pub const CONTEXTS: usize = 14;
/// Names of the contexts' groups, for the figures by part.
pub const fn part_of(ctx: usize) -> usize {
    match ctx {
        CTX_TEMPLATE | CTX_LEAF => 0,
        1..=3 => 1,
        _ => 2,
    }
}

/// Entries of the corner cache (most recently used vertices first).
pub const CACHE: usize = 16;
/// Corner symbol of a vertex seen for the first time (the next local id).
pub const SYM_NEW: u32 = 0;
/// The largest corner symbol: a vertex outside the cache, sent as its
/// distance below the next id.
pub const MAX_CORNER_SYM: u32 = CACHE as u32 + MAX_TREE_VERTICES as u32;
/// Bits of a template symbol: the template id (5 bits) and, per node at
/// template depth 3 without children in the template (at most 8), whether
/// it is a template leaf.
pub const MAX_TEMPLATE_SYM: u32 = (1 << 13) - 1;
/// Incident triangles a vertex's list is searched for an edge, at most
/// (the same bound both sides, so that the search is linear in the tree).
pub const EDGE_SEARCH: usize = 16;

/// A malformed symbol or structure (the decoder turns it into an error
/// naming the tree).
pub type Bad = &'static str;

/// A low-level tree's node positions as templates are allocated: the
/// i-HCCMesh's layout (`encode.rs`: templates breadth-first, the two child
/// templates of a template leaf back to back, template leaves taken from
/// a stack), rebuilt from template symbols.
#[derive(Default)]
pub struct Layout {
    /// Node type of each position.
    pub types: Vec<u32>,
    /// Positions of each inner node's children (unused for leaves).
    pub kids: Vec<[u32; 2]>,
    /// Inter-connection index of each template leaf (`u32::MAX` otherwise).
    pub ic_of: Vec<u32>,
    /// Template leaves whose child templates are still to come.
    pub pending: Vec<u32>,
    /// Per inter-connection: left template, right template, left start.
    pub ics: Vec<(u8, u8, u32)>,
    /// Template id of the root template.
    pub root_template: u8,
}

impl Layout {
    /// Clears the layout for the next tree.
    pub fn clear(&mut self) {
        self.types.clear();
        self.kids.clear();
        self.ic_of.clear();
        self.pending.clear();
        self.ics.clear();
    }

    /// Lays out the template of symbol `sym` at the end; returns its id and
    /// first position.
    pub fn alloc(&mut self, sym: u32) -> Result<(u8, u32), Bad> {
        let id = (sym & 31) as usize;
        if id >= TEMPLATE_COUNT || sym > MAX_TEMPLATE_SYM {
            return Err("a template symbol is out of range");
        }
        let t = TEMPLATES[id];
        let start = self.types.len() as u32;
        if self.types.len() + t.nodes as usize > MAX_TREE_NODES {
            return Err("a low-level tree has more nodes than positions address");
        }
        let mut tl_bits = sym >> 5;
        let mut depth = [0u8; MAX_TEMPLATE_NODES];
        for i in 0..t.nodes as u32 {
            if t.has_children(i) {
                let c = t.children(i);
                depth[c as usize] = depth[i as usize] + 1;
                depth[c as usize + 1] = depth[i as usize] + 1;
                self.types.push(TYPE_INNER);
                self.kids.push([start + c, start + c + 1]);
                self.ic_of.push(u32::MAX);
            } else {
                let deepest = depth[i as usize] as usize == MAX_HEIGHT - 1;
                let ty = if deepest && tl_bits & 1 == 1 {
                    TYPE_TEMPLATE_LEAF
                } else {
                    TYPE_LEAF
                };
                if deepest {
                    tl_bits >>= 1;
                }
                if ty == TYPE_TEMPLATE_LEAF {
                    self.pending.push(start + i);
                }
                self.types.push(ty);
                self.kids.push([0; 2]);
                self.ic_of.push(u32::MAX);
            }
        }
        if tl_bits != 0 {
            return Err("a template symbol marks nodes the template does not have");
        }
        Ok((id as u8, start))
    }

    /// Starts a tree with the root template's symbol.
    pub fn root(&mut self, sym: u32) -> Result<(), Bad> {
        self.clear();
        let (id, _) = self.alloc(sym)?;
        self.root_template = id;
        Ok(())
    }

    /// Gives the next template leaf its two child templates (symbols
    /// `left`, `right`); its inter-connection is the next one.
    pub fn expand(&mut self, at: u32, left: u32, right: u32) -> Result<(), Bad> {
        if self.ics.len() >= MAX_TREE_INTERCONNECTIONS {
            return Err("a low-level tree has more inter-connections than 9 bits index");
        }
        let (lt, ls) = self.alloc(left)?;
        let (rt, rs) = self.alloc(right)?;
        self.ic_of[at as usize] = self.ics.len() as u32;
        self.kids[at as usize] = [ls, rs];
        self.ics.push((lt, rt, ls));
        Ok(())
    }
}

/// The template symbol of the template `id` laid out from position
/// `start`, whose nodes have types `types` (by position).
pub fn template_symbol(id: u8, start: usize, types: &[u32]) -> Option<u32> {
    let t = TEMPLATES.get(id as usize)?;
    let mut depth = [0u8; MAX_TEMPLATE_NODES];
    let (mut bits, mut n) = (0u32, 0);
    for i in 0..t.nodes as u32 {
        if t.has_children(i) {
            let c = t.children(i) as usize;
            depth[c] = depth[i as usize] + 1;
            depth[c + 1] = depth[i as usize] + 1;
        } else if depth[i as usize] as usize == MAX_HEIGHT - 1 {
            if *types.get(start + i as usize)? == TYPE_TEMPLATE_LEAF {
                bits |= 1 << n;
            }
            n += 1;
        }
    }
    Some(u32::from(id) | bits << 5)
}

/// The most recently used vertices of the tree, most recent first: 16
/// lanes of 16 bits in two `u128` halves (lanes 0–7, 8–15), so that moving
/// an entry to the front is a few shifts and masks, not a loop.
#[derive(Default)]
pub struct CornerCache {
    lanes: [u128; 2],
    len: usize,
}

const _: () = assert!(CACHE == 16);

impl CornerCache {
    /// Slot `r` (< 16).
    #[inline(always)]
    fn slot(&self, r: usize) -> u32 {
        (self.lanes[r / 8] >> (16 * (r % 8))) as u16 as u32
    }

    /// Empties the cache (a new tree).
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// The symbol of corner `v` when `next` vertices are known (encoder).
    pub fn symbol(&self, v: u32, next: u32) -> u32 {
        if v == next {
            return SYM_NEW;
        }
        match (0..self.len).position(|r| self.slot(r) == v) {
            Some(r) => 1 + r as u32,
            None => 1 + CACHE as u32 + (next - 1 - v),
        }
    }

    /// The vertex of corner symbol `sym` when `next` vertices are known
    /// (decoder): `next` itself for a new one; moves it to the front as
    /// [`touch`](Self::touch) does, without searching (the symbol says
    /// where it is).
    #[inline(always)]
    pub fn decode(&mut self, sym: u32, next: u32) -> Result<u32, Bad> {
        let (v, at) = if sym == SYM_NEW {
            (next, self.grow())
        } else if sym <= CACHE as u32 {
            let at = sym as usize - 1;
            if at >= self.len {
                return Err("a corner names an empty cache slot");
            }
            (self.slot(at), at)
        } else {
            let back = sym - 1 - CACHE as u32;
            let v = next
                .checked_sub(1 + back)
                .ok_or("a corner names a vertex before the tree's first")?;
            (v, self.grow())
        };
        self.move_front(at, v);
        Ok(v)
    }

    /// Makes room for one more entry; returns the slot to move from (the
    /// last one in use, dropped when the cache is full).
    #[inline(always)]
    fn grow(&mut self) -> usize {
        self.len = (self.len + 1).min(CACHE);
        self.len - 1
    }

    /// Moves `v` to the front (inserting it if absent).
    pub fn touch(&mut self, v: u32) {
        let at = match (0..self.len).position(|r| self.slot(r) == v) {
            Some(at) => at,
            None => self.grow(),
        };
        self.move_front(at, v);
    }

    /// Shifts slots `0..at` back by one and puts `v` in front; slots
    /// after `at` keep their entries.
    #[inline(always)]
    fn move_front(&mut self, at: usize, v: u32) {
        let [lo, hi] = self.lanes;
        let shifted = [lo << 16 | u128::from(v as u16), hi << 16 | lo >> 112];
        // Lanes 0..=at take the shifted value.
        let lanes = 16 * (at as u32 + 1);
        let mask = |bits: u32| match bits {
            0 => 0,
            128.. => u128::MAX,
            b => (1u128 << b) - 1,
        };
        let m = [mask(lanes.min(128)), mask(lanes.saturating_sub(128))];
        for h in 0..2 {
            self.lanes[h] = shifted[h] & m[h] | self.lanes[h] & !m[h];
        }
    }
}

/// Triangles by vertex, most recent first, to find the triangle across an
/// edge: `head[v]` is `v`'s last corner (triangle · 3 + slot), `prev` links
/// each corner to the vertex's previous one.
#[derive(Default)]
pub struct Adjacency {
    head: Vec<u32>,
    prev: Vec<u32>,
    tris: Vec<[u32; 3]>,
}

const NONE: u32 = u32::MAX;

impl Adjacency {
    /// Empties it for a new tree.
    pub fn clear(&mut self) {
        if self.head.len() < MAX_TREE_VERTICES {
            self.head.resize(MAX_TREE_VERTICES, NONE);
        }
        self.prev.clear();
        self.tris.clear();
    }

    /// Vertex `v` is new: no triangles yet.
    #[inline(always)]
    pub fn new_vertex(&mut self, v: u32) {
        self.head[v as usize] = NONE;
    }

    /// Adds triangle `c` (every corner known).
    #[inline(always)]
    pub fn add(&mut self, c: [u32; 3]) {
        let t = self.tris.len() as u32;
        for (k, &v) in c.iter().enumerate() {
            self.prev.push(self.head[v as usize]);
            self.head[v as usize] = 3 * t + k as u32;
        }
        self.tris.push(c);
    }

    /// The third corner of the most recent triangle with edge `a`–`b`
    /// (either orientation), among `a`'s last [`EDGE_SEARCH`] triangles.
    #[inline(always)]
    pub fn opposite(&self, a: u32, b: u32) -> Option<u32> {
        let mut at = self.head[a as usize];
        for _ in 0..EDGE_SEARCH {
            if at == NONE {
                return None;
            }
            let t = self.tris[(at / 3) as usize];
            let k = (at % 3) as usize;
            let (n1, n2) = (t[(k + 1) % 3], t[(k + 2) % 3]);
            if n1 == b {
                return Some(n2);
            }
            if n2 == b {
                return Some(n1);
            }
            at = self.prev[at as usize];
        }
        None
    }
}

/// The prediction of corner `k` of triangle `c` (grid coordinates) and the
/// residual contexts' base (`CTX_PARA`, `CTX_NEAR` or `CTX_FAR`), from the
/// corners already known (`known`), the tree's vertices `pos`, the
/// adjacency and the tree's last decoded vertex.
#[inline(always)]
pub fn predict(
    c: [u32; 3],
    k: usize,
    known: [bool; 3],
    pos: &[[u32; 3]],
    adj: &Adjacency,
    last: [u32; 3],
    max_q: u32,
) -> ([u32; 3], usize) {
    let (a, b) = ((k + 1) % 3, (k + 2) % 3);
    match (known[a], known[b]) {
        (true, true) => {
            let (pa, pb) = (pos[c[a] as usize], pos[c[b] as usize]);
            match adj.opposite(c[a], c[b]) {
                Some(o) => {
                    let po = pos[o as usize];
                    let p = std::array::from_fn(|x| {
                        let v = i64::from(pa[x]) + i64::from(pb[x]) - i64::from(po[x]);
                        v.clamp(0, i64::from(max_q)) as u32
                    });
                    (p, CTX_PARA)
                }
                None => (
                    std::array::from_fn(|x| ((u64::from(pa[x]) + u64::from(pb[x])) / 2) as u32),
                    CTX_NEAR,
                ),
            }
        }
        (true, false) => (pos[c[a] as usize], CTX_NEAR),
        (false, true) => (pos[c[b] as usize], CTX_NEAR),
        (false, false) => (last, CTX_FAR),
    }
}

// A local vertex index fits the 9-bit fields.
const _: () = assert!(MAX_TREE_VERTICES <= 1 << INDEX_BITS);

#[cfg(test)]
mod tests {
    use super::*;

    /// The lane cache is a most-recently-used list: the encoder's symbols
    /// name the ranks a plain list gives, and the decoder gets the
    /// vertices back.
    #[test]
    fn corner_cache_is_a_most_recently_used_list() {
        let (mut enc, mut dec) = (CornerCache::default(), CornerCache::default());
        let mut list: Vec<u32> = Vec::new();
        let mut next = 0u32;
        let mut x = 12345u64;
        for _ in 0..5000 {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let r = (x >> 33) as u32;
            // New vertices, recent ones and far ones.
            let v = match r % 4 {
                0 if next < 511 => next,
                1 | 2 if next > 0 => next - 1 - (r >> 8) % next.min(20),
                _ if next > 0 => (r >> 8) % next,
                _ => next,
            };
            let want = if v == next {
                SYM_NEW
            } else {
                match list.iter().position(|&u| u == v) {
                    Some(p) => 1 + p as u32,
                    None => 1 + CACHE as u32 + (next - 1 - v),
                }
            };
            let sym = enc.symbol(v, next);
            assert_eq!(sym, want);
            enc.touch(v);
            assert_eq!(dec.decode(sym, next), Ok(v));
            list.retain(|&u| u != v);
            list.insert(0, v);
            list.truncate(CACHE);
            if v == next {
                next += 1;
            }
        }
        assert!(dec.decode(1 + CACHE as u32 + next, next).is_err());
        dec.clear();
        assert!(dec.decode(1, 0).is_err(), "an empty cache has no rank 0");
    }

    #[test]
    fn layouts_rebuild_the_templates_they_were_given() {
        // The complete height-4 template with its 8 deepest nodes as
        // template leaves, each expanded into two single leaves.
        let full = crate::codec::hcc::template::id_of_mask(0x7f).unwrap();
        let sym = u32::from(full) | 0xff << 5;
        let mut lay = Layout::default();
        lay.root(sym).unwrap();
        assert_eq!(lay.pending.len(), 8);
        while let Some(at) = lay.pending.pop() {
            lay.expand(at, 0, 0).unwrap();
        }
        assert_eq!(lay.types.len(), 15 + 16);
        assert_eq!(lay.ics.len(), 8);
        assert_eq!(template_symbol(full, 0, &lay.types), Some(sym));
        assert!(
            Layout::default()
                .root(u32::from(full) | 0x1ff << 5)
                .is_err()
        );
        assert!(Layout::default().root(26).is_err());
    }
}
