//! Closest hits of a packet of coherent rays (a camera tile), traversed
//! together: each node is fetched once for the whole packet instead of once
//! per ray, which is what bounds single-ray traversal on large meshes.
//!
//! The traversal is *masked* (after Wald, Boulos, Shirley: "Ray tracing
//! deformable scenes using dynamic bounding volume hierarchies", TOG 2007):
//! a node carries the set of rays (a 64-bit mask) that met its parent; an
//! interval-arithmetic test over the whole packet may discard it at once,
//! else popping it keeps the rays whose own slab test passes, and its
//! children inherit that set. Leaves test each triangle against those rays.
//! Children are pushed in the order of the set's first ray.
//!
//! Every ray uses the same slab test, triangle test and tie rule (nearer,
//! or as near with the smaller triangle id) as
//! [`closest_hit`](super::closest_hit), and a node is skipped for a ray only
//! when that ray's slab test against it fails with its current best
//! distance, so the hits are the single-ray hits.

use super::ray::{RayHit, keep_closer};
use super::{RayCursor, Stack, far_first};
use crate::cursor::{Children, MAX_CHILDREN, NodeCursor, TraversalStats};
use crate::geom::{Aabb, Ray, SLAB_EXIT_SCALE, ray_triangle};

/// A child to push: its entry distance for the packet's first ray, the
/// child and its box.
type Kid<N> = (f32, (N, Aabb));

/// The largest packet [`closest_hits`] takes.
pub const MAX_PACKET: usize = 64;

/// The packet's rays as structure-of-arrays, for slab tests over many rays
/// in loops the compiler vectorizes, and the interval bounds of the packet
/// (origins and reciprocal directions per axis) for a whole-packet cull.
struct Lanes {
    o: [[f32; MAX_PACKET]; 3],
    inv: [[f32; MAX_PACKET]; 3],
    /// Per axis: the origins' range and the reciprocal directions' range,
    /// if every ray's direction has the same strict sign on that axis.
    bounds: Option<[(f32, f32, f32, f32); 3]>,
}

