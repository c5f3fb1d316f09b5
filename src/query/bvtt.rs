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

use crate::cursor::{Children, NodeCursor, TraversalStats};
use crate::geom::{Aabb, Pose, Triangle};

/// A node pair of the traversal: `A`'s node and box, `B`'s node and its
/// box in `A`'s frame.
pub type NodePair<NA, NB> = (NA, Aabb, NB, Aabb);

/// A node pair waiting on the traversal's stack, with its prediction.
type Pending<NA, NB> = (NodePair<NA, NB>, f32);

/// The prediction distance of a traversal, which may depend on where `B`'s
/// points are: a pair whose `B` side lies in a region that barely moves
/// needs a smaller margin than the largest (see
/// [`MotionBound`](crate::contact::MotionBound)). A plain `f32` is the same
/// distance everywhere.
pub trait Prediction: Sync {
    /// The largest distance: the root pair and the task front use it.
    fn at_most(&self) -> f32;
    /// The distance for the points of `B` inside `b_box` (in `A`'s frame);
    /// never above [`at_most`](Self::at_most).
    fn within(&self, b_box: &Aabb) -> f32;
    /// The least distance [`within`](Self::within) gives anywhere: a node
    /// pair whose prediction is at most this keeps it for all its
    /// descendants, and the traversal skips their bounds.
    fn floor(&self) -> f32;

    /// `within(b_box)`, capped at the enclosing pair's `prediction`; the
    /// bound is not computed when that cap is at the floor already.
    #[inline]
    fn within_capped(&self, b_box: &Aabb, prediction: f32) -> f32 {
        if prediction <= self.floor() {
            prediction
        } else {
            self.within(b_box).min(prediction)
        }
    }
}

impl Prediction for f32 {
    #[inline]
    fn at_most(&self) -> f32 {
        *self
    }
    #[inline]
    fn within(&self, _: &Aabb) -> f32 {
        *self
    }
    #[inline]
    fn floor(&self) -> f32 {
        *self
    }
}

/// The root pair, if the roots' boxes come within `prediction`.
fn root_pair<A: NodeCursor, B: NodeCursor>(
    a: &A,
    b: &B,
    b_to_a: &Pose,
    prediction: f32,
    stats: &mut TraversalStats,
) -> Option<NodePair<A::Node, B::Node>> {
    let (ra, ba) = a.root();
    let (rb, bb) = b.root();
    let bb = bb.transformed(b_to_a);
    stats.nodes_visited += 1;
    if ba.is_empty() || bb.is_empty() || !ba.loosened(prediction).intersects(&bb) {
        return None;
    }
    Some((ra, ba, rb, bb))
}

/// The batches [`descend`] fills: one for each tree's children.
struct Scratch<NA, NB> {
    a: Children<NA>,
    b: Children<NB>,
}

impl<NA: Copy, NB: Copy> Scratch<NA, NB> {
    fn new(&(na, _, nb, _): &NodePair<NA, NB>) -> Self {
        Self {
            a: Children::new(na),
            b: Children::new(nb),
        }
    }
}

