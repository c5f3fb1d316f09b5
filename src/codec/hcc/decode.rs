//! [`NodeCursor`] over an [`HccBvh`]: boxes from vertex indices, the parent
//! box and the reuse mask; structure from templates and inter-connections.

use glam::Vec3A;

use super::HccBvh;
use super::block::{Block, slot_bits};
use super::node::{
    HighNode, INDEX_MASK, Interconnection, TYPE_LEAF, TYPE_TEMPLATE_LEAF, TreeHeader, field,
    mask_half, multi_leaf, node_type,
};
use super::template::TEMPLATES;
use super::vertices::Vertices;
use crate::cursor::NodeCursor;
use crate::geom::{Aabb, Triangle};

const KIND_HIGH: u8 = 3;
const KIND_EMPTY: u8 = 4;

/// A node handle: the node's decoded box (the parent box its children are
/// decoded against), where it is, and which template it sits in.
#[derive(Clone, Copy, Debug)]
pub struct HccNode {
    bounds: Aabb,
    /// Low-level tree (unused for high-level nodes).
    tree: u32,
    /// Node word index, or high-level node index.
    pos: u32,
    /// Node word index of the first node of the node's template.
    block: u32,
    /// The template's id.
    template: u8,
    /// Node type (`TYPE_*`), [`KIND_HIGH`] or [`KIND_EMPTY`].
    kind: u8,
}

impl HccNode {
    /// The node's decoded box.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// The node word index (low-level nodes).
    pub(super) fn pos(&self) -> u32 {
        self.pos
    }

    /// The node word index of the first node of the node's template.
    pub(super) fn block(&self) -> u32 {
        self.block
    }