impl Lanes {
    fn new(rays: &[Ray]) -> Self {
        let mut o = [[0.0; MAX_PACKET]; 3];
        let mut inv = [[0.0; MAX_PACKET]; 3];
        for (i, r) in rays.iter().enumerate() {
            for a in 0..3 {
                o[a][i] = r.origin[a];
                inv[a][i] = r.inv_dir[a];
            }
        }
        let n = rays.len();
        let mut bounds = [(0.0, 0.0, 0.0, 0.0); 3];
        let mut ok = n > 0;
        for a in 0..3 {
            let (olo, ohi) = o[a][..n]
                .iter()
                .fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), &v| {
                    (l.min(v), h.max(v))
                });
            let (ilo, ihi) = inv[a][..n]
                .iter()
                .fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), &v| {
                    (l.min(v), h.max(v))
                });
            let finite = olo.is_finite() && ohi.is_finite() && ilo.is_finite() && ihi.is_finite();
            ok &= finite && (ilo > 0.0 || ihi < 0.0);
            bounds[a] = (olo, ohi, ilo, ihi);
        }
        Self {
            o,
            inv,
            bounds: ok.then_some(bounds),
        }
    }

    /// Whether every ray certainly misses `b` within `[0, t_max_hi]`
    /// (interval arithmetic over the packet; `false` when unsure).
    #[inline]
    fn all_miss(&self, b: &Aabb, t_max_hi: f32) -> bool {
        let Some(bounds) = &self.bounds else {
            return false;
        };
        let mut enter_lo = 0.0f32;
        let mut exit_hi = t_max_hi;
        for (a, &(olo, ohi, ilo, ihi)) in bounds.iter().enumerate() {
            // (face - origin) over the packet, times the reciprocal range.
            let (lo_d, hi_d) = (b.min[a] - ohi, b.max[a] - olo);
            let (near, far) = if ilo > 0.0 {
                ((lo_d * ihi).min(lo_d * ilo), (hi_d * ilo).max(hi_d * ihi))
            } else {
                ((hi_d * ilo).min(hi_d * ihi), (lo_d * ihi).max(lo_d * ilo))
            };
            enter_lo = enter_lo.max(near);
            exit_hi = exit_hi.min(far);
        }
        // The per-ray tests' margin, and a little for this test's rounding.
        enter_lo > exit_hi * SLAB_EXIT_SCALE + f32::MIN_POSITIVE
    }

    /// Of the rays in `mask`, those that meet `b` within `[0, best_t]`:
    /// the same operations as [`Ray::intersect_aabb`], ray by ray. With
    /// many rays in the mask, all rays are tested in one loop the compiler
    /// vectorizes; with few, only those.
    #[inline]
    fn hits(&self, b: &Aabb, best_t: &[f32; MAX_PACKET], mask: u64) -> u64 {
        let bmin = b.min.to_array();
        let bmax = b.max.to_array();
        let lane = |i: usize| {
            let mut tmin = [0.0f32; 3];
            let mut tmax = [0.0f32; 3];
            for a in 0..3 {
                let inv = self.inv[a][i];
                // The planes the ray enters and leaves by, as the
                // single-box test chooses them.
                let (near, far) = if inv < 0.0 {
                    (bmax[a], bmin[a])
                } else {
                    (bmin[a], bmax[a])
                };
                tmin[a] = (near - self.o[a][i]) * inv;
                tmax[a] = (far - self.o[a][i]) * inv;
            }
            let enter = tmin[0].max(tmin[1]).max(tmin[2]).max(0.0);
            let exit = tmax[0].min(tmax[1]).min(tmax[2]).min(best_t[i]) * SLAB_EXIT_SCALE;
            enter <= exit
        };
        if mask.count_ones() <= 8 {
            let mut out = 0u64;
            let mut m = mask;
            while m != 0 {
                let i = m.trailing_zeros() as usize;
                m &= m - 1;
                out |= u64::from(lane(i)) << i;
            }
            return out;
        }
        // All rays, axis by axis, in loops of plain arrays that compile to
        // vector instructions. `max`/`min` ignore NaN and are exact, so the
        // order in which the axes are folded in does not change the result.
        let mut enter = [0.0f32; MAX_PACKET];
        let mut exit = *best_t;
        for a in 0..3 {
            let (o, inv) = (&self.o[a], &self.inv[a]);
            for i in 0..MAX_PACKET {
                let by_max = inv[i] < 0.0;
                let near = if by_max { bmax[a] } else { bmin[a] };
                let far = if by_max { bmin[a] } else { bmax[a] };
                enter[i] = ((near - o[i]) * inv[i]).max(enter[i]);
                exit[i] = ((far - o[i]) * inv[i]).min(exit[i]);
            }
        }
        let mut ok = [0u8; MAX_PACKET];
        for i in 0..MAX_PACKET {
            ok[i] = u8::from(enter[i] <= exit[i] * SLAB_EXIT_SCALE);
        }
        // Eight 0/1 bytes to eight bits at a time.
        let mut out = 0u64;
        for (k, bytes) in ok.chunks_exact(8).enumerate() {
            let x = u64::from_le_bytes(bytes.try_into().expect("8 bytes"));
            out |= (x.wrapping_mul(0x0102_0408_1020_4080) >> 56) << (8 * k);
        }
        out & mask
    }
}

/// The closest hit of every ray of `rays` (at most [`MAX_PACKET`]) within
/// `[0, t_max]`, written to `out` (same length). Equal, hit for hit, to
/// [`closest_hit`](super::closest_hit) ray by ray; faster when the rays are
/// coherent (a tile of camera rays), slower when they are not.
///
/// # Panics
/// If `rays` has more than [`MAX_PACKET`] rays or `out` another length.
pub fn closest_hits<C: RayCursor>(
    c: &C,
    rays: &[Ray],
    t_max: f32,
    out: &mut [Option<RayHit>],
    stats: &mut TraversalStats,
) {
    closest_hits_within(
        c,
        rays,
        &[t_max; MAX_PACKET][..rays.len().min(MAX_PACKET)],
        out,
        stats,
    )
}

