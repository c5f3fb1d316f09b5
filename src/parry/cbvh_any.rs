//! cbvh shape vs any other shape (convex, parry `TriMesh`, compound, …) for
//! the queries that look for one best answer: distance, closest points and
//! linear shape casts. A best-first search on the cbvh tree, whose node
//! bound comes from the other shape's box, hands each triangle to the
//! dispatcher chain against the other shape, so a composite other shape is
//! searched with its own tree (and another cbvh shape with this module).

use parry3d::math::{Pose as PPose, Real, Vector};
use parry3d::query::{
    ClosestPoints, QueryDispatcher, ShapeCastHit, ShapeCastOptions, ShapeDistance,
};
use parry3d::shape::Shape;

use super::shape::{CbvhShape, from_parry_aabb, to_parry_triangle};
use crate::cursor::TraversalStats;
use crate::geom::{Aabb, Ray};
use crate::query::find_best;

fn box_distance(x: &Aabb, y: &Aabb) -> f32 {
    (x.min - y.max)
        .max(y.min - x.max)
        .max(glam::Vec3A::ZERO)
        .length()
}

/// The other shape's pose in the mesh's frame.
fn other_in_mesh(pos12: &PPose, mesh_first: bool) -> PPose {
    if mesh_first { *pos12 } else { pos12.inverse() }
}

/// Distance between `mesh` and `other` (`mesh_first`: the mesh is shape 1).
pub fn distance<D: QueryDispatcher>(
    dispatcher: &D,
    pos12: &PPose,
    mesh: &CbvhShape,
    other: &dyn Shape,
    mesh_first: bool,
) -> ShapeDistance {
    let other_box = from_parry_aabb(&other.compute_aabb(&other_in_mesh(pos12, mesh_first)));
    let mut stats = TraversalStats::default();
    let found = with_cursor!(mesh, |c| find_best(
        c,
        f32::MAX,
        &mut stats,
        |b| box_distance(b, &other_box),
        |_, tri, _| {
            let t = to_parry_triangle(tri);
            let d = if mesh_first {
                dispatcher.distance(pos12, &t, other)
            } else {
                dispatcher.distance(pos12, other, &t)
            };
            d.ok().map(|d| (d.distance, d))
        }
    ));
    match found {
        Some((id, _, d)) if mesh_first => {
            ShapeDistance::new(d.distance).with_subshapes(id, d.subshape2)
        }
        Some((id, _, d)) => ShapeDistance::new(d.distance).with_subshapes(d.subshape1, id),
        None => ShapeDistance::new(Real::MAX),
    }
}

/// Cost of a closest-points answer: `-1` for intersecting (it beats all).
pub(crate) fn closest_cost(cp: &ClosestPoints, pos12: &PPose) -> Option<f32> {
    match cp {
        ClosestPoints::Intersecting => Some(-1.0),
        ClosestPoints::WithinMargin(p1, p2) => Some((*p1 - pos12.transform_point(*p2)).length()),
        ClosestPoints::Disjoint => None,
    }
}

/// Closest points between `mesh` and `other` within `max_dist`.
pub fn closest_points<D: QueryDispatcher>(
    dispatcher: &D,
    pos12: &PPose,
    mesh: &CbvhShape,
    other: &dyn Shape,
    mesh_first: bool,
    max_dist: Real,
) -> ClosestPoints {
    let other_box = from_parry_aabb(&other.compute_aabb(&other_in_mesh(pos12, mesh_first)));
    let mut stats = TraversalStats::default();
    let bound = max_dist + max_dist.abs() * 1e-6 + 1e-7;
    let found = with_cursor!(mesh, |c| find_best(
        c,
        bound,
        &mut stats,
        |b| box_distance(b, &other_box),
        |_, tri, _| {
            let t = to_parry_triangle(tri);
            let cp = if mesh_first {
                dispatcher.closest_points(pos12, &t, other, max_dist)
            } else {
                dispatcher.closest_points(pos12, other, &t, max_dist)
            }
            .ok()?;
            closest_cost(&cp, pos12).map(|k| (k, cp))
        }
    ));
    found.map(|f| f.2).unwrap_or(ClosestPoints::Disjoint)
}

/// Linear shape cast: `pos12` places shape 2 in shape 1's frame and
/// `local_vel12` is shape 2's velocity relative to shape 1, in shape 1's frame.
#[allow(clippy::too_many_arguments)]
pub fn cast_shapes<D: QueryDispatcher>(
    dispatcher: &D,
    pos12: &PPose,
    local_vel12: Vector,
    mesh: &CbvhShape,
    other: &dyn Shape,
    mesh_first: bool,
    options: ShapeCastOptions,
) -> Option<ShapeCastHit> {
    let other_pose = other_in_mesh(pos12, mesh_first);
    // The other shape's velocity relative to the mesh, in the mesh's frame.
    let vel = if mesh_first {
        local_vel12
    } else {
        pos12.rotation.inverse() * (-local_vel12)
    };
    let ob = from_parry_aabb(&other.compute_aabb(&other_pose)).loosened(options.target_distance);
    let ray = Ray::new(ob.center(), vel.into());
    let half = ob.half_extents();
    let mut stats = TraversalStats::default();
    let found = with_cursor!(mesh, |c| find_best(
        c,
        options.max_time_of_impact,
        &mut stats,
        |b| {
            // When the other box, swept along `vel`, first touches `b`.
            let grown = Aabb::new(b.min - half, b.max + half);
            ray.intersect_aabb(&grown, options.max_time_of_impact)
                .unwrap_or(f32::INFINITY)
        },
        |_, tri, best| {
            let t = to_parry_triangle(tri);
            let opts = ShapeCastOptions {
                max_time_of_impact: best,
                ..options
            };
            let hit = if mesh_first {
                dispatcher.cast_shapes(pos12, local_vel12, &t, other, opts)
            } else {
                dispatcher.cast_shapes(pos12, local_vel12, other, &t, opts)
            };
            hit.ok().flatten().map(|h| (h.time_of_impact, h))
        }
    ));
    found.map(|(id, _, mut h)| {
        if mesh_first {
            h.subshape1 = id;
        } else {
            h.subshape2 = id;
        }
        h
    })
}
