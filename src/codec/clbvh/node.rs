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
/// (`encode.rs`) holding all the node's triangles, lane by lane.
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::codec::common::quant::Grid;

    #[test]
    fn eight_bit_boxes_round_outward_even_far_from_origin() {
        let boxes = [
            Aabb::from_arrays([0.0; 3], [1.0; 3]),
            Aabb::from_arrays([1e7, -1e7, 3.0], [1e7 + 0.5, -1e7 + 2.0, 3.0]),
            Aabb::from_arrays([-3e9, 1e-30, 0.0], [3e9, 2e-30, 1e-3]),
        ];
        for outer in boxes {
            let f = Grid::new(&outer, 8);
            let deq = |a: usize, q: u32| f.origin[a] + q as f32 * f.step[a];
            for a in 0..3 {
                assert!(deq(a, 255) >= outer.max[a]);
            }
            let e = outer.extent();
            for k in 0..50 {
                let s = k as f32 / 50.0;
                let inner = Aabb::new(
                    outer.min + e * s * 0.5,
                    outer.min + e * (0.5 + s * 0.5).min(1.0),
                );
                let q = f.quantize(&inner);
                for a in 0..3 {
                    assert!(q.max[a] <= 255);
                    assert!(deq(a, q.min[a]) <= inner.min[a], "{inner:?}");
                    assert!(deq(a, q.max[a]) >= inner.max[a], "{inner:?}");
                }
                let m = MultiLeafNode {
                    start: f.origin.to_array(),
                    step: f.step.to_array(),
                    lo_x: [q.min.x as u8; 8],
                    hi_x: [q.max.x as u8; 8],
                    lo_y: [q.min.y as u8; 8],
                    hi_y: [q.max.y as u8; 8],
                    lo_z: [q.min.z as u8; 8],
                    hi_z: [q.max.z as u8; 8],
                };
                assert!(m.child_box(3).contains(&inner));
            }
        }
    }
}