/// [`closest_hits`] with a distance limit per ray (`t_max[i]` for
/// `rays[i]`), as a scene of several meshes needs.
///
/// Runs the cursor's
/// [`closest_hits_within`](RayCursor::closest_hits_within): the generic
/// packet traversal ([`closest_hits_generic`]) unless the codec has a
/// faster way (CLBVH casts the rays one by one through its own traversal).
///
/// # Panics
/// If `rays` has more than [`MAX_PACKET`] rays or `t_max` or `out` another
/// length.
pub fn closest_hits_within<C: RayCursor>(
    c: &C,
    rays: &[Ray],
    t_max: &[f32],
    out: &mut [Option<RayHit>],
    stats: &mut TraversalStats,
) {
    check_packet(rays, t_max, out);
    c.closest_hits_within(rays, t_max, out, stats);
}

/// The lengths [`closest_hits_within`] accepts.
fn check_packet(rays: &[Ray], t_max: &[f32], out: &[Option<RayHit>]) {
    let n = rays.len();
    assert!(n <= MAX_PACKET, "a packet holds at most {MAX_PACKET} rays");
    assert_eq!(out.len(), n, "one output slot per ray");
    assert_eq!(t_max.len(), n, "one distance limit per ray");
}

/// [`closest_hits_within`] through the generic packet traversal, one walk
/// of the tree for the whole packet, whatever the codec: the default of
/// [`RayCursor::closest_hits_within`], and the reference a codec's own
/// packet path is tested against.
///
/// # Panics
/// As [`closest_hits_within`].
pub fn closest_hits_generic<C: NodeCursor>(
    c: &C,
    rays: &[Ray],
    t_max: &[f32],
    out: &mut [Option<RayHit>],
    stats: &mut TraversalStats,
) {
    check_packet(rays, t_max, out);
    let n = rays.len();
    out.fill(None);
    if n == 0 {
        return;
    }
    let lanes = Lanes::new(rays);
    let mut best_t = [0.0f32; MAX_PACKET];
    best_t[..n].copy_from_slice(t_max);
    // The largest best distance of the packet, for the whole-packet cull
    // (only ever lowered to a value still above every ray's).
    let mut worst_t = best_t[..n].iter().fold(0.0f32, |w, &t| w.max(t));
    let (root, root_box) = c.root();
    let all = if n == MAX_PACKET {
        u64::MAX
    } else {
        (1u64 << n) - 1
    };
    let mut stack = Stack::new();
    stack.push((root, root_box, all));
    let mut batch = Children::new(root);
    let mut kids: [Kid<C::Node>; MAX_CHILDREN] = [(0.0, (root, root_box)); MAX_CHILDREN];
    while let Some((node, b, mask)) = stack.pop() {
        stats.nodes_visited += 1;
        if mask.count_ones() > 4 && lanes.all_miss(&b, worst_t) {
            continue;
        }
        let mask = lanes.hits(&b, &best_t, mask);
        if mask == 0 {
            continue;
        }
        let first = mask.trailing_zeros() as usize;
        if c.is_leaf(&node) {
            let mut hit_any = false;
            c.for_each_triangle(&node, |id, tri| {
                let mut m = mask;
                while m != 0 {
                    let i = m.trailing_zeros() as usize;
                    m &= m - 1;
                    stats.primitive_tests += 1;
                    if let Some(h) = ray_triangle(&rays[i], tri, best_t[i]) {
                        hit_any |= keep_closer(&mut out[i], &mut best_t[i], id, &h);
                    }
                }
            });
            if hit_any {
                worst_t = best_t[..n].iter().fold(0.0f32, |w, &t| w.max(t));
            }
            continue;
        }
        // far first (as seen by the set's first ray) so the
        // near one is popped next.
        // Every child is pushed (the other rays may meet it); one slab test
        // over the batch orders them.
        c.children(&node, &mut batch);
        let boxes = batch.boxes();
        let (hit, t) = boxes.slab(&rays[first], best_t[first]);
        let k = boxes.len();
        for (i, kid) in kids[..k].iter_mut().enumerate() {
            let ti = if hit >> i & 1 != 0 {
                t[i]
            } else {
                f32::INFINITY
            };
            *kid = (ti, (batch.node(i), boxes.get(i)));
        }
        let kids = &mut kids[..k];
        far_first(kids);
        for &(_, (child, cb)) in kids.iter() {
            stack.push((child, cb, mask));
        }
    }
}
