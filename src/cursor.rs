//! [`NodeCursor`]: the one traversal interface every codec implements.
//!
//! A cursor hands out opaque node handles. A handle carries whatever decode
//! state its codec needs to decode the node's children (for the plain codec
//! just an index; for hierarchical quantization the parent's box; for a
//! template codec a template position). Traversals ask a cursor for:
//!
//! - the root handle and the root's box;
//! - whether a handle is a leaf;
//! - an inner node's children, each with its *conservative* decoded box
//!   (binary trees give two, 8-wide trees up to [`MAX_CHILDREN`]);
//! - a leaf's triangles, as stable triangle ids (the original mesh's ids)
//!   with their corners.
//!
//! The queries in [`crate::query`] are written once over this trait, with
//! the primitive test passed in as a closure, and monomorphized per codec.

use crate::geom::{Aabb, Triangle};

/// The most children an inner node may have (8-wide trees).
pub const MAX_CHILDREN: usize = 8;

/// Traversal of a bounding volume hierarchy, independent of how it is stored.
///
/// Implementations must guarantee the invariant every codec is tested for:
/// the box given for a node contains every triangle below it.
pub trait NodeCursor: Sync {
    /// An opaque node handle with the codec's decode state.
    type Node: Copy + Send + Sync;

    /// The root handle and the root's box. For a tree over no triangles the
    /// box is empty and the root is a leaf without triangles.
    fn root(&self) -> (Self::Node, Aabb);

    /// Whether `node` is a leaf.
    fn is_leaf(&self, node: &Self::Node) -> bool;

    /// Calls `f` with each child of the inner node `node` and the child's
    /// conservative box. Must not be called on a leaf.
    fn for_each_child(&self, node: &Self::Node, f: impl FnMut(Self::Node, Aabb));

    /// Calls `f` with the id and corners of each triangle of the leaf
    /// `node`. Must not be called on an inner node.
    fn for_each_triangle(&self, node: &Self::Node, f: impl FnMut(u32, &Triangle));

    /// The corners of triangle `id` (an id a leaf reported).
    fn triangle(&self, id: u32) -> Triangle;

    /// Number of triangles in the tree.
    fn triangle_count(&self) -> usize;
}

/// Traversal counters, for the papers' "travs/isecs" figures.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct TraversalStats {
    /// Nodes whose box was tested or whose children were decoded.
    pub nodes_visited: u64,
    /// Primitive (triangle or triangle-pair) tests.
    pub primitive_tests: u64,
}

impl TraversalStats {
    /// Adds another set of counters to this one.
    pub fn add(&mut self, o: &TraversalStats) {
        self.nodes_visited += o.nodes_visited;
        self.primitive_tests += o.primitive_tests;
    }
}

/// Hints the processor to bring the cache line at `p` in (for cursors that
/// know which nodes a traversal reads next); never faults, so any address
/// (even one past the array) is fine.
#[inline(always)]
pub(crate) fn prefetch<T>(p: *const T) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        // SAFETY: a prefetch is a hint that never dereferences its address
        // architecturally (no fault on any address); SSE is part of x86_64.
        unsafe { _mm_prefetch::<_MM_HINT_T0>(p.cast::<i8>()) };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}
