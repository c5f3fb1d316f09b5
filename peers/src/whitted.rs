//! Full Whitted renders (cbvh's renderer: primary rays, shadow rays to
//! three lights, two mirror bounces) with every structure behind cbvh's
//! `RayTarget`, so that all of them trace exactly the same rays.
//!
//! The scene has no vertex normals, so every target is shaded with face
//! normals and the shading work is the same for all; only the structure's
//! closest-hit and any-hit queries differ (and cbvh's codecs cast primary
//! rays in 8×8 packets, as `cbvh render` does).

use std::time::Instant;

use cbvh::TraversalStats;
use cbvh::geom::{Aabb, Ray, Triangle};
use cbvh::query::RayHit;
use cbvh::render::{RayTarget, RenderOptions, Scene, render};

/// A foreign structure's two ray queries, in cbvh's terms.
pub trait Queries: Sync {
    /// The closest hit within `[0, t_max]`: distance and original triangle
    /// id.
    fn closest(&self, ray: &Ray, t_max: f32) -> Option<(f32, u32)>;
    /// Whether anything is hit within `[0, t_max]`.
    fn any(&self, ray: &Ray, t_max: f32) -> bool;
}

/// A foreign structure behind cbvh's `RayTarget`, over the mesh it was
/// built from (for the triangles shading needs). Barycentrics are not
/// reported: the scene is shaded with face normals.
pub struct Foreign<'a, Q> {
    pub queries: Q,
    pub mesh: &'a cbvh::Mesh,
    pub bytes: usize,
    pub name: &'static str,
}

impl<Q: Queries> RayTarget for Foreign<'_, Q> {
    fn closest(&self, ray: &Ray, t_max: f32, _stats: &mut TraversalStats) -> Option<RayHit> {
        let (t, triangle) = self.queries.closest(ray, t_max)?;
        Some(RayHit {
            t,
            triangle,
            u: 0.0,
            v: 0.0,
        })
    }

    fn any(&self, ray: &Ray, t_max: f32, _stats: &mut TraversalStats) -> bool {
        self.queries.any(ray, t_max)
    }

    fn triangle(&self, id: u32) -> Triangle {
        cbvh::geom::triangle_from_arrays(self.mesh.triangle_vertices(id as usize))
    }

    fn triangle_count(&self) -> usize {
        self.mesh.triangle_count()
    }

    fn bounds(&self) -> Aabb {
        let (lo, hi) = self.mesh.bounds().unwrap_or(([0.0; 3], [0.0; 3]));
        Aabb::from_arrays(lo, hi)
    }

    fn bytes_total(&self) -> usize {
        self.bytes
    }

    fn counts_traversal(&self) -> bool {
        false
    }

    fn name(&self) -> &str {
        self.name
    }
}

/// obvhs's CWBVH with its triangles in BVH order.
pub struct Obvhs<'a> {
    pub cw: &'a obvhs::cwbvh::CwBvh,
    pub tris: &'a [obvhs::triangle::Triangle],
}

impl Queries for Obvhs<'_> {
    fn closest(&self, ray: &Ray, t_max: f32) -> Option<(f32, u32)> {
        let r = obvhs::ray::Ray::new(ray.origin, ray.dir, 0.0, t_max);
        let mut hit = obvhs::ray::RayHit::none();
        self.cw
            .ray_traverse(r, &mut hit, |r, id| self.tris[id].intersect(r))
            .then(|| (hit.t, self.cw.primitive_indices[hit.primitive_id as usize]))
    }

    fn any(&self, ray: &Ray, t_max: f32) -> bool {
        let r = obvhs::ray::Ray::new(ray.origin, ray.dir, 0.0, t_max);
        !self
            .cw
            .ray_traverse_miss(r, |r, id| self.tris[id].intersect(r))
    }
}

/// Renders the statue once with `target` on `pool`; returns (rays,
/// seconds).
pub fn timed_render(
    target: &dyn RayTarget,
    opts: &RenderOptions,
    pool: &rayon::ThreadPool,
) -> (u64, f64) {
    let scene = Scene::single(target, None);
    pool.install(|| {
        let t0 = Instant::now();
        let (_, stats) = render(&scene, opts, &|_, _| {}).expect("render");
        (stats.rays.total(), t0.elapsed().as_secs_f64())
    })
}
