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

/// A node pair with its lower bound and boxes (B's in A's frame).
type PairEntry<NA, NB> = (f32, NA, Aabb, NB, Aabb);

/// Branch-and-bound over two hierarchies: the triangle pair with the
/// smallest cost below `max_cost`. A node pair's lower bound is the distance
/// between `A`'s box and the box bounding `B`'s box after `b_to_a`, so the
/// cost must be at least the distance between the two triangles (a distance,
/// or anything it bounds from below). `leaf(i, tri_i, j, tri_j_local, best)`
/// returns the pair's cost and a payload when it beats `best`.
pub fn bvtt_min<A: NodeCursor, B: NodeCursor, T>(
    a: &A,
    b: &B,
    b_to_a: &Pose,
    max_cost: f32,
    stats: &mut TraversalStats,
    mut leaf: impl FnMut(u32, &Triangle, u32, &Triangle, f32) -> Option<(f32, T)>,
) -> Option<(u32, u32, f32, T)> {
    let box_dist = |x: &Aabb, y: &Aabb| {
        let d = (x.min - y.max).max(y.min - x.max).max(glam::Vec3A::ZERO);
        d.length()
    };
    let (ra, ba) = a.root();
    let (rb, bb) = b.root();
    if ba.is_empty() || bb.is_empty() {
        return None;
    }
    let bb = bb.transformed(b_to_a);
    stats.nodes_visited += 1;
    let mut best_cost = max_cost;
    let mut best: Option<(u32, u32, f32, T)> = None;
    let d0 = box_dist(&ba, &bb);
    if d0 >= best_cost {
        return None;
    }
    let mut stack: Vec<PairEntry<A::Node, B::Node>> = vec![(d0, ra, ba, rb, bb)];
    let mut kids: Vec<PairEntry<A::Node, B::Node>> = Vec::with_capacity(8);
    while let Some((d, na, box_a, nb, box_b)) = stack.pop() {
        if d >= best_cost {
            continue;
        }
        let leaf_a = a.is_leaf(&na);
        let leaf_b = b.is_leaf(&nb);
        if leaf_a && leaf_b {
            let mut b_tris: Vec<(u32, Triangle)> = Vec::new();
            b.for_each_triangle(&nb, |j, tj| b_tris.push((j, *tj)));
            a.for_each_triangle(&na, |i, ti| {
                for (j, tj) in &b_tris {
                    stats.primitive_tests += 1;
                    if let Some((k, payload)) = leaf(i, ti, *j, tj, best_cost)
                        && k < best_cost
                    {
                        best_cost = k;
                        best = Some((i, *j, k, payload));
                    }
                }
            });
            continue;
        }
        kids.clear();
        if leaf_b || (!leaf_a && box_a.half_area() >= box_b.half_area()) {
            a.for_each_child(&na, |ca, cb| {
                stats.nodes_visited += 1;
                kids.push((box_dist(&cb, &box_b), ca, cb, nb, box_b));
            });
        } else {
            b.for_each_child(&nb, |cn, cb| {
                stats.nodes_visited += 1;
                let moved = cb.transformed(b_to_a);
                kids.push((box_dist(&box_a, &moved), na, box_a, cn, moved));
            });
        }
        kids.sort_unstable_by(|x, y| y.0.total_cmp(&x.0));
        stack.extend(kids.drain(..).filter(|k| k.0 < best_cost));
    }
    best
}
