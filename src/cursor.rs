//! [`NodeCursor`]: the one traversal interface every codec implements.
//!
//! A cursor hands out opaque node handles. A handle carries whatever decode
//! state its codec needs to decode the node's children (for the plain codec
//! just an index; for hierarchical quantization the parent's box; for a
//! template codec a template position). Traversals ask a cursor for:
//!
//! - the root handle and the root's box;
//! - whether a handle is a leaf;
//! - an inner node's children as a *batch* ([`Children`]): their handles and
//!   their *conservative* decoded boxes in structure-of-arrays form
//!   ([`ChildBoxes`]), so that a traversal tests all of them at once (binary
//!   trees give two, 8-wide trees up to [`MAX_CHILDREN`]);
//! - a leaf's triangles, as stable triangle ids (the original mesh's ids)
//!   with their corners; or, for a traversal that tests many triangles and
//!   reports few, as *keys* that the cursor turns into ids on request
//!   ([`NodeCursor::for_each_triangle_keyed`], [`NodeCursor::id_of_key`]),
//!   so that a codec whose ids cost a look-up (i-HCCMesh's rank-to-id map)
//!   pays only for the ids reported.
//!
//! The queries in [`crate::query`] are written once over this trait, with
//! the primitive test passed in as a closure, and monomorphized per codec.
//! Which child a query descends into first is the query's choice (nearest
//! first for closest hits, lane order elsewhere), never the cursor's.
//!
//! This module calls no query. The three ray queries that a codec may
//! answer with a traversal of its own (closest hit, any hit, a packet's
//! closest hits) are methods of
//! [`query::RayCursor`](crate::query::RayCursor), a trait over this one in
//! the query layer, which every codec's cursor implements: the codecs
//! depend on the queries, the queries on this trait, and this trait on
//! nothing above it.

mod batch;
mod scaled;

pub use batch::ChildBoxes;
pub use scaled::Scaled;

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
    /// conservative box, in the node's child order. Must not be called on a
    /// leaf.
    ///
    /// This is the fallback the default [`children`](Self::children) builds
    /// on; the queries use [`children`](Self::children) only.
    fn for_each_child(&self, node: &Self::Node, f: impl FnMut(Self::Node, Aabb));

    /// Writes the children of the inner node `node` into `out` as one
    /// batch, replacing what it held: lane `i` is the `i`-th child (the
    /// order of [`for_each_child`](Self::for_each_child)) with its
    /// conservative box. Must not be called on a leaf.
    ///
    /// The default collects what [`for_each_child`](Self::for_each_child)
    /// gives; a codec overrides it when it can write the batch directly.
    /// The binary codecs (plain, RACBVH, HCC) write their two children at
    /// once ([`Children::set`] with a pair, so that the traversal compiled
    /// for them sees a batch of two: through the default, RACBVH and HCC
    /// ran 25–50 % more instructions per closest- or any-hit ray); CLBVH,
    /// 8-wide, writes its float or dequantized child boxes straight into
    /// the lanes with [`ChildBoxes::from_rows`].
    #[inline(always)]
    fn children(&self, node: &Self::Node, out: &mut Children<Self::Node>) {
        // Two children (a binary node) are staged in registers' worth of
        // memory and written whole; more are pushed one by one.
        let mut first = [(*node, Aabb::EMPTY); 2];
        let mut n = 0;
        self.for_each_child(node, |c, b| {
            if let Some(slot) = first.get_mut(n) {
                *slot = (c, b);
            }
            n += 1;
        });
        if n == first.len() {
            // A binary node: two lanes, written whole.
            out.set(&first);
        } else if n < first.len() {
            out.set(&first[..n]);
        } else {
            collect_children(self, node, out);
        }
    }

    /// Calls `f` with the id and corners of each triangle of the leaf
    /// `node`. Must not be called on an inner node.
    fn for_each_triangle(&self, node: &Self::Node, f: impl FnMut(u32, &Triangle));

    /// [`for_each_triangle`](Self::for_each_triangle) with a *key* in
    /// place of each id: [`id_of_key`](Self::id_of_key) turns it into the
    /// id. A codec whose ids cost a look-up of their own (i-HCCMesh maps
    /// its storage order to the input's ids) passes its storage rank, so
    /// that a traversal that tests many triangles and reports few (the
    /// two-tree traversal) looks up only the ids it reports. The default
    /// passes the id itself.
    #[inline(always)]
    fn for_each_triangle_keyed(&self, node: &Self::Node, f: impl FnMut(u32, &Triangle)) {
        self.for_each_triangle(node, f)
    }

    /// The id of the triangle that [`for_each_triangle_keyed`](Self::for_each_triangle_keyed)
    /// named `key`. The default is `key` itself.
    #[inline(always)]
    fn id_of_key(&self, key: u32) -> u32 {
        key
    }

    /// The corners of the triangle with the original mesh's id `id`.
    ///
    /// Defined for every `id < triangle_count()`, not only for ids a leaf
    /// reported, with the same corners, bit for bit, as the leaf that holds
    /// the triangle reports; and cheap (no tree search): the renderer shades
    /// every hit through it and parry's compatibility path looks parts up by
    /// it. Ids are always the original mesh's, never a codec's storage
    /// order, because results depend on them (ties go to the smaller id), so
    /// that every codec answers every query alike. A codec that stores
    /// triangles implicitly (a template codec such as i-HCCMesh, where a
    /// triangle is a position in a low-level tree) therefore stores the map
    /// from original id to that position (and leaves report original ids
    /// through its inverse), and counts the map in its bytes by part.
    fn triangle(&self, id: u32) -> Triangle;

    /// Number of triangles in the tree.
    fn triangle_count(&self) -> usize;
}

