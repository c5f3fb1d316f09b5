//! The box coding of one sibling pair (§4.2): which extents each child
//! inherits from the box its parent decodes to (the reuse mask) and which
//! vertices give the others. One function, used by the i-HCCMesh encoder
//! and by the o-HCCMesh decoder when it rebuilds the node words, so that
//! both make the same choice, tie for tie.
//!
//! Boxes go through it as [`Lanes`]: the minima, the negated maxima and
//! two padding lanes, so that on every lane "farther out" is "smaller" and
//! a pair is coded with the same operation on all eight lanes (which the
//! compiler turns into vector compares and blends) rather than a branch
//! per extent. Negating is exact, so the choices are those of the six
//! extents themselves.
//!
//! With quantized vertices, both code boxes in the grid's integer
//! coordinates (exact in `f32`), not in the values they decode to: a pair
//! then codes the same whatever the grid's values round to, and the
//! o-HCCMesh decoder, which has the grid coordinates, compares integers
//! (16-bit lanes in [`grid16`](super::grid16) on grids of at most 16 bits).
//! The grid is monotone, so a box on it decodes to the box of the values.

/// An extent `e` of a box as six numbers: 0–2 the minimum, 3–5 the maximum.
pub(super) type Extents = [f32; 6];

/// A box as eight lanes: the minimum (0–2), the negated maximum (3–5) and
/// two lanes of +∞ (padding, never chosen).
pub(super) type Lanes = [f32; 8];

/// Per lane of a [`Lanes`] box, the vertex attaining it.
pub(super) type LaneVertices = [u32; 8];

/// The empty box, ready to grow.
pub(super) const EMPTY: Extents = [
    f32::INFINITY,
    f32::INFINITY,
    f32::INFINITY,
    f32::NEG_INFINITY,
    f32::NEG_INFINITY,
    f32::NEG_INFINITY,
];

/// Whether extent `e`'s value `a` is farther out than `b`.
#[inline(always)]
pub(super) fn outer(e: usize, a: f32, b: f32) -> bool {
    if e < 3 { a < b } else { a > b }
}

/// `e` as [`Lanes`].
#[inline(always)]
pub(super) fn to_lanes(e: &Extents) -> Lanes {
    [
        e[0],
        e[1],
        e[2],
        -e[3],
        -e[4],
        -e[5],
        f32::INFINITY,
        f32::INFINITY,
    ]
}

/// The extents of lanes `l`.
#[inline(always)]
pub(super) fn to_extents(l: &Lanes) -> Extents {
    [l[0], l[1], l[2], -l[3], -l[4], -l[5]]
}

/// Per lane, `b`'s value and vertex where `b` is farther out than `a`,
/// else `a`'s (ties to `a`): the union of two boxes with the vertices
/// attaining it.
#[inline(always)]
pub(super) fn union(
    (a, va): (&Lanes, &LaneVertices),
    (b, vb): (&Lanes, &LaneVertices),
) -> (Lanes, LaneVertices) {
    let take = lane::less(b, a);
    (lane::pick(&take, b, a), lane::pick_u32(&take, vb, va))
}

/// The operations on all eight lanes that the pair coding is made of:
/// SSE2 on x86-64 (where the compiler does not keep the lanes in vector
/// registers by itself: it compares and selects lane by lane), plain
/// loops elsewhere. Masks are all ones or zero per lane.
mod lane {
    use super::{LaneVertices, Lanes};

    #[cfg(not(target_arch = "x86_64"))]
    pub use plain::*;
    #[cfg(target_arch = "x86_64")]
    pub use sse2::*;

    /// The reference (the lanes elsewhere, and what the SSE2 lanes are
    /// tested against).
    #[cfg_attr(target_arch = "x86_64", allow(dead_code))]
    pub mod plain {
        use super::{LaneVertices, Lanes};

        fn mask(b: bool) -> u32 {
            u32::from(b).wrapping_neg()
        }

        /// `a < b`.
        #[inline(always)]
        pub fn less(a: &Lanes, b: &Lanes) -> [u32; 8] {
            std::array::from_fn(|i| mask(a[i] < b[i]))
        }

        /// Bit `i` set where mask lane `i` is set.
        #[inline(always)]
        pub fn bits(m: &[u32; 8]) -> u32 {
            (0..8).fold(0, |b, i| b | (m[i] & 1) << i)
        }

        /// Bit `i` set where lane `i` of `a` differs from `b`'s.
        #[inline(always)]
        pub fn differs(a: &Lanes, b: &Lanes) -> u32 {
            (0..8).fold(0, |m, i| m | u32::from(a[i] != b[i]) << i)
        }

