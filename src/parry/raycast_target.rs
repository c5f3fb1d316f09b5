//! parry's `TriMesh` as a [`RayTarget`], so the ray tracer can render
//! through parry's own ray casting, side by side with cbvh's codecs.
//!
//! - closest hit: `CompositeShapeRef::cast_local_ray`, which is what
//!   `TriMesh::cast_local_ray` calls, but which also returns the triangle id
//!   (parry's best-first traversal with its SIMD ray-box test, and its own
//!   ray/triangle test). Barycentrics are recomputed from the hit point.
//! - any hit: `RayCast::intersects_local_ray`. parry has no early-exit
//!   ray query for a `TriMesh`: it runs the closest-hit search and tests
//!   the result, which is what a parry user gets for a shadow ray.
//!
//! parry does not count traversal steps, so this target reports none
//! ([`RayTarget::counts_traversal`] is `false`).

use glam::Vec3A;
use parry3d::math::Vector;
use parry3d::query::{Ray as ParryRay, RayCast};
use parry3d::shape::{CompositeShapeRef, TriMesh};

use super::trimesh::trimesh_bytes_by_part;
use crate::cursor::TraversalStats;
use crate::geom::{Aabb, Ray, Triangle};
use crate::query::ray::RayHit;
use crate::render::RayTarget;

#[inline]
fn to_parry(ray: &Ray) -> ParryRay {
    ParryRay::new(
        Vector::new(ray.origin.x, ray.origin.y, ray.origin.z),
        Vector::new(ray.dir.x, ray.dir.y, ray.dir.z),
    )
}

#[inline]
fn to_vec3a(v: Vector) -> Vec3A {
    Vec3A::new(v.x, v.y, v.z)
}

/// Barycentric coordinates `(u, v)` of corners 1 and 2 of the point of
/// triangle `t`'s plane nearest to `p`, clamped into the triangle.
fn barycentrics(t: &Triangle, p: Vec3A) -> (f32, f32) {
    let e0 = t[1] - t[0];
    let e1 = t[2] - t[0];
    let d = p - t[0];
    let d00 = e0.dot(e0);
    let d01 = e0.dot(e1);
    let d11 = e1.dot(e1);
    let d20 = d.dot(e0);
    let d21 = d.dot(e1);
    let den = d00 * d11 - d01 * d01;
    if den == 0.0 || !den.is_finite() {
        return (0.0, 0.0);
    }
    let u = ((d11 * d20 - d01 * d21) / den).clamp(0.0, 1.0);
    let v = ((d00 * d21 - d01 * d20) / den).clamp(0.0, 1.0 - u);
    (u, v)
}

impl RayTarget for TriMesh {
    fn closest(&self, ray: &Ray, t_max: f32, _stats: &mut TraversalStats) -> Option<RayHit> {
        let (id, t) = CompositeShapeRef(self).cast_local_ray(&to_parry(ray), t_max, true)?;
        let (u, v) = barycentrics(&RayTarget::triangle(self, id), ray.at(t));
        Some(RayHit {
            t,
            triangle: id,
            u,
            v,
        })
    }

    fn any(&self, ray: &Ray, t_max: f32, _stats: &mut TraversalStats) -> bool {
        self.intersects_local_ray(&to_parry(ray), t_max)
    }

    fn triangle(&self, id: u32) -> Triangle {
        let t = TriMesh::triangle(self, id);
        [to_vec3a(t.a), to_vec3a(t.b), to_vec3a(t.c)]
    }

    fn triangle_count(&self) -> usize {
        self.indices().len()
    }

    fn bounds(&self) -> Aabb {
        if self.indices().is_empty() {
            return Aabb::EMPTY;
        }
        let b = self.local_aabb();
        Aabb::new(to_vec3a(b.mins), to_vec3a(b.maxs))
    }

    fn bytes_total(&self) -> usize {
        trimesh_bytes_by_part(self).iter().map(|p| p.1).sum()
    }

    fn vertex_indices(&self, id: u32) -> Option<[u32; 3]> {
        Some(self.indices()[id as usize])
    }

    fn counts_traversal(&self) -> bool {
        false
    }

    fn name(&self) -> &str {
        "parry"
    }
}
