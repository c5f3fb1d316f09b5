//! [`NodeCursor`] over an [`HccBvh`]: boxes from vertex indices, the parent
//! box and the reuse mask; structure from templates and inter-connections.
//! Its [`RayCursor`] casts rays through i-HCCMesh's own traversal
//! (`trace.rs`).

use glam::Vec3A;

use super::HccBvh;
use super::block::{Block, slot_bits};
use super::node::{
    HccNode, HighNode, INDEX_MASK, Interconnection, KIND_EMPTY, KIND_HIGH, TYPE_LEAF,
    TYPE_TEMPLATE_LEAF, TreeHeader, field, mask_half, multi_leaf, node_type,
};
use super::template::TEMPLATES;
use super::vertices::{F32Verts, TreeVerts, Vertices};
use crate::cursor::{Children, NodeCursor, TraversalStats};
use crate::geom::{Aabb, Ray, Triangle};
use crate::query::{RayCursor, RayHit};

#[inline(always)]
fn set_extent(b: &mut Aabb, e: usize, v: f32) {
    if e < 3 {
        b.min[e] = v;
    } else {
        b.max[e - 3] = v;
    }
}

impl HccBvh {
    /// The handle of low-level tree `tree`'s root, whose box is `bounds`.
    #[inline]
    pub(super) fn low_root(&self, tree: u32, bounds: Aabb) -> HccNode {
        let start = self.headers[tree as usize].node_start;
        let w = self.nodes[start as usize];
        let ty = node_type(w);
        HccNode::new(
            bounds,
            tree,
            start,
            start,
            if ty == TYPE_LEAF { 0 } else { (w & 31) as u8 },
            ty as u8,
        )
    }

    #[inline(always)]
    fn high_child(&self, i: u32) -> HccNode {
        let h: &HighNode = &self.high[i as usize];
        let bounds = Aabb::from_arrays(h.min, h.max);
        if h.is_leaf() {
            self.low_root(h.a, bounds)
        } else {
            HccNode::high(i, bounds)
        }
    }

    /// Vertex field `j` of the word at `pos` (a template leaf's third field
    /// lives in its inter-connection).
    #[inline(always)]
    fn vertex_field(&self, h: &TreeHeader, w: u32, j: usize) -> u32 {
        if j == 2 && node_type(w) == TYPE_TEMPLATE_LEAF {
            self.ics[(h.ic_start + field(w, 2)) as usize] & INDEX_MASK
        } else {
            field(w, j as u32)
        }
    }

    /// Vertex `local` of tree `tree` (header `h`).
    pub(super) fn point(&self, tree: u32, h: &TreeHeader, local: u32) -> [f32; 3] {
        match &self.vertices {
            Vertices::F32(v) => v[(h.vertex_start + local) as usize],
            Vertices::Packed(q) => q.point(tree as usize, local),
        }
    }