        /// Where the left child inherits the parent's `d` (see
        /// [`code_pair`](super::super::code_pair)).
        #[inline(always)]
        pub fn left_inherits(d: &Lanes, tl: &Lanes, tr: &Lanes) -> [u32; 8] {
            std::array::from_fn(|i| {
                mask(
                    (tl[i] == d[i])
                        | ((tr[i] != d[i]) & ((d[i] - tl[i]).abs() <= (d[i] - tr[i]).abs())),
                )
            })
        }

        /// `a` where `m`, else `b`.
        #[inline(always)]
        pub fn pick(m: &[u32; 8], a: &Lanes, b: &Lanes) -> Lanes {
            std::array::from_fn(|i| f32::from_bits(a[i].to_bits() & m[i] | b[i].to_bits() & !m[i]))
        }

        /// [`pick`] of vertices.
        #[inline(always)]
        pub fn pick_u32(m: &[u32; 8], a: &LaneVertices, b: &LaneVertices) -> LaneVertices {
            std::array::from_fn(|i| a[i] & m[i] | b[i] & !m[i])
        }
    }

    #[cfg(target_arch = "x86_64")]
    mod sse2 {
        use super::{LaneVertices, Lanes};
        use std::arch::x86_64::*;

        type Ps = [__m128; 2];
        type Si = [__m128i; 2];

        fn ps(a: &Lanes) -> Ps {
            bytemuck::cast(*a)
        }

        fn si(a: &[u32; 8]) -> Si {
            bytemuck::cast(*a)
        }

        // SAFETY (every `unsafe` call below): SSE2 is part of the x86-64
        // baseline, so every CPU this target runs on has it.

        /// As [`plain::less`](super::plain::less).
        #[inline(always)]
        pub fn less(a: &Lanes, b: &Lanes) -> [u32; 8] {
            #[inline]
            #[target_feature(enable = "sse2")]
            fn go(a: Ps, b: Ps) -> [u32; 8] {
                bytemuck::cast([
                    _mm_castps_si128(_mm_cmplt_ps(a[0], b[0])),
                    _mm_castps_si128(_mm_cmplt_ps(a[1], b[1])),
                ])
            }
            // SAFETY: see above.
            unsafe { go(ps(a), ps(b)) }
        }

        /// As [`plain::bits`](super::plain::bits).
        #[inline(always)]
        pub fn bits(m: &[u32; 8]) -> u32 {
            #[inline]
            #[target_feature(enable = "sse2")]
            fn go(m: Si) -> u32 {
                let lo = _mm_movemask_ps(_mm_castsi128_ps(m[0]));
                let hi = _mm_movemask_ps(_mm_castsi128_ps(m[1]));
                (lo | hi << 4) as u32
            }
            // SAFETY: see above.
            unsafe { go(si(m)) }
        }

        /// As [`plain::differs`](super::plain::differs).
        #[inline(always)]
        pub fn differs(a: &Lanes, b: &Lanes) -> u32 {
            #[inline]
            #[target_feature(enable = "sse2")]
            fn go(a: Ps, b: Ps) -> u32 {
                let lo = _mm_movemask_ps(_mm_cmpneq_ps(a[0], b[0]));
                let hi = _mm_movemask_ps(_mm_cmpneq_ps(a[1], b[1]));
                (lo | hi << 4) as u32
            }
            // SAFETY: see above.
            unsafe { go(ps(a), ps(b)) }
        }

        /// As [`plain::left_inherits`](super::plain::left_inherits).
        #[inline(always)]
        pub fn left_inherits(d: &Lanes, tl: &Lanes, tr: &Lanes) -> [u32; 8] {
            #[inline]
            #[target_feature(enable = "sse2")]
            fn go(d: Ps, tl: Ps, tr: Ps) -> [u32; 8] {
                let abs = _mm_castsi128_ps(_mm_set1_epi32(0x7fff_ffff));
                let half = |h: usize| {
                    let dl = _mm_and_ps(_mm_sub_ps(d[h], tl[h]), abs);
                    let dr = _mm_and_ps(_mm_sub_ps(d[h], tr[h]), abs);
                    let closer = _mm_and_ps(_mm_cmpneq_ps(tr[h], d[h]), _mm_cmple_ps(dl, dr));
                    _mm_castps_si128(_mm_or_ps(_mm_cmpeq_ps(tl[h], d[h]), closer))
                };
                bytemuck::cast([half(0), half(1)])
            }
            // SAFETY: see above.
            unsafe { go(ps(d), ps(tl), ps(tr)) }
        }

