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
};
use parry3d::shape::{CompositeShape, Shape, TriMesh};

use super::shape::{CbvhShape, from_parry_aabb, to_parry_triangle, with_cursor};
use super::workspace::ManifoldUpdate;
use crate::cursor::TraversalStats;
use crate::query::overlap;

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
    with_cursor!(mesh.codec(), |c| {
        overlap(c, &query, &mut stats, |i, tri| {
            let ptri = to_parry_triangle(tri);
            let b = ptri.compute_aabb(&mesh_in_tm).loosened(prediction);
            for j in tm.bvh().intersect_aabb(&b) {
                tm.map_part_at(j, &mut |_, part, normals| {
                    if flipped {
                        let m = update.manifold(j, i);
                        let _ = DefaultQueryDispatcher.contact_manifold_convex_convex(
                            pos12, part, &ptri, normals, None, prediction, m,
                        );
                    } else {
                        let m = update.manifold(i, j);
                        let _ = DefaultQueryDispatcher.contact_manifold_convex_convex(
                            pos12, &ptri, part, None, normals, prediction, m,
                        );
                    }
                });
            }
            ControlFlow::Continue(())
        });
    });
}
