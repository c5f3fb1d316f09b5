//! cbvh shape vs a convex shape (ball, cuboid, capsule, convex polyhedron,
//! …): an overlap query on the cbvh tree with the convex shape's box, then
//! parry's convex-convex code per triangle. The intersection test and
//! contact here serve any non-cbvh shape (parry's default dispatcher takes
//! each triangle against a composite shape with that shape's own tree).

use std::ops::ControlFlow;

use parry3d::math::{Pose as PPose, Real};
use parry3d::query::{
    Contact, ContactManifold, ContactManifoldsWorkspace, DefaultQueryDispatcher,
    PersistentQueryDispatcher, QueryDispatcher, ShapeIntersection, TrackedContact,
};
use parry3d::shape::Shape;

use parry3d::query::details::NormalConstraints;

use super::cones::EdgeCone;
use super::patches::{ContactCounters, ContactMode, manifolds_in_mode};
use super::shape::{CbvhShape, from_parry_aabb, to_parry_triangle};
use super::workspace::ManifoldUpdate;
use crate::contact::{Facing, PatchOptions, PatchPoint, PatchSet};
use crate::cursor::TraversalStats;
use crate::geom::Triangle;
use crate::query::overlap;

/// Calls `f` for each triangle of `mesh` whose box comes within
/// `prediction` of the box of `convex` placed at `pose` (in the mesh's frame).
fn for_each_triangle_near(
    mesh: &CbvhShape,
    convex: &dyn Shape,
    pose: &PPose,
    prediction: Real,
    mut f: impl FnMut(u32, &Triangle) -> ControlFlow<()>,
) {
    let query = from_parry_aabb(&convex.compute_aabb(pose)).loosened(prediction);
    let mut stats = TraversalStats::default();
    with_cursor!(mesh, |c| {
        overlap(c, &query, &mut stats, &mut f);
    });
}

/// How the mesh's triangles face a convex shape placed at `pose` in the
/// mesh's frame: toward its centre when two-sided.
fn convex_facing(mesh: &CbvhShape, convex: &dyn Shape, pose: &PPose) -> Facing {
    let c = *pose * convex.compute_local_aabb().center();
    mesh.facing(glam::Vec3A::from(c.to_array()))
}

/// Contact manifolds in the dispatcher's `mode`; `flipped` says the cbvh
/// shape is the second shape of the pair.
#[allow(clippy::too_many_arguments)]
pub fn contact_manifolds_in<M: Default + Clone + Send + Sync, C: Default + Copy + Send + Sync>(
    mode: &ContactMode,
    counters: Option<&ContactCounters>,
    pos12: &PPose,
    mesh: &CbvhShape,
    convex: &dyn Shape,
    flipped: bool,
    prediction: Real,
    manifolds: &mut Vec<ContactManifold<M, C>>,
    workspace: &mut Option<ContactManifoldsWorkspace>,
) {
    manifolds_in_mode(
        mode,
        counters,
        pos12,
        &mesh.local_aabb(),
        &from_parry_aabb(&convex.compute_local_aabb()),
        flipped,
        prediction,
        manifolds,
        workspace,
        // `pose`: the convex shape's pose in the mesh's frame.
        |pose, bound, opts| patches(pose, mesh, convex, bound.prediction, opts, false, counters),
        |manifolds, workspace| {
            contact_manifolds(
                pos12, mesh, convex, flipped, prediction, manifolds, workspace,
            )
        },
    );
}

/// The contact patches of a cbvh shape and a convex shape placed at `pose`
/// in the mesh's frame (patches in the mesh's frame; `j` is always 0): each
/// triangle near the convex shape goes through parry's convex-convex
/// manifold code, and the points are reduced into patches.
pub fn patches(
    pose: &PPose,
    mesh: &CbvhShape,
    convex: &dyn Shape,
    prediction: Real,
    opts: &PatchOptions,
    record: bool,
    counters: Option<&ContactCounters>,
) -> PatchSet {
    let size = {
        let own = mesh.local_aabb().extent().length();
        let e = convex.compute_local_aabb().extents();
        own.min(e.length())
    };
    let mut set = PatchSet::new(opts, size, record);
    let mut scratch: ContactManifold<(), ()> = ContactManifold::new();
    let (mut candidates, mut contacts) = (0u64, 0u64);
    let facing = convex_facing(mesh, convex, pose);
    for_each_triangle_near(mesh, convex, pose, prediction, |i, t| {
        candidates += 1;
        scratch.points.clear();
        let Some(mut cone) = EdgeCone::new(t, mesh.edge_flags_of(i), facing) else {
            return ControlFlow::Continue(());
        };
        let tri = to_parry_triangle(t);
        let run = |cone: &EdgeCone, scratch: &mut ContactManifold<(), ()>| {
            let _ = DefaultQueryDispatcher.contact_manifold_convex_convex(
                pose,
                &tri,
                convex,
                Some(cone),
                None,
                prediction,
                scratch,
            );
        };
        run(&cone, &mut scratch);
        // The normal leaned over a shared edge: bound the lean by the
        // neighbour's face normal and compute the contact again.
        if cone.wanted() != 0 {
            cone.complete(mesh, i, t);
            scratch.points.clear();
            run(&cone, &mut scratch);
        }
        let n = glam::Vec3A::from(scratch.local_n1.to_array());
        let mut first = true;
        for (k, p) in scratch
            .points
            .iter()
            .enumerate()
            .filter(|(_, p)| p.dist <= prediction)
        {
            let q2 = *pose * p.local_p2;
            set.add_point(
                n,
                PatchPoint {
                    p1: glam::Vec3A::from(p.local_p1.to_array()),
                    p2: glam::Vec3A::from(q2.to_array()),
                    dist: p.dist,
                    i,
                    j: 0,
                    feature: k as u8,
                },
                first,
            );
            contacts += u64::from(first);
            first = false;
        }
        ControlFlow::Continue(())
    });
    let centre = *pose * convex.compute_local_aabb().center();
    set.drop_opposed(glam::Vec3A::from(centre.to_array()) - mesh.local_aabb().center());
    if let Some(c) = counters {
        c.add(candidates, contacts, set.patches.len() as u64);
    }
    set
}