    /// The template id of the template the node sits in (low-level nodes;
    /// `None` for high-level nodes).
    pub fn template(&self) -> Option<u8> {
        (self.kind <= TYPE_LEAF as u8).then_some(self.template)
    }
}

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
        HccNode {
            bounds,
            tree,
            pos: start,
            block: start,
            template: if ty == TYPE_LEAF { 0 } else { (w & 31) as u8 },
            kind: ty as u8,
        }
    }

    #[inline(always)]
    fn high_child(&self, i: u32) -> HccNode {
        let h: &HighNode = &self.high[i as usize];
        let bounds = Aabb::from_arrays(h.min, h.max);
        if h.is_leaf() {
            self.low_root(h.a, bounds)
        } else {
            HccNode {
                bounds,
                tree: 0,
                pos: i,
                block: 0,
                template: 0,
                kind: KIND_HIGH,
            }
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

    /// Coordinate `a` of vertex `local` of tree `tree` (header `h`).
    #[inline(always)]
    fn coord(&self, tree: u32, h: &TreeHeader, local: u32, a: usize) -> f32 {
        match &self.vertices {
            Vertices::F32(v) => v[(h.vertex_start + local) as usize][a],
            Vertices::Packed(q) => q.coord(tree as usize, local, a),
        }
    }

    /// Vertex `local` of tree `tree` (header `h`).
    #[inline(always)]
    pub(super) fn point(&self, tree: u32, h: &TreeHeader, local: u32) -> [f32; 3] {
        match &self.vertices {
            Vertices::F32(v) => v[(h.vertex_start + local) as usize],
            Vertices::Packed(q) => q.point(tree as usize, local),
        }
    }

    #[inline(always)]
    fn corners(&self, tree: u32, h: &TreeHeader, c: [u32; 3]) -> Triangle {
        c.map(|i| Vec3A::from(self.point(tree, h, i)))
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
    #[inline]
    fn leaf_box(&self, tree: u32, h: &TreeHeader, pos: u32) -> Aabb {
        let w = self.nodes[pos as usize];
        if self.multi {
            let (b, count) = self.leaf_block(tree, w);
            let mut bx = Aabb::EMPTY;
            for j in 0..count {
                for p in self.corners(tree, h, b.corners(&self.blocks, j)) {
                    bx.grow(p);
                }
            }
            bx
        } else {
            Aabb::of_triangle(&self.corners(tree, h, [field(w, 0), field(w, 1), field(w, 2)]))
        }
    }

    /// Decodes the boxes of the sibling pair at word indices `l`, `l + 1`
    /// … or `l`, `r` for the roots of two templates, children of `parent`.
    #[inline(always)]
    fn child_pair(&self, parent: &HccNode, l: u32, r: u32) -> (Aabb, Aabb, u32, u32) {
        let tree = parent.tree;
        let h = &self.headers[tree as usize];
        let (wl, wr) = (self.nodes[l as usize], self.nodes[r as usize]);
        let (tl, tr) = (node_type(wl), node_type(wr));
        let d = parent.bounds;
        let mask = mask_half(wl) | mask_half(wr) << 3;
        let (bl, br) = match (tl == TYPE_LEAF, tr == TYPE_LEAF) {
            (false, false) => {
                let (mut bl, mut br) = (d, d);
                for e in 0..6 {
                    let w = if e < 3 { wl } else { wr };
                    let v = self.coord(tree, h, self.vertex_field(h, w, e % 3), e % 3);
                    if mask >> e & 1 != 0 {
                        set_extent(&mut br, e, v);
                    } else {
                        set_extent(&mut bl, e, v);
                    }
                }
                (bl, br)
            }
            (true, true) => (self.leaf_box(tree, h, l), self.leaf_box(tree, h, r)),
            (leaf_left, _) => {
                let wi = if leaf_left { wr } else { wl };
                let mut bi = d;
                let mut j = 0;
                for e in 0..6 {
                    if mask >> e & 1 == 0 {
                        let v = self.coord(tree, h, self.vertex_field(h, wi, j), e % 3);
                        set_extent(&mut bi, e, v);
                        j += 1;
                    }
                }
                if leaf_left {
                    (self.leaf_box(tree, h, l), bi)
                } else {
                    (bi, self.leaf_box(tree, h, r))
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
        let mut bits = self.leaf_bits[w];
        for _ in 0..k - self.leaf_rank[w] {
            bits &= bits - 1;
        }
        (w * 64) as u32 + bits.trailing_zeros()
    }

    /// The tree, leaf word and local corners of the triangle of storage
    /// rank `rank`. One triangle a leaf: the leaf word of rank `rank` by
    /// select. Several: the tree by a binary search over the trees' first
    /// ranks, then the leaf by a binary search over the tree's leaves'
    /// first slots (ascending in node-word order).
    fn locate(&self, rank: u32) -> (u32, [u32; 3]) {
        if self.multi {
            let tree = self.headers.partition_point(|h| h.first_triangle <= rank) - 1;
            let h = &self.headers[tree];
            let slot = rank - h.first_triangle;
            let (node_end, _, _) = self.tree_ends(tree);
            let (lo, hi) = (
                self.leaves_before(h.node_start),
                self.leaves_before(node_end),
            );
            let first_slot = |k: u32| {
                let w = self.nodes[self.select_leaf(k) as usize];
                self.leaf_block(tree as u32, w).0.slot
            };
            // The last leaf whose first slot is at most `slot`.
            let (mut a, mut b) = (lo, hi);
            while b - a > 1 {
                let m = a + (b - a) / 2;
                if first_slot(m) <= slot {
                    a = m;
                } else {
                    b = m;
                }
            }
            let w = self.nodes[self.select_leaf(a) as usize];
            let (blk, _) = self.leaf_block(tree as u32, w);
            (tree as u32, blk.corners(&self.blocks, slot - blk.slot))
        } else {
            let pos = self.select_leaf(rank);
            let w = self.nodes[pos as usize];
            (
                self.tree_of_word(pos) as u32,
                [field(w, 0), field(w, 1), field(w, 2)],
            )
        }
    }

    /// Leaf words before word `pos` (`pos` up to the number of words).
    fn leaves_before(&self, pos: u32) -> u32 {
        let (w, b) = ((pos / 64) as usize, pos % 64);
        match self.leaf_bits.get(w) {
            Some(bits) => self.leaf_rank[w] + (bits & ((1u64 << b) - 1)).count_ones(),
            None => self.leaf_rank.last().map_or(0, |&r| {
                r + self.leaf_bits.last().map_or(0, |b| b.count_ones())
            }),
        }
    }

    /// Triangle `id`'s corners as indices into [`HccBvh::decoded_mesh`]'s
    /// vertices (the input's vertex indices when vertex ids are kept).
    /// Finds the triangle's rank through the id map's shortcuts, then its
    /// leaf (see `locate`).
    pub fn triangle_vertex_indices(&self, id: u32) -> [u32; 3] {
        let rank = self.ids.rank(id).unwrap_or(0);
        let (tree, c) = self.locate(rank);
        let base = self.headers[tree as usize].vertex_start;
        c.map(|l| self.vertex_index(base + l))
    }

    /// The low-level tree holding node word `pos`.
    fn tree_of_word(&self, pos: u32) -> usize {
        self.headers.partition_point(|h| h.node_start <= pos) - 1
    }
}

impl NodeCursor for HccBvh {
    type Node = HccNode;

    fn root(&self) -> (HccNode, Aabb) {
        if self.headers.is_empty() {
            let n = HccNode {
                bounds: Aabb::EMPTY,
                tree: 0,
                pos: 0,
                block: 0,
                template: 0,
                kind: KIND_EMPTY,
            };
            return (n, Aabb::EMPTY);
        }
        let n = self.high_child(0);
        (n, n.bounds)
    }

    #[inline(always)]
    fn is_leaf(&self, node: &HccNode) -> bool {
        node.kind == TYPE_LEAF as u8 || node.kind == KIND_EMPTY
    }

    #[inline]
    fn for_each_child(&self, node: &HccNode, mut f: impl FnMut(HccNode, Aabb)) {
        if node.kind == KIND_HIGH {
            let h = &self.high[node.pos as usize];
            for c in [h.a, h.b] {
                let n = self.high_child(c);
                f(n, n.bounds);
            }
            return;
        }
        let (l, r, bl, br, tl, tr) = if node.kind == TYPE_TEMPLATE_LEAF as u8 {
            let h = &self.headers[node.tree as usize];
            let w = self.nodes[node.pos as usize];
            let ic = Interconnection::unpack(self.ics[(h.ic_start + field(w, 2)) as usize]);
            let l = h.node_start + ic.left_start;
            let r = l + TEMPLATES[ic.left_template as usize].nodes as u32;
            (l, r, l, r, ic.left_template, ic.right_template)
        } else {
            let t = &TEMPLATES[node.template as usize];
            let l = node.block + t.children(node.pos - node.block);
            (
                l,
                l + 1,
                node.block,
                node.block,
                node.template,
                node.template,
            )
        };
        let (bxl, bxr, kl, kr) = self.child_pair(node, l, r);
        let child = |pos, block, template, kind: u32, bounds| HccNode {
            bounds,
            tree: node.tree,
            pos,
            block,
            template,
            kind: kind as u8,
        };
        f(child(l, bl, tl, kl, bxl), bxl);
        f(child(r, br, tr, kr, bxr), bxr);
    }

    #[inline]
    fn for_each_triangle(&self, node: &HccNode, mut f: impl FnMut(u32, &Triangle)) {
        if node.kind == KIND_EMPTY {
            return;
        }
        let h = &self.headers[node.tree as usize];
        self.leaf_triangles(node.tree, node.pos, |rank, c| {
            f(self.ids.id(rank), &self.corners(node.tree, h, c));
        });
    }

    fn triangle(&self, id: u32) -> Triangle {
        let rank = self.ids.rank(id).unwrap_or(0);
        let (tree, c) = self.locate(rank);
        self.corners(tree, &self.headers[tree as usize], c)
    }

    fn triangle_count(&self) -> usize {
        self.triangle_count as usize
    }
}
