//! cbvh shape vs cbvh shape: simultaneous BVH-vs-BVH traversal (BVTT) on
//! both trees. In [`ContactMode::Patches`] the traversal runs on rayon's
//! threads from a fixed front of node pairs, each task feeding cbvh's
//! triangle-pair kernel and its own patch set; the sets are merged in front
//! order (so the result does not depend on the thread count) and become one
//! manifold per patch. In [`ContactMode::PerTrianglePair`] triangle pairs go
//! through parry's convex-convex code, one persistent manifold per pair.

use std::ops::ControlFlow;

use parry3d::math::{Pose as PPose, Real};
use parry3d::query::{
    ClosestPoints, Contact, ContactManifold, ContactManifoldsWorkspace, DefaultQueryDispatcher,
    PersistentQueryDispatcher, QueryDispatcher, ShapeDistance, ShapeIntersection,
};

use super::cones::{MeshNeighbours, PairRule};
use super::patches::{ContactCounters, ContactMode, manifolds_in_mode};
use super::shape::{CbvhShape, pose_from_parry, to_parry_triangle};
use super::workspace::ManifoldUpdate;
use crate::contact::{Interference, PairFacing, PairKernel, PatchOptions, PatchSet};
use crate::cursor::TraversalStats;
use crate::geom::Triangle;
use crate::query::{Prediction, bvtt, bvtt_min, bvtt_par, bvtt_par_within};

/// Node pairs the parallel traversal starts from: enough tasks to balance
/// two to a few dozen threads, few enough that a small contact costs little.
pub const FRONT_TASKS: usize = 32;

/// The smaller of the two shapes' bounding-box diagonals (the patch gap's
/// scale).
pub(crate) fn smaller_size(a: &CbvhShape, b: &CbvhShape) -> f32 {
    let d = |s: &CbvhShape| s.local_aabb().extent().length();
    d(a).min(d(b))
}

/// Contact manifolds in the dispatcher's `mode`.
#[allow(clippy::too_many_arguments)]
pub fn contact_manifolds_in<M: Default + Clone + Send + Sync, C: Default + Copy + Send + Sync>(
    mode: &ContactMode,
    counters: Option<&ContactCounters>,
    pos12: &PPose,
    s1: &CbvhShape,
    s2: &CbvhShape,
    prediction: Real,
    manifolds: &mut Vec<ContactManifold<M, C>>,
    workspace: &mut Option<ContactManifoldsWorkspace>,
) {
    manifolds_in_mode(
        mode,
        counters,
        pos12,
        &s1.local_aabb(),
        &s2.local_aabb(),
        false,
        prediction,
        manifolds,
        workspace,
        |pos12, bound, opts| patches(pos12, s1, s2, bound, opts, false, counters),
        |manifolds, workspace| contact_manifolds(pos12, s1, s2, prediction, manifolds, workspace),
    );
}

/// The contact patches of two cbvh shapes (in `s1`'s frame): the parallel
/// two-tree traversal feeding the triangle-pair kernel. `prediction` is a
/// distance (`f32`) or a [`MotionBound`](crate::contact::MotionBound), which each node pair of the
/// traversal bounds by the motion of its box of `s2`. With `record`, every
/// patch lists its triangle pairs.
pub fn patches(
    pos12: &PPose,
    s1: &CbvhShape,
    s2: &CbvhShape,
    prediction: &impl Prediction,
    opts: &PatchOptions,
    record: bool,
    counters: Option<&ContactCounters>,
) -> PatchSet {
    let pose = pose_from_parry(pos12);
    let size = smaller_size(s1, s2);
    let mut merged = PatchSet::new(opts, size, record);
    let (mut candidates, mut contacts) = (0u64, 0u64);
    let largest = prediction.at_most();
    let facing = pair_facing(&pose, s1, s2);
    // No neighbour lookups here: at the papers' scale they made the patch
    // narrow phase about three times slower (patch_bench, 2 M statue on a
    // 200 k turbine: 2.0 ms to 5.5 ms), most pairs of a CAD part's sharp
    // edges asking for one. The per-pair mode uses them.
    with_cursor!(s1, |a| with_cursor!(s2, |b| {
        let (states, _stats) = bvtt_par_within(
            a,
            b,
            &pose,
            prediction,
            FRONT_TASKS,
            || {
                (
                    PairKernel::new(largest)
                        .exact_separation(false)
                        .oriented(Some(facing)),
                    PatchSet::new(opts, size, record),
                )
            },
            |(kernel, set), i, ti, j, tj, p| {
                let (fi, fj) = (s1.edge_flags_of(i), s2.edge_flags_of(j));
                kernel.push_flagged((i, ti, fi), (j, tj, fj), p, set)
            },
        );
        for (mut kernel, mut set) in states {
            kernel.flush_into(&mut set);
            candidates += kernel.stats.pairs;
            contacts += kernel.stats.contacts;
            merged.merge(set);
        }
    }));
    let toward = pose.transform_point(s2.local_aabb().center()) - s1.local_aabb().center();
    merged.drop_opposed(toward);
    if let Some(c) = counters {
        c.add(candidates, contacts, merged.patches.len() as u64);
    }
    merged
}