    /// Tree `tree`'s vertices when they are `f32`s.
    #[inline(always)]
    fn f32_verts<'a>(&self, all: &'a [[f32; 3]], tree: u32) -> F32Verts<'a> {
        F32Verts {
            all,
            start: self.headers[tree as usize].vertex_start,
        }
    }

    /// The block of the multi-triangle leaf word `w` of tree `tree`, and
    /// its triangle count.
    #[inline(always)]
    pub(super) fn leaf_block(&self, tree: u32, w: u32) -> (Block, u32) {
        let (off, count) = multi_leaf(w);
        let at = u64::from(self.block_start[tree as usize]) * 8 + u64::from(off);
        let sb = slot_bits(self.tree_triangles(tree as usize));
        (Block::read(&self.blocks, at, sb), count)
    }

    /// Calls `f` with the storage rank and local corners of each triangle
    /// of the leaf at node word `pos` of tree `tree`.
    #[inline(always)]
    pub(super) fn leaf_triangles(&self, tree: u32, pos: u32, mut f: impl FnMut(u32, [u32; 3])) {
        let w = self.nodes[pos as usize];
        if self.multi {
            let first = self.headers[tree as usize].first_triangle;
            let (b, count) = self.leaf_block(tree, w);
            for j in 0..count {
                f(first + b.slot + j, b.corners(&self.blocks, j));
            }
        } else {
            f(
                self.leaf_rank_of(pos),
                [field(w, 0), field(w, 1), field(w, 2)],
            );
        }
    }

    /// The tight box of the leaf at node word `pos`'s triangles.
    #[inline(always)]
    fn leaf_box<V: TreeVerts>(&self, v: &V, tree: u32, pos: u32) -> Aabb {
        let w = self.nodes[pos as usize];
        if self.multi {
            let (b, count) = self.leaf_block(tree, w);
            let (mut lo, mut hi) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
            for j in 0..count {
                let [c0, c1, c2] = b.corners(&self.blocks, j);
                let (p0, p1, p2) = (v.point(c0), v.point(c1), v.point(c2));
                lo = lo.min(p0.min(p1).min(p2));
                hi = hi.max(p0.max(p1).max(p2));
            }
            Aabb::new(lo, hi)
        } else {
            let (p0, p1, p2) = (
                v.point(field(w, 0)),
                v.point(field(w, 1)),
                v.point(field(w, 2)),
            );
            Aabb::new(p0.min(p1).min(p2), p0.max(p1).max(p2))
        }
    }

    /// Decodes the boxes of the sibling pair at word indices `l`, `l + 1`
    /// … or `l`, `r` for the roots of two templates, children of `parent`.
    #[inline(always)]
    fn child_pair<V: TreeVerts>(
        &self,
        v: &V,
        parent: &HccNode,
        l: u32,
        r: u32,
    ) -> (Aabb, Aabb, u32, u32) {
        let tree = parent.tree();
        let h = &self.headers[tree as usize];
        let (wl, wr) = (self.nodes[l as usize], self.nodes[r as usize]);
        let (tl, tr) = (node_type(wl), node_type(wr));
        let d = parent.bounds();
        let mask = mask_half(wl) | mask_half(wr) << 3;
        let (bl, br) = match (tl == TYPE_LEAF, tr == TYPE_LEAF) {
            (false, false) => {
                let (mut bl, mut br) = (d, d);
                for e in 0..6 {
                    let w = if e < 3 { wl } else { wr };
                    let c = v.coord(self.vertex_field(h, w, e % 3), e % 3);
                    if mask >> e & 1 != 0 {
                        set_extent(&mut br, e, c);
                    } else {
                        set_extent(&mut bl, e, c);
                    }
                }
                (bl, br)
            }
            (true, true) => (self.leaf_box(v, tree, l), self.leaf_box(v, tree, r)),
            (leaf_left, _) => {
                let wi = if leaf_left { wr } else { wl };
                let mut bi = d;
                let mut j = 0;
                for e in 0..6 {
                    if mask >> e & 1 == 0 {
                        let c = v.coord(self.vertex_field(h, wi, j), e % 3);
                        set_extent(&mut bi, e, c);
                        j += 1;
                    }
                }
                if leaf_left {
                    (self.leaf_box(v, tree, l), bi)
                } else {
                    (bi, self.leaf_box(v, tree, r))
                }
            }
        };
        (bl, br, tl, tr)
    }

    /// The id of the one-triangle leaf at word `pos`: its rank among the
    /// leaf words.
    #[inline(always)]
    fn leaf_rank_of(&self, pos: u32) -> u32 {
        let (w, b) = ((pos / 64) as usize, pos % 64);
        self.leaf_rank[w] + (self.leaf_bits[w] & ((1u64 << b) - 1)).count_ones()
    }

    /// The node word of the leaf of rank `k` among all leaf words (select
    /// over the leaf bits); `k` must be below the number of leaves.
    fn select_leaf(&self, k: u32) -> u32 {
        let w = self.leaf_rank.partition_point(|&r| r <= k) - 1;
        (w * 64) as u32 + select_in_word(self.leaf_bits[w], k - self.leaf_rank[w])
    }

    /// The first leaf word at or after `pos` and before `end`.
    fn next_leaf(&self, pos: u32, end: u32) -> Option<u32> {
        let mut w = (pos / 64) as usize;
        let mut bits = *self.leaf_bits.get(w)? & (u64::MAX << (pos % 64));
        while bits == 0 {
            w += 1;
            if w * 64 >= end as usize {
                return None;
            }
            bits = *self.leaf_bits.get(w)?;
        }
        let p = (w * 64) as u32 + bits.trailing_zeros();
        (p < end).then_some(p)
    }

    /// The tree and local corners of the triangle of storage rank `rank`.
    /// One triangle a leaf: the leaf word of rank `rank`, by select. Several:
    /// the tree by a binary search over the trees' first ranks, then the
    /// leaf by a binary search over the tree's node words (leaves' first
    /// slots ascend in node-word order; the leaf bits find the next leaf).
    fn locate(&self, rank: u32) -> (u32, [u32; 3]) {
        if self.multi {
            let tree = self.headers.partition_point(|h| h.first_triangle <= rank) - 1;
            let h = &self.headers[tree];
            let slot = rank - h.first_triangle;
            let (end, _, _) = self.tree_ends(tree);
            let block = |p: u32| self.leaf_block(tree as u32, self.nodes[p as usize]).0;
            let Some(mut lo) = self.next_leaf(h.node_start, end) else {
                return (tree as u32, [0; 3]);
            };
            let mut hi = end;
            while hi - lo > 1 {
                let mid = lo + (hi - lo) / 2;
                match self.next_leaf(mid, hi) {
                    Some(q) if block(q).slot <= slot => lo = q,
                    _ => hi = mid,
                }
            }
            let b = block(lo);
            (
                tree as u32,
                b.corners(&self.blocks, slot.wrapping_sub(b.slot)),
            )
        } else {
            let pos = self.select_leaf(rank);
            let w = self.nodes[pos as usize];
            (
                self.tree_of_word(pos) as u32,
                [field(w, 0), field(w, 1), field(w, 2)],
            )
        }
    }

    /// Triangle `id`'s corners as indices into [`HccBvh::decoded_mesh`]'s
    /// vertices (the input's vertex indices when vertex ids are kept).
    /// Finds the triangle's rank through the id map's shortcuts, then its
    /// leaf (see `locate`).
    pub fn triangle_vertex_indices(&self, id: u32) -> [u32; 3] {
        let (tree, c) = self.locate(self.rank_of(id));
        let base = self.headers[tree as usize].vertex_start;
        c.map(|l| self.vertex_index(base + l))
    }

    /// The triangle id of storage rank `rank` (`< triangle_count`): the
    /// input's id through the map, or the rank itself in tree order.
    #[inline(always)]
    pub(super) fn id_of(&self, rank: u32) -> u32 {
        match &self.ids {
            Some(m) => m.id(rank),
            None => rank,
        }
    }

    /// The storage rank of triangle `id`; 0 for an id out of range (or
    /// one an unverified map cannot find).
    fn rank_of(&self, id: u32) -> u32 {
        match &self.ids {
            Some(m) => m.rank(id).unwrap_or(0),
            None if id < self.triangle_count => id,
            None => 0,
        }
    }

    /// The low-level tree holding node word `pos`.
    fn tree_of_word(&self, pos: u32) -> usize {
        self.headers.partition_point(|h| h.node_start <= pos) - 1
    }
}

