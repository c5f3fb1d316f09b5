//! The pair coding ([`code_pair`]) on 16-bit lanes, for the o-HCCMesh
//! decoder's rebuild when the grid has at most 16 bits: a box is one SSE2
//! register of eight `i16` lanes, and so are the vertices attaining it,
//! where [`Lanes`] take four registers. With quantized vertices the
//! i-HCCMesh encoder codes boxes on the grid's integer coordinates, so
//! these lanes code every pair exactly as [`Lanes`] of the same
//! coordinates do: the mapping below is exact and strictly monotone, and
//! the one comparison of distances is of exact integers in both.
//!
//! Lanes, as [`Lanes`]' "farther out is smaller": the minima as
//! `g − 32768`, the maxima as `32767 − g`, and two padding lanes of 32767
//! (never farther out than another value).

use super::pair::{
    BoxLanes, Extents, FIRST_THREE, LaneVertices, Lanes, PairCode, code_pair, to_extents,
};
use std::arch::x86_64::*;

/// A box on a grid of at most 16 bits, as 16-bit lanes.
#[derive(Clone, Copy)]
pub(super) struct Box16(__m128i);

/// Per lane of a [`Box16`], the vertex attaining it (9-bit local indices).
#[derive(Clone, Copy)]
pub(super) struct Vertices16(__m128i);

impl Default for Box16 {
    fn default() -> Self {
        Self(bytemuck::Zeroable::zeroed())
    }
}

impl Default for Vertices16 {
    fn default() -> Self {
        Self(bytemuck::Zeroable::zeroed())
    }
}

impl Box16 {
    /// The lanes as numbers.
    fn lanes(self) -> [i16; 8] {
        bytemuck::cast(self.0)
    }

    /// The same box as [`Lanes`] of grid coordinates.
    pub(super) fn to_grid(self) -> Lanes {
        let l = self.lanes();
        std::array::from_fn(|e| match e {
            0..=2 => (i32::from(l[e]) + 32768) as f32,
            3..=5 => -((32767 - i32::from(l[e])) as f32),
            _ => f32::INFINITY,
        })
    }

    /// `l` ([`Lanes`] of grid coordinates below 2^16) as 16-bit lanes.
    pub(super) fn from_grid(l: &Lanes) -> Self {
        let lanes: [i16; 8] = std::array::from_fn(|e| match e {
            0..=2 => (l[e] as i32 - 32768) as i16,
            3..=5 => (32767 - (-l[e]) as i32) as i16,
            _ => i16::MAX,
        });
        Self(bytemuck::cast(lanes))
    }
}

impl Vertices16 {
    /// As [`LaneVertices`].
    pub(super) fn to_lanes(self) -> LaneVertices {
        let v: [u16; 8] = bytemuck::cast(self.0);
        v.map(u32::from)
    }
}

// SAFETY (every `unsafe` call below): SSE2 is part of the x86-64 baseline,
// so every CPU this target runs on has it.

/// `a` where `m`, else `b`.
#[inline]
#[target_feature(enable = "sse2")]
fn pick(m: __m128i, a: __m128i, b: __m128i) -> __m128i {
    _mm_or_si128(_mm_and_si128(m, a), _mm_andnot_si128(m, b))
}

/// Bit `i` set where 16-bit mask lane `i` is set.
#[inline]
#[target_feature(enable = "sse2")]
fn bits(m: __m128i) -> u32 {
    _mm_movemask_epi8(_mm_packs_epi16(m, _mm_setzero_si128())) as u32
}

#[inline]
#[target_feature(enable = "sse2")]
fn union16(a: (__m128i, __m128i), b: (__m128i, __m128i)) -> (Box16, Vertices16) {
    // Ties to `a`.
    let take = _mm_cmpgt_epi16(a.0, b.0);
    (
        Box16(_mm_min_epi16(a.0, b.0)),
        Vertices16(pick(take, b.1, a.1)),
    )
}