/// One descent step from a pair that is not two leaves: the larger box (by
/// half area, never a leaf) is split and the child pairs that still come
/// within `prediction` are pushed, in child order, each with its own
/// prediction: the pair's, or when `B` is split, `bound`'s for the child's
/// box if that is smaller.
///
/// The split node's children are tested as one batch against the other
/// node's box; when `B` is split, its children's boxes are moved into `A`'s
/// frame in one batch transform per expansion. Which side is split, and the
/// order of the pushed pairs, are those of the box-by-box traversal before
/// batches: the order in which triangle pairs reach the caller (and so the
/// contact patches built from them) is unchanged.
///
/// Always inlined: as a call, the node pair (160 bytes with HCCMesh's
/// handles as they were, 48 bytes with their box; 128 bytes now) went
/// through a `memcpy` at every step;
/// inlined, HCCMesh's pair enumeration takes 28 % less time
/// (`CURSOR_BENCH_ONLY=hcc:bvtt cargo run --release --features sims --example cursor_bench
/// -- 200000 15`: 18.5 → 13.3 ms; plain unchanged at 7.3–7.7).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn descend<A: NodeCursor, B: NodeCursor>(
    a: &A,
    b: &B,
    b_to_a: &Pose,
    (prediction, bound): (f32, &impl Prediction),
    (na, box_a, nb, box_b): NodePair<A::Node, B::Node>,
    leaf_a: bool,
    leaf_b: bool,
    scratch: &mut Scratch<A::Node, B::Node>,
    stats: &mut TraversalStats,
    mut push: impl FnMut(NodePair<A::Node, B::Node>, f32),
) {
    let descend_a = leaf_b || (!leaf_a && box_a.half_area() >= box_b.half_area());
    if descend_a {
        let kids = &mut scratch.a;
        a.children(&na, kids);
        let boxes = kids.boxes();
        stats.nodes_visited += boxes.len() as u64;
        // Loosen A's side, as the leaf test does, so that rounding
        // cannot prune a pair the leaf test would report.
        let mask = boxes.overlaps_grown(prediction, &box_b);
        boxes.for_each_in(mask, |i| {
            push((kids.node(i), boxes.get(i), nb, box_b), prediction)
        });
    } else {
        let grown_a = box_a.loosened(prediction);
        let kids = &mut scratch.b;
        b.children(&nb, kids);
        stats.nodes_visited += kids.len() as u64;
        let moved = kids.boxes().transformed(b_to_a);
        let mask = moved.overlaps(&grown_a);
        moved.for_each_in(mask, |i| {
            let child = moved.get(i);
            let p = bound.within_capped(&child, prediction);
            push((na, box_a, kids.node(i), child), p)
        });
    }
}

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
    f: impl FnMut(u32, &Triangle, u32, &Triangle) -> ControlFlow<()>,
) -> bool {
    match root_pair(a, b, b_to_a, prediction, stats) {
        Some(root) => bvtt_from(a, b, b_to_a, prediction, root, stats, f),
        None => false,
    }
}

/// [`bvtt`] from one node pair of the traversal (see [`bvtt_front`]).
pub fn bvtt_from<A: NodeCursor, B: NodeCursor>(
    a: &A,
    b: &B,
    b_to_a: &Pose,
    prediction: f32,
    start: NodePair<A::Node, B::Node>,
    stats: &mut TraversalStats,
    mut f: impl FnMut(u32, &Triangle, u32, &Triangle) -> ControlFlow<()>,
) -> bool {
    traverse(
        a,
        b,
        b_to_a,
        &prediction,
        start,
        prediction,
        stats,
        |i, ti, j, tj, _, _| f(i, ti, j, tj),
    )
}