/// Where the triangles sharing an edge of `s1`'s or `s2`'s (placed by
/// `pose` in `s1`'s frame) are found, for oriented contacts
/// ([`crate::contact::Neighbours`]).
pub fn neighbours_of(
    s1: &CbvhShape,
    s2: &CbvhShape,
    pose: &crate::geom::Pose,
) -> std::sync::Arc<dyn crate::contact::Neighbours> {
    std::sync::Arc::new(MeshNeighbours {
        a: s1.clone(),
        b: Some((s2.clone(), *pose)),
    })
}

/// How the triangles of `s1` (in its own frame) and of `s2` (placed by
/// `pose` in `s1`'s frame) face each other: each toward the other's centre
/// when two-sided.
pub fn pair_facing(pose: &crate::geom::Pose, s1: &CbvhShape, s2: &CbvhShape) -> PairFacing {
    let c1 = s1.local_aabb().center();
    let c2 = pose.transform_point(s2.local_aabb().center());
    PairFacing::new(s1.facing(c2), s2.facing(c1))
}

/// The papers' interference figure: the number of intersecting (or
/// touching) triangle pairs of the two shapes, found by the parallel
/// two-tree traversal and an exact triangle-triangle test, with no contacts.
pub fn interference(pos12: &PPose, s1: &CbvhShape, s2: &CbvhShape) -> u64 {
    let pose = pose_from_parry(pos12);
    with_cursor!(s1, |a| with_cursor!(s2, |b| {
        let (states, _) = bvtt_par(
            a,
            b,
            &pose,
            0.0,
            FRONT_TASKS,
            Interference::default,
            |t, _, ti, _, tj| t.push(ti, tj),
        );
        states
            .into_iter()
            .map(|mut t| {
                t.flush();
                t.intersecting
            })
            .sum()
    }))
}

/// Calls `f` with every triangle pair of `s1` and `s2` (shape 2 placed by
/// `pos12` in shape 1's frame) whose boxes come within `prediction`.
pub fn for_each_pair(
    s1: &CbvhShape,
    s2: &CbvhShape,
    pos12: &PPose,
    prediction: Real,
    stats: &mut TraversalStats,
    mut f: impl FnMut(u32, &Triangle, u32, &Triangle) -> ControlFlow<()>,
) {
    let pose = pose_from_parry(pos12);
    with_cursor!(s1, |a| with_cursor!(s2, |b| {
        bvtt(a, b, &pose, prediction, stats, &mut f);
    }));
}

/// Triangle pairs from which contact generation runs on rayon's threads.
const PARALLEL_PAIRS: usize = 512;

/// Contact manifolds, one per triangle pair, persistent across steps.
///
/// The traversal collects the candidate pairs (and their manifolds from the
/// last step, for warm starting) in a fixed order; parry's convex-convex
/// code then runs on each pair, in parallel over rayon's threads when there
/// are many. Each pair only touches its own manifold, so the result does
/// not depend on the thread count.
pub fn contact_manifolds<M: Default + Clone + Send + Sync, C: Default + Copy + Send + Sync>(
    pos12: &PPose,
    s1: &CbvhShape,
    s2: &CbvhShape,
    prediction: Real,
    manifolds: &mut Vec<ContactManifold<M, C>>,
    workspace: &mut Option<ContactManifoldsWorkspace>,
) {
    let mut update = ManifoldUpdate::begin(workspace, manifolds);
    let mut stats = TraversalStats::default();
    let mut pairs: Vec<(PairRule, Triangle)> = Vec::new();
    let pose = pose_from_parry(pos12);
    let facing = pair_facing(&pose, s1, s2);
    let neighbours = neighbours_of(s1, s2, &pose);
    // Every pair the traversal finds goes to parry, as parry's own
    // composite-shape code does: parry keeps points beyond the prediction
    // distance too, so no pair may be culled by its own test first. The
    // traversal hands shape 2's triangle in its own frame, as parry takes
    // it; the rule takes both in shape 1's.
    for_each_pair(s1, s2, pos12, prediction, &mut stats, |i, t1, j, t2| {
        update.manifold(i, j);
        let rule = PairRule {
            a: *t1,
            fa: s1.edge_flags_of(i),
            b: t2.map(|v| pose.transform_point(v)),
            fb: s2.edge_flags_of(j),
            facing,
            prediction,
            ids: (i, j),
            neighbours: Some(neighbours.clone()),
        };
        pairs.push((rule, *t2));
        ControlFlow::Continue(())
    });
    let generate = |m: &mut ContactManifold<M, C>, (rule, t2): &(PairRule, Triangle)| {
        let _ = DefaultQueryDispatcher.contact_manifold_convex_convex(
            pos12,
            &to_parry_triangle(&rule.a),
            &to_parry_triangle(t2),
            Some(rule),
            None,
            prediction,
            m,
        );
    };
    let ms = update.manifolds_mut();
    debug_assert_eq!(ms.len(), pairs.len());
    if pairs.len() >= PARALLEL_PAIRS {
        use rayon::prelude::*;
        ms.par_iter_mut()
            .zip(pairs.par_iter())
            .with_min_len(64)
            .for_each(|(m, p)| generate(m, p));
    } else {
        ms.iter_mut().zip(&pairs).for_each(|(m, p)| generate(m, p));
    }
}

