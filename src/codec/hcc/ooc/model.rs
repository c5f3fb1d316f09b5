//! What the o-HCCMesh encoder and decoder compute alike, so that they stay
//! symmetric: the contexts, the template layout of a low-level tree (the
//! i-HCCMesh's own, rebuilt from template symbols), the corner cache of the
//! streaming vertex indices, the edge look-up for parallelogram prediction
//! and the predictor itself.

use super::super::node::{
    INDEX_BITS, MAX_TREE_INTERCONNECTIONS, MAX_TREE_NODES, MAX_TREE_VERTICES, TYPE_INNER,
    TYPE_LEAF, TYPE_TEMPLATE_LEAF,
};
use super::super::template::{
    MAX_HEIGHT, MAX_TEMPLATE_NODES, TEMPLATE_COUNT, TEMPLATES, build_table,
};

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
/// The part (of the figures by part) of the templates and leaf sizes.
pub const PART_TEMPLATES: usize = 0;
/// The part of the corner symbols.
pub const PART_CORNERS: usize = 1;
/// The part of the vertex residuals.
pub const PART_VERTICES: usize = 2;
/// The part context `ctx` belongs to.
pub const fn part_of(ctx: usize) -> usize {
    match ctx {
        CTX_TEMPLATE | CTX_LEAF => PART_TEMPLATES,
        1..=3 => PART_CORNERS,
        _ => PART_VERTICES,
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
///
/// The per-position vectors keep room for one more template past
/// [`positions`](Self::positions): a template is written as its whole
/// fixed-size table, without growing a vector, and the room stays from
/// tree to tree (no vector is cut or cleared).
#[derive(Default)]
pub struct Layout {
    /// Node type of each position (and room past them).
    types: Vec<u32>,
    /// Positions of each inner node's children (unused for leaves).
    kids: Vec<[u32; 2]>,
    /// Inter-connection index of each template leaf (`u32::MAX` otherwise).
    ic_of: Vec<u32>,
    /// Template leaves whose child templates are still to come.
    pub pending: Vec<u32>,
    /// Per inter-connection: left template, right template, left start.
    pub ics: Vec<(u8, u8, u32)>,
    /// Template id of the root template.
    pub root_template: u8,
    /// Positions of the leaves (see [`leaves`](Self::leaves)), and room
    /// past them for one more template's.
    leaves: Vec<u32>,
    /// Positions of the other nodes (see [`inner`](Self::inner)), and room
    /// past them.
    inner: Vec<u32>,
    /// Entries of `leaves` and `inner` in use.
    lists: [usize; 2],
    /// Positions laid out so far.
    len: usize,
}

/// A template's nodes as [`Layout::alloc`] lays them out, by local index:
/// their types with every childless node at the template's deepest level
/// a leaf (the symbol makes some of them template leaves), their children
/// (local indices; `[0, 0]` for childless nodes), and the local indices of
/// the deepest childless nodes, in order.
#[derive(Clone, Copy)]
struct Shape {
    nodes: u8,
    types: [u32; MAX_TEMPLATE_NODES],
    kids: [[u32; 2]; MAX_TEMPLATE_NODES],
    /// How many nodes `deep` lists.
    deepest: u8,
    deep: [u8; 8],
    /// The childless nodes' local indices, in increasing order (unused
    /// entries 0), and how many there are.
    childless: [u8; 8],
    childless_count: u8,
    /// Per entry of `childless`, its bit in the symbol's template-leaf
    /// bits (the entry's index in `deep`), or 8 (no bit) for one above the
    /// deepest level.
    deep_bit: [u8; 8],
    /// The nodes with children, in increasing order (unused entries 0),
    /// and how many there are.
    parents: [u8; 8],
    parent_count: u8,
}

/// Every template's [`Shape`], by template id.
static SHAPES: [Shape; TEMPLATE_COUNT] = shapes();

const fn shapes() -> [Shape; TEMPLATE_COUNT] {
    let table = build_table();
    let mut out = [Shape {
        nodes: 0,
        types: [TYPE_LEAF; MAX_TEMPLATE_NODES],
        kids: [[0; 2]; MAX_TEMPLATE_NODES],
        deepest: 0,
        deep: [0; 8],
        childless: [0; 8],
        childless_count: 0,
        deep_bit: [8; 8],
        parents: [0; 8],
        parent_count: 0,
    }; TEMPLATE_COUNT];
    let mut id = 0;
    while id < TEMPLATE_COUNT {
        let mask = table[id].mask as u32;
        let nodes = table[id].nodes as usize;
        let mut depth = [0u8; MAX_TEMPLATE_NODES];
        let mut i = 0;
        while i < nodes {
            if mask >> i & 1 != 0 {
                // As `Template::children`.
                let c = 2 * (mask & ((1u32 << i) - 1)).count_ones() as usize + 1;
                depth[c] = depth[i] + 1;
                depth[c + 1] = depth[i] + 1;
                out[id].types[i] = TYPE_INNER;
                out[id].kids[i] = [c as u32, c as u32 + 1];
                out[id].parents[out[id].parent_count as usize] = i as u8;
                out[id].parent_count += 1;
            } else {
                let k = out[id].childless_count as usize;
                out[id].childless[k] = i as u8;
                out[id].childless_count += 1;
                if depth[i] as usize == MAX_HEIGHT - 1 {
                    out[id].deep_bit[k] = out[id].deepest;
                    out[id].deep[out[id].deepest as usize] = i as u8;
                    out[id].deepest += 1;
                }
            }
            i += 1;
        }
        out[id].nodes = nodes as u8;
        id += 1;
    }
    out
}

impl Layout {
    /// Clears the layout for the next tree.
    pub fn clear(&mut self) {
        self.len = 0;
        self.pending.clear();
        self.ics.clear();
        self.lists = [0; 2];
    }

    /// Positions of the leaves (type [`TYPE_LEAF`]), in increasing order:
    /// each template lists its own as it is laid out (templates are laid
    /// out at increasing positions, and their types are final then).
    pub fn leaves(&self) -> &[u32] {
        &self.leaves[..self.lists[0]]
    }

    /// Positions of the other nodes (inner nodes and template leaves,
    /// which have children), in increasing order, listed as
    /// [`leaves`](Self::leaves) are: a template's nodes with children,
    /// then its template leaves (which sit on its deepest level, numbered
    /// after every node with children: templates number their nodes
    /// breadth-first).
    pub fn inner(&self) -> &[u32] {
        &self.inner[..self.lists[1]]
    }

    /// Positions laid out so far.
    pub fn positions(&self) -> usize {
        self.len
    }

    /// Node type of each position.
    pub fn types(&self) -> &[u32] {
        &self.types[..self.len]
    }

    /// Positions of each node's children (unused for leaves).
    pub fn kids(&self) -> &[[u32; 2]] {
        &self.kids[..self.len]
    }

    /// Inter-connection index of each position (`u32::MAX` but for
    /// template leaves).
    pub fn ic_of(&self) -> &[u32] {
        &self.ic_of[..self.len]
    }

    /// Grows the per-position vectors to hold `n` positions.
    #[cold]
    fn grow(&mut self, n: usize) {
        let n = n
            .max(2 * self.types.len())
            .min(MAX_TREE_NODES + MAX_TEMPLATE_NODES);
        self.types.resize(n, TYPE_LEAF);
        self.kids.resize(n, [0; 2]);
        self.ic_of.resize(n, u32::MAX);
        // Each list holds at most every position, and room for one more
        // template's entries written whole (8 leaves; 8 nodes with
        // children and 8 template leaves).
        self.leaves.resize(n + 8, 0);
        self.inner.resize(n + 16, 0);
    }

    /// Lays out the template of symbol `sym` at the end; returns its id and
    /// first position.
    #[inline]
    pub fn alloc(&mut self, sym: u32) -> Result<(u8, u32), Bad> {
        let id = (sym & 31) as usize;
        if id >= TEMPLATE_COUNT || sym > MAX_TEMPLATE_SYM {
            return Err("a template symbol is out of range");
        }
        let shape = &SHAPES[id];
        let start = self.len;
        let nodes = shape.nodes as usize;
        if start + nodes > MAX_TREE_NODES {
            return Err("a low-level tree has more nodes than positions address");
        }
        let mut tl_bits = sym >> 5;
        if tl_bits >> shape.deepest != 0 {
            return Err("a template symbol marks nodes the template does not have");
        }
        // The template's whole (fixed-size) tables, with every deepest
        // childless node a leaf, written at the end (the vectors keep room
        // for them; the positions past its nodes are overwritten by the
        // next template), then the template leaves the symbol marks.
        let end = start + MAX_TEMPLATE_NODES;
        if self.types.len() < end {
            self.grow(end);
        }
        let at = start as u32;
        self.types[start..end].copy_from_slice(&shape.types);
        for (k, s) in self.kids[start..end].iter_mut().zip(&shape.kids) {
            *k = [s[0] + at, s[1] + at];
        }
        self.ic_of[start..end].fill(u32::MAX);
        self.len = start + nodes;
        // The lists, written whole into their room (the grown vectors
        // hold the positions and the room) and kept in part, without
        // branches on the template's shape: its childless nodes that the
        // symbol does not mark are leaves, in order; its nodes with
        // children, then the template leaves it marks, are the others.
        let [nl, ni] = self.lists;
        let marks = tl_bits;
        let leaves: &mut [u32; 8] = (&mut self.leaves[nl..nl + 8]).try_into().unwrap();
        let mut kept = 0;
        for k in 0..8 {
            leaves[kept % 8] = at + u32::from(shape.childless[k]);
            let marked = marks >> shape.deep_bit[k] & 1;
            kept += usize::from(k < usize::from(shape.childless_count)) & (1 - marked) as usize;
        }
        let inner: &mut [u32; 16] = (&mut self.inner[ni..ni + 16]).try_into().unwrap();
        for (slot, &local) in inner.iter_mut().zip(&shape.parents) {
            *slot = at + u32::from(local);
        }
        let mut listed = usize::from(shape.parent_count);
        while tl_bits != 0 {
            let p = at + u32::from(shape.deep[tl_bits.trailing_zeros() as usize % 8]);
            tl_bits &= tl_bits - 1;
            self.types[p as usize] = TYPE_TEMPLATE_LEAF;
            self.pending.push(p);
            inner[listed % 16] = p;
            listed += 1;
        }
        self.lists = [nl + kept, ni + listed];
        Ok((id as u8, at))
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
/// lanes of 16 bits in four `u64` words (lanes 0–3, 4–7, 8–11, 12–15), so
/// that reading an entry is one shift and moving an entry to the front is
/// a few shifts and masks, not a loop.
#[derive(Default)]
pub struct CornerCache {
    lanes: [u64; 4],
    len: usize,
}

const _: () = assert!(CACHE == 16);

impl CornerCache {
    /// Slot `r` (< 16).
    #[inline(always)]
    fn slot(&self, r: usize) -> u32 {
        (self.lanes[(r / 4) % 4] >> (16 * (r % 4))) as u16 as u32
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
        let l = self.lanes;
        let shifted = [
            l[0] << 16 | u64::from(v as u16),
            l[1] << 16 | l[0] >> 48,
            l[2] << 16 | l[1] >> 48,
            l[3] << 16 | l[2] >> 48,
        ];
        // Lanes 0..=at take the shifted value.
        let m = FRONT_MASKS[at % CACHE];
        for h in 0..4 {
            self.lanes[h] = shifted[h] & m[h] | l[h] & !m[h];
        }
    }
}

/// The decoder's corner cache: the most-recently-used list of
/// [`CornerCache`], kept as each entry's rank (0 the most recent) and
/// vertex, so that a corner is moved to the front by the same compare,
/// add and select on all 16 ranks (one SSE2 register on x86-64,
/// [`ranks`]), not by shifting the list: each corner's update depends on
/// the last one's, and that chain is three instructions long. The vertex
/// a hit reads (through a move mask and a load) is off that chain.
#[derive(Clone, Copy, Default)]
pub struct RankCache {
    lanes: ranks::Lanes,
    len: u32,
}

impl RankCache {
    /// The vertex of corner symbol `sym` when `next` vertices are known:
    /// `next` itself for a new one; moves it to the front as
    /// [`CornerCache::touch`] does (a vertex outside the cache takes the
    /// last rank in use, dropped when the cache is full, or a new one).
    /// Selects rather than branches on the kind of symbol, which the
    /// stream does not make predictable.
    #[inline(always)]
    pub fn decode(&mut self, sym: u32, next: u32) -> Result<u32, Bad> {
        let rank = sym.wrapping_sub(1);
        let cached = rank < CACHE as u32;
        if cached && rank >= self.len {
            return Err("a corner names an empty cache slot");
        }
        if sym > next + CACHE as u32 {
            return Err("a corner names a vertex before the tree's first");
        }
        // A vertex outside the cache: `next` for a new one, else
        // `next − 1 − (sym − 1 − CACHE)`.
        let outside = if sym == SYM_NEW {
            next
        } else {
            (next + CACHE as u32).wrapping_sub(sym)
        };
        let at = if cached {
            rank
        } else {
            self.len.min(CACHE as u32 - 1)
        };
        let hit = self.lanes.front(at as u16, !cached, outside as u16);
        self.len += u32::from(!cached & (self.len < CACHE as u32));
        Ok(if cached { u32::from(hit) } else { outside })
    }
}

/// [`RankCache`]'s lanes: every lane's rank (a permutation of 0..16; lanes
/// ranked at or past the cache's length are empty) and vertex.
pub mod ranks {
    use super::CACHE;

    /// The lanes as plain arrays, and the one update on them (on x86-64,
    /// the reference the vector lanes are tested against).
    #[cfg_attr(target_arch = "x86_64", allow(dead_code))]
    #[derive(Clone, Copy)]
    pub struct Plain {
        ranks: [u16; CACHE],
        verts: [u16; CACHE],
    }

    impl Default for Plain {
        fn default() -> Self {
            Self {
                ranks: std::array::from_fn(|i| i as u16),
                verts: [0; CACHE],
            }
        }
    }

    #[cfg_attr(target_arch = "x86_64", allow(dead_code))]
    impl Plain {
        /// Moves the lane ranked `at` to the front and returns its vertex
        /// (as it was); with `put`, its vertex becomes `v`.
        #[inline(always)]
        pub fn front(&mut self, at: u16, put: bool, v: u16) -> u16 {
            let mut hit = 0;
            for i in 0..CACHE {
                let r = self.ranks[i];
                if r == at {
                    hit = self.verts[i];
                    self.ranks[i] = 0;
                    if put {
                        self.verts[i] = v;
                    }
                } else {
                    self.ranks[i] = r + u16::from(r < at);
                }
            }
            hit
        }
    }

    #[cfg(target_arch = "x86_64")]
    pub use x86::Sse2 as Lanes;

    #[cfg(not(target_arch = "x86_64"))]
    pub use Plain as Lanes;

    #[cfg(target_arch = "x86_64")]
    mod x86 {
        use std::arch::x86_64::*;

        /// [`Plain`](super::Plain) with the ranks in one SSE2 register
        /// (sixteen 8-bit lanes) and the vertices in memory: the rank
        /// update is three vector instructions, and the lane it fronts is
        /// found by a move mask, its vertex read by a load.
        #[derive(Clone, Copy)]
        pub struct Sse2 {
            ranks: __m128i,
            /// The lanes' vertices, and a spare entry that takes the
            /// writes of hits.
            verts: [u16; 17],
        }

        impl Default for Sse2 {
            fn default() -> Self {
                let ranks: [u8; 16] = std::array::from_fn(|i| i as u8);
                Self {
                    ranks: bytemuck::cast(ranks),
                    verts: [0; 17],
                }
            }
        }

        impl Sse2 {
            /// As [`Plain::front`](super::Plain::front).
            #[inline(always)]
            pub fn front(&mut self, at: u16, put: bool, v: u16) -> u16 {
                #[inline]
                #[target_feature(enable = "sse2")]
                fn go(ranks: __m128i, at: u16) -> (__m128i, u32) {
                    let a = _mm_set1_epi8(at as i8);
                    let front = _mm_cmpeq_epi8(ranks, a);
                    // All ones below `at`: subtracting adds one.
                    let below = _mm_cmplt_epi8(ranks, a);
                    let ranks = _mm_andnot_si128(front, _mm_sub_epi8(ranks, below));
                    (ranks, _mm_movemask_epi8(front) as u32)
                }
                // SAFETY: SSE2 is part of the x86-64 baseline: every CPU
                // this target runs on has it.
                let (ranks, front) = unsafe { go(self.ranks, at) };
                self.ranks = ranks;
                // The ranks are a permutation of 0..16 and `at` < 16: one
                // lane is ranked `at`.
                let lane = front.trailing_zeros() as usize % 16;
                let hit = self.verts[lane];
                self.verts[if put { lane } else { 16 }] = v;
                hit
            }
        }
    }
}

/// Per slot `at`, the bits of lanes `0..=at` in [`CornerCache`]'s words.
static FRONT_MASKS: [[u64; 4]; CACHE] = {
    let mut m = [[0u64; 4]; CACHE];
    let mut at = 0;
    while at < CACHE {
        let mut lane = 0;
        while lane <= at {
            m[at][lane / 4] |= 0xffff << (16 * (lane % 4));
            lane += 1;
        }
        at += 1;
    }
    m
};

/// Triangles by vertex, most recent first, to find the triangle across an
/// edge: `head[v]` is `v`'s last corner, and each corner holds the
/// vertex's previous corner and the triangle's two other vertices, in
/// order (the next corner's, then the one after).
#[derive(Default)]
pub struct Adjacency {
    head: Vec<u32>,
    corners: Vec<[u32; 3]>,
}

const NONE: u32 = u32::MAX;

/// Entries of [`Adjacency`]'s heads: every local vertex index (corners
/// are 9-bit fields).
const HEADS: usize = MAX_TREE_VERTICES;

impl Adjacency {
    /// Empties it for a new tree.
    pub fn clear(&mut self) {
        if self.head.len() < HEADS {
            self.head.resize(HEADS, NONE);
        }
        self.corners.clear();
    }

    /// Empties it for a new tree of `vertices` vertices (at most
    /// `MAX_TREE_VERTICES`), all without triangles.
    pub fn start(&mut self, vertices: usize) {
        self.clear();
        self.head[..vertices].fill(NONE);
    }

    /// Vertex `v` is new: no triangles yet (`v` < `MAX_TREE_VERTICES`).
    #[inline(always)]
    pub fn new_vertex(&mut self, v: u32) {
        self.head[v as usize] = NONE;
    }

    /// Adds triangle `c` (every corner known).
    #[inline(always)]
    pub fn add(&mut self, c: [u32; 3]) {
        let t = self.corners.len() as u32;
        let mut corners = [[0; 3]; 3];
        for k in 0..3 {
            let v = c[k] as usize;
            corners[k] = [self.head[v], c[(k + 1) % 3], c[(k + 2) % 3]];
            self.head[v] = t + k as u32;
        }
        self.corners.extend_from_slice(&corners);
    }

    /// The third corner of the most recent triangle with edge `a`–`b`
    /// (either orientation), among `a`'s last [`EDGE_SEARCH`] triangles.
    #[inline(always)]
    pub fn opposite(&self, a: u32, b: u32) -> Option<u32> {
        let mut at = self.head[a as usize];
        for _ in 0..EDGE_SEARCH {
            // `NONE` is past every corner.
            let &[prev, n1, n2] = self.corners.get(at as usize)?;
            if n1 == b {
                return Some(n2);
            }
            if n2 == b {
                return Some(n1);
            }
            at = prev;
        }
        None
    }
}

/// How new vertex `v`, corner `k` of triangle `c` (local indices), is
/// predicted: the base of its residual contexts (`CTX_PARA`, `CTX_NEAR` or
/// `CTX_FAR`) and three grid slots (vertex `i` at slot `i + 1`, slot 0
/// the grid's centre) that [`predicted`] combines, from the corners known
/// before it (those below `v`: a tree numbers its vertices by first use)
/// and the adjacency of the triangles before `c`:
/// - both other corners known, and an earlier triangle across their edge
///   (third corner `o`): the parallelogram `a + b − o` [AG04];
/// - both known, no such triangle: their midpoint;
/// - one known: that corner;
/// - none: the tree's last decoded vertex (`v − 1`; the centre for the
///   first).
///
/// It depends on connectivity alone, so a decoder plans every vertex of a
/// tree before it reads any residual.
#[inline(always)]
pub fn plan(c: [u32; 3], k: usize, v: u32, adj: &Adjacency) -> (usize, [u32; 3]) {
    let (a, b) = (c[(k + 1) % 3], c[(k + 2) % 3]);
    match (a < v, b < v) {
        (true, true) => match adj.opposite(a, b) {
            Some(o) => (CTX_PARA, [a + 1, b + 1, o + 1]),
            None => (CTX_NEAR, [a + 1, b + 1, 0]),
        },
        (true, false) => (CTX_NEAR, [a + 1, a + 1, 0]),
        (false, true) => (CTX_NEAR, [b + 1, b + 1, 0]),
        (false, false) => (CTX_FAR, [v, v, 0]),
    }
}

/// The prediction [`plan`] describes (`ctx`, `slots`), over the grid
/// coordinates `pos` of its slots: `a + b − o` clamped to the grid for a
/// parallelogram, `(a + b) / 2` otherwise (which is `a` when both slots
/// are `a`).
#[inline(always)]
pub fn predicted(ctx: usize, [a, b, o]: [u32; 3], pos: &[[u32; 3]], max_q: u32) -> [u32; 3] {
    let (pa, pb, po) = (pos[a as usize], pos[b as usize], pos[o as usize]);
    let para = ctx == CTX_PARA;
    // Axis by axis, written out: `array::from_fn` here stays a call.
    let axis = |x: usize| {
        let sum = i64::from(pa[x]) + i64::from(pb[x]);
        let p = (sum - i64::from(po[x])).clamp(0, i64::from(max_q));
        if para { p as u32 } else { (sum >> 1) as u32 }
    };
    [axis(0), axis(1), axis(2)]
}

/// The grid slot 0 of [`plan`]: the centre of a grid of `max_q` + 1 steps.
pub fn centre(max_q: u32) -> [u32; 3] {
    [max_q / 2; 3]
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
        let (mut enc, mut dec) = (CornerCache::default(), RankCache::default());
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
        let mut dec = RankCache::default();
        assert!(dec.decode(1, 0).is_err(), "an empty cache has no rank 0");
    }

    /// The vector lanes and the plain ones agree, hit for hit.
    #[test]
    fn rank_lanes_match_the_plain_ones() {
        let (mut plain, mut lanes) = (ranks::Plain::default(), ranks::Lanes::default());
        let mut x = 99u64;
        for i in 0..20_000u32 {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let at = (x >> 40) as u16 % 16;
            let put = x >> 33 & 1 != 0;
            let v = (i % 600) as u16;
            assert_eq!(plain.front(at, put, v), lanes.front(at, put, v), "step {i}");
        }
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
        assert_eq!(lay.types().len(), 15 + 16);
        assert_eq!(lay.leaves().len(), 16);
        assert_eq!(lay.inner().len(), 15);
        // The lists as the types give them: every position in one, in
        // increasing order.
        let (leaves, inner): (Vec<u32>, Vec<u32>) =
            (0..lay.positions() as u32).partition(|&p| lay.types()[p as usize] == TYPE_LEAF);
        assert_eq!((lay.leaves(), lay.inner()), (&leaves[..], &inner[..]));
        assert_eq!(lay.ics.len(), 8);
        assert_eq!(template_symbol(full, 0, lay.types()), Some(sym));
        assert!(
            Layout::default()
                .root(u32::from(full) | 0x1ff << 5)
                .is_err()
        );
        assert!(Layout::default().root(26).is_err());
    }

    /// Random mixes of templates and template leaves: the leaf and inner
    /// lists each template adds as it is laid out are the types' own, in
    /// increasing order, across trees laid out one after the other.
    #[test]
    fn layouts_list_leaves_and_other_nodes_in_position_order() {
        let mut x = 5u64;
        let mut next = |n: u32| {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (x >> 33) as u32 % n
        };
        let mut lay = Layout::default();
        let mut template_leaves = 0;
        for _ in 0..300 {
            // A symbol of a random template with random template leaves
            // (masked to the nodes it has), fewer of them deeper down.
            let sym = |next: &mut dyn FnMut(u32) -> u32, depth: u32| {
                let id = next(TEMPLATE_COUNT as u32) as usize;
                let marks = if depth < 3 { next(256) } else { 0 };
                id as u32 | (marks & ((1 << SHAPES[id].deepest) - 1)) << 5
            };
            lay.root(sym(&mut next, 0)).unwrap();
            let mut depth = 0;
            while let Some(at) = lay.pending.pop() {
                depth += 1;
                let (l, r) = (sym(&mut next, depth / 8), sym(&mut next, depth / 8));
                lay.expand(at, l, r).unwrap();
            }
            let types = lay.types();
            template_leaves += types.iter().filter(|&&t| t == TYPE_TEMPLATE_LEAF).count();
            let (leaves, inner): (Vec<u32>, Vec<u32>) =
                (0..lay.positions() as u32).partition(|&p| types[p as usize] == TYPE_LEAF);
            assert_eq!((lay.leaves(), lay.inner()), (&leaves[..], &inner[..]));
        }
        assert!(template_leaves > 300, "the mixes have template leaves");
    }
}
