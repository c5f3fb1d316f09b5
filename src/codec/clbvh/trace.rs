//! CLBVH's own single-ray traversal: closest hit and any hit, eight child
//! boxes per AVX2 instruction, straight from the stored nodes.
//!
//! The generic traversal ([`crate::query::ray`]) asks the cursor for a
//! batch of child handles and boxes, sorts `(distance, handle)` pairs and
//! pushes every child it will visit. This one reads a node where it lies:
//! an inner node's six `f32` rows, or a multi-leaf node's six rows of
//! 8-bit bounds, dequantized in registers; the rows the ray enters and
//! leaves by are chosen once per ray, so a node's slab test is six loads
//! (or dequantizations), six subtractions, six multiplications and the
//! folds. Then:
//!
//! - an inner node with one child hit descends into it without touching
//!   the stack; with more, the nearest is taken next and the others are
//!   pushed farthest first (so they pop nearest first);
//! - a multi-leaf node's hit lanes are leaves, so their triangles are
//!   tested right away, nearest lane first, stopping at the first lane that
//!   starts beyond the best hit so far: what the stack would do, without
//!   it;
//! - a leaf's triangles are tested four at a time, their corners
//!   transposed into nine four-lane rows in registers.
//!
//! # Same answers as the generic traversal
//! The slab test is the generic one's ([`ChildBoxes::slab`]), operation for
//! operation, in eight lanes (`vmaxps`/`vminps` keep the running value when
//! a plane distance is NaN, as `maxps`/`minps` do in the four-lane chunks);
//! a multi-leaf node's bounds are dequantized with the same multiply and
//! add as [`MultiLeafNode::child_box`]; triangles go through the same
//! [`ray_triangle`] and the same tie rule ([`keep_closer`]). The order in
//! which nodes are visited may differ from the generic traversal's; the
//! tie rule makes the closest hit independent of it. `tests/suite/clbvh.rs`
//! checks both hit for hit (distance, triangle and barycentrics, bit for
//! bit) on random and camera rays over several meshes.
//!
//! # Scalar path
//! Without AVX2 (or on other architectures), or with a NaN `t_max`, both
//! functions run the generic traversal over [`ClBvh`]'s cursor, which is
//! portable (SSE2 or scalar glam) and is the reference the tests compare
//! against.
//!
//! # No AVX-512 path
//! A node has eight lanes, one 256-bit register of `f32`; a 512-bit
//! register would hold two nodes' rows, or a row's minima and maxima,
//! which a single ray's ordered walk does not test together. The AVX2
//! kernel compiled a second time with `avx512f`, `avx512vl`, `avx512bw`
//! and `avx512dq` enabled (so that the compiler may use mask registers and
//! the sixteen extra vector registers) and chosen per ray in the same
//! process cast 15.38 and 15.13 M camera rays/s on the 1 M statue against
//! 15.40 and 15.22 for the AVX2 build (one thread, the 2-vCPU Zen 4
//! "AMD EPYC", which runs 512-bit operations as two 256-bit halves). With
//! nothing to gain, there is one x86 kernel, and AVX-512 machines run it.
//!
//! [`ChildBoxes::slab`]: crate::cursor::ChildBoxes::slab
//! [`MultiLeafNode::child_box`]: super::MultiLeafNode::child_box
//! [`ray_triangle`]: crate::geom::ray_triangle
//! [`keep_closer`]: crate::query::ray

use super::ClBvh;
use crate::cursor::TraversalStats;
use crate::geom::Ray;
use crate::query::ray::{RayHit, any_hit_generic, closest_hit_generic};

/// The closest hit of `ray` within `[0, t_max]` (see the module docs).
#[inline]
pub(super) fn closest_hit(
    bvh: &ClBvh,
    ray: &Ray,
    t_max: f32,
    stats: &mut TraversalStats,
) -> Option<RayHit> {
    #[cfg(target_arch = "x86_64")]
    if !t_max.is_nan() && std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: AVX2 was just detected.
        return unsafe { x86::closest_hit(bvh, ray, t_max, stats) };
    }
    closest_hit_generic(bvh, ray, t_max, stats)
}