/// Whether any triangle of `s1` intersects one of `s2`.
pub fn intersection_test(pos12: &PPose, s1: &CbvhShape, s2: &CbvhShape) -> ShapeIntersection {
    let mut stats = TraversalStats::default();
    let mut found = ShapeIntersection::new(false);
    for_each_pair(s1, s2, pos12, 0.0, &mut stats, |i, t1, j, t2| {
        let hit = DefaultQueryDispatcher
            .intersection_test(pos12, &to_parry_triangle(t1), &to_parry_triangle(t2))
            .is_ok_and(|r| r.intersecting);
        if hit {
            found = ShapeIntersection::new(true).with_subshapes(i, j);
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    });
    found
}

/// The deepest (smallest distance) contact within `prediction`.
pub fn contact(pos12: &PPose, s1: &CbvhShape, s2: &CbvhShape, prediction: Real) -> Option<Contact> {
    let mut stats = TraversalStats::default();
    let mut best: Option<Contact> = None;
    for_each_pair(s1, s2, pos12, prediction, &mut stats, |i, t1, j, t2| {
        if let Ok(Some(c)) = DefaultQueryDispatcher.contact(
            pos12,
            &to_parry_triangle(t1),
            &to_parry_triangle(t2),
            prediction,
        ) && best.is_none_or(|b| c.dist < b.dist)
        {
            best = Some(c.with_subshapes(i, j));
        }
        ControlFlow::Continue(())
    });
    best
}

/// Distance between the two meshes: branch and bound over both trees.
pub fn distance(pos12: &PPose, s1: &CbvhShape, s2: &CbvhShape) -> ShapeDistance {
    let pose = pose_from_parry(pos12);
    let mut stats = TraversalStats::default();
    let found = with_cursor!(s1, |a| with_cursor!(s2, |b| bvtt_min(
        a,
        b,
        &pose,
        f32::MAX,
        &mut stats,
        |_, t1, _, t2, _| {
            let d = DefaultQueryDispatcher
                .distance(pos12, &to_parry_triangle(t1), &to_parry_triangle(t2))
                .ok()?;
            Some((d.distance, ()))
        }
    )));
    match found {
        Some((i, j, d, ())) => ShapeDistance::new(d).with_subshapes(i, j),
        None => ShapeDistance::new(Real::MAX),
    }
}

/// Closest points within `max_dist`: branch and bound over both trees.
pub fn closest_points(
    pos12: &PPose,
    s1: &CbvhShape,
    s2: &CbvhShape,
    max_dist: Real,
) -> ClosestPoints {
    let pose = pose_from_parry(pos12);
    let mut stats = TraversalStats::default();
    let bound = max_dist + max_dist.abs() * 1e-6 + 1e-7;
    let found = with_cursor!(s1, |a| with_cursor!(s2, |b| bvtt_min(
        a,
        b,
        &pose,
        bound,
        &mut stats,
        |_, t1, _, t2, _| {
            let cp = DefaultQueryDispatcher
                .closest_points(
                    pos12,
                    &to_parry_triangle(t1),
                    &to_parry_triangle(t2),
                    max_dist,
                )
                .ok()?;
            super::cbvh_any::closest_cost(&cp, pos12).map(|k| (k, cp))
        }
    )));
    found.map(|f| f.3).unwrap_or(ClosestPoints::Disjoint)
}
