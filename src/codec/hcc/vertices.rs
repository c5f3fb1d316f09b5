//! The low-level trees' vertex arrays: raw `f32` ([`Vertices::F32`],
//! lossless) or quantized on one grid over the mesh and bit-packed tree by
//! tree ([`Vertices::Packed`]).
//!
//! # Quantization
//!
//! One grid over the mesh's bounding box, `2^bits − 1` steps per axis
//! (16 bits by default), each vertex rounded to the *nearest* grid point.
//! The grid is the mesh's, not each low-level tree's, so a vertex stored in
//! several trees decodes to the same point in each (the decoded mesh stays
//! one mesh, and a triangle decodes alike wherever it is read). The error
//! bound is half a step per axis; the encoder measures the largest error
//! it made and stores it ([`Quantized::error`]).
//!
//! Boxes need no rounding of their own: the encoder builds every box from
//! the *decoded* vertices (the tight boxes of the quantized mesh), and the
//! cursor reads boxes from the same decoded vertices, evaluated the same
//! way (`origin + q · step` in `f32`), so a decoded box contains its
//! subtree's decoded triangles exactly.
//!
//! # Packing
//!
//! A low-level tree spans a small part of the mesh, so its grid
//! coordinates are stored as offsets from the tree's smallest, in as many
//! bits per axis as the tree's span needs ([`VertexTree`]): the precision
//! of the mesh-wide grid at the cost of a per-tree one (about 11 bits a
//! coordinate at 16-bit precision on a 1 M-triangle scan). Vertex `i` of a
//! tree is `wx + wy + wz` bits at bit `i · (wx + wy + wz)` of the tree's
//! run, x first.

use glam::Vec3A;

use crate::codec::common::FormatError;
use crate::codec::common::le::u64_at_padded;
use crate::mesh::MAX_COORDINATE;

/// Bits of a [`VertexTree`] field's base.
pub const BASE_BITS: u32 = 24;
/// The most bits a quantized coordinate may have.
pub const MAX_VERTEX_BITS: u32 = BASE_BITS;

/// One low-level tree's packed vertex run.
///
/// # Layout
/// | bytes | field |
/// |---|---|
/// | 0–11 | per axis: the tree's smallest grid coordinate (bits 0–23) and the offsets' width in bits (bits 24–28) |
/// | 12–15 | byte offset of the tree's run in the packed data |
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct VertexTree {
    /// Per axis: base | width << 24.
    pub axes: [u32; 3],
    /// Byte offset of the run.
    pub byte: u32,
}

const _: () = assert!(size_of::<VertexTree>() == 16);

impl VertexTree {
    /// Axis `a`'s base grid coordinate.
    #[inline(always)]
    pub fn base(&self, a: usize) -> u32 {
        self.axes[a] & ((1 << BASE_BITS) - 1)
    }

    /// Axis `a`'s offset width in bits.
    #[inline(always)]
    pub fn width(&self, a: usize) -> u32 {
        self.axes[a] >> BASE_BITS
    }

    /// Bits per vertex.
    #[inline(always)]
    pub fn stride(&self) -> u32 {
        self.width(0) + self.width(1) + self.width(2)
    }
}

/// The quantization grid and the packed vertices.
#[derive(Clone, Debug, PartialEq)]
pub struct Quantized {
    /// Bits per coordinate.
    pub bits: u32,
    /// The grid's minimum corner.
    pub origin: [f32; 3],
    /// One step per axis (0 on a flat axis).
    pub step: [f32; 3],
    /// The largest distance per axis between an input vertex and its
    /// decoded position, measured when encoding.
    pub error: [f32; 3],
    /// Per low-level tree, its run.
    pub trees: Vec<VertexTree>,
    /// The runs, back to back (each starting on a byte).
    pub data: Vec<u8>,
}

/// Reads `n` (≤ 32) bits at bit `at` of `data`, past the end as zeros.
#[inline(always)]
pub fn bits_at(data: &[u8], at: u64, n: u32) -> u32 {
    let w = u64_at_padded(data, (at >> 3) as usize) >> (at & 7);
    (w & ((1u64 << n) - 1)) as u32
}

/// Bits that hold every value `0..=span` (0 for `span` 0).
#[inline]
pub fn width_of(span: u32) -> u32 {
    32 - span.leading_zeros()
}

