//! The batched separating-axis test of the triangle-pair kernel: up to
//! [`LANES`] pairs in structure-of-arrays form, every arithmetic step a loop
//! over the lanes so that it vectorizes, with an AVX2 build of the same code
//! chosen at run time (see [`super::kernel`] for the axes).

use crate::geom::Triangle;

/// Pairs tested together by the batched separating-axis test.
pub const LANES: usize = 8;

/// Which implementation of the batched test runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Simd {
    /// Whatever the processor supports (AVX2 when detected).
    Auto,
    /// The portable path (the target's baseline vector width).
    Scalar,
}

pub(super) type Lanes = [f32; LANES];

/// Triangle corners of a batch: `[corner][coordinate][lane]`.
pub(super) type Corners = [[Lanes; 3]; 3];

/// Up to [`LANES`] queued pairs in structure-of-arrays form.
#[derive(Clone)]
pub(super) struct Batch {
    pub(super) a: Corners,
    pub(super) b: Corners,
    pub(super) ids: [(u32, u32); LANES],
    /// Each pair's edge flags (A's triangle, B's), for oriented contacts.
    pub(super) flags: [(u8, u8); LANES],
    /// Each pair's prediction distance.
    pub(super) pred: Lanes,
    pub(super) len: usize,
}

impl Default for Batch {
    fn default() -> Self {
        Self {
            a: [[[0.0; LANES]; 3]; 3],
            b: [[[0.0; LANES]; 3]; 3],
            ids: [(0, 0); LANES],
            flags: [(0, 0); LANES],
            pred: [0.0; LANES],
            len: 0,
        }
    }
}

impl Batch {
    /// Queues the pair `a`, `b` with its ids and prediction distance in
    /// the next lane; returns whether the batch is now full.
    #[inline]
    pub(super) fn put(&mut self, a: &Triangle, b: &Triangle, ids: (u32, u32), pred: f32) -> bool {
        let l = self.len;
        for c in 0..3 {
            for k in 0..3 {
                self.a[c][k][l] = a[c][k];
                self.b[c][k][l] = b[c][k];
            }
        }
        self.ids[l] = ids;
        self.flags[l] = (super::edges::ALL_ACTIVE, super::edges::ALL_ACTIVE);
        self.pred[l] = pred;
        self.len += 1;
        self.len == LANES
    }
}

/// The result of the separating-axis test of each lane.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct SatOut {
    /// The largest signed separation over the axes.
    pub(super) sep: Lanes,
    /// The axis that gave it. (32-bit lanes, as wide as the separations, so
    /// that keeping the best axis is a blend, not a per-lane branch: with
    /// `u8` and `bool` lanes the AVX2 build extracted every lane and
    /// branched, and the test took 85 ns per pair.)
    pub(super) axis: [u32; LANES],
    /// Whether B lies on the axis's positive side (1) or not (0).
    pub(super) up: [u32; LANES],
}

pub(super) fn sat_dispatch(batch: &Batch, simd: Simd) -> SatOut {
    #[cfg(target_arch = "x86_64")]
    if simd == Simd::Auto && std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the processor supports AVX2, checked just above; the
        // function has no other requirement.
        return unsafe { sat_avx2(batch) };
    }
    let _ = simd;
    sat_lanes(batch)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn sat_avx2(batch: &Batch) -> SatOut {
    sat_lanes(batch)
}

#[inline(always)]
fn sub(x: &Lanes, y: &Lanes) -> Lanes {
    std::array::from_fn(|l| x[l] - y[l])
}

#[inline(always)]
fn sub3(x: &[Lanes; 3], y: &[Lanes; 3]) -> [Lanes; 3] {
    [sub(&x[0], &y[0]), sub(&x[1], &y[1]), sub(&x[2], &y[2])]
}

#[inline(always)]
fn cross(x: &[Lanes; 3], y: &[Lanes; 3]) -> [Lanes; 3] {
    [
        std::array::from_fn(|l| x[1][l] * y[2][l] - x[2][l] * y[1][l]),
        std::array::from_fn(|l| x[2][l] * y[0][l] - x[0][l] * y[2][l]),
        std::array::from_fn(|l| x[0][l] * y[1][l] - x[1][l] * y[0][l]),
    ]
}

