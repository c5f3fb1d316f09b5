//! Simultaneous traversal of two hierarchies: the bounding volume test tree.
//!
//! Tree `A` is the reference frame; `b_to_a` maps `B`'s local coordinates
//! into `A`'s. A node pair is kept when `A`'s box, grown by the prediction
//! distance, overlaps the box bounding `B`'s box after the transform (a
//! conservative test: the transformed box is bounded by its centre and the
//! absolute rotation times its half extents). A triangle pair `(i, j)` is
//! reported exactly when the tight box of `A`'s triangle `i`, grown by the
//! prediction distance, overlaps the tight box of `B`'s triangle `j` after
//! the transform. Brute force over all pairs with that predicate gives the
//! same set, which the tests check.

use std::ops::ControlFlow;

use crate::cursor::{NodeCursor, TraversalStats};
use crate::geom::{Aabb, Pose, Triangle};

/// Calls `f(i, tri_i, j, tri_j_local)` for each triangle pair whose boxes
/// come within `prediction` (see the module docs). `tri_i` is in `A`'s
/// frame, `tri_j_local` in `B`'s own frame. `f` may stop early; returns
/// whether it did.
pub fn bvtt<A: NodeCursor, B: NodeCursor>(
    a: &A,
    b: &B,
    b_to_a: &Pose,
    prediction: f32,
    stats: &mut TraversalStats,
    mut f: impl FnMut(u32, &Triangle, u32, &Triangle) -> ControlFlow<()>,
) -> bool {
    let (ra, ba) = a.root();
    let (rb, bb) = b.root();
    let bb = bb.transformed(b_to_a);
    stats.nodes_visited += 1;
    if ba.is_empty() || bb.is_empty() || !ba.loosened(prediction).intersects(&bb) {
        return false;
    }
    let mut stack: Vec<(A::Node, Aabb, B::Node, Aabb)> = Vec::with_capacity(128);
    stack.push((ra, ba, rb, bb));
    let mut b_tris: Vec<(u32, Triangle, Triangle, Aabb)> = Vec::new();
    while let Some((na, box_a, nb, box_b)) = stack.pop() {
        let leaf_a = a.is_leaf(&na);
        let leaf_b = b.is_leaf(&nb);
        if leaf_a && leaf_b {
            b_tris.clear();
            b.for_each_triangle(&nb, |j, tj| {
                let moved = tj.map(|p| b_to_a.transform_point(p));
                b_tris.push((j, *tj, moved, Aabb::of_triangle(&moved)));
            });
            let mut stop = false;
            a.for_each_triangle(&na, |i, ti| {
                if stop {
                    return;
                }
                let bi = Aabb::of_triangle(ti).loosened(prediction);
                for (j, tj, _, bj) in &b_tris {
                    stats.primitive_tests += 1;
                    if bi.intersects(bj) && f(i, ti, *j, tj).is_break() {
                        stop = true;
                        return;
                    }
                }
            });
            if stop {
                return true;
            }
            continue;
        }
        // Descend the larger box (by half area); never a leaf.
        let descend_a = leaf_b || (!leaf_a && box_a.half_area() >= box_b.half_area());
        if descend_a {
            a.for_each_child(&na, |ca, cb| {
                stats.nodes_visited += 1;
                // Loosen A's side, as the leaf test does, so that rounding
                // cannot prune a pair the leaf test would report.
                if cb.loosened(prediction).intersects(&box_b) {
                    stack.push((ca, cb, nb, box_b));
                }
            });
        } else {
            let grown_a = box_a.loosened(prediction);
            b.for_each_child(&nb, |cb_node, cb| {
                stats.nodes_visited += 1;
                let moved = cb.transformed(b_to_a);
                if moved.intersects(&grown_a) {
                    stack.push((na, box_a, cb_node, moved));
                }
            });
        }
    }
    false
}

/// All pairs `(i, j)` that [`bvtt`] reports, sorted.
pub fn bvtt_pairs<A: NodeCursor, B: NodeCursor>(
    a: &A,
    b: &B,
    b_to_a: &Pose,
    prediction: f32,
    stats: &mut TraversalStats,
) -> Vec<(u32, u32)> {
    let mut pairs = Vec::new();
    bvtt(a, b, b_to_a, prediction, stats, |i, _, j, _| {
        pairs.push((i, j));
        ControlFlow::Continue(())
    });
    pairs.sort_unstable();
    pairs
}
