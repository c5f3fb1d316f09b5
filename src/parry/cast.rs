//! Nonlinear shape casts (rapier's CCD sweeps) with a cbvh shape on either
//! side, on the cbvh tree: a best-first search whose node test casts the
//! node's bounding ball, as parry's composite-shape cast does, and whose
//! leaves go to the dispatcher for the triangle against the other shape
//! (which recurses into the other cbvh tree when both are cbvh shapes).

use parry3d::math::Real;
use parry3d::query::details::{
    NonlinearShapeCastMode, cast_shapes_nonlinear_support_map_support_map,
};
use parry3d::query::{NonlinearRigidMotion, QueryDispatcher, ShapeCastHit, ShapeCastStatus};
use parry3d::shape::{Ball, Shape};

use super::shape::{CbvhShape, to_parry_triangle};
use crate::cursor::TraversalStats;
use crate::geom::Aabb;
use crate::query::find_best;

/// Time at which the ball around `b` (moving with `m1`) meets the ball of
/// `other` (moving with `m2`), or `f32::MAX`.
fn ball_toi<D: ?Sized + QueryDispatcher>(
    dispatcher: &D,
    b: &Aabb,
    m1: &NonlinearRigidMotion,
    sphere2: &parry3d::bounding_volume::BoundingSphere,
    m2: &NonlinearRigidMotion,
    start: Real,
    end: Real,
) -> Real {
    let ball1 = Ball::new(b.half_extents().length());
    let ball2 = Ball::new(sphere2.radius());
    let bm1 = m1.prepend_translation(b.center().into());
    let bm2 = m2.prepend_translation(sphere2.center);
    cast_shapes_nonlinear_support_map_support_map(
        dispatcher,
        &bm1,
        &ball1,
        &ball1,
        &bm2,
        &ball2,
        &ball2,
        start,
        end,
        NonlinearShapeCastMode::StopAtPenetration,
    )
    .map(|h| h.time_of_impact)
    .unwrap_or(Real::MAX)
}

/// Casts `mesh` (moving with `m_mesh`) against `other` (moving with
/// `m_other`). `mesh_first` says the mesh is shape 1 of the query, so the
/// hit's sides follow the caller's order.
#[allow(clippy::too_many_arguments)]
pub fn cast_nonlinear<D: ?Sized + QueryDispatcher>(
    dispatcher: &D,
    mesh: &CbvhShape,
    m_mesh: &NonlinearRigidMotion,
    other: &dyn Shape,
    m_other: &NonlinearRigidMotion,
    mesh_first: bool,
    start: Real,
    end: Real,
    stop_at_penetration: bool,
) -> Option<ShapeCastHit> {
    let sphere = other.compute_local_bounding_sphere();
    let mut stats = TraversalStats::default();
    let found = with_cursor!(mesh, |c| find_best(
        c,
        end,
        &mut stats,
        |b| ball_toi(dispatcher, b, m_mesh, &sphere, m_other, start, end),
        |_, tri, _| {
            let t = to_parry_triangle(tri);
            let hit = if mesh_first {
                dispatcher.cast_shapes_nonlinear(
                    m_mesh,
                    &t,
                    m_other,
                    other,
                    start,
                    end,
                    stop_at_penetration,
                )
            } else {
                dispatcher.cast_shapes_nonlinear(
                    m_other,
                    other,
                    m_mesh,
                    &t,
                    start,
                    end,
                    stop_at_penetration,
                )
            };
            // A cast whose iteration failed to converge reports an arbitrary
            // time; taking it would make rapier's CCD clamp the body's motion
            // to that time on every step, freezing it in place.
            hit.ok()
                .flatten()
                .filter(|h| h.status != ShapeCastStatus::Failed)
                .map(|h| (h.time_of_impact, h))
        }
    ));
    found.map(|(id, _, mut hit)| {
        if mesh_first {
            hit.subshape1 = id;
        } else {
            hit.subshape2 = id;
        }
        hit
    })
}
