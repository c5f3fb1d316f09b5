//! [`NodeCursor`] over a [`PlainBvh`], and [`RayCursor`] with the generic
//! ray traversals.

use glam::Vec3A;

use super::PlainBvh;
use super::node::PlainNode;
use crate::cursor::{Children, NodeCursor, prefetch};
use crate::geom::{Aabb, Triangle};
use crate::query::RayCursor;

impl PlainBvh {
    /// The inner node `node` and its two children, with the grandchildren
    /// asked for: a traversal that descends into a child reads them next,
    /// and the far one is a cache miss otherwise.
    #[inline]
    fn child_nodes(&self, node: u32) -> (&PlainNode, &PlainNode, &PlainNode) {
        let n = &self.nodes[node as usize];
        let (l, r) = (&self.nodes[n.left as usize], &self.nodes[n.right as usize]);
        for c in [l, r] {
            if !c.is_leaf() {
                prefetch(self.nodes.as_ptr().wrapping_add(c.left as usize));
                prefetch(self.nodes.as_ptr().wrapping_add(c.right as usize));
            }
        }
        (n, l, r)
    }
}

impl NodeCursor for PlainBvh {
    /// A node index.
    type Node = u32;

    #[inline]
    fn root(&self) -> (u32, Aabb) {
        (0, self.nodes[0].aabb())
    }

    #[inline]
    fn is_leaf(&self, node: &u32) -> bool {
        self.nodes[*node as usize].is_leaf()
    }

    #[inline]
    fn for_each_child(&self, node: &u32, mut f: impl FnMut(u32, Aabb)) {
        let (n, l, r) = self.child_nodes(*node);
        f(n.left, l.aabb());
        f(n.right, r.aabb());
    }

    #[inline(always)]
    fn children(&self, node: &u32, out: &mut Children<u32>) {
        let (n, l, r) = self.child_nodes(*node);
        out.set(&[(n.left, l.aabb()), (n.right, r.aabb())]);
    }

    #[inline]
    fn for_each_triangle(&self, node: &u32, mut f: impl FnMut(u32, &Triangle)) {
        let n = &self.nodes[*node as usize];
        if self.leaf_ids.is_empty() {
            if n.leaf_count() == 1 {
                f(n.left, &self.triangle(n.left));
            }
        } else {
            let first = n.left as usize;
            for &id in &self.leaf_ids[first..first + n.leaf_count() as usize] {
                f(id, &self.triangle(id));
            }
        }
    }

    #[inline]
    fn triangle(&self, id: u32) -> Triangle {
        let [a, b, c] = self.triangles[id as usize];
        [
            Vec3A::from(self.vertices[a as usize]),
            Vec3A::from(self.vertices[b as usize]),
            Vec3A::from(self.vertices[c as usize]),
        ]
    }

    fn triangle_count(&self) -> usize {
        self.triangles.len()
    }
}

/// The generic ray traversals.
impl RayCursor for PlainBvh {}