/// Contact manifolds between a cbvh shape and a convex shape, one per
/// triangle (the per-triangle-pair mode). `flipped` says the cbvh shape is
/// the second shape of the pair.
pub fn contact_manifolds<M: Default + Clone + Send + Sync, C: Default + Copy + Send + Sync>(
    pos12: &PPose,
    mesh: &CbvhShape,
    convex: &dyn Shape,
    flipped: bool,
    prediction: Real,
    manifolds: &mut Vec<ContactManifold<M, C>>,
    workspace: &mut Option<ContactManifoldsWorkspace>,
) {
    let mut update = ManifoldUpdate::begin(workspace, manifolds);
    // The convex shape's pose in the mesh's frame.
    let pose = if flipped { pos12.inverse() } else { *pos12 };
    let facing = convex_facing(mesh, convex, &pose);
    // The manifold as it was before a first computation that may be
    // redone (its points keep the warm-start impulses).
    let mut saved: Vec<TrackedContact<C>> = Vec::new();
    for_each_triangle_near(mesh, convex, &pose, prediction, |i, t| {
        let tri = to_parry_triangle(t);
        let mut cone = EdgeCone::new(t, mesh.edge_flags_of(i), facing);
        let m = if flipped {
            update.manifold(0, i)
        } else {
            update.manifold(i, 0)
        };
        let run = |cone: &Option<EdgeCone>, m: &mut ContactManifold<M, C>| {
            let nc = cone.as_ref().map(|c| c as &dyn NormalConstraints);
            if flipped {
                let _ = DefaultQueryDispatcher
                    .contact_manifold_convex_convex(pos12, convex, &tri, None, nc, prediction, m);
            } else {
                let _ = DefaultQueryDispatcher
                    .contact_manifold_convex_convex(pos12, &tri, convex, nc, None, prediction, m);
            }
        };
        let may_redo = cone.as_ref().is_some_and(EdgeCone::has_shared);
        let normals = (m.local_n1, m.local_n2);
        if may_redo {
            saved.clear();
            saved.extend_from_slice(&m.points);
        }
        run(&cone, m);
        // The normal leaned over a shared edge: bound the lean by the
        // neighbour's face normal and compute the contact again, from the
        // manifold as it was.
        if let Some(c) = cone.as_mut().filter(|c| c.wanted() != 0) {
            c.complete(mesh, i, t);
            m.points.clear();
            m.points.extend_from_slice(&saved);
            (m.local_n1, m.local_n2) = normals;
            run(&cone, m);
        }
        ControlFlow::Continue(())
    });
}

/// Whether the convex shape intersects a triangle of the cbvh shape.
pub fn intersection_test(
    pos12: &PPose,
    mesh: &CbvhShape,
    convex: &dyn Shape,
    flipped: bool,
) -> ShapeIntersection {
    let pose = if flipped { pos12.inverse() } else { *pos12 };
    let mut found = ShapeIntersection::new(false);
    for_each_triangle_near(mesh, convex, &pose, 0.0, |i, t| {
        let tri = to_parry_triangle(t);
        let r = if flipped {
            DefaultQueryDispatcher.intersection_test(pos12, convex, &tri)
        } else {
            DefaultQueryDispatcher.intersection_test(pos12, &tri, convex)
        };
        match r {
            Ok(r) if r.intersecting => {
                // The other shape's part as its own query named it (a
                // composite shape's triangle; 0 for a convex shape).
                found = if flipped {
                    ShapeIntersection::new(true).with_subshapes(r.subshape1, i)
                } else {
                    ShapeIntersection::new(true).with_subshapes(i, r.subshape2)
                };
                ControlFlow::Break(())
            }
            _ => ControlFlow::Continue(()),
        }
    });
    found
}

/// The deepest contact within `prediction`.
pub fn contact(
    pos12: &PPose,
    mesh: &CbvhShape,
    convex: &dyn Shape,
    flipped: bool,
    prediction: Real,
) -> Option<Contact> {
    let pose = if flipped { pos12.inverse() } else { *pos12 };
    let mut best: Option<Contact> = None;
    for_each_triangle_near(mesh, convex, &pose, prediction, |i, t| {
        let tri = to_parry_triangle(t);
        let r = if flipped {
            DefaultQueryDispatcher
                .contact(pos12, convex, &tri, prediction)
                .map(|c| c.map(|c| c.with_subshapes(c.subshape1, i)))
        } else {
            DefaultQueryDispatcher
                .contact(pos12, &tri, convex, prediction)
                .map(|c| c.map(|c| c.with_subshapes(i, c.subshape2)))
        };
        if let Ok(Some(c)) = r
            && best.is_none_or(|b| c.dist < b.dist)
        {
            best = Some(c);
        }
        ControlFlow::Continue(())
    });
    best
}