        /// As [`plain::pick`](super::plain::pick).
        #[inline(always)]
        pub fn pick(m: &[u32; 8], a: &Lanes, b: &Lanes) -> Lanes {
            #[inline]
            #[target_feature(enable = "sse2")]
            fn go(m: Si, a: Ps, b: Ps) -> Lanes {
                let half = |h: usize| {
                    let m = _mm_castsi128_ps(m[h]);
                    _mm_or_ps(_mm_and_ps(m, a[h]), _mm_andnot_ps(m, b[h]))
                };
                bytemuck::cast([half(0), half(1)])
            }
            // SAFETY: see above.
            unsafe { go(si(m), ps(a), ps(b)) }
        }

        /// As [`plain::pick_u32`](super::plain::pick_u32).
        #[inline(always)]
        pub fn pick_u32(m: &[u32; 8], a: &LaneVertices, b: &LaneVertices) -> LaneVertices {
            #[inline]
            #[target_feature(enable = "sse2")]
            fn go(m: Si, a: Si, b: Si) -> LaneVertices {
                let half = |h: usize| {
                    _mm_or_si128(_mm_and_si128(m[h], a[h]), _mm_andnot_si128(m[h], b[h]))
                };
                bytemuck::cast([half(0), half(1)])
            }
            // SAFETY: see above.
            unsafe { go(si(m), si(a), si(b)) }
        }
    }

    #[cfg(all(test, target_arch = "x86_64"))]
    mod tests {
        use super::{plain, sse2};

        /// The SSE2 lanes and the plain ones agree, including on the
        /// padding lanes' infinities and on ties.
        #[test]
        fn sse2_lanes_match_the_plain_ones() {
            let mut x = 7u64;
            let mut next = || {
                x = x
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                // Few distinct values, so that ties are common.
                match x >> 61 {
                    0 => f32::INFINITY,
                    1 => -0.0,
                    v => v as f32 * 0.5 - 2.0,
                }
            };
            for _ in 0..5000 {
                let [d, a, b]: [[f32; 8]; 3] =
                    std::array::from_fn(|_| std::array::from_fn(|_| next()));
                let va: [u32; 8] = std::array::from_fn(|i| i as u32);
                let vb: [u32; 8] = std::array::from_fn(|i| 100 + i as u32);
                let m = plain::less(&a, &b);
                assert_eq!(m, sse2::less(&a, &b));
                assert_eq!(plain::differs(&a, &b), sse2::differs(&a, &b));
                assert_eq!(plain::bits(&m), sse2::bits(&m));
                assert_eq!(
                    plain::left_inherits(&d, &a, &b),
                    sse2::left_inherits(&d, &a, &b)
                );
                let (p, q) = (plain::pick(&m, &a, &b), sse2::pick(&m, &a, &b));
                assert_eq!(p.map(f32::to_bits), q.map(f32::to_bits));
                assert_eq!(plain::pick_u32(&m, &va, &vb), sse2::pick_u32(&m, &va, &vb));
            }
        }
    }
}

/// What one sibling pair codes, with boxes as `L`.
pub(super) struct PairCode<L = Lanes> {
    /// The six reuse-mask bits (bits 0–2 go to the left word, 3–5 to the
    /// right one).
    pub mask: u32,
    /// The vertex fields of the left and right word, in the callers' vertex
    /// numbering; only the first `used[side]` are set, the others are 0.
    pub fields: [[u32; 3]; 2],
    /// How many fields of each word the pair sets (0 for a leaf, whose
    /// fields hold its corners).
    pub used: [usize; 2],
    /// The boxes the two children decode to.
    pub boxes: [L; 2],
    /// Extents the inner child of a leaf–inner pair inherits although it
    /// does not attain them.
    pub loose: usize,
}

/// A box as lanes that a pair is coded on, with the vertices attaining its
/// lanes: [`Lanes`] (any positions), or the 16-bit lanes of
/// [`grid16`](super::grid16) (grid coordinates of at most 16 bits), which
/// code every pair exactly as [`Lanes`] of the same grid coordinates do.
pub(super) trait BoxLanes: Copy + Default {
    /// Per lane, the vertex attaining it.
    type Vertices: Copy + Default;
    /// The box of the vertex at grid coordinates `g`.
    fn point(g: [u32; 3]) -> Self;
    /// Vertex `v` on every lane.
    fn vertex(v: u32) -> Self::Vertices;
    /// As [`union`].
    fn union(a: (&Self, &Self::Vertices), b: (&Self, &Self::Vertices)) -> (Self, Self::Vertices);
    /// As [`code_pair`].
    fn code(
        d: &Self,
        l: (&Self, &Self::Vertices, bool),
        r: (&Self, &Self::Vertices, bool),
    ) -> PairCode<Self>;
    /// The box's extents (in its coordinates).
    fn extents(&self) -> Extents;
}

impl BoxLanes for Lanes {
    type Vertices = LaneVertices;