impl Quantized {
    /// The grid of `bits` bits per coordinate over the box `lo`–`hi`.
    pub fn grid(bits: u32, lo: [f32; 3], hi: [f32; 3]) -> Self {
        let n = ((1u64 << bits) - 1) as f32;
        let mut step = [0f32; 3];
        for a in 0..3 {
            if hi[a] > lo[a] {
                let mut s = (hi[a] - lo[a]) / n;
                // Grow the step until the last grid point reaches `hi`.
                while lo[a] + n * s < hi[a] {
                    s = f32::from_bits(s.to_bits() + 1);
                }
                step[a] = s;
            }
        }
        Self {
            bits,
            origin: lo,
            step,
            error: [0.0; 3],
            trees: Vec::new(),
            data: Vec::new(),
        }
    }

    /// The largest grid coordinate.
    pub fn max_q(&self) -> u32 {
        ((1u64 << self.bits) - 1) as u32
    }

    /// The decoded value of grid coordinate `q` on axis `a`: the one
    /// formula the encoder and the cursor share.
    #[inline(always)]
    pub fn value(&self, a: usize, q: u32) -> f32 {
        self.origin[a] + q as f32 * self.step[a]
    }

    /// The grid coordinate nearest `v` on axis `a`.
    pub fn nearest(&self, a: usize, v: f32) -> u32 {
        if self.step[a] == 0.0 {
            return 0;
        }
        let guess = ((v - self.origin[a]) / self.step[a]).round();
        let q = guess.clamp(0.0, self.max_q() as f32) as u32;
        let err = |q: u32| (self.value(a, q) - v).abs();
        let mut best = q;
        for c in [q.saturating_sub(1), (q + 1).min(self.max_q())] {
            if err(c) < err(best) {
                best = c;
            }
        }
        best
    }

    /// Appends a tree whose vertices have grid coordinates `q`.
    pub fn push_tree(&mut self, q: &[[u32; 3]]) {
        let mut t = VertexTree {
            byte: self.data.len() as u32,
            ..Default::default()
        };
        let (mut lo, mut hi) = ([u32::MAX; 3], [0u32; 3]);
        for v in q {
            for a in 0..3 {
                lo[a] = lo[a].min(v[a]);
                hi[a] = hi[a].max(v[a]);
            }
        }
        if q.is_empty() {
            lo = [0; 3];
        }
        for a in 0..3 {
            t.axes[a] = lo[a] | width_of(hi[a] - lo[a]) << BASE_BITS;
        }
        // Vertex i at bit i · stride of the run, x first, least-significant
        // bit first: fields appended one after the other (as a bit writer
        // would), flushed 32 bits at a time, the last byte zero-padded.
        let base = [0, 1, 2].map(|a| t.base(a));
        let width = [0, 1, 2].map(|a| t.width(a));
        let (mut acc, mut n) = (0u64, 0u32);
        self.data
            .reserve((q.len() * width.iter().sum::<u32>() as usize).div_ceil(8));
        for v in q {
            for a in 0..3 {
                // A field has at most 24 bits and fewer than 32 wait, so
                // `acc` never holds more than 55.
                acc |= u64::from(v[a] - base[a]) << n;
                n += width[a];
                if n >= 32 {
                    self.data.extend_from_slice(&(acc as u32).to_le_bytes());
                    acc >>= 32;
                    n -= 32;
                }
            }
        }
        self.data
            .extend_from_slice(&acc.to_le_bytes()[..n.div_ceil(8) as usize]);
        self.trees.push(t);
    }

    /// The grid coordinates of vertex `local` of tree `tree`.
    #[inline(always)]
    pub fn grid_point(&self, tree: usize, local: u32) -> [u32; 3] {
        let t = &self.trees[tree];
        let mut at = u64::from(t.byte) * 8 + u64::from(local) * u64::from(t.stride());
        std::array::from_fn(|a| {
            let w = t.width(a);
            let q = t.base(a) + bits_at(&self.data, at, w);
            at += u64::from(w);
            q
        })
    }

