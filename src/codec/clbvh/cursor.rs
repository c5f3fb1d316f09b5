//! [`NodeCursor`] over a [`ClBvh`], and its [`RayCursor`] through CLBVH's
//! own traversal (`trace.rs`); [`ClBvhCompact`]'s both delegate to its
//! [`ClBvh`].

use glam::Vec3A;

use super::node::{
    ChildRef, ENDS_WORDS, MULTI_WORDS, MultiLeafNode, TAG_INNER, TAG_LEAF, TAG_MULTI, ref_index,
    ref_tag,
};
use super::simd::{SoaBoxes, dequantize};
use super::{ClBvh, ClBvhCompact, LeafKind};
use crate::cursor::{ChildBoxes, Children, MAX_CHILDREN, NodeCursor, TraversalStats};
use crate::geom::{Aabb, Ray, Triangle};
use crate::query::{RayCursor, RayHit};

/// Lane value of a [`ClNode`] that stands for a whole node.
const WHOLE: u32 = u32::MAX;

/// A node handle: an inner node, a multi-leaf node, one lane (leaf) of a
/// multi-leaf node, or an isolated leaf.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ClNode {
    r: ChildRef,
    lane: u32,
}

/// What a [`ClNode`] stands for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NodeKind {
    /// A regular inner multi-node.
    Inner,
    /// A compressed multi-leaf node (its children are its lanes).
    MultiLeaf,
    /// One lane of a multi-leaf node: a leaf.
    Lane,
    /// An isolated leaf (the child of a regular inner node, or the root).
    Leaf,
}

impl ClBvh {
    /// What `node` stands for.
    pub fn kind(&self, node: &ClNode) -> NodeKind {
        match ref_tag(node.r) {
            TAG_INNER => NodeKind::Inner,
            TAG_LEAF => NodeKind::Leaf,
            _ if node.lane == WHOLE => NodeKind::MultiLeaf,
            _ => NodeKind::Lane,
        }
    }

    /// The leaf ends of the multi-leaf node at word `at`.
    #[inline]
    pub(super) fn ends(&self, at: usize) -> [u8; 8] {
        let w = &self.arena[at + MULTI_WORDS..at + MULTI_WORDS + ENDS_WORDS];
        let (a, b) = (w[0].to_le_bytes(), w[1].to_le_bytes());
        [a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3]]
    }

    /// Calls `f` for triangles `range` of the leaf block at word `b`.
    #[inline]
    fn block_triangles(
        &self,
        b: usize,
        range: std::ops::Range<usize>,
        mut f: impl FnMut(u32, &Triangle),
    ) {
        let hdr = self.arena[b];
        let n = (hdr & 0xFFFF) as usize;
        match self.options.leaves {
            LeafKind::Fast => {
                let ids = &self.arena[b + 1..b + 1 + n];
                let corners = &self.arena[b + 1 + n..b + 1 + 10 * n];
                for j in range {
                    let c = &corners[9 * j..9 * j + 9];
                    let p = |k: usize| {
                        Vec3A::new(
                            f32::from_bits(c[3 * k]),
                            f32::from_bits(c[3 * k + 1]),
                            f32::from_bits(c[3 * k + 2]),
                        )
                    };
                    f(ids[j], &[p(0), p(1), p(2)]);
                }
            }
            LeafKind::Compact => {
                let u = (hdr >> 16) as usize;
                let uniq = &self.arena[b + 1..b + 1 + u];
                let ids = &self.arena[b + 1 + u..b + 1 + u + n];
                let local: &[u8] = bytemuck::cast_slice(&self.arena[b + 1 + u + n..]);
                for j in range {
                    let v = [0, 1, 2].map(|k| uniq[local[3 * j + k] as usize]);
                    f(ids[j], &self.corners(v));
                }
            }
        }
    }
}

impl NodeCursor for ClBvh {
    type Node = ClNode;