/// [`NodeCursor::children`] for a node with more than two children, by
/// [`NodeCursor::for_each_child`] again (kept out of the traversals' loops:
/// a codec with wide nodes overrides `children`).
#[cold]
fn collect_children<C: NodeCursor + ?Sized>(c: &C, node: &C::Node, out: &mut Children<C::Node>) {
    out.clear();
    c.for_each_child(node, |n, b| out.push(n, b));
}

/// The children of one inner node as a batch: their handles and their
/// boxes ([`ChildBoxes`], lane `i` for child `i`), which
/// [`NodeCursor::children`] writes. A traversal keeps one and has it
/// rewritten at every inner node (no copies of the batch on the way).
#[derive(Clone, Copy, Debug)]
pub struct Children<N> {
    boxes: ChildBoxes,
    /// Lane `i`'s handle; slots past the length hold stale or fill
    /// handles and are never read. Writing a binary node's batch writes
    /// two slots.
    nodes: [N; MAX_CHILDREN],
}

impl<N: Copy> Children<N> {
    /// An empty batch; `fill` only initialises the handle slots (any
    /// handle of the tree will do, such as its root).
    #[inline]
    pub fn new(fill: N) -> Self {
        Self {
            boxes: ChildBoxes::EMPTY,
            nodes: [fill; MAX_CHILDREN],
        }
    }

    /// Empties the batch.
    #[inline(always)]
    pub fn clear(&mut self) {
        self.boxes.clear();
    }

    /// Appends a child and its box.
    ///
    /// # Panics
    /// If the batch already holds [`MAX_CHILDREN`] children.
    #[inline(always)]
    pub fn push(&mut self, node: N, b: Aabb) {
        let i = self.boxes.len();
        self.boxes.push(b);
        self.nodes[i] = node;
    }

    /// Replaces the batch by `kids` (handle and box, in child order).
    ///
    /// # Panics
    /// With more than [`MAX_CHILDREN`] children.
    #[inline(always)]
    pub fn set(&mut self, kids: &[(N, Aabb)]) {
        // Written whole, without reading what the batch held, so that the
        // tests that follow see constants where the compiler can tell.
        self.boxes = ChildBoxes::from_lanes(kids.len(), |i| kids[i].1);
        for (slot, &(n, _)) in self.nodes.iter_mut().zip(kids) {
            *slot = n;
        }
    }

    /// Replaces the boxes by `boxes` and the handles by `nodes`, lane `i`'s
    /// handle being `nodes[i]` (for codecs that decode a node's child boxes
    /// as rows, [`ChildBoxes::from_rows`]); handles past `boxes.len()` are
    /// not used.
    #[inline(always)]
    pub fn set_boxes(&mut self, boxes: ChildBoxes, nodes: [N; MAX_CHILDREN]) {
        self.boxes = boxes;
        self.nodes = nodes;
    }

    /// Scales every child's box by `s` ([`ChildBoxes::scaled`]).
    #[inline(always)]
    pub fn scale_boxes(&mut self, s: glam::Vec3A) {
        self.boxes = self.boxes.scaled(s);
    }

    /// Number of children.
    #[inline]
    pub fn len(&self) -> usize {
        self.boxes.len()
    }

    /// Whether the batch holds no child.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.boxes.is_empty()
    }

    /// The children's boxes.
    #[inline(always)]
    pub fn boxes(&self) -> &ChildBoxes {
        &self.boxes
    }

    /// The handle of child `i`.
    ///
    /// # Panics
    /// If `i >= len()`.
    #[inline(always)]
    pub fn node(&self, i: usize) -> N {
        assert!(i < self.len(), "child {i} of {}", self.len());
        self.nodes[i]
    }
}

/// Traversal counters, for the papers' "travs/isecs" figures.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
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