impl HccBvh {
    /// The storage rank and corners of each triangle of the leaf `node`,
    /// over the tree's vertices `v` (the keys of
    /// [`NodeCursor::for_each_triangle_keyed`]).
    #[inline(always)]
    fn ranked_triangles_with<V: TreeVerts>(
        &self,
        v: &V,
        node: &HccNode,
        f: &mut impl FnMut(u32, &Triangle),
    ) {
        self.leaf_triangles(node.tree(), node.pos(), |rank, [c0, c1, c2]| {
            f(rank, &[v.point(c0), v.point(c1), v.point(c2)]);
        });
    }
}

/// The position of the set bit of rank `k` in `w` (`k < popcount(w)`): a
/// byte at a time, then a bit at a time.
#[inline]
fn select_in_word(mut w: u64, mut k: u32) -> u32 {
    let mut base = 0;
    loop {
        let c = (w & 0xFF).count_ones();
        if k < c || base >= 56 {
            break;
        }
        k -= c;
        w >>= 8;
        base += 8;
    }
    for _ in 0..k {
        w &= w.wrapping_sub(1);
    }
    base + w.trailing_zeros().min(63)
}

impl HccBvh {
    /// The two children of the inner node `node` with their boxes.
    // Always inlined, as `for_each_child` was with its closure: a call
    // would return the pair through memory. Only in optimised builds (no
    // debug assertions), as are `pair` and `children` below and in
    // `ooc::contract`: unoptimised, forced inlining copied the whole child
    // decode into every call site of every traversal, once per codec pair
    // (single BVTT functions of 88 000 LLVM instructions), and made a
    // user's cold debug build of cbvh take 80 s of CPU instead of 31.
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    pub(super) fn children_of(&self, node: &HccNode) -> [(HccNode, Aabb); 2] {
        if node.kind() == KIND_HIGH {
            let h = &self.high[node.pos() as usize];
            return [h.a, h.b].map(|c| {
                let n = self.high_child(c);
                (n, n.bounds())
            });
        }
        let (l, r, bl, br, tl, tr) = if node.kind() == TYPE_TEMPLATE_LEAF as u8 {
            let h = &self.headers[node.tree() as usize];
            let w = self.nodes[node.pos() as usize];
            let ic = Interconnection::unpack(self.ics[(h.ic_start + field(w, 2)) as usize]);
            let l = h.node_start + ic.left_start;
            let r = l + TEMPLATES[ic.left_template as usize].nodes as u32;
            (l, r, l, r, ic.left_template, ic.right_template)
        } else {
            let t = &TEMPLATES[node.template_id() as usize];
            let l = node.block() + t.children(node.pos() - node.block());
            (
                l,
                l + 1,
                node.block(),
                node.block(),
                node.template_id(),
                node.template_id(),
            )
        };
        // One branch on the vertex format per expansion.
        let (bxl, bxr, kl, kr) = match &self.vertices {
            Vertices::F32(all) => self.child_pair(&self.f32_verts(all, node.tree()), node, l, r),
            Vertices::Packed(q) => self.child_pair(&q.tree(node.tree() as usize), node, l, r),
        };
        let tree = node.tree();
        let child = |pos, block, template, kind: u32, bounds| {
            HccNode::new(bounds, tree, pos, block, template, kind as u8)
        };
        [
            (child(l, bl, tl, kl, bxl), bxl),
            (child(r, br, tr, kr, bxr), bxr),
        ]
    }
}