    /// Vertex `local` of tree `tree`.
    #[inline(always)]
    pub fn point(&self, tree: usize, local: u32) -> [f32; 3] {
        let t = &self.trees[tree];
        let mut at = u64::from(t.byte) * 8 + u64::from(local) * u64::from(t.stride());
        std::array::from_fn(|a| {
            let w = t.width(a);
            let q = t.base(a) + bits_at(&self.data, at, w);
            at += u64::from(w);
            self.value(a, q)
        })
    }

    /// Checks tree `tree`'s run of `count` vertices: widths within
    /// `bits`, the run inside the data. (Any base and offset decode to a
    /// finite value: both are below 2^24.)
    pub fn check_tree(&self, tree: usize, count: u32) -> Result<(), &'static str> {
        let t = &self.trees[tree];
        if (0..3).any(|a| t.width(a) > self.bits) {
            return Err("a packed vertex run's width is out of range");
        }
        let end = u64::from(t.byte) * 8 + u64::from(count) * u64::from(t.stride());
        if end > self.data.len() as u64 * 8 {
            return Err("a packed vertex run lies past the data");
        }
        Ok(())
    }

    /// Checks the grid itself: bits in range, finite origin and steps, the
    /// whole grid (origin to its far corner) within the encoder's limit
    /// on coordinates ([`MAX_COORDINATE`]), and the recorded quantization
    /// error no larger than a step (plus the rounding of coordinates of
    /// that magnitude).
    pub fn check_grid(&self) -> Result<(), FormatError> {
        if !(1..=MAX_VERTEX_BITS).contains(&self.bits) {
            return Err(FormatError::header(
                "vertex bits",
                format!("{} is not in 1..={MAX_VERTEX_BITS}", self.bits),
            ));
        }
        if self
            .origin
            .iter()
            .chain(&self.step)
            .chain(&self.error)
            .any(|c| !c.is_finite())
            || self.step.iter().any(|&s| s < 0.0)
        {
            return Err(FormatError::header(
                "vertex grid",
                "a value is not finite or a step is negative",
            ));
        }
        // The far corner is origin + step · max_q in f32 steps: allow it
        // the rounding of a step computed from a mesh at the limit.
        let limit = f64::from(MAX_COORDINATE) * (1.0 + 1e-6);
        for a in 0..3 {
            let origin = f64::from(self.origin[a]);
            let far = origin + f64::from(self.step[a]) * f64::from(self.max_q());
            if origin.abs() > limit || far.abs() > limit {
                return Err(FormatError::header(
                    "vertex grid",
                    format!(
                        "axis {a} spans {origin:e} to {far:e}, beyond the coordinate limit ±{limit:e}"
                    ),
                ));
            }
            let rounding = 1e-6 * origin.abs().max(far.abs());
            let error = f64::from(self.error[a]);
            if !(0.0..=f64::from(self.step[a]) + rounding).contains(&error) {
                return Err(FormatError::header(
                    "vertex grid",
                    format!(
                        "axis {a}'s quantization error {error:e} is not within its step {:e}",
                        self.step[a]
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// One low-level tree's vertices as the cursor reads them: the cursor is
/// monomorphized over the two forms, so the format is chosen once per
/// node expansion, not once per coordinate.
pub trait TreeVerts {
    /// Coordinate `a` of vertex `local`.
    fn coord(&self, local: u32, a: usize) -> f32;
    /// Vertex `local`.
    fn point(&self, local: u32) -> Vec3A;
}

/// A tree's `f32` vertices: the shared array and the tree's first index.
pub struct F32Verts<'a> {
    /// Every tree's vertices.
    pub all: &'a [[f32; 3]],
    /// The tree's first vertex.
    pub start: u32,
}

impl TreeVerts for F32Verts<'_> {
    #[inline(always)]
    fn coord(&self, local: u32, a: usize) -> f32 {
        self.all[(self.start + local) as usize][a]
    }

    #[inline(always)]
    fn point(&self, local: u32) -> Vec3A {
        Vec3A::from(self.all[(self.start + local) as usize])
    }
}

/// A tree's packed run, its fields unpacked once.
pub struct PackedVerts<'a> {
    data: &'a [u8],
    bit: u64,
    stride: u64,
    skip: [u64; 3],
    width: [u32; 3],
    base: [u32; 3],
    origin: [f32; 3],
    step: [f32; 3],
}

impl TreeVerts for PackedVerts<'_> {
    #[inline(always)]
    fn coord(&self, local: u32, a: usize) -> f32 {
        let at = self.bit + u64::from(local) * self.stride + self.skip[a];
        let q = self.base[a] + bits_at(self.data, at, self.width[a]);
        // The formula of `Quantized::value`, which the encoder used.
        self.origin[a] + q as f32 * self.step[a]
    }

    #[inline(always)]
    fn point(&self, local: u32) -> Vec3A {
        if self.stride > 57 {
            return Vec3A::new(
                self.coord(local, 0),
                self.coord(local, 1),
                self.coord(local, 2),
            );
        }
        // One 64-bit read holds the whole vertex.
        let at = self.bit + u64::from(local) * self.stride;
        let w = u64_at_padded(self.data, (at >> 3) as usize) >> (at & 7);
        let q = |a: usize| {
            let f = (w >> self.skip[a]) & ((1u64 << self.width[a]) - 1);
            self.origin[a] + (self.base[a] + f as u32) as f32 * self.step[a]
        };
        Vec3A::new(q(0), q(1), q(2))
    }
}

impl Quantized {
    /// Tree `tree`'s run, ready to read.
    #[inline(always)]
    pub fn tree(&self, tree: usize) -> PackedVerts<'_> {
        let t = &self.trees[tree];
        let width = [t.width(0), t.width(1), t.width(2)];
        PackedVerts {
            data: &self.data,
            bit: u64::from(t.byte) * 8,
            stride: u64::from(width[0] + width[1] + width[2]),
            skip: [0, u64::from(width[0]), u64::from(width[0] + width[1])],
            width,
            base: [t.base(0), t.base(1), t.base(2)],
            origin: self.origin,
            step: self.step,
        }
    }
}

/// The vertex arrays.
#[derive(Clone, Debug, PartialEq)]
pub enum Vertices {
    /// Raw `f32` coordinates, the trees' arrays one after the other.
    F32(Vec<[f32; 3]>),
    /// Quantized and packed.
    Packed(Quantized),
}

impl Default for Vertices {
    fn default() -> Self {
        Vertices::F32(Vec::new())
    }
}

impl Vertices {
    /// Bytes in memory.
    pub fn bytes(&self) -> usize {
        match self {
            Vertices::F32(v) => v.len() * 12,
            Vertices::Packed(q) => q.data.len() + q.trees.len() * size_of::<VertexTree>(),
        }
    }

    /// The quantization, if any.
    pub fn quantized(&self) -> Option<&Quantized> {
        match self {
            Vertices::F32(_) => None,
            Vertices::Packed(q) => Some(q),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packed_runs_round_trip_within_half_a_step() {
        let mut q = Quantized::grid(16, [-1.0, 5.0, 2.0], [3.0, 5.0, 1e6]);
        let pts: Vec<[f32; 3]> = (0..300)
            .map(|i| {
                let t = i as f32 / 299.0;
                [-1.0 + 4.0 * t * t, 5.0, 2.0 + (1e6 - 2.0) * t]
            })
            .collect();
        let grid: Vec<[u32; 3]> = pts
            .iter()
            .map(|p| std::array::from_fn(|a| q.nearest(a, p[a])))
            .collect();
        q.push_tree(&grid[..100]);
        q.push_tree(&grid[100..]);
        q.push_tree(&[]);
        for (k, p) in pts.iter().enumerate() {
            let (tree, local) = if k < 100 { (0, k) } else { (1, k - 100) };
            let d = q.point(tree, local as u32);
            for a in 0..3 {
                assert_eq!(d[a], q.tree(tree).coord(local as u32, a));
                assert_eq!(d[a], q.tree(tree).point(local as u32)[a]);
                assert_eq!(d[a], q.value(a, grid[k][a]));
                assert!((d[a] - p[a]).abs() <= q.step[a] * 0.5 + p[a].abs() * 1e-6);
            }
        }
        assert_eq!(q.trees[0].width(1), 0, "a flat axis takes no bits");
        q.check_tree(0, 100).unwrap();
        q.check_tree(1, 200).unwrap();
        assert!(q.check_tree(1, 100_000).is_err());
        q.check_grid().unwrap();
    }
}
