//! Queries written once over [`NodeCursor`](crate::cursor::NodeCursor) and
//! monomorphized per codec:
//!
//! - [`ray`]: closest hit (distance, triangle id, barycentrics) and any hit
//!   within a distance (shadow rays);
//! - [`packet`]: closest hits of a packet of coherent rays traversed
//!   together (camera tiles);
//! - [`mod@overlap`]: triangles whose boxes overlap a box, and a generic
//!   box-pruned visit;
//! - [`point`]: the closest point of the mesh to a point;
//! - [`best`]: best-first branch-and-bound search for the cheapest triangle;
//! - [`mod@bvtt`]: simultaneous traversal of two hierarchies under a relative
//!   rigid pose (the bounding volume test tree), enumerating the triangle
//!   pairs whose boxes come within a prediction distance.
//!
//! Every query counts [`TraversalStats`](crate::cursor::TraversalStats).
//!
//! The ray queries (closest hit, any hit, a packet's closest hits) run
//! through [`RayCursor`], a trait over the cursor whose defaults are the
//! generic traversals of [`ray`] and [`packet`] and which a codec
//! implements, overriding them where its layout allows a faster traversal
//! that gives the same hits. [`RayHit`], what they return, is a geometry
//! type ([`crate::geom`]), re-exported here.

pub mod best;
pub mod bvtt;
pub mod overlap;
pub mod packet;
pub mod point;
pub mod ray;
mod ray_cursor;

use std::mem::MaybeUninit;

pub use best::find_best;
pub use bvtt::{
    Prediction, bvtt, bvtt_best, bvtt_from, bvtt_front, bvtt_min, bvtt_pairs, bvtt_par,
    bvtt_par_within,
};
pub use overlap::{overlap, visit, visit_batch};
pub use packet::{closest_hits, closest_hits_within};
pub use point::{PointHit, closest_point};
pub use ray::{RayHit, any_hit, any_hit_with, closest_hit, closest_hit_with};
pub use ray_cursor::RayCursor;

/// Orders children by entry distance, farthest first, so that pushing them
/// in this order pops the nearest next (two children, the usual case,
/// without a sort).
#[inline]
pub(crate) fn far_first<T>(kids: &mut [(f32, T)]) {
    if kids.len() == 2 {
        if kids[0].0 < kids[1].0 {
            kids.swap(0, 1);
        }
    } else {
        kids.sort_unstable_by(|a, b| b.0.total_cmp(&a.0));
    }
}

/// A traversal stack that lives on the call stack for the usual depths and
/// spills to the heap only for very deep trees: per-query allocations cost
/// more than a ray's traversal on small trees. The inline slots are left
/// uninitialised: filling 96 of a codec's handles (48 bytes each for hcc
/// then, with the parent box; 32 now) cost every query a 4–6 KB copy
/// before its first node.
pub(crate) struct Stack<T: Copy> {
    inline: [MaybeUninit<T>; 96],
    len: usize,
    spill: Vec<T>,
}

impl<T: Copy> Stack<T> {
    /// An empty stack.
    #[inline]
    pub(crate) fn new() -> Self {
        Self {
            inline: [MaybeUninit::uninit(); 96],
            len: 0,
            spill: Vec::new(),
        }
    }

    #[inline]
    pub(crate) fn push(&mut self, v: T) {
        if self.len < self.inline.len() {
            self.inline[self.len] = MaybeUninit::new(v);
            self.len += 1;
        } else {
            self.spill.push(v);
        }
    }

    #[inline]
    pub(crate) fn pop(&mut self) -> Option<T> {
        if let Some(v) = self.spill.pop() {
            return Some(v);
        }
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        // SAFETY: slots `0..len` were written by `push` (it writes slot
        // `len` before incrementing `len`, and only `pop` decrements it),
        // so slot `len - 1`, read here after the decrement, is initialised;
        // `T: Copy`, so reading it leaves nothing to drop.
        Some(unsafe { self.inline[self.len].assume_init() })
    }
}

#[cfg(test)]
mod stack_tests {
    use super::Stack;

    #[test]
    fn stack_is_lifo_across_the_inline_slots_and_the_spill() {
        let mut s = Stack::new();
        let mut model: Vec<(u64, [f32; 3])> = Vec::new();
        let mut x = 0x9e37_79b9u64;
        for step in 0..5000u64 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            // Mostly pushes early, mostly pops late: crosses 96 both ways.
            let push = (x % 100) < if step < 2500 { 70 } else { 30 };
            if push {
                let v = (step, [step as f32, -(step as f32), 0.5]);
                s.push(v);
                model.push(v);
            } else {
                assert_eq!(s.pop(), model.pop(), "step {step}");
            }
        }
        while let Some(v) = model.pop() {
            assert_eq!(s.pop(), Some(v));
        }
        assert_eq!(s.pop(), None);
    }
}
