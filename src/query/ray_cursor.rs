//! [`RayCursor`]: the ray queries a cursor answers, with defaults over
//! its batches that a codec may replace with a traversal of its own.

use crate::cursor::{NodeCursor, TraversalStats};
use crate::geom::{Ray, RayHit};

/// A [`NodeCursor`] that answers the ray queries: by default with the
/// generic traversals over its batches, or with a traversal of its own
/// where the codec's layout allows a faster one, giving the same hits bit
/// for bit.
///
/// A trait over [`NodeCursor`] in the query layer, so that the
/// dependencies run one way (cursor ← query ← codec). Every codec's cursor
/// implements it: with an empty `impl` where the defaults serve (plain,
/// RACBVH), overriding where it has its own traversal (CLBVH and
/// i-HCCMesh replace [`closest_hit`](Self::closest_hit) and
/// [`any_hit`](Self::any_hit); CLBVH casts a packet's rays one by one).
/// The queries [`closest_hit`](super::closest_hit),
/// [`any_hit`](super::any_hit) and
/// [`closest_hits_within`](super::closest_hits_within) call these methods,
/// statically dispatched.
pub trait RayCursor: NodeCursor {
    /// The closest hit of `ray` within `[0, t_max]`, as
    /// [`query::closest_hit`](super::closest_hit) defines it.
    ///
    /// The default is the generic traversal over
    /// [`children`](NodeCursor::children) and
    /// [`for_each_triangle`](NodeCursor::for_each_triangle)
    /// ([`closest_hit_generic`](super::ray::closest_hit_generic)).
    /// A codec whose layout allows a faster traversal overrides it (CLBVH
    /// tests eight stored boxes per AVX2 instruction without building
    /// batches; i-HCCMesh descends into the nearer of a decoded pair
    /// without copying its 32-byte handles through a batch and the stack);
    /// the override must give the same hit, bit for bit, and is tested
    /// against the default.
    #[inline]
    fn closest_hit(&self, ray: &Ray, t_max: f32, stats: &mut TraversalStats) -> Option<RayHit>
    where
        Self: Sized,
    {
        super::ray::closest_hit_generic(self, ray, t_max, stats)
    }

    /// Whether `ray` hits a triangle within `[0, t_max]`, as
    /// [`query::any_hit`](super::any_hit) defines it; overridden,
    /// like [`closest_hit`](Self::closest_hit), by codecs with a faster
    /// traversal.
    #[inline]
    fn any_hit(&self, ray: &Ray, t_max: f32, stats: &mut TraversalStats) -> bool
    where
        Self: Sized,
    {
        super::ray::any_hit_generic(self, ray, t_max, stats)
    }

    /// The closest hits of a packet of coherent rays, as
    /// [`query::closest_hits_within`](super::closest_hits_within)
    /// defines them (the same hits as [`closest_hit`](Self::closest_hit)
    /// ray by ray).
    ///
    /// The default is the generic packet traversal, one walk of the tree
    /// for the whole packet
    /// ([`closest_hits_generic`](super::packet::closest_hits_generic)).
    /// A codec whose own single-ray traversal is faster than that walk
    /// overrides it with a loop over [`closest_hit`](Self::closest_hit):
    /// CLBVH, whose AVX2 traversal casts 17.0 M camera rays/s one by one
    /// on the 1 M statue against 10.1 M in 8×8 packets
    /// (`examples/packet_bench.rs`). Called with `rays`, `t_max` and `out`
    /// of one length, at most [`MAX_PACKET`](super::packet::MAX_PACKET).
    #[inline]
    fn closest_hits_within(
        &self,
        rays: &[Ray],
        t_max: &[f32],
        out: &mut [Option<RayHit>],
        stats: &mut TraversalStats,
    ) where
        Self: Sized,
    {
        super::packet::closest_hits_generic(self, rays, t_max, out, stats)
    }
}
