//! [`NodeCursor`] over an [`HccBvh`]: boxes from vertex indices, the parent
//! box and the reuse mask; structure from templates and inter-connections.

use glam::Vec3A;

use super::HccBvh;
use super::node::{
    HighNode, INDEX_BITS, INDEX_MASK, Interconnection, TYPE_LEAF, TYPE_TEMPLATE_LEAF, TreeHeader,
    field, mask_half, multi_range, node_type,
};
use super::template::TEMPLATES;
use crate::cursor::{Children, NodeCursor};
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

    #[inline(always)]
    fn vertex(&self, h: &TreeHeader, local: u32) -> [f32; 3] {
        self.vertices[(h.vertex_start + local) as usize]
    }

    /// The corners (local vertex indices) of triangle slot `t`.
    #[inline(always)]
    pub(super) fn multi_corners(&self, t: u32) -> [u32; 3] {
        let w = self.triangles[t as usize];
        [
            w & INDEX_MASK,
            w >> INDEX_BITS & INDEX_MASK,
            w >> (2 * INDEX_BITS) & INDEX_MASK,
        ]
    }

    #[inline(always)]
    fn corners(&self, h: &TreeHeader, c: [u32; 3]) -> Triangle {
        c.map(|i| Vec3A::from(self.vertex(h, i)))
    }

    /// The tight box of a leaf word's triangles.
    #[inline]
    fn leaf_box(&self, h: &TreeHeader, w: u32) -> Aabb {
        if self.multi {
            let (start, count) = multi_range(w);
            let mut b = Aabb::EMPTY;
            for t in h.first_triangle + start..h.first_triangle + start + count {
                for p in self.corners(h, self.multi_corners(t)) {
                    b.grow(p);
                }
            }
            b
        } else {
            Aabb::of_triangle(&self.corners(h, [field(w, 0), field(w, 1), field(w, 2)]))
        }
    }

    /// Decodes the boxes of the sibling pair at word indices `l`, `l + 1`
    /// … or `l`, `r` for the roots of two templates, children of `parent`.
    #[inline(always)]
    fn child_pair(&self, parent: &HccNode, l: u32, r: u32) -> (Aabb, Aabb, u32, u32) {
        let h = &self.headers[parent.tree as usize];
        let (wl, wr) = (self.nodes[l as usize], self.nodes[r as usize]);
        let (tl, tr) = (node_type(wl), node_type(wr));
        let d = parent.bounds;
        let mask = mask_half(wl) | mask_half(wr) << 3;
        let (bl, br) = match (tl == TYPE_LEAF, tr == TYPE_LEAF) {
            (false, false) => {
                let (mut bl, mut br) = (d, d);
                for e in 0..6 {
                    let w = if e < 3 { wl } else { wr };
                    let v = self.vertex(h, self.vertex_field(h, w, e % 3))[e % 3];
                    if mask >> e & 1 != 0 {
                        set_extent(&mut br, e, v);
                    } else {
                        set_extent(&mut bl, e, v);
                    }
                }
                (bl, br)
            }
            (true, true) => (self.leaf_box(h, wl), self.leaf_box(h, wr)),
            (leaf_left, _) => {
                let wi = if leaf_left { wr } else { wl };
                let mut bi = d;
                let mut j = 0;
                for e in 0..6 {
                    if mask >> e & 1 == 0 {
                        let v = self.vertex(h, self.vertex_field(h, wi, j))[e % 3];
                        set_extent(&mut bi, e, v);
                        j += 1;
                    }
                }
                if leaf_left {
                    (self.leaf_box(h, wl), bi)
                } else {
                    (bi, self.leaf_box(h, wr))
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

    /// Triangle `id`'s corners as indices into the stored vertex array
    /// (the low-level trees' arrays one after the other, as
    /// [`HccBvh::decoded_mesh`] gives them). With one triangle a leaf, the
    /// leaf word of rank `id` is found by select over the leaf bits; with
    /// several, the tree by a binary search over the first ids.
    pub fn triangle_vertex_indices(&self, id: u32) -> [u32; 3] {
        if self.multi {
            let tree = self.headers.partition_point(|h| h.first_triangle <= id) - 1;
            let base = self.headers[tree].vertex_start;
            self.multi_corners(id).map(|c| base + c)
        } else {
            let w = self.leaf_rank.partition_point(|&r| r <= id) - 1;
            let mut bits = self.leaf_bits[w];
            for _ in 0..id - self.leaf_rank[w] {
                bits &= bits - 1;
            }
            let pos = (w * 64) as u32 + bits.trailing_zeros();
            let base = self.headers[self.tree_of_word(pos)].vertex_start;
            let word = self.nodes[pos as usize];
            [0, 1, 2].map(|j| base + field(word, j))
        }
    }

    /// The low-level tree holding node word `pos`.
    fn tree_of_word(&self, pos: u32) -> usize {
        self.headers.partition_point(|h| h.node_start <= pos) - 1
    }
}

impl HccBvh {
    /// The two children of the inner node `node` with their boxes.
    // Always inlined, as `for_each_child` was with its closure: a call
    // would return the pair through memory.
    #[inline(always)]
    fn children_of(&self, node: &HccNode) -> [(HccNode, Aabb); 2] {
        if node.kind == KIND_HIGH {
            let h = &self.high[node.pos as usize];
            return [h.a, h.b].map(|c| {
                let n = self.high_child(c);
                (n, n.bounds)
            });
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
        [
            (child(l, bl, tl, kl, bxl), bxl),
            (child(r, br, tr, kr, bxr), bxr),
        ]
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
        for (child, b) in self.children_of(node) {
            f(child, b);
        }
    }

    /// Both children written at once (a batch of two, known as such where
    /// the traversal is compiled).
    #[inline(always)]
    fn children(&self, node: &HccNode, out: &mut Children<HccNode>) {
        out.set(&self.children_of(node));
    }

    #[inline]
    fn for_each_triangle(&self, node: &HccNode, mut f: impl FnMut(u32, &Triangle)) {
        if node.kind == KIND_EMPTY {
            return;
        }
        let h = &self.headers[node.tree as usize];
        let w = self.nodes[node.pos as usize];
        if self.multi {
            let (start, count) = multi_range(w);
            for t in h.first_triangle + start..h.first_triangle + start + count {
                f(t, &self.corners(h, self.multi_corners(t)));
            }
        } else {
            let id = self.leaf_rank_of(node.pos);
            f(
                id,
                &self.corners(h, [field(w, 0), field(w, 1), field(w, 2)]),
            );
        }
    }

    fn triangle(&self, id: u32) -> Triangle {
        let [a, b, c] = self.triangle_vertex_indices(id);
        [a, b, c].map(|v| Vec3A::from(self.vertices[v as usize]))
    }

    fn triangle_count(&self) -> usize {
        self.triangle_count as usize
    }
}
