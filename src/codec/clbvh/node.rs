//! The two multi-node types, child references, and the conservative 8-bit
//! quantizer of the compressed multi-leaf node.

use glam::Vec3A;

use crate::geom::Aabb;

/// Tag (low two bits of a [`ChildRef`]) of an empty lane.
pub const TAG_EMPTY: u32 = 0;
/// Tag of a regular inner multi-node; the upper bits index
/// [`ClBvh`](super::ClBvh)'s inner-node array.
pub const TAG_INNER: u32 = 1;
/// Tag of an isolated leaf; the upper bits are the word offset of its leaf
/// block in the arena.
pub const TAG_LEAF: u32 = 2;
/// Tag of a compressed multi-leaf node; the upper bits are the word offset
/// of the node in the arena (its leaf data follows it).
pub const TAG_MULTI: u32 = 3;
/// The largest index or word offset a [`ChildRef`] can hold (30 bits).
pub const MAX_REF_INDEX: u32 = (1 << 30) - 1;

/// A tagged child reference: `index << 2 | tag`, tag one of
/// [`TAG_EMPTY`], [`TAG_INNER`], [`TAG_LEAF`], [`TAG_MULTI`]. The paper's
/// inner nodes need "one more bit" in the child pointer to tell an isolated
/// leaf from a compressed multi-leaf node; here that is the second tag bit.
pub type ChildRef = u32;

/// Makes a child reference (`index` at most [`MAX_REF_INDEX`]).
#[inline]
pub const fn child_ref(tag: u32, index: u32) -> ChildRef {
    index << 2 | tag
}

/// The tag of a child reference.
#[inline]
pub const fn ref_tag(r: ChildRef) -> u32 {
    r & 3
}

/// The index (inner node) or arena word offset (leaf, multi-leaf node) of a
/// child reference.
#[inline]
pub const fn ref_index(r: ChildRef) -> usize {
    (r >> 2) as usize
}

/// A regular 8-wide inner multi-node: eight `f32` child boxes in
/// structure-of-arrays form and eight tagged child references.
///
/// # Layout
/// | bytes | field | meaning |
/// |---|---|---|
/// | 0–31    | `min_x` | child box minima, x, lanes 0–7 (f32) |
/// | 32–63   | `max_x` | child box maxima, x |
/// | 64–95   | `min_y` | |
/// | 96–127  | `max_y` | |
/// | 128–159 | `min_z` | |
/// | 160–191 | `max_z` | |
/// | 192–223 | `child` | [`ChildRef`] per lane (u32), [`TAG_EMPTY`] for an unused lane |
///
/// Embree's BVH8 node is 256 bytes (64-bit pointers); 32-bit references
/// make this one 224. Used lanes come first. An empty lane's box is
/// inverted (`min = +inf`, `max = -inf`) and its reference is 0; traversal
/// masks lanes by the reference, never by the box.
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C, align(32))]
pub struct InnerNode {
    /// Child box minima, x.
    pub min_x: [f32; 8],
    /// Child box maxima, x.
    pub max_x: [f32; 8],
    /// Child box minima, y.
    pub min_y: [f32; 8],
    /// Child box maxima, y.
    pub max_y: [f32; 8],
    /// Child box minima, z.
    pub min_z: [f32; 8],
    /// Child box maxima, z.
    pub max_z: [f32; 8],
    /// Tagged child references.
    pub child: [ChildRef; 8],
}

const _: () = assert!(size_of::<InnerNode>() == 224);

impl InnerNode {
    /// A node with every lane empty.
    pub const EMPTY: InnerNode = InnerNode {
        min_x: [f32::INFINITY; 8],
        max_x: [f32::NEG_INFINITY; 8],
        min_y: [f32::INFINITY; 8],
        max_y: [f32::NEG_INFINITY; 8],
        min_z: [f32::INFINITY; 8],
        max_z: [f32::NEG_INFINITY; 8],
        child: [0; 8],
    };