#[inline]
#[target_feature(enable = "sse2")]
fn code16(
    d: Box16,
    (tl, vl, ll): (Box16, Vertices16, bool),
    (tr, vr, rl): (Box16, Vertices16, bool),
) -> PairCode<Box16> {
    if ll == rl {
        // As `code_pair`: the left child inherits where it attains the
        // parent's extent, or where the right one does not and the left
        // one loses no more. A parent's decoded box holds its children's
        // tight ones, so on every lane `t − d` is a distance in 0..2^16.
        let inner = _mm_set1_epi16(if ll { 0 } else { -1 });
        let dl = _mm_sub_epi16(tl.0, d.0);
        let dr = _mm_sub_epi16(tr.0, d.0);
        let closer = _mm_cmpeq_epi16(_mm_subs_epu16(dl, dr), _mm_setzero_si128());
        let right_off = _mm_cmpeq_epi16(dr, _mm_setzero_si128());
        let left = _mm_or_si128(
            _mm_cmpeq_epi16(dl, _mm_setzero_si128()),
            _mm_andnot_si128(right_off, closer),
        );
        let keep_l = _mm_and_si128(left, inner);
        let keep_r = _mm_andnot_si128(left, inner);
        let f: [u16; 8] = bytemuck::cast(_mm_and_si128(pick(left, vr.0, vl.0), inner));
        let f = f.map(u32::from);
        let used = 3 * usize::from(!ll);
        return PairCode {
            mask: bits(left) & 0b11_1111 & if ll { 0 } else { u32::MAX },
            fields: [[f[0], f[1], f[2]], [f[3], f[4], f[5]]],
            used: [used; 2],
            boxes: [
                Box16(pick(keep_l, d.0, tl.0)),
                Box16(pick(keep_r, d.0, tr.0)),
            ],
            loose: 0,
        };
    }
    let (ti, vi) = if ll { (tr, vr) } else { (tl, vl) };
    let need = !bits(_mm_cmpeq_epi16(ti.0, d.0)) & 0b11_1111;
    let n = need.count_ones() as usize;
    if n > 3 {
        // Which three extents to keep is decided on distances relative to
        // the box (floating point): taken from the reference, on the same
        // coordinates.
        let pc = code_pair(
            &d.to_grid(),
            (&tl.to_grid(), &vl.to_lanes(), ll),
            (&tr.to_grid(), &vr.to_lanes(), rl),
        );
        return PairCode {
            mask: pc.mask,
            fields: pc.fields,
            used: pc.used,
            boxes: pc.boxes.map(|b| Box16::from_grid(&b)),
            loose: pc.loose,
        };
    }
    // At most three extents differ from the parent's: the inner child
    // sends their vertices and inherits the others, which it attains; its
    // decoded box is its tight one.
    let v: [u16; 8] = bytemuck::cast(vi.0);
    let mut f = [0u32; 3];
    for (j, &e) in FIRST_THREE[need as usize].iter().enumerate() {
        f[j] = if j < n { u32::from(v[e as usize]) } else { 0 };
    }
    let (fields, used) = if ll {
        ([[0; 3], f], [0, n])
    } else {
        ([f, [0; 3]], [n, 0])
    };
    PairCode {
        mask: !need & 0b11_1111,
        fields,
        used,
        boxes: [tl, tr],
        loose: 0,
    }
}

impl BoxLanes for Box16 {
    type Vertices = Vertices16;

    #[inline(always)]
    fn point(g: [u32; 3]) -> Self {
        let lo = g.map(|c| (c as i32 - 32768) as i16);
        let hi = g.map(|c| (32767 - c as i32) as i16);
        Self(bytemuck::cast([
            lo[0],
            lo[1],
            lo[2],
            hi[0],
            hi[1],
            hi[2],
            i16::MAX,
            i16::MAX,
        ]))
    }

    #[inline(always)]
    fn vertex(v: u32) -> Vertices16 {
        Vertices16(bytemuck::cast([v as u16; 8]))
    }

    #[inline(always)]
    fn union(a: (&Self, &Vertices16), b: (&Self, &Vertices16)) -> (Self, Vertices16) {
        // SAFETY: see above.
        unsafe { union16((a.0.0, a.1.0), (b.0.0, b.1.0)) }
    }

    #[inline(always)]
    fn code(
        d: &Self,
        (tl, vl, ll): (&Self, &Vertices16, bool),
        (tr, vr, rl): (&Self, &Vertices16, bool),
    ) -> PairCode<Self> {
        // SAFETY: see above.
        unsafe { code16(*d, (*tl, *vl, ll), (*tr, *vr, rl)) }
    }