/// Whether `ray` hits a triangle within `[0, t_max]` (see the module
/// docs).
#[inline]
pub(super) fn any_hit(bvh: &ClBvh, ray: &Ray, t_max: f32, stats: &mut TraversalStats) -> bool {
    #[cfg(target_arch = "x86_64")]
    if !t_max.is_nan() && std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: AVX2 was just detected.
        return unsafe { x86::any_hit(bvh, ray, t_max, stats) };
    }
    any_hit_generic(bvh, ray, t_max, stats)
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    use glam::Vec3A;

    use super::super::node::{
        ChildRef, ENDS_WORDS, MULTI_WORDS, TAG_INNER, TAG_LEAF, TAG_MULTI, ref_index, ref_tag,
    };
    use super::super::{ClBvh, LeafKind};
    use crate::cursor::{TraversalStats, prefetch};
    use crate::geom::{Ray, SLAB_EXIT_SCALE, TriHit, ray_triangle};
    use crate::query::Stack;
    use crate::query::ray::{RayHit, keep_closer};

    /// Byte offset of `lo_x` in a multi-leaf node (after `start`, `step`).
    const Q_ROWS: usize = 24;

    /// Per-ray constants.
    struct Frame {
        org: [__m256; 3],
        inv: [__m256; 3],
        /// Per axis, the row of an inner node ([`InnerNode`] as seven rows
        /// of eight) the ray enters by, and the one it leaves by.
        ///
        /// [`InnerNode`]: super::super::InnerNode
        near: [usize; 3],
        far: [usize; 3],
        /// The same rows' byte offsets in a multi-leaf node.
        qnear: [usize; 3],
        qfar: [usize; 3],
    }

    impl Frame {
        #[inline]
        #[target_feature(enable = "avx2")]
        fn new(ray: &Ray) -> Frame {
            let o = ray.origin.to_array();
            let inv = ray.inv_dir.to_array();
            let neg = ray.enters_by_max().map(usize::from);
            let near: [usize; 3] = std::array::from_fn(|a| 2 * a + neg[a]);
            let far: [usize; 3] = std::array::from_fn(|a| 2 * a + 1 - neg[a]);
            Frame {
                org: o.map(|v| _mm256_set1_ps(v)),
                inv: inv.map(|v| _mm256_set1_ps(v)),
                near,
                far,
                qnear: near.map(|r| Q_ROWS + 8 * r),
                qfar: far.map(|r| Q_ROWS + 8 * r),
            }
        }
    }

    /// Loads eight floats.
    #[inline]
    #[target_feature(enable = "avx2")]
    fn load8(row: &[f32; 8]) -> __m256 {
        // SAFETY: `row` is 32 readable bytes; the load is unaligned.
        unsafe { _mm256_loadu_ps(row.as_ptr()) }
    }

    /// The slab test of eight boxes given by the rows the ray enters and
    /// leaves by: the lanes met within `[0, limit]` and the entry
    /// distances (the generic test's operations, see the module docs).
    #[inline]
    #[target_feature(enable = "avx2")]
    fn slab(f: &Frame, near: [__m256; 3], far: [__m256; 3], limit: f32) -> (u32, __m256) {
        let mut enter = _mm256_setzero_ps();
        let mut exit = _mm256_set1_ps(limit);
        for a in 0..3 {
            let tn = _mm256_mul_ps(_mm256_sub_ps(near[a], f.org[a]), f.inv[a]);
            let tf = _mm256_mul_ps(_mm256_sub_ps(far[a], f.org[a]), f.inv[a]);
            enter = _mm256_max_ps(tn, enter);
            exit = _mm256_min_ps(tf, exit);
        }
        let exit = _mm256_mul_ps(exit, _mm256_set1_ps(SLAB_EXIT_SCALE));
        let m = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(enter, exit)) as u32;
        (m, enter)
    }

    /// The lanes of an inner node the ray meets within `limit`, their
    /// entry distances, and the used lanes.
    #[inline]
    #[target_feature(enable = "avx2")]
    fn test_inner(bvh: &ClBvh, at: usize, f: &Frame, limit: f32) -> (u32, __m256, [f32; 8], u32) {
        let n = &bvh.inner[at];
        let rows: &[[f32; 8]; 7] = bytemuck::cast_ref(n);
        let near = f.near.map(|r| load8(&rows[r]));
        let far = f.far.map(|r| load8(&rows[r]));
        let (hit, enter) = slab(f, near, far, limit);
        let child = _mm256_castps_si256(load8(&rows[6]));
        let empty = _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(
            child,
            _mm256_setzero_si256(),
        ))) as u32;
        let used = !empty & 0xFF;
        let mut t = [0.0f32; 8];
        // SAFETY: `t` is 32 writable bytes; the store is unaligned.
        unsafe { _mm256_storeu_ps(t.as_mut_ptr(), enter) };
        (hit & used, enter, t, used)
    }

    /// The eight bounds of axis `a` stored at byte `off` (a multiple of 8)
    /// of a multi-leaf node, dequantized (`start + q * step`, multiply then add).
    #[inline]
    #[target_feature(enable = "avx2")]
    fn dequantize(words: &[u32; MULTI_WORDS + ENDS_WORDS], a: usize, off: usize) -> __m256 {
        let w = off / 4;
        let q = u64::from(words[w]) | u64::from(words[w + 1]) << 32;
        let q = _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(_mm_cvtsi64_si128(q as i64)));
        let start = _mm256_set1_ps(f32::from_bits(words[a]));
        let step = _mm256_set1_ps(f32::from_bits(words[3 + a]));
        _mm256_add_ps(start, _mm256_mul_ps(q, step))
    }

    /// The lanes of the multi-leaf node at word `at` the ray meets within
    /// `limit`, their entry distances, the used lanes and the leaf ends.
    ///
    /// # Safety
    /// Only for AVX2 code: a plain function (so that it may be
    /// `#[inline(always)]`, which `#[target_feature]` functions may not be),
    /// inlined into the AVX2 kernel, where its intrinsics inline too.
    #[inline(always)]
    unsafe fn test_multi(
        bvh: &ClBvh,
        at: usize,
        f: &Frame,
        limit: f32,
    ) -> (u32, __m256, [f32; 8], u32, [u8; 8]) {
        // SAFETY: the caller runs with AVX2 (see `# Safety`), which every
        // intrinsic below needs; the one store writes `t`, 32 writable
        // bytes (unaligned).
        unsafe {
            let words: &[u32; MULTI_WORDS + ENDS_WORDS] = bvh.arena
                [at..at + MULTI_WORDS + ENDS_WORDS]
                .try_into()
                .expect("a whole node");
            let near = [
                dequantize(words, 0, f.qnear[0]),
                dequantize(words, 1, f.qnear[1]),
                dequantize(words, 2, f.qnear[2]),
            ];
            let far = [
                dequantize(words, 0, f.qfar[0]),
                dequantize(words, 1, f.qfar[1]),
                dequantize(words, 2, f.qfar[2]),
            ];
            let (hit, enter) = slab(f, near, far, limit);
            let ends = u64::from(words[MULTI_WORDS]) | u64::from(words[MULTI_WORDS + 1]) << 32;
            // A lane is used when its end passes the previous lane's.
            let same = _mm_movemask_epi8(_mm_cmpeq_epi8(
                _mm_cvtsi64_si128(ends as i64),
                _mm_cvtsi64_si128((ends << 8) as i64),
            )) as u32;
            let used = !same & 0xFF;
            let mut t = [0.0f32; 8];
            _mm256_storeu_ps(t.as_mut_ptr(), enter);
            (hit & used, enter, t, used, ends.to_le_bytes())
        }
    }

    /// The hit lanes of `hit` nearest first (`by_rank[r]` is the lane of
    /// rank `r`; equal distances in lane order), from their entry
    /// distances `enter` (also stored as `t`). One or two lanes are
    /// ordered by one comparison; with more, each hit lane's
    /// rank is counted with two eight-lane comparisons: the lanes hit
    /// nearer than it, or as near and before it. (A fixed eight rounds of
    /// that, one per lane hit or not, measured 5 % slower than this loop's
    /// mispredicted exit; a three-lane special case gained nothing.)
    #[inline]
    #[target_feature(enable = "avx2")]
    fn ranked(hit: u32, enter: __m256, t: &[f32; 8]) -> [u32; 8] {
        let mut by_rank = [0u32; 8];
        // One or two lanes, by one comparison.
        let rest = hit & hit.wrapping_sub(1);
        if hit != 0 && rest & rest.wrapping_sub(1) == 0 {
            let a = hit.trailing_zeros();
            if rest == 0 {
                by_rank[0] = a;
            } else {
                let b = rest.trailing_zeros();
                // `a < b`: `a` first unless `b` is strictly nearer.
                let swap = t[b as usize] < t[a as usize];
                by_rank[0] = if swap { b } else { a };
                by_rank[1] = if swap { a } else { b };
            }
            return by_rank;
        }
        let mut m = hit;
        while m != 0 {
            let i = m.trailing_zeros();
            m &= m - 1;
            let ti = _mm256_set1_ps(t[i as usize]);
            let nearer = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LT_OQ>(enter, ti)) as u32;
            let tied = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_EQ_OQ>(enter, ti)) as u32;
            let r = ((nearer | tied & ((1 << i) - 1)) & hit).count_ones();
            by_rank[r as usize] = i;
        }
        by_rank
    }

    /// The watertight test's per-ray constants ([`ray_triangle`]'s), in
    /// four lanes.
    struct Water {
        k: [usize; 3],
        org: [__m128; 3],
        shear: [__m128; 3],
    }

    impl Water {
        #[inline]
        #[target_feature(enable = "avx2")]
        fn new(ray: &Ray) -> Water {
            let (k, shear) = ray.shear_frame();
            let o = ray.origin.to_array();
            Water {
                k,
                org: k.map(|a| _mm_set1_ps(o[a])),
                shear: shear.map(|v| _mm_set1_ps(v)),
            }
        }
    }

    /// Up to four triangles, corner `c`'s axis `a` in row `3 * c + a`, one
    /// triangle a lane.
    type Rows4 = [__m128; 9];

    /// Rows 0–3 of four triangles from their first four floats each (and
    /// rows 4–7 from the next four): a 4 × 4 transpose in registers. Built
    /// lane by lane in memory instead, each row's load waited for four
    /// scalar stores it could not be forwarded from.
    ///
    /// # Safety
    /// Only for AVX2 code (see [`triangles4`]).
    #[inline(always)]
    unsafe fn transpose4(a: __m128, b: __m128, c: __m128, d: __m128) -> [__m128; 4] {
        // SAFETY: the caller runs with AVX2 (see `# Safety`), a superset of
        // the SSE these shuffles need; no memory is touched.
        unsafe {
            let (t0, t1) = (_mm_unpacklo_ps(a, b), _mm_unpacklo_ps(c, d));
            let (t2, t3) = (_mm_unpackhi_ps(a, b), _mm_unpackhi_ps(c, d));
            [
                _mm_movelh_ps(t0, t1),
                _mm_movehl_ps(t1, t0),
                _mm_movelh_ps(t2, t3),
                _mm_movehl_ps(t3, t2),
            ]
        }
    }

    /// Hits of up to four triangles found at once.
    struct Hits4 {
        /// Lanes hit within the limit.
        mask: u32,
        t: [f32; 4],
        u: [f32; 4],
        v: [f32; 4],
    }

    /// [`ray_triangle`] on lanes `0..live` of `rows` at once, with its
    /// operations in its order, so that each lane gives its bits. `None`
    /// when a live lane has an edge function exactly zero: the scalar test
    /// then decides that edge in double precision, so the caller runs it.
    ///
    /// # Safety
    /// Only for AVX2 code: a plain function (so that it may be
    /// `#[inline(always)]`, which `#[target_feature]` functions may not be),
    /// inlined into the AVX2 kernel, where its intrinsics inline too.
    #[inline(always)]
    unsafe fn triangles4(w: &Water, rows: &Rows4, live: usize, limit: f32) -> Option<Hits4> {
        // SAFETY: the caller runs with AVX2 (see `# Safety`), which every
        // intrinsic below needs; each store writes an array of four, 16
        // writable bytes (unaligned).
        unsafe {
            let [kx, ky, kz] = w.k;
            let [ox, oy, oz] = w.org;
            let [sx, sy, sz] = w.shear;
            // Corner `c` relative to the origin, on the permuted axes.
            let rel = |c: usize| {
                (
                    _mm_sub_ps(rows[3 * c + kx], ox),
                    _mm_sub_ps(rows[3 * c + ky], oy),
                    _mm_sub_ps(rows[3 * c + kz], oz),
                )
            };
            let (a, b, c) = (rel(0), rel(1), rel(2));
            let shear = |p: (__m128, __m128, __m128)| {
                (
                    _mm_sub_ps(p.0, _mm_mul_ps(sx, p.2)),
                    _mm_sub_ps(p.1, _mm_mul_ps(sy, p.2)),
                )
            };
            let ((ax, ay), (bx, by), (cx, cy)) = (shear(a), shear(b), shear(c));
            let u = _mm_sub_ps(_mm_mul_ps(cx, by), _mm_mul_ps(cy, bx));
            let v = _mm_sub_ps(_mm_mul_ps(ax, cy), _mm_mul_ps(ay, cx));
            let e = _mm_sub_ps(_mm_mul_ps(bx, ay), _mm_mul_ps(by, ax));
            let lanes = (1u32 << live) - 1;
            let zero = _mm_setzero_ps();
            let on_edge = _mm_or_ps(
                _mm_or_ps(_mm_cmpeq_ps(u, zero), _mm_cmpeq_ps(v, zero)),
                _mm_cmpeq_ps(e, zero),
            );
            if _mm_movemask_ps(on_edge) as u32 & lanes != 0 {
                return None;
            }
            let below = _mm_or_ps(
                _mm_or_ps(_mm_cmplt_ps(u, zero), _mm_cmplt_ps(v, zero)),
                _mm_cmplt_ps(e, zero),
            );
            let above = _mm_or_ps(
                _mm_or_ps(_mm_cmpgt_ps(u, zero), _mm_cmpgt_ps(v, zero)),
                _mm_cmpgt_ps(e, zero),
            );
            let det = _mm_add_ps(_mm_add_ps(u, v), e);
            // `det != 0 && det.is_finite()`: NaN fails both comparisons.
            let abs = _mm_andnot_ps(_mm_set1_ps(-0.0), det);
            let det_ok = _mm_and_ps(
                _mm_cmpgt_ps(abs, zero),
                _mm_cmplt_ps(abs, _mm_set1_ps(f32::INFINITY)),
            );
            let t = _mm_div_ps(
                _mm_add_ps(
                    _mm_add_ps(
                        _mm_mul_ps(u, _mm_mul_ps(sz, a.2)),
                        _mm_mul_ps(v, _mm_mul_ps(sz, b.2)),
                    ),
                    _mm_mul_ps(e, _mm_mul_ps(sz, c.2)),
                ),
                det,
            );
            let t_ok = _mm_and_ps(_mm_cmpge_ps(t, zero), _mm_cmple_ps(t, _mm_set1_ps(limit)));
            let ok = _mm_andnot_ps(_mm_and_ps(below, above), _mm_and_ps(det_ok, t_ok));
            let mask = _mm_movemask_ps(ok) as u32 & lanes;
            let mut h = Hits4 {
                mask,
                t: [0.0; 4],
                u: [0.0; 4],
                v: [0.0; 4],
            };
            if mask != 0 {
                _mm_storeu_ps(h.t.as_mut_ptr(), t);
                _mm_storeu_ps(h.u.as_mut_ptr(), _mm_div_ps(v, det));
                _mm_storeu_ps(h.v.as_mut_ptr(), _mm_div_ps(e, det));
            }
            Some(h)
        }
    }

    /// Tests triangles `first..last` of the leaf block at word `b`, four
    /// at a time ([`triangles4`]), calling `hit(id, hit, limit)` for each
    /// one met within `limit` (which `hit` may lower), in triangle order.
    /// Returns `true`, early, when `hit` does.
    ///
    /// A group is tested against the limit at its start; a hit that a
    /// lower limit found within the group would have rejected is rejected
    /// by `hit` (the tie rule keeps only hits no farther than the best),
    /// so the result is the one-by-one test's.
    #[inline]
    #[target_feature(enable = "avx2")]
    #[allow(clippy::too_many_arguments)]
    fn block(
        bvh: &ClBvh,
        w: &Water,
        b: usize,
        first: usize,
        last: usize,
        ray: &Ray,
        stats: &mut TraversalStats,
        limit: &mut f32,
        mut hit: impl FnMut(u32, &TriHit, &mut f32) -> bool,
    ) -> bool {
        let hdr = bvh.arena[b];
        let n = (hdr & 0xFFFF) as usize;
        let mut ids = [0u32; 4];
        let mut j = first;
        while j < last {
            let live = (last - j).min(4);
            // Dead lanes repeat the last live triangle.
            let tri = |l: usize| j + l.min(live - 1);
            let rows: Rows4 = match bvh.options.leaves {
                LeafKind::Fast => {
                    let id = &bvh.arena[b + 1..b + 1 + n];
                    let corners = &bvh.arena[b + 1 + n..b + 1 + 10 * n];
                    let c: [&[u32; 9]; 4] = std::array::from_fn(|l| {
                        ids[l] = id[tri(l)];
                        corners[9 * tri(l)..9 * tri(l) + 9]
                            .try_into()
                            .expect("nine words")
                    });
                    // SAFETY: each load reads four of a triangle's nine
                    // words, 16 readable bytes (unaligned); this function
                    // runs with AVX2, which `transpose4` needs.
                    unsafe {
                        let ld = |l: usize, o: usize| _mm_loadu_ps(c[l][o..].as_ptr().cast());
                        let lo = transpose4(ld(0, 0), ld(1, 0), ld(2, 0), ld(3, 0));
                        let mid = transpose4(ld(0, 4), ld(1, 4), ld(2, 4), ld(3, 4));
                        let z2 = |l: usize| f32::from_bits(c[l][8]);
                        [
                            lo[0],
                            lo[1],
                            lo[2],
                            lo[3],
                            mid[0],
                            mid[1],
                            mid[2],
                            mid[3],
                            _mm_setr_ps(z2(0), z2(1), z2(2), z2(3)),
                        ]
                    }
                }
                LeafKind::Compact => {
                    let u = (hdr >> 16) as usize;
                    let uniq = &bvh.arena[b + 1..b + 1 + u];
                    let id = &bvh.arena[b + 1 + u..b + 1 + u + n];
                    let local: &[u8] = bytemuck::cast_slice(&bvh.arena[b + 1 + u + n..]);
                    for (l, i) in ids.iter_mut().enumerate() {
                        *i = id[tri(l)];
                    }
                    let vertex = |l: usize, c: usize| {
                        let v = &bvh.vertices[uniq[local[3 * tri(l) + c] as usize] as usize];
                        _mm_setr_ps(v[0], v[1], v[2], 0.0)
                    };
                    let corner = |c: usize| {
                        // SAFETY: this function runs with AVX2, which
                        // `transpose4` needs.
                        unsafe {
                            transpose4(vertex(0, c), vertex(1, c), vertex(2, c), vertex(3, c))
                        }
                    };
                    let (a, b, c) = (corner(0), corner(1), corner(2));
                    [a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2]]
                }
            };
            stats.primitive_tests += live as u64;
            // SAFETY: this function runs with AVX2.
            match unsafe { triangles4(w, &rows, live, *limit) } {
                Some(h) => {
                    let mut m = h.mask;
                    while m != 0 {
                        let l = m.trailing_zeros() as usize;
                        m &= m - 1;
                        let th = TriHit {
                            t: h.t[l],
                            u: h.u[l],
                            v: h.v[l],
                        };
                        if hit(ids[l], &th, limit) {
                            return true;
                        }
                    }
                }
                None => {
                    let mut lanes = [[0.0f32; 4]; 9];
                    for (lane, row) in lanes.iter_mut().zip(&rows) {
                        // SAFETY: `lane` is 16 writable bytes (unaligned).
                        unsafe { _mm_storeu_ps(lane.as_mut_ptr(), *row) };
                    }
                    for l in 0..live {
                        let p = |c: usize| {
                            Vec3A::new(lanes[3 * c][l], lanes[3 * c + 1][l], lanes[3 * c + 2][l])
                        };
                        if let Some(h) = ray_triangle(ray, &[p(0), p(1), p(2)], *limit)
                            && hit(ids[l], &h, limit)
                        {
                            return true;
                        }
                    }
                }
            }
            j += live;
        }
        false
    }

    /// Cache lines asked for from the start of a multi-leaf node when a ray
    /// enters it: the node's own (loaded anyway) and the next 15, a
    /// kilobyte of its leaf block.
    ///
    /// The leaf block lies right behind the node, but which lanes' triangles
    /// a ray needs is known only once the node's boxes have been tested, and
    /// they may lie a kilobyte further on (a block of the default `M = 4`
    /// holds up to 32 triangles, 40 bytes each). Read when needed, they
    /// were a second cache miss after the node's, waited for in turn; asked
    /// for with the node, they arrive while its boxes are tested. The count
    /// cannot follow the block's size, which is read from the block itself.
    /// Camera rays on the 1 M statue, one thread, in one process against no
    /// prefetch: 6 lines +8 %, 12 lines +12 %, 16 to 24 lines +14–15 %
    /// (32: +14 %); on the 10 M statue 12 to 20 lines +20 %. Prefetching a
    /// pushed child's node, an isolated leaf's block, or the hit lanes'
    /// lines once the node is tested, gained nothing.
    const BLOCK_LINES: usize = 16;

    /// Cache lines asked for from the start of an isolated leaf's block
    /// when a ray reaches it: 256 bytes, the whole block of up to 4
    /// triangles (the default `M`). Its corners' place follows from the
    /// triangle count in its first word, so they too were a miss after a
    /// miss. The 8-wide tree without multi-leaf nodes
    /// ([`ClOptions::multi_leaf`](super::super::ClOptions::multi_leaf)
    /// `= false`), all of whose leaves are isolated, casts camera rays on
    /// the 1 M statue 5 % faster with it (13.2 to 13.9 M rays/s); CLBVH,
    /// with few isolated leaves, the same.
    const LEAF_LINES: usize = 4;

    /// Asks for cache lines `1..lines` from arena word `at` on (line 0 is
    /// read at once anyway).
    #[inline(always)]
    fn prefetch_lines(bvh: &ClBvh, at: usize, lines: usize) {
        let p = bvh.arena.as_ptr().wrapping_add(at).cast::<u8>();
        for line in 1..lines {
            prefetch(p.wrapping_add(64 * line));
        }
    }

    /// The closest hit (see the module docs).
    ///
    /// # Safety
    /// The processor must support AVX2.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn closest_hit(
        bvh: &ClBvh,
        ray: &Ray,
        t_max: f32,
        stats: &mut TraversalStats,
    ) -> Option<RayHit> {
        stats.nodes_visited += 1;
        ray.intersect_aabb(&bvh.root_box, t_max)?;
        let f = Frame::new(ray);
        let w = Water::new(ray);
        let mut best: Option<RayHit> = None;
        let mut best_t = t_max;
        let mut stack: Stack<(ChildRef, f32)> = Stack::new();
        let mut cur = bvh.root;
        'walk: loop {
            let at = ref_index(cur);
            match ref_tag(cur) {
                TAG_INNER => {
                    let (hit, enter, t, used) = test_inner(bvh, at, &f, best_t);
                    stats.nodes_visited += u64::from(used.count_ones());
                    if hit != 0 {
                        let child = &bvh.inner[at].child;
                        if hit & (hit - 1) == 0 {
                            cur = child[hit.trailing_zeros() as usize];
                            continue;
                        }
                        let by_rank = ranked(hit, enter, &t);
                        for &l in by_rank[1..hit.count_ones() as usize].iter().rev() {
                            stack.push((child[l as usize], t[l as usize]));
                        }
                        cur = child[by_rank[0] as usize];
                        continue;
                    }
                }
                TAG_MULTI => {
                    prefetch_lines(bvh, at, BLOCK_LINES);
                    // SAFETY: this function runs with AVX2.
                    let (hit, enter, t, used, ends) = unsafe { test_multi(bvh, at, &f, best_t) };
                    stats.nodes_visited += u64::from(used.count_ones());
                    let by_rank = ranked(hit, enter, &t);
                    for &l in &by_rank[..hit.count_ones() as usize] {
                        let l = l as usize;
                        if t[l] > best_t * SLAB_EXIT_SCALE {
                            break;
                        }
                        let first = if l == 0 { 0 } else { ends[l - 1] as usize };
                        let b = at + MULTI_WORDS + ENDS_WORDS;
                        block(
                            bvh,
                            &w,
                            b,
                            first,
                            ends[l] as usize,
                            ray,
                            stats,
                            &mut best_t,
                            |id, h, lim| {
                                keep_closer(&mut best, lim, id, h);
                                false
                            },
                        );
                    }
                }
                TAG_LEAF => {
                    prefetch_lines(bvh, at, LEAF_LINES);
                    let n = (bvh.arena[at] & 0xFFFF) as usize;
                    block(bvh, &w, at, 0, n, ray, stats, &mut best_t, |id, h, lim| {
                        keep_closer(&mut best, lim, id, h);
                        false
                    });
                }
                _ => {}
            }
            loop {
                let Some((r, t)) = stack.pop() else {
                    break 'walk;
                };
                if t <= best_t * SLAB_EXIT_SCALE {
                    cur = r;
                    continue 'walk;
                }
            }
        }
        best
    }

    /// Any hit (see the module docs).
    ///
    /// # Safety
    /// The processor must support AVX2.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn any_hit(
        bvh: &ClBvh,
        ray: &Ray,
        t_max: f32,
        stats: &mut TraversalStats,
    ) -> bool {
        stats.nodes_visited += 1;
        if ray.intersect_aabb(&bvh.root_box, t_max).is_none() {
            return false;
        }
        let f = Frame::new(ray);
        let w = Water::new(ray);
        // Shadow rays keep their limit: any hit will do.
        let mut limit = t_max;
        let mut stack: Stack<ChildRef> = Stack::new();
        let mut cur = bvh.root;
        loop {
            let at = ref_index(cur);
            match ref_tag(cur) {
                TAG_INNER => {
                    let (hit, _, _, used) = test_inner(bvh, at, &f, t_max);
                    stats.nodes_visited += u64::from(used.count_ones());
                    let child = &bvh.inner[at].child;
                    let mut m = hit;
                    while m != 0 {
                        stack.push(child[m.trailing_zeros() as usize]);
                        m &= m - 1;
                    }
                }
                TAG_MULTI => {
                    prefetch_lines(bvh, at, BLOCK_LINES);
                    // SAFETY: this function runs with AVX2.
                    let (hit, _, _, used, ends) = unsafe { test_multi(bvh, at, &f, t_max) };
                    stats.nodes_visited += u64::from(used.count_ones());
                    let mut m = hit;
                    while m != 0 {
                        let l = m.trailing_zeros() as usize;
                        m &= m - 1;
                        let first = if l == 0 { 0 } else { ends[l - 1] as usize };
                        let b = at + MULTI_WORDS + ENDS_WORDS;
                        if block(
                            bvh,
                            &w,
                            b,
                            first,
                            ends[l] as usize,
                            ray,
                            stats,
                            &mut limit,
                            |_, _, _| true,
                        ) {
                            return true;
                        }
                    }
                }
                TAG_LEAF => {
                    prefetch_lines(bvh, at, LEAF_LINES);
                    let n = (bvh.arena[at] & 0xFFFF) as usize;
                    if block(bvh, &w, at, 0, n, ray, stats, &mut limit, |_, _, _| true) {
                        return true;
                    }
                }
                _ => {}
            }
            match stack.pop() {
                Some(r) => cur = r,
                None => return false,
            }
        }
    }
}