    /// Sets lane `k` to child `r` with box `b`.
    pub fn set(&mut self, k: usize, r: ChildRef, b: &Aabb) {
        self.min_x[k] = b.min.x;
        self.min_y[k] = b.min.y;
        self.min_z[k] = b.min.z;
        self.max_x[k] = b.max.x;
        self.max_y[k] = b.max.y;
        self.max_z[k] = b.max.z;
        self.child[k] = r;
    }

    /// The box of lane `k`.
    #[inline]
    pub fn child_box(&self, k: usize) -> Aabb {
        Aabb::new(
            Vec3A::new(self.min_x[k], self.min_y[k], self.min_z[k]),
            Vec3A::new(self.max_x[k], self.max_y[k], self.max_z[k]),
        )
    }
}

/// The compressed multi-leaf node of the paper's Listing 1 (72 bytes): the
/// dequantization frame and eight 8-bit child boxes; every child is a leaf
/// and the leaf data follows the node in memory (no child pointers).
///
/// # Layout
/// | bytes | field | meaning |
/// |---|---|---|
/// | 0–11  | `start` | frame origin (f32 × 3): the node's float box minimum |
/// | 12–23 | `step`  | size of one quantum per axis (f32 × 3; 0 for a flat axis) |
/// | 24–31 | `lo_x`  | child box minima, x, lanes 0–7 (u8) |
/// | 32–39 | `hi_x`  | child box maxima, x |
/// | 40–47 | `lo_y`  | |
/// | 48–55 | `hi_y`  | |
/// | 56–63 | `lo_z`  | |
/// | 64–71 | `hi_z`  | |
///
/// A child box decodes as `start + q as f32 * step` per bound, a multiply
/// then an add (no fused multiply-add, in the scalar and every SIMD path, so
/// all of them give the same bits). The paper stores the frame's *extent*;
/// storing the step instead saves the divide by 255 per bound and is the
/// same information. Bytes are in structure-of-arrays order so that one
/// 8-byte load gives a bound of all eight lanes.
///
/// Right behind the node (in the arena) come 8 bytes of *leaf ends*
/// (`ends[k]` = triangles in lanes `0..=k`; a lane with no triangles is
/// unused and its box is never reported) and then one leaf block
/// ([`super::encode`]) holding all the node's triangles, lane by lane.
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct MultiLeafNode {
    /// Frame origin.
    pub start: [f32; 3],
    /// Quantum size per axis.
    pub step: [f32; 3],
    /// Quantized minima, x.
    pub lo_x: [u8; 8],
    /// Quantized maxima, x.
    pub hi_x: [u8; 8],
    /// Quantized minima, y.
    pub lo_y: [u8; 8],
    /// Quantized maxima, y.
    pub hi_y: [u8; 8],
    /// Quantized minima, z.
    pub lo_z: [u8; 8],
    /// Quantized maxima, z.
    pub hi_z: [u8; 8],
}

const _: () = assert!(size_of::<MultiLeafNode>() == 72);

/// Size of a [`MultiLeafNode`] in 4-byte arena words.
pub const MULTI_WORDS: usize = 18;
/// Words of leaf ends right behind a multi-leaf node.
pub const ENDS_WORDS: usize = 2;

impl MultiLeafNode {
    /// Decodes lane `k`'s box (conservative: it contains the lane's
    /// triangles).
    #[inline]
    pub fn child_box(&self, k: usize) -> Aabb {
        let d = |a: usize, q: u8| self.start[a] + q as f32 * self.step[a];
        Aabb::new(
            Vec3A::new(d(0, self.lo_x[k]), d(1, self.lo_y[k]), d(2, self.lo_z[k])),
            Vec3A::new(d(0, self.hi_x[k]), d(1, self.hi_y[k]), d(2, self.hi_z[k])),
        )
    }

    /// Reads the node at word offset `at` of `arena`. Panics if it runs
    /// past the end (a verified tree never does).
    #[inline]
    pub fn read(arena: &[u32], at: usize) -> MultiLeafNode {
        bytemuck::pod_read_unaligned(bytemuck::cast_slice(&arena[at..at + MULTI_WORDS]))
    }
}