    #[inline(always)]
    fn point(g: [u32; 3]) -> Self {
        let p = g.map(|c| c as f32);
        to_lanes(&[p[0], p[1], p[2], p[0], p[1], p[2]])
    }

    #[inline(always)]
    fn vertex(v: u32) -> LaneVertices {
        [v; 8]
    }

    #[inline(always)]
    fn union(a: (&Self, &LaneVertices), b: (&Self, &LaneVertices)) -> (Self, LaneVertices) {
        union(a, b)
    }

    #[inline(always)]
    fn code(
        d: &Self,
        l: (&Self, &LaneVertices, bool),
        r: (&Self, &LaneVertices, bool),
    ) -> PairCode<Self> {
        code_pair(d, l, r)
    }

    #[inline(always)]
    fn extents(&self) -> Extents {
        to_extents(self)
    }
}

/// Per six-bit set of extents (at most three), the extents in increasing
/// order (unused entries 0).
pub(super) static FIRST_THREE: [[u8; 3]; 64] = {
    let mut t = [[0u8; 3]; 64];
    let mut m = 0;
    while m < 64 {
        let (mut e, mut n) = (0, 0);
        while e < 6 {
            if m >> e & 1 != 0 && n < 3 {
                t[m][n] = e as u8;
                n += 1;
            }
            e += 1;
        }
        m += 1;
    }
    t
};

/// Codes the pair of children with tight boxes `tl`, `tr` attained by
/// vertices `vl`, `vr` (per lane), under a parent that decodes to `d`;
/// `ll`, `rl` say which children are leaves.
#[inline(always)]
pub(super) fn code_pair(
    d: &Lanes,
    (tl, vl, ll): (&Lanes, &LaneVertices, bool),
    (tr, vr, rl): (&Lanes, &LaneVertices, bool),
) -> PairCode {
    if ll == rl {
        // Two inner children (two leaves code nothing: everything is
        // computed as for inner ones, then cleared). Lane by lane, without
        // branches on the extents (whichever child attains an extent is a
        // coin toss): `|` and `&` rather than `||` and `&&`.
        let inner = u32::from(!ll).wrapping_neg();
        // A parent decoded looser than tight: the child that loses less
        // inherits.
        let left = lane::left_inherits(d, tl, tr);
        let keep_l = left.map(|l| l & inner);
        let keep_r = left.map(|l| !l & inner);
        let boxes = [lane::pick(&keep_l, d, tl), lane::pick(&keep_r, d, tr)];
        // Minima in the left word, maxima in the right one.
        let f = lane::pick_u32(&left, vr, vl).map(|v| v & inner);
        let mask = lane::bits(&left) & 0b11_1111;
        let used = 3 * usize::from(!ll);
        return PairCode {
            mask: mask & inner,
            fields: [[f[0], f[1], f[2]], [f[3], f[4], f[5]]],
            used: [used; 2],
            boxes,
            loose: 0,
        };
    }
    let leaf_left = ll;
    let (ti, vi) = if leaf_left { (tr, vr) } else { (tl, vl) };
    let mut need = lane::differs(ti, d) as usize & 0b11_1111;
    let mut loose = 0;
    let mut n = need.count_ones() as usize;
    if n > 3 {
        // Three vertex fields: keep the three extents that shrink the box
        // most; the rest inherit (loose but conservative).
        let axis = |e: usize| (-d[e % 3 + 3] - d[e % 3]).max(f32::MIN_POSITIVE);
        let mut order = [0usize; 6];
        let mut k = 0;
        for e in 0..6 {
            order[k] = e;
            k += need >> e & 1;
        }
        order[..n].sort_by(|&a, &b| {
            let la = (d[a] - ti[a]).abs() / axis(a);
            let lb = (d[b] - ti[b]).abs() / axis(b);
            lb.total_cmp(&la).then(a.cmp(&b))
        });
        loose = n - 3;
        n = 3;
        need = order[..3].iter().fold(0, |m, &e| m | 1 << e);
    }
    let mask = !need as u32 & 0b11_1111;
    let mut f = [0u32; 3];
    for (j, &e) in FIRST_THREE[need].iter().enumerate() {
        f[j] = if j < n { vi[e as usize] } else { 0 };
    }
    let inherit: [u32; 8] = std::array::from_fn(|e| (mask >> e & 1).wrapping_neg());
    let inner = lane::pick(&inherit, d, ti);
    let (fields, used, boxes) = if leaf_left {
        ([[0; 3], f], [0, n], [*tl, inner])
    } else {
        ([f, [0; 3]], [n, 0], [inner, *tr])
    };
    PairCode {
        mask,
        fields,
        used,
        boxes,
        loose,
    }
}