    #[inline]
    fn root(&self) -> (ClNode, Aabb) {
        (
            ClNode {
                r: self.root,
                lane: WHOLE,
            },
            self.root_box,
        )
    }

    #[inline]
    fn is_leaf(&self, node: &ClNode) -> bool {
        match ref_tag(node.r) {
            TAG_LEAF => true,
            TAG_MULTI => node.lane != WHOLE,
            _ => false,
        }
    }

    #[inline]
    fn for_each_child(&self, node: &ClNode, mut f: impl FnMut(ClNode, Aabb)) {
        let at = ref_index(node.r);
        if ref_tag(node.r) == TAG_INNER {
            let n = &self.inner[at];
            for k in 0..8 {
                let r = n.child[k];
                if r == 0 {
                    break;
                }
                f(ClNode { r, lane: WHOLE }, n.child_box(k));
            }
        } else {
            let m = MultiLeafNode::read(&self.arena, at);
            let mut prev = 0;
            for (k, end) in self.ends(at).into_iter().enumerate() {
                if end > prev {
                    f(
                        ClNode {
                            r: node.r,
                            lane: k as u32,
                        },
                        m.child_box(k),
                    );
                }
                prev = end;
            }
        }
    }

    /// The node's child boxes go into the batch's lanes as rows: an inner
    /// node's are stored as rows already, a multi-leaf node's eight 8-bit
    /// boxes are dequantized at once ([`dequantize`], the same bits as
    /// [`MultiLeafNode::child_box`]). Same children, same order, same boxes
    /// as [`for_each_child`](NodeCursor::for_each_child).
    #[inline]
    fn children(&self, node: &ClNode, out: &mut Children<ClNode>) {
        let at = ref_index(node.r);
        if ref_tag(node.r) == TAG_INNER {
            let n = &self.inner[at];
            // Used lanes come first (`verify` proves it).
            let used = n.child.iter().take_while(|&&r| r != 0).count();
            let boxes = ChildBoxes::from_rows(
                used,
                [&n.min_x, &n.min_y, &n.min_z],
                [&n.max_x, &n.max_y, &n.max_z],
            );
            let kids: [ClNode; MAX_CHILDREN] = std::array::from_fn(|k| ClNode {
                r: n.child[k],
                lane: WHOLE,
            });
            out.set_boxes(boxes, kids);
        } else {
            let m = MultiLeafNode::read(&self.arena, at);
            let ends = self.ends(at);
            // A lane is used when it holds triangles; the encoder puts the
            // used lanes first, and a verified file may (harmlessly) not.
            let mut lanes = 0u32;
            let mut prev = 0;
            for (k, &end) in ends.iter().enumerate() {
                lanes |= u32::from(end > prev) << k;
                prev = end;
            }
            if lanes & (lanes + 1) != 0 {
                return scattered_lanes(self, node, out);
            }
            let used = lanes.count_ones() as usize;
            let mut soa: SoaBoxes = [[0.0; 8]; 6];
            dequantize(&m, &mut soa);
            let [min_x, max_x, min_y, max_y, min_z, max_z] = &soa;
            let boxes = ChildBoxes::from_rows(used, [min_x, min_y, min_z], [max_x, max_y, max_z]);
            let kids: [ClNode; MAX_CHILDREN] = std::array::from_fn(|k| ClNode {
                r: node.r,
                lane: k as u32,
            });
            out.set_boxes(boxes, kids);
        }
    }

    #[inline]
    fn for_each_triangle(&self, node: &ClNode, f: impl FnMut(u32, &Triangle)) {
        let at = ref_index(node.r);
        if ref_tag(node.r) == TAG_LEAF {
            let n = (self.arena[at] & 0xFFFF) as usize;
            self.block_triangles(at, 0..n, f);
        } else {
            let ends = self.ends(at);
            let k = node.lane as usize;
            let first = if k == 0 { 0 } else { ends[k - 1] as usize };
            self.block_triangles(at + MULTI_WORDS + ENDS_WORDS, first..ends[k] as usize, f);
        }
    }

