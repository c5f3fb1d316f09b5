//! [`NodeCursor`] over a [`PlainBvh`].

use glam::Vec3A;

use super::PlainBvh;
use crate::cursor::NodeCursor;
use crate::geom::{Aabb, Triangle};

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
        let n = &self.nodes[*node as usize];
        f(n.left, self.nodes[n.left as usize].aabb());
        f(n.right, self.nodes[n.right as usize].aabb());
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