#[inline(always)]
fn dot(x: &[Lanes; 3], y: &[Lanes; 3]) -> Lanes {
    std::array::from_fn(|l| x[0][l] * y[0][l] + x[1][l] * y[1][l] + x[2][l] * y[2][l])
}

/// One axis of the batched test: the signed separation of every lane along
/// `l3`, kept where it beats the best so far.
#[inline(always)]
fn test_axis(
    out: &mut SatOut,
    a: &Corners,
    b: &Corners,
    axis: u32,
    l3: &[Lanes; 3],
    reference: &Lanes,
) {
    let len2 = dot(l3, l3);
    let pa = [dot(l3, &a[0]), dot(l3, &a[1]), dot(l3, &a[2])];
    let pb = [dot(l3, &b[0]), dot(l3, &b[1]), dot(l3, &b[2])];
    for l in 0..LANES {
        let min_a = pa[0][l].min(pa[1][l]).min(pa[2][l]);
        let max_a = pa[0][l].max(pa[1][l]).max(pa[2][l]);
        let min_b = pb[0][l].min(pb[1][l]).min(pb[2][l]);
        let max_b = pb[0][l].max(pb[1][l]).max(pb[2][l]);
        let s_up = min_b - max_a;
        let s_dn = min_a - max_b;
        let up = (s_up >= s_dn) as u32;
        let s = s_up.max(s_dn) / len2[l].sqrt();
        let valid = len2[l] > 1e-12 * reference[l];
        let better = valid && s > out.sep[l];
        out.sep[l] = if better { s } else { out.sep[l] };
        out.axis[l] = if better { axis } else { out.axis[l] };
        out.up[l] = if better { up } else { out.up[l] };
    }
}

/// The 17-axis test over a batch, written lane-wise so that it vectorizes.
/// Axis order: 0 A's face normal, 1 B's, 2..=10 `edge_A(k/3) × edge_B(k%3)`,
/// 11..=13 `n_A × edge_A`, 14..=16 `n_B × edge_B`. Axes shorter than a tiny
/// fraction of their edges' product (parallel edges) are skipped. Ties keep
/// the earlier axis, so face normals win over edge axes.
#[inline(always)]
fn sat_lanes(batch: &Batch) -> SatOut {
    let a = &batch.a;
    let b = &batch.b;
    let ea = [sub3(&a[1], &a[0]), sub3(&a[2], &a[1]), sub3(&a[0], &a[2])];
    let eb = [sub3(&b[1], &b[0]), sub3(&b[2], &b[1]), sub3(&b[0], &b[2])];
    let la: [Lanes; 3] = [0, 1, 2].map(|k| dot(&ea[k], &ea[k]));
    let lb: [Lanes; 3] = [0, 1, 2].map(|k| dot(&eb[k], &eb[k]));
    let na = cross(&ea[0], &ea[1]);
    let nb = cross(&eb[0], &eb[1]);
    let mut out = SatOut {
        sep: [f32::NEG_INFINITY; LANES],
        axis: [0; LANES],
        up: [1; LANES],
    };
    let mut test = |axis: u32, l3: &[Lanes; 3], reference: &Lanes| {
        test_axis(&mut out, a, b, axis, l3, reference)
    };
    // The reference scale of a face normal: the product of two edges' squares.
    let ra: Lanes = std::array::from_fn(|l| la[0][l] * la[1][l]);
    let rb: Lanes = std::array::from_fn(|l| lb[0][l] * lb[1][l]);
    test(0, &na, &ra);
    test(1, &nb, &rb);
    for i in 0..3 {
        for j in 0..3 {
            let axis = cross(&ea[i], &eb[j]);
            let r: Lanes = std::array::from_fn(|l| la[i][l] * lb[j][l]);
            test(2 + (3 * i + j) as u32, &axis, &r);
        }
    }
    for i in 0..3 {
        let axis = cross(&na, &ea[i]);
        let r: Lanes = std::array::from_fn(|l| ra[l] * la[i][l]);
        test(11 + i as u32, &axis, &r);
    }
    for j in 0..3 {
        let axis = cross(&nb, &eb[j]);
        let r: Lanes = std::array::from_fn(|l| rb[l] * lb[j][l]);
        test(14 + j as u32, &axis, &r);
    }
    out
}
