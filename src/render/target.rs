//! [`RayTarget`]: what the ray tracer needs from an acceleration structure,
//! and [`CursorTarget`], its implementation for every [`Codec`] (a
//! [`NodeCursor`](crate::cursor::NodeCursor) traversed through
//! [`crate::query::ray`]).
//!
//! parry's `TriMesh` implements the trait in `crate::parry::raycast_target`
//! (only `src/parry/` may import parry3d).

use crate::codec::{AnyCodec, CacheStats, Codec};
use crate::cursor::TraversalStats;
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

    /// The counters of the structure's decode cache, if it has one
    /// ([`Codec::cache_stats`]).
    fn cache_stats(&self) -> Option<CacheStats> {
        None
    }
}

/// A codec as a [`RayTarget`]: rays go through [`closest_hit`] and
/// [`any_hit`], monomorphized for `C`; shaded smoothly through the codec's
/// vertex indices ([`Codec::triangle_vertices`]).
pub struct CursorTarget<C> {
    cursor: C,
    name: &'static str,
    bytes: usize,
    bounds: Aabb,
    smooth: bool,
}

impl<C: Codec> CursorTarget<C> {
    /// Wraps `codec`, reported under its registry name, smooth-shaded.
    pub fn new(codec: C) -> Self {
        let bytes = codec.bytes_total();
        let bounds = codec.root().1;
        Self {
            cursor: codec,
            name: C::KIND.name(),
            bytes,
            bounds,
            smooth: true,
        }
    }

    /// Reports the target as `name` instead of the codec's name.
    pub fn with_name(mut self, name: &'static str) -> Self {
        self.name = name;
        self
    }

    /// Hides the vertex indices, so that the renderer shades with face
    /// normals.
    pub fn flat(mut self) -> Self {
        self.smooth = false;
        self
    }

    /// The wrapped codec.
    pub fn cursor(&self) -> &C {
        &self.cursor
    }
}

/// Any codec as a boxed [`RayTarget`] (a [`CursorTarget`] of the concrete
/// codec inside).
pub fn any_target(codec: AnyCodec) -> Box<dyn RayTarget> {
    crate::with_codec!(codec, |c| Box::new(CursorTarget::new(c)))
}

impl<C: Codec> RayTarget for CursorTarget<C> {
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
        self.smooth.then(|| self.cursor.triangle_vertices(id))
    }

    fn name(&self) -> &str {
        self.name
    }

    fn cache_stats(&self) -> Option<CacheStats> {
        self.cursor.cache_stats()
    }
}