/// The traversal behind [`bvtt_from`]: `f(i, tri_i, j, tri_j_local,
/// tri_j_in_a, prediction)` also receives `B`'s triangle moved into `A`'s
/// frame, which the leaf test computes anyway (once per triangle of a leaf
/// pair, not once per reported pair), and the prediction the pair was
/// found with (see [`Prediction`]; the start pair's is `start_prediction`).
#[allow(clippy::too_many_arguments)]
fn traverse<A: NodeCursor, B: NodeCursor>(
    a: &A,
    b: &B,
    b_to_a: &Pose,
    bound: &impl Prediction,
    start: NodePair<A::Node, B::Node>,
    start_prediction: f32,
    stats: &mut TraversalStats,
    mut f: impl FnMut(u32, &Triangle, u32, &Triangle, &Triangle, f32) -> ControlFlow<()>,
) -> bool {
    let mut stack: Vec<Pending<A::Node, B::Node>> = Vec::with_capacity(128);
    stack.push((start, start_prediction));
    let mut b_tris: Vec<(u32, Triangle, Triangle, Aabb, f32)> = Vec::new();
    let mut scratch = Scratch::new(&start);
    while let Some((pair, prediction)) = stack.pop() {
        let (na, _, nb, _) = pair;
        let leaf_a = a.is_leaf(&na);
        let leaf_b = b.is_leaf(&nb);
        if leaf_a && leaf_b {
            b_tris.clear();
            // Keys, not ids: most pairs tested here are not reported, and
            // a codec may pay for each id (see `for_each_triangle_keyed`).
            // Each triangle of B gets the prediction of its own box, not
            // of the leaf's: a pair is then found with the same prediction
            // whatever tree it sits in, so every codec gives the same pairs
            // (and contacts) under a motion bound.
            b.for_each_triangle_keyed(&nb, |j, tj| {
                let moved = tj.map(|p| b_to_a.transform_point(p));
                let own = Aabb::of_triangle(&moved);
                let p = bound.within_capped(&own, prediction);
                b_tris.push((j, *tj, moved, own.loosened(p), p));
            });
            let mut stop = false;
            a.for_each_triangle_keyed(&na, |i, ti| {
                if stop {
                    return;
                }
                let bi = Aabb::of_triangle(ti);
                for (j, tj, moved, bj, p) in &b_tris {
                    stats.primitive_tests += 1;
                    if bi.intersects(bj)
                        && f(a.id_of_key(i), ti, b.id_of_key(*j), tj, moved, *p).is_break()
                    {
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
        descend(
            a,
            b,
            b_to_a,
            (prediction, bound),
            pair,
            leaf_a,
            leaf_b,
            &mut scratch,
            stats,
            |p, pred| stack.push((p, pred)),
        );
    }
    false
}

/// The traversal's front expanded breadth-first until it holds at least
/// `target` node pairs (or nothing is left to expand): independent starting
/// points for [`bvtt_from`] whose pairs together are exactly [`bvtt`]'s.
/// The front depends only on the trees, the pose and `target`, never on the
/// thread count.
///
/// A sweep stops expanding as soon as the pairs it has made and the pairs
/// still to come reach `target`; those are kept as they are. Expanding
/// whole levels overshot: one level of eight-wide nodes can multiply the
/// front by up to 64, and every pair becomes a task with its own state to
/// set up and merge. On the default upright drop scene CLBVH's front went
/// from about 40 to 124 pairs on the steps where the statue turns on the
/// blade tips, and those steps took 1.6× plain's time. Now the front holds
/// at most `target` plus one expansion's children less one.
pub fn bvtt_front<A: NodeCursor, B: NodeCursor>(
    a: &A,
    b: &B,
    b_to_a: &Pose,
    prediction: f32,
    target: usize,
    stats: &mut TraversalStats,
) -> Vec<NodePair<A::Node, B::Node>> {
    let Some(root) = root_pair(a, b, b_to_a, prediction, stats) else {
        return Vec::new();
    };
    let mut scratch = Scratch::new(&root);
    let mut front = vec![root];
    let mut next = Vec::new();
    while front.len() < target {
        let mut expanded = false;
        next.clear();
        for (k, &pair) in front.iter().enumerate() {
            if next.len() + (front.len() - k) >= target {
                next.extend_from_slice(&front[k..]);
                break;
            }
            let leaf_a = a.is_leaf(&pair.0);
            let leaf_b = b.is_leaf(&pair.2);
            if leaf_a && leaf_b {
                next.push(pair);
            } else {
                expanded = true;
                descend(
                    a,
                    b,
                    b_to_a,
                    (prediction, &prediction),
                    pair,
                    leaf_a,
                    leaf_b,
                    &mut scratch,
                    stats,
                    |p, _| next.push(p),
                );
            }
        }
        std::mem::swap(&mut front, &mut next);
        if !expanded {
            break;
        }
    }
    front
}

/// [`bvtt`] on rayon's threads: the front ([`bvtt_front`] with `target`
/// pairs) is traversed task by task, each task with its own state from
/// `init` and calling `leaf(state, i, tri_i, j, tri_j)` for its pairs, with
/// `tri_j` already moved into `A`'s frame (unlike [`bvtt`]'s callback, which
/// gets `B`'s own coordinates: the traversal has moved it for its leaf test).
/// Returns the states in front order (so that combining them in order gives
/// a result independent of the thread count) and the summed counters.
pub fn bvtt_par<A: NodeCursor, B: NodeCursor, S: Send>(
    a: &A,
    b: &B,
    b_to_a: &Pose,
    prediction: f32,
    target: usize,
    init: impl Fn() -> S + Sync,
    leaf: impl Fn(&mut S, u32, &Triangle, u32, &Triangle) + Sync,
) -> (Vec<S>, TraversalStats) {
    bvtt_par_within(
        a,
        b,
        b_to_a,
        &prediction,
        target,
        init,
        |s, i, ti, j, tj, _| leaf(s, i, ti, j, tj),
    )
}

/// [`bvtt_par`] with a prediction that depends on where `B`'s points are
/// ([`Prediction`]): the front is found with its largest distance, and
/// below the front each pair keeps the smallest distance of the `B` boxes
/// above it. `leaf(state, i, tri_i, j, tri_j, prediction)` gets the pair's.
pub fn bvtt_par_within<A: NodeCursor, B: NodeCursor, S: Send>(
    a: &A,
    b: &B,
    b_to_a: &Pose,
    bound: &impl Prediction,
    target: usize,
    init: impl Fn() -> S + Sync,
    leaf: impl Fn(&mut S, u32, &Triangle, u32, &Triangle, f32) + Sync,
) -> (Vec<S>, TraversalStats) {
    use rayon::prelude::*;
    let mut stats = TraversalStats::default();
    let prediction = bound.at_most();
    let front = bvtt_front(a, b, b_to_a, prediction, target, &mut stats);
    let task = |start: NodePair<A::Node, B::Node>| {
        let mut s = init();
        let mut st = TraversalStats::default();
        let p = bound.within_capped(&start.3, prediction);
        traverse(
            a,
            b,
            b_to_a,
            bound,
            start,
            p,
            &mut st,
            |i, ti, j, _, tj, p| {
                leaf(&mut s, i, ti, j, tj, p);
                ControlFlow::Continue(())
            },
        );
        (s, st)
    };
    // On one thread the same tasks run in order on the caller's thread,
    // without handing them to the pool and waiting for it.
    let results: Vec<(S, TraversalStats)> = if rayon::current_num_threads() <= 1 {
        front.into_iter().map(task).collect()
    } else {
        front.into_par_iter().map(task).collect()
    };
    let mut states = Vec::with_capacity(results.len());
    for (s, st) in results {
        stats.add(&st);
        states.push(s);
    }
    (states, stats)
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
    let (mut batch_a, mut batch_b) = (Children::new(ra), Children::new(rb));
    let mut b_tris: Vec<(u32, Triangle)> = Vec::new();
    while let Some((d, na, box_a, nb, box_b)) = stack.pop() {
        if d >= best_cost {
            continue;
        }
        let leaf_a = a.is_leaf(&na);
        let leaf_b = b.is_leaf(&nb);
        if leaf_a && leaf_b {
            leaf_pairs(
                a,
                b,
                &na,
                &nb,
                &mut b_tris,
                stats,
                &mut best_cost,
                &mut best,
                &mut leaf,
            );
            continue;
        }
        kids.clear();
        if leaf_b || (!leaf_a && box_a.half_area() >= box_b.half_area()) {
            a.children(&na, &mut batch_a);
            let boxes = batch_a.boxes();
            stats.nodes_visited += boxes.len() as u64;
            let d = boxes.box_distances(&box_b, true);
            for (i, &d) in d[..boxes.len()].iter().enumerate() {
                kids.push((d, batch_a.node(i), boxes.get(i), nb, box_b));
            }
        } else {
            b.children(&nb, &mut batch_b);
            stats.nodes_visited += batch_b.len() as u64;
            let moved = batch_b.boxes().transformed(b_to_a);
            let d = moved.box_distances(&box_a, false);
            for (i, &d) in d[..moved.len()].iter().enumerate() {
                kids.push((d, na, box_a, batch_b.node(i), moved.get(i)));
            }
        }
        kids.sort_unstable_by(|x, y| y.0.total_cmp(&x.0));
        stack.extend(kids.drain(..).filter(|k| k.0 < best_cost));
    }
    best
}

/// Branch-and-bound over two hierarchies with a caller's node bound: the
/// triangle pair with the smallest cost below `max_cost`, as [`bvtt_min`],
/// but each node pair's lower bound is `node_cost(box_a, box_b)` with
/// both boxes in their own tree's frame (for bounds that are not a
/// distance under one fixed pose, such as the first time two moving
/// bounding balls can meet). `leaf(i, tri_i, j, tri_j, best)` sees both
/// triangles in their own frames.
pub fn bvtt_best<A: NodeCursor, B: NodeCursor, T>(
    a: &A,
    b: &B,
    max_cost: f32,
    stats: &mut TraversalStats,
    mut node_cost: impl FnMut(&Aabb, &Aabb) -> f32,
    mut leaf: impl FnMut(u32, &Triangle, u32, &Triangle, f32) -> Option<(f32, T)>,
) -> Option<(u32, u32, f32, T)> {
    let (ra, ba) = a.root();
    let (rb, bb) = b.root();
    if ba.is_empty() || bb.is_empty() {
        return None;
    }
    stats.nodes_visited += 1;
    let c0 = node_cost(&ba, &bb);
    // Written so that a NaN cost prunes too.
    if c0.is_nan() || c0 >= max_cost {
        return None;
    }
    let mut best_cost = max_cost;
    let mut best: Option<(u32, u32, f32, T)> = None;
    let mut stack: Vec<PairEntry<A::Node, B::Node>> = vec![(c0, ra, ba, rb, bb)];
    let mut kids: Vec<PairEntry<A::Node, B::Node>> = Vec::with_capacity(16);
    let (mut batch_a, mut batch_b) = (Children::new(ra), Children::new(rb));
    let mut b_tris: Vec<(u32, Triangle)> = Vec::new();
    while let Some((k, na, box_a, nb, box_b)) = stack.pop() {
        if k >= best_cost {
            continue;
        }
        let leaf_a = a.is_leaf(&na);
        let leaf_b = b.is_leaf(&nb);
        if leaf_a && leaf_b {
            leaf_pairs(
                a,
                b,
                &na,
                &nb,
                &mut b_tris,
                stats,
                &mut best_cost,
                &mut best,
                &mut leaf,
            );
            continue;
        }
        kids.clear();
        if leaf_b || (!leaf_a && box_a.half_area() >= box_b.half_area()) {
            a.children(&na, &mut batch_a);
            let boxes = batch_a.boxes();
            stats.nodes_visited += boxes.len() as u64;
            for i in 0..boxes.len() {
                let bx = boxes.get(i);
                kids.push((node_cost(&bx, &box_b), batch_a.node(i), bx, nb, box_b));
            }
        } else {
            b.children(&nb, &mut batch_b);
            let boxes = batch_b.boxes();
            stats.nodes_visited += boxes.len() as u64;
            for i in 0..boxes.len() {
                let bx = boxes.get(i);
                kids.push((node_cost(&box_a, &bx), na, box_a, batch_b.node(i), bx));
            }
        }
        kids.sort_unstable_by(|x, y| y.0.total_cmp(&x.0));
        stack.extend(kids.drain(..).filter(|k| !k.0.is_nan() && k.0 < best_cost));
    }
    best
}

/// The leaf pair `na` × `nb` of [`bvtt_min`] and [`bvtt_best`]: every
/// triangle pair through `leaf`, the best so far in `best_cost` / `best`
/// (`b_tris`: scratch for `nb`'s triangles).
#[allow(clippy::too_many_arguments)]
fn leaf_pairs<A: NodeCursor, B: NodeCursor, T>(
    a: &A,
    b: &B,
    na: &A::Node,
    nb: &B::Node,
    b_tris: &mut Vec<(u32, Triangle)>,
    stats: &mut TraversalStats,
    best_cost: &mut f32,
    best: &mut Option<(u32, u32, f32, T)>,
    leaf: &mut impl FnMut(u32, &Triangle, u32, &Triangle, f32) -> Option<(f32, T)>,
) {
    b_tris.clear();
    b.for_each_triangle(nb, |j, tj| b_tris.push((j, *tj)));
    a.for_each_triangle(na, |i, ti| {
        for (j, tj) in b_tris.iter() {
            stats.primitive_tests += 1;
            if let Some((k, payload)) = leaf(i, ti, *j, tj, *best_cost)
                && k < *best_cost
            {
                *best_cost = k;
                *best = Some((i, *j, k, payload));
            }
        }
    });
}
