//! [`NodeCursor`] for [`RacBvh`], with the node handle [`RacNode`], and
//! [`RayCursor`] with the generic ray traversals.

use super::RacBvh;
use super::cache;
use super::decode::Cluster;
use super::node::INCOMPLETE;
use crate::build::LEAF_FLAG;
use crate::cursor::{Children, NodeCursor};
use crate::geom::{Aabb, Triangle};
use crate::query::RayCursor;

/// The cursor's node handle: the global node index with the node's words
/// 6 and 7 (children, or a leaf's triangle id / slot and count), so that
/// `is_leaf`, `for_each_child` and a one-triangle leaf's
/// `for_each_triangle` do not read the node again.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RacNode {
    index: u32,
    a: u32,
    b: u32,
}

impl RacNode {
    /// The global node index (for the random-access API).
    pub fn index(&self) -> u32 {
        self.index
    }

    #[inline]
    fn new(index: u32, w: &[u32; 8]) -> Self {
        Self {
            index,
            a: w[6],
            b: w[7],
        }
    }
}

impl RacBvh {
    /// The two children of the inner node `node` with their boxes.
    // Always inlined, as `for_each_child` was with its closure: a call
    // would return the pair through memory.
    #[inline(always)]
    fn children_of(&self, node: &RacNode) -> [(RacNode, Aabb); 2] {
        // With a node cache (a budget smaller than the tree), each child
        // from it, else as `words` finds it.
        if self.nodes.is_some() {
            let [wa, wb] = [self.words(node.a), self.words(node.b)];
            return [
                (RacNode::new(node.a, &wa), self.box_of(&wa)),
                (RacNode::new(node.b, &wb), self.box_of(&wb)),
            ];
        }
        // Fast path: both children complete in the thread's pinned cluster
        // (one thread-local look-up for the two).
        let cb = self.header.cluster_bits;
        let c = node.a >> cb;
        let fast = cache::with_pinned(self.id, c, |cl: &Cluster| {
            let mut out = [[0u32; 8]; 2];
            for (slot, child) in out.iter_mut().zip([node.a, node.b]) {
                if child >> cb != c {
                    return None;
                }
                let cw = cl.nodes[(child - cl.first) as usize].words();
                if cw[0] & INCOMPLETE != 0 {
                    return None;
                }
                *slot = cw;
            }
            Some(out)
        });
        let [wa, wb] = fast.unwrap_or_else(|| [self.words(node.a), self.words(node.b)]);
        [
            (RacNode::new(node.a, &wa), self.box_of(&wa)),
            (RacNode::new(node.b, &wb), self.box_of(&wb)),
        ]
    }
}

impl NodeCursor for RacBvh {
    type Node = RacNode;

    fn root(&self) -> (RacNode, Aabb) {
        let w = self.words(0);
        (RacNode::new(0, &w), self.box_of(&w))
    }

    #[inline]
    fn is_leaf(&self, node: &RacNode) -> bool {
        node.b & LEAF_FLAG != 0
    }

    #[inline]
    fn for_each_child(&self, node: &RacNode, mut f: impl FnMut(RacNode, Aabb)) {
        for (child, b) in self.children_of(node) {
            f(child, b);
        }
    }

    /// Both children written at once (a batch of two, known as such where
    /// the traversal is compiled).
    #[inline(always)]
    fn children(&self, node: &RacNode, out: &mut Children<RacNode>) {
        out.set(&self.children_of(node));
    }

    #[inline]
    fn for_each_triangle(&self, node: &RacNode, mut f: impl FnMut(u32, &Triangle)) {
        let count = node.b & !LEAF_FLAG;
        if count == 1 {
            f(node.a, &self.cached_triangle(node.a));
        } else if count > 1 {
            self.try_leaf_ids(node.index, &mut |id| f(id, &self.cached_triangle(id)))
                .unwrap_or_else(|e| panic!("racbvh: {e}"));
        }
    }

    #[inline]
    fn triangle(&self, id: u32) -> Triangle {
        self.cached_triangle(id)
    }

    fn triangle_count(&self) -> usize {
        self.header.triangle_count as usize
    }
}

/// The generic ray traversals.
impl RayCursor for RacBvh {}