impl super::trace::Pairs for HccBvh {
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    fn pair(&self, node: &HccNode) -> [(HccNode, Aabb); 2] {
        self.children_of(node)
    }
}

impl NodeCursor for HccBvh {
    type Node = HccNode;

    fn root(&self) -> (HccNode, Aabb) {
        if self.headers.is_empty() {
            return (HccNode::empty(), Aabb::EMPTY);
        }
        let n = self.high_child(0);
        (n, n.bounds())
    }

    #[inline(always)]
    fn is_leaf(&self, node: &HccNode) -> bool {
        node.is_leaf()
    }

    #[inline]
    fn for_each_child(&self, node: &HccNode, mut f: impl FnMut(HccNode, Aabb)) {
        for (child, b) in self.children_of(node) {
            f(child, b);
        }
    }

    /// Both children written at once (a batch of two, known as such where
    /// the traversal is compiled).
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    fn children(&self, node: &HccNode, out: &mut Children<HccNode>) {
        out.set(&self.children_of(node));
    }

    #[inline]
    fn for_each_triangle(&self, node: &HccNode, mut f: impl FnMut(u32, &Triangle)) {
        self.for_each_triangle_keyed(node, |rank, t| f(self.id_of(rank), t));
    }

    /// Keys are storage ranks: the id map is read only for the triangles
    /// a traversal reports.
    #[inline]
    fn for_each_triangle_keyed(&self, node: &HccNode, mut f: impl FnMut(u32, &Triangle)) {
        if node.kind() == KIND_EMPTY {
            return;
        }
        match &self.vertices {
            Vertices::F32(all) => {
                self.ranked_triangles_with(&self.f32_verts(all, node.tree()), node, &mut f)
            }
            Vertices::Packed(q) => {
                self.ranked_triangles_with(&q.tree(node.tree() as usize), node, &mut f)
            }
        }
    }

    #[inline(always)]
    fn id_of_key(&self, key: u32) -> u32 {
        self.id_of(key)
    }

    fn triangle(&self, id: u32) -> Triangle {
        let (tree, c) = self.locate(self.rank_of(id));
        let h = &self.headers[tree as usize];
        c.map(|l| Vec3A::from(self.point(tree, h, l)))
    }

    fn triangle_count(&self) -> usize {
        self.triangle_count as usize
    }
}

impl RayCursor for HccBvh {
    /// i-HCCMesh's own traversal (`trace.rs`).
    #[inline]
    fn closest_hit(&self, ray: &Ray, t_max: f32, stats: &mut TraversalStats) -> Option<RayHit> {
        super::trace::closest_hit(self, self, ray, t_max, stats)
    }

    /// i-HCCMesh's own traversal (`trace.rs`).
    #[inline]
    fn any_hit(&self, ray: &Ray, t_max: f32, stats: &mut TraversalStats) -> bool {
        super::trace::any_hit(self, self, ray, t_max, stats)
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn select_in_word_finds_every_set_bit() {
        for w in [1u64, u64::MAX, 0x8000_0000_0000_0001, 0xF0F0_0000_1234_5678] {
            let mut k = 0;
            for p in 0..64 {
                if w >> p & 1 == 1 {
                    assert_eq!(super::select_in_word(w, k), p, "{w:x} {k}");
                    k += 1;
                }
            }
        }
    }
}
