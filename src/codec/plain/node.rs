//! The 32-byte plain node.

use crate::build::LEAF_FLAG;
use crate::geom::Aabb;

/// RACBVH Listing 1: an AABB and two indices.
///
/// # Layout
/// | bytes | field | meaning |
/// |---|---|---|
/// | 0–11  | `min`   | box minimum, 3 × f32 |
/// | 12–23 | `max`   | box maximum, 3 × f32 |
/// | 24–27 | `left`  | inner: left child index; leaf with one triangle: the triangle's id; leaf with several: first slot in the leaf-id array |
/// | 28–31 | `right` | inner: right child index; leaf: [`LEAF_FLAG`] \| triangle count |
///
/// All fields little-endian when stored in a file. [`LEAF_FLAG`] is the
/// canonical tree's leaf flag, `0x8000_0000`: the file format fixes it.
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct PlainNode {
    /// Box minimum.
    pub min: [f32; 3],
    /// Box maximum.
    pub max: [f32; 3],
    /// Left child, or triangle id / first leaf slot.
    pub left: u32,
    /// Right child, or [`LEAF_FLAG`] | count.
    pub right: u32,
}

const _: () = assert!(std::mem::size_of::<PlainNode>() == 32);
const _: () = assert!(LEAF_FLAG == 0x8000_0000);

impl PlainNode {
    /// Whether this node is a leaf.
    #[inline]
    pub fn is_leaf(&self) -> bool {
        self.right & LEAF_FLAG != 0
    }

    /// Number of triangles of a leaf.
    #[inline]
    pub fn leaf_count(&self) -> u32 {
        self.right & !LEAF_FLAG
    }

    /// The box.
    #[inline]
    pub fn aabb(&self) -> Aabb {
        Aabb::from_arrays(self.min, self.max)
    }
}