    #[inline(always)]
    fn extents(&self) -> Extents {
        to_extents(&self.to_grid())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::codec::hcc::pair::union;

    /// A small generator, with few distinct coordinates (ties are common)
    /// and the grid's ends.
    struct Rng(u64);

    impl Rng {
        fn next(&mut self) -> u32 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (self.0 >> 33) as u32
        }

        fn coordinate(&mut self) -> u32 {
            match self.next() % 8 {
                0 => 0,
                1 => 65535,
                2 => self.next() % 65536,
                _ => 30000 + self.next() % 6,
            }
        }

        fn point(&mut self) -> [u32; 3] {
            [0; 3].map(|_| self.coordinate())
        }
    }

    /// The box of points `ps` (vertices numbered from `first`) both ways.
    fn boxes(ps: &[[u32; 3]], first: u32) -> ((Lanes, LaneVertices), (Box16, Vertices16)) {
        let mut a = (<Lanes as BoxLanes>::point(ps[0]), [first; 8]);
        let mut b = (Box16::point(ps[0]), Box16::vertex(first));
        for (i, &p) in ps.iter().enumerate().skip(1) {
            let v = first + i as u32;
            a = BoxLanes::union((&a.0, &a.1), (&Lanes::point(p), &[v; 8]));
            b = BoxLanes::union((&b.0, &b.1), (&Box16::point(p), &Box16::vertex(v)));
        }
        (a, b)
    }

    fn same(a: &Lanes, b: Box16) -> bool {
        a.map(f32::to_bits) == b.to_grid().map(f32::to_bits)
    }

    /// Unions and pair codes on 16-bit lanes equal those on [`Lanes`] of
    /// the same grid coordinates: boxes, vertices, masks, fields, counts,
    /// for inner, mixed and leaf pairs under parents decoded tight or
    /// looser, with many ties.
    #[test]
    fn sixteen_bit_lanes_code_pairs_as_float_lanes_do() {
        let mut rng = Rng(3);
        let mut loose = 0;
        for round in 0..20_000 {
            let nl = 1 + rng.next() as usize % 4;
            let nr = 1 + rng.next() as usize % 4;
            let pl: Vec<[u32; 3]> = (0..nl).map(|_| rng.point()).collect();
            let pr: Vec<[u32; 3]> = (0..nr).map(|_| rng.point()).collect();
            let ((tl, vl), (tl16, vl16)) = boxes(&pl, 0);
            let ((tr, vr), (tr16, vr16)) = boxes(&pr, 100);
            assert!(same(&tl, tl16) && vl == vl16.to_lanes());
            assert!(same(&tr, tr16) && vr == vr16.to_lanes());
            // The parent: the children's union, pushed out on some
            // extents (a parent decoded looser than tight).
            let (mut d, _) = union((&tl, &vl), (&tr, &vr));
            for (e, de) in d.iter_mut().take(6).enumerate() {
                if rng.next().is_multiple_of(3) {
                    let g = if e < 3 { *de } else { -*de };
                    let out = if e < 3 {
                        g - (g.min(rng.next() as f32 % 3.0))
                    } else {
                        g + ((65535.0 - g).min(rng.next() as f32 % 3.0))
                    };
                    *de = if e < 3 { out } else { -out };
                }
            }
            let d16 = Box16::from_grid(&d);
            assert!(same(&d, d16), "round {round}");
            let (ll, rl) = (rng.next().is_multiple_of(3), rng.next().is_multiple_of(3));
            let a = code_pair(&d, (&tl, &vl, ll), (&tr, &vr, rl));
            let b = Box16::code(&d16, (&tl16, &vl16, ll), (&tr16, &vr16, rl));
            assert_eq!(
                (a.mask, a.fields, a.used, a.loose),
                (b.mask, b.fields, b.used, b.loose),
                "round {round}"
            );
            assert!(
                same(&a.boxes[0], b.boxes[0]) && same(&a.boxes[1], b.boxes[1]),
                "round {round}"
            );
            loose += a.loose;
        }
        assert!(loose > 0, "some mixed pairs keep three of more extents");
    }
}
