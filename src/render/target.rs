//! [`RayTarget`]: what the ray tracer needs from an acceleration structure,
//! and [`CursorTarget`], its implementation for every
//! [`NodeCursor`] through [`crate::query::ray`].
//!
//! parry's `TriMesh` implements the trait in `crate::parry::raycast_target`
//! (only `src/parry/` may import parry3d).

use crate::codec::ByteSize;
use crate::codec::plain::PlainBvh;
use crate::codec::racbvh::RacBvh;
use crate::cursor::{NodeCursor, TraversalStats};
use crate::geom::{Aabb, Ray, Triangle};
use crate::query::packet::closest_hits_within;
use crate::query::ray::{RayHit, any_hit, closest_hit};

/// An acceleration structure the ray tracer can shoot rays at, in its own
/// (local) coordinates.
pub trait RayTarget: Sync {
    /// The closest hit of `ray` with `t` in `[0, t_max]`.
    fn closest(&self, ray: &Ray, t_max: f32, stats: &mut TraversalStats) -> Option<RayHit>;

    /// Whether `ray` hits anything with `t` in `[0, t_max]` (shadow rays).
    fn any(&self, ray: &Ray, t_max: f32, stats: &mut TraversalStats) -> bool;

    /// The closest hits of a packet of up to
    /// [`MAX_PACKET`](crate::query::packet::MAX_PACKET) coherent rays,
    /// `rays[i]` within `[0, t_max[i]]` into `out[i]`: the same hits as
    /// [`RayTarget::closest`] ray by ray (which is what this default does).
    fn closest_packet(
        &self,
        rays: &[Ray],
        t_max: &[f32],
        out: &mut [Option<RayHit>],
        stats: &mut TraversalStats,
    ) {
        for ((ray, &t), o) in rays.iter().zip(t_max).zip(out.iter_mut()) {
            *o = self.closest(ray, t, stats);
        }
    }

    /// The corners of triangle `id` (an id [`RayTarget::closest`] reported).
    fn triangle(&self, id: u32) -> Triangle;

    /// Number of triangles.
    fn triangle_count(&self) -> usize;

    /// A box containing every triangle (empty for an empty structure).
    fn bounds(&self) -> Aabb;

    /// Bytes of the whole structure, mesh included.
    fn bytes_total(&self) -> usize;

    /// [`RayTarget::bytes_total`] per triangle.
    fn bytes_per_triangle(&self) -> f64 {
        self.bytes_total() as f64 / self.triangle_count().max(1) as f64
    }

    /// The vertex indices of triangle `id`, if the structure exposes them
    /// (smooth shading needs them); `None` means "shade with face normals".
    fn vertex_indices(&self, _id: u32) -> Option<[u32; 3]> {
        None
    }

    /// Whether [`RayTarget::closest`] and [`RayTarget::any`] fill the
    /// [`TraversalStats`] they are given (a foreign structure may not).
    fn counts_traversal(&self) -> bool {
        true
    }

    /// A short name for reports (`plain`, `parry`, …).
    fn name(&self) -> &str;
}

/// A [`NodeCursor`] as a [`RayTarget`]: rays go through
/// [`closest_hit`] and [`any_hit`], monomorphized for `C`.
pub struct CursorTarget<C> {
    cursor: C,
    name: &'static str,
    bytes: usize,
    bounds: Aabb,
    indices: Option<fn(&C, u32) -> [u32; 3]>,
}

impl<C: NodeCursor + ByteSize> CursorTarget<C> {
    /// Wraps `cursor`, reported as `name`. Without
    /// [`CursorTarget::with_vertex_indices`] it is shaded with face normals.
    pub fn new(cursor: C, name: &'static str) -> Self {
        let bytes = cursor.bytes_total();
        let bounds = cursor.root().1;
        Self {
            cursor,
            name,
            bytes,
            bounds,
            indices: None,
        }
    }
}

impl<C> CursorTarget<C> {
    /// Lets the renderer look up a triangle's vertex indices (for smooth
    /// normals) with `f`.
    pub fn with_vertex_indices(mut self, f: fn(&C, u32) -> [u32; 3]) -> Self {
        self.indices = Some(f);
        self
    }

    /// The wrapped cursor.
    pub fn cursor(&self) -> &C {
        &self.cursor
    }
}

impl CursorTarget<RacBvh> {
    /// The RACBVH codec, with vertex indices (smooth shading, like
    /// [`CursorTarget::plain`]).
    pub fn racbvh(rac: RacBvh) -> Self {
        CursorTarget::new(rac, "racbvh").with_vertex_indices(|r, id| r.triangle_indices(id))
    }
}

impl CursorTarget<PlainBvh> {
    /// The plain codec, with vertex indices (smooth shading).
    pub fn plain(bvh: PlainBvh) -> Self {
        CursorTarget::new(bvh, "plain").with_vertex_indices(|b, id| b.triangles()[id as usize])
    }
}

impl<C: NodeCursor> RayTarget for CursorTarget<C> {
    #[inline]
    fn closest(&self, ray: &Ray, t_max: f32, stats: &mut TraversalStats) -> Option<RayHit> {
        closest_hit(&self.cursor, ray, t_max, stats)
    }

    #[inline]
    fn any(&self, ray: &Ray, t_max: f32, stats: &mut TraversalStats) -> bool {
        any_hit(&self.cursor, ray, t_max, stats)
    }

    fn closest_packet(
        &self,
        rays: &[Ray],
        t_max: &[f32],
        out: &mut [Option<RayHit>],
        stats: &mut TraversalStats,
    ) {
        closest_hits_within(&self.cursor, rays, t_max, out, stats);
    }

    fn triangle(&self, id: u32) -> Triangle {
        self.cursor.triangle(id)
    }

    fn triangle_count(&self) -> usize {
        self.cursor.triangle_count()
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }

    fn bytes_total(&self) -> usize {
        self.bytes
    }

    fn vertex_indices(&self, id: u32) -> Option<[u32; 3]> {
        self.indices.map(|f| f(&self.cursor, id))
    }

    fn name(&self) -> &str {
        self.name
    }
}
