//! cbvh shape vs parry `TriMesh`: contact manifolds.
//!
//! parry's `Bvh` keeps its nodes private (`pub(super)`), so a simultaneous
//! traversal of both trees cannot be written outside parry. The cbvh tree is
//! traversed once against the `TriMesh`'s box; each cbvh triangle found then
//! queries the `TriMesh`'s own `Bvh` (`intersect_aabb`). Triangle pairs go
//! through parry's convex-convex code with the `TriMesh`'s normal
//! constraints, and manifolds persist per triangle pair.

use std::ops::ControlFlow;

use parry3d::bounding_volume::BoundingVolume;
use parry3d::math::{Pose as PPose, Real};
use parry3d::query::{
    ContactManifold, ContactManifoldsWorkspace, DefaultQueryDispatcher, PersistentQueryDispatcher,
    TrackedContact,
};
use parry3d::shape::{CompositeShape, Shape, TriMesh};

use super::patches::{ContactCounters, ContactMode, manifolds_in_mode};
use super::shape::{CbvhShape, from_parry_aabb, to_parry_triangle};
use super::workspace::ManifoldUpdate;
use parry3d::query::details::NormalConstraints;

use super::cones::EdgeCone;
use crate::contact::edges::ALL_ACTIVE;
use crate::contact::{Facing, PairFacing, PairKernel, PatchOptions, PatchSet};
use crate::cursor::TraversalStats;
use crate::query::overlap;

/// Contact manifolds in the dispatcher's `mode`; `flipped` says the cbvh
/// shape is the second shape of the pair.
#[allow(clippy::too_many_arguments)]
pub fn contact_manifolds_in<M: Default + Clone + Send + Sync, C: Default + Copy + Send + Sync>(
    mode: &ContactMode,
    counters: Option<&ContactCounters>,
    pos12: &PPose,
    mesh: &CbvhShape,
    tm: &TriMesh,
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
        &from_parry_aabb(&tm.local_aabb()),
        flipped,
        prediction,
        manifolds,
        workspace,
        // `pose`: the `TriMesh`'s pose in the mesh's frame.
        |pose, bound, opts| patches(pose, mesh, tm, bound.prediction, opts, false, counters),
        |manifolds, workspace| {
            contact_manifolds(pos12, mesh, tm, flipped, prediction, manifolds, workspace)
        },
    );
}

/// The contact patches of a cbvh shape and a `TriMesh` placed at
/// `tm_in_mesh` in the mesh's frame (patches in the mesh's frame): every
/// cbvh triangle near the `TriMesh` queries its `Bvh`, and each pair goes
/// through cbvh's triangle-pair kernel.
pub fn patches(
    tm_in_mesh: &PPose,
    mesh: &CbvhShape,
    tm: &TriMesh,
    prediction: Real,
    opts: &PatchOptions,
    record: bool,
    counters: Option<&ContactCounters>,
) -> PatchSet {
    let mesh_in_tm = tm_in_mesh.inverse();
    let size = mesh
        .local_aabb()
        .extent()
        .length()
        .min(tm.local_aabb().extents().length());
    let mut set = PatchSet::new(opts, size, record);
    let to_mesh = |p: parry3d::math::Vector| glam::Vec3A::from((*tm_in_mesh * p).to_array());
    // parry's TriMesh carries no active-edge flags: its triangles count as
    // having every edge active, two-sided toward the cbvh shape's centre.
    let facing = PairFacing::new(
        mesh.facing(to_mesh(tm.local_aabb().center())),
        Facing::TwoSided {
            toward: mesh.local_aabb().center(),
        },
    );
    let mut kernel = PairKernel::new(prediction)
        .exact_separation(false)
        .oriented(Some(facing));
    let query = from_parry_aabb(&tm.compute_aabb(tm_in_mesh)).loosened(prediction);
    let mut stats = TraversalStats::default();
    with_cursor!(mesh, |c| {
        overlap(c, &query, &mut stats, |i, tri| {
            let ptri = to_parry_triangle(tri);
            let b = ptri.compute_aabb(&mesh_in_tm).loosened(prediction);
            for j in tm.bvh().intersect_aabb(&b) {
                let t = tm.triangle(j);
                let moved = [to_mesh(t.a), to_mesh(t.b), to_mesh(t.c)];
                kernel.push_flagged(
                    (i, tri, mesh.edge_flags_of(i)),
                    (j, &moved, ALL_ACTIVE),
                    prediction,
                    &mut set,
                );
            }
            ControlFlow::Continue(())
        });
    });
    kernel.flush_into(&mut set);
    set.drop_opposed(to_mesh(tm.local_aabb().center()) - mesh.local_aabb().center());
    if let Some(c) = counters {
        c.add(
            kernel.stats.pairs,
            kernel.stats.contacts,
            set.patches.len() as u64,
        );
    }
    set
}