/// The 8-bit conservative quantization frame of a multi-leaf node:
/// `255` steps over the node's box per axis, the step grown by ulps until
/// the last grid point reaches the box's maximum. A minimum rounds down to
/// the largest grid point at or below it, a maximum up to the smallest at
/// or above it, both checked with the decoder's own `f32` arithmetic.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// The box minimum.
    pub start: [f32; 3],
    /// One quantum per axis (0 for a flat axis).
    pub step: [f32; 3],
}

const MAX_Q: u32 = 255;

impl Frame {
    /// The frame over `b` (finite, non-empty).
    pub fn new(b: &Aabb) -> Frame {
        let n = MAX_Q as f32;
        let mut step = [0f32; 3];
        for (a, s) in step.iter_mut().enumerate() {
            let (lo, hi) = (b.min[a], b.max[a]);
            if hi > lo {
                let mut st = (hi - lo) / n;
                if st == 0.0 {
                    st = f32::from_bits(1);
                }
                // Grow the step until the last grid point reaches `hi`: by
                // ulps while close, by doubling the gap if far (huge
                // coordinates whose difference overflowed are not finite
                // input, so this ends).
                let mut ulps = 1u32;
                while lo + n * st < hi {
                    st = f32::from_bits(st.to_bits() + ulps);
                    ulps = ulps.saturating_mul(2);
                }
                *s = st;
            }
        }
        Frame {
            start: b.min.to_array(),
            step,
        }
    }

    #[inline]
    fn deq(&self, a: usize, q: u32) -> f32 {
        self.start[a] + q as f32 * self.step[a]
    }

    /// The largest `q` whose grid point is at or below `v` (0 if none).
    fn floor(&self, a: usize, v: f32) -> u32 {
        if self.step[a] == 0.0 {
            return 0;
        }
        let guess = ((v - self.start[a]) / self.step[a]).floor();
        let mut q = guess.clamp(0.0, MAX_Q as f32) as u32;
        while q > 0 && self.deq(a, q) > v {
            q -= 1;
        }
        while q < MAX_Q && self.deq(a, q + 1) <= v {
            q += 1;
        }
        q
    }

    /// The smallest `q` whose grid point is at or above `v` (255 if none).
    fn ceil(&self, a: usize, v: f32) -> u32 {
        if self.step[a] == 0.0 {
            return 0;
        }
        let guess = ((v - self.start[a]) / self.step[a]).ceil();
        let mut q = guess.clamp(0.0, MAX_Q as f32) as u32;
        while q < MAX_Q && self.deq(a, q) < v {
            q += 1;
        }
        while q > 0 && self.deq(a, q - 1) >= v {
            q -= 1;
        }
        q
    }

    /// Conservative quantization of `b` (inside the frame's box): the
    /// `(lo, hi)` grid indices per axis.
    pub fn quantize(&self, b: &Aabb) -> ([u8; 3], [u8; 3]) {
        let mut lo = [0u8; 3];
        let mut hi = [0u8; 3];
        for a in 0..3 {
            let l = self.floor(a, b.min[a]);
            lo[a] = l as u8;
            hi[a] = self.ceil(a, b.max[a]).max(l) as u8;
        }
        (lo, hi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_rounds_outward_even_far_from_origin() {
        let boxes = [
            Aabb::from_arrays([0.0; 3], [1.0; 3]),
            Aabb::from_arrays([1e7, -1e7, 3.0], [1e7 + 0.5, -1e7 + 2.0, 3.0]),
            Aabb::from_arrays([-3e9, 1e-30, 0.0], [3e9, 2e-30, 1e-3]),
        ];
        for outer in boxes {
            let f = Frame::new(&outer);
            for a in 0..3 {
                assert!(f.deq(a, 255) >= outer.max[a]);
            }
            let e = outer.extent();
            for k in 0..50 {
                let s = k as f32 / 50.0;
                let inner = Aabb::new(
                    outer.min + e * s * 0.5,
                    outer.min + e * (0.5 + s * 0.5).min(1.0),
                );
                let (lo, hi) = f.quantize(&inner);
                for a in 0..3 {
                    assert!(f.deq(a, lo[a] as u32) <= inner.min[a], "{inner:?}");
                    assert!(f.deq(a, hi[a] as u32) >= inner.max[a], "{inner:?}");
                }
            }
        }
    }
}