    #[inline]
    fn triangle(&self, id: u32) -> Triangle {
        self.corners(self.vertex_indices(id))
    }

    fn triangle_count(&self) -> usize {
        match self.options.leaves {
            LeafKind::Fast => self.triangles.len(),
            LeafKind::Compact => self.slot_of.len(),
        }
    }
}

impl RayCursor for ClBvh {
    /// CLBVH's own traversal (`trace.rs`).
    #[inline]
    fn closest_hit(&self, ray: &Ray, t_max: f32, stats: &mut TraversalStats) -> Option<RayHit> {
        super::trace::closest_hit(self, ray, t_max, stats)
    }

    /// CLBVH's own traversal (`trace.rs`).
    #[inline]
    fn any_hit(&self, ray: &Ray, t_max: f32, stats: &mut TraversalStats) -> bool {
        super::trace::any_hit(self, ray, t_max, stats)
    }

    /// Ray by ray through CLBVH's own traversal, which is faster than the
    /// generic packet walk over this tree's batches (see
    /// [`RayCursor::closest_hits_within`]).
    #[inline]
    fn closest_hits_within(
        &self,
        rays: &[Ray],
        t_max: &[f32],
        out: &mut [Option<RayHit>],
        stats: &mut TraversalStats,
    ) {
        for ((ray, &t), hit) in rays.iter().zip(t_max).zip(out) {
            *hit = super::trace::closest_hit(self, ray, t, stats);
        }
    }
}

/// [`NodeCursor::children`] of a multi-leaf node whose used lanes are not
/// the first ones: lane by lane (no file the encoder writes has one).
#[cold]
fn scattered_lanes(c: &ClBvh, node: &ClNode, out: &mut Children<ClNode>) {
    out.clear();
    c.for_each_child(node, |n, b| out.push(n, b));
}

impl NodeCursor for ClBvhCompact {
    type Node = super::ClNode;

    #[inline]
    fn root(&self) -> (Self::Node, crate::geom::Aabb) {
        self.0.root()
    }

    #[inline]
    fn is_leaf(&self, node: &Self::Node) -> bool {
        self.0.is_leaf(node)
    }

    #[inline]
    fn for_each_child(&self, node: &Self::Node, f: impl FnMut(Self::Node, crate::geom::Aabb)) {
        self.0.for_each_child(node, f)
    }

    #[inline]
    fn children(&self, node: &Self::Node, out: &mut crate::cursor::Children<Self::Node>) {
        self.0.children(node, out)
    }

    #[inline]
    fn for_each_triangle(&self, node: &Self::Node, f: impl FnMut(u32, &crate::geom::Triangle)) {
        self.0.for_each_triangle(node, f)
    }

    #[inline]
    fn triangle(&self, id: u32) -> crate::geom::Triangle {
        self.0.triangle(id)
    }

    fn triangle_count(&self) -> usize {
        self.0.triangle_count()
    }
}

impl RayCursor for ClBvhCompact {
    #[inline]
    fn closest_hit(
        &self,
        ray: &crate::geom::Ray,
        t_max: f32,
        stats: &mut crate::cursor::TraversalStats,
    ) -> Option<crate::query::RayHit> {
        self.0.closest_hit(ray, t_max, stats)
    }

    #[inline]
    fn any_hit(
        &self,
        ray: &crate::geom::Ray,
        t_max: f32,
        stats: &mut crate::cursor::TraversalStats,
    ) -> bool {
        self.0.any_hit(ray, t_max, stats)
    }

    #[inline]
    fn closest_hits_within(
        &self,
        rays: &[crate::geom::Ray],
        t_max: &[f32],
        out: &mut [Option<crate::query::RayHit>],
        stats: &mut crate::cursor::TraversalStats,
    ) {
        self.0.closest_hits_within(rays, t_max, out, stats)
    }
}