/// Contact manifolds between a cbvh shape and a `TriMesh`; `flipped` says
/// the cbvh shape is the second shape of the pair.
#[allow(clippy::too_many_arguments)]
pub fn contact_manifolds<M: Default + Clone + Send + Sync, C: Default + Copy + Send + Sync>(
    pos12: &PPose,
    mesh: &CbvhShape,
    tm: &TriMesh,
    flipped: bool,
    prediction: Real,
    manifolds: &mut Vec<ContactManifold<M, C>>,
    workspace: &mut Option<ContactManifoldsWorkspace>,
) {
    let mut update = ManifoldUpdate::begin(workspace, manifolds);
    let tm_in_mesh = if flipped { pos12.inverse() } else { *pos12 };
    let mesh_in_tm = tm_in_mesh.inverse();
    let query = from_parry_aabb(&tm.compute_aabb(&tm_in_mesh)).loosened(prediction);
    let mut stats = TraversalStats::default();
    let tm_center = glam::Vec3A::from((tm_in_mesh * tm.local_aabb().center()).to_array());
    let facing = mesh.facing(tm_center);
    let mut saved: Vec<TrackedContact<C>> = Vec::new();
    with_cursor!(mesh, |c| {
        overlap(c, &query, &mut stats, |i, tri| {
            let ptri = to_parry_triangle(tri);
            let b = ptri.compute_aabb(&mesh_in_tm).loosened(prediction);
            for j in tm.bvh().intersect_aabb(&b) {
                tm.map_part_at(j, &mut |_, part, normals| {
                    // A cone per pair: what one pair's normal leaned over
                    // says nothing of the next's.
                    let mut cone = EdgeCone::new(tri, mesh.edge_flags_of(i), facing);
                    let may_redo = cone.as_ref().is_some_and(EdgeCone::has_shared);
                    let m = if flipped {
                        update.manifold(j, i)
                    } else {
                        update.manifold(i, j)
                    };
                    let run = |cone: &Option<EdgeCone>, m: &mut ContactManifold<M, C>| {
                        let own = cone.as_ref().map(|c| c as &dyn NormalConstraints);
                        let _ = if flipped {
                            DefaultQueryDispatcher.contact_manifold_convex_convex(
                                pos12, part, &ptri, normals, own, prediction, m,
                            )
                        } else {
                            DefaultQueryDispatcher.contact_manifold_convex_convex(
                                pos12, &ptri, part, own, normals, prediction, m,
                            )
                        };
                    };
                    let normals12 = (m.local_n1, m.local_n2);
                    if may_redo {
                        saved.clear();
                        saved.extend_from_slice(&m.points);
                    }
                    run(&cone, m);
                    // As against a convex shape: a normal that leaned over
                    // a shared edge goes no further than the neighbour's
                    // face normal, computed again from the manifold as it was.
                    if let Some(c) = cone.as_mut().filter(|c| c.wanted() != 0) {
                        c.complete(mesh, i, tri);
                        m.points.clear();
                        m.points.extend_from_slice(&saved);
                        (m.local_n1, m.local_n2) = normals12;
                        run(&cone, m);
                    }
                });
            }
            ControlFlow::Continue(())
        });
    });
}
