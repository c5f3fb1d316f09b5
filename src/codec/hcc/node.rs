//! The i-HCCMesh words: 4-byte nodes, 4-byte inter-connections, 16-byte
//! low-level headers and 32-byte high-level nodes.
//!
//! # Layout
//!
//! **Node word** (`u32`, HCCMesh Fig. 5; bit 0 is the least significant):
//!
//! | bits  | template intermediate | template leaf | leaf (one triangle) | leaf (several) |
//! |-------|----------------------|---------------|---------------------|-----------------------------|
//! | 0–8   | vertex index 0 | vertex index 0 | corner 0 | block's bit offset, bits 0–8 |
//! | 9–17  | vertex index 1 | vertex index 1 | corner 1 | block's bit offset, bits 9–17 |
//! | 18–26 | vertex index 2 | inter-connection index | corner 2 | bits 18–20: offset bits 18–20; 21–26: triangle count − 1 |
//! | 27–29 | reuse-mask half | reuse-mask half | reuse-mask half | reuse-mask half |
//! | 30–31 | `0` | `1` | `2` | `2` |
//!
//! Vertex indices and corners index the low-level tree's vertex array; a
//! multi-triangle leaf's block (`block.rs`) is at the
//! given bit offset of the tree's block stream. The
//! root node of a low-level tree has no sibling and takes its box from the
//! high-level tree, so an inner root's bits 0–4 hold its template id
//! instead (a leaf root is always template 0).
//!
//! **Inter-connection** (`u32`, one per template leaf): bits 0–8 the
//! vertex index the template leaf's word gave up for the inter-connection
//! index; 9–13 the left child's template id; 14–18 the right child's
//! template id; 19–31 the node index, within the low-level tree, of the left
//! child's template (the right child's template follows it directly, so its
//! index is not stored).
//!
//! **Low-level header** ([`TreeHeader`], 16 bytes) and **high-level node**
//! ([`HighNode`], 32 bytes): see their docs.

/// Bits of a vertex index (the paper's `C`).
pub const INDEX_BITS: u32 = 9;
/// Vertices a low-level tree may hold: fewer than `2^INDEX_BITS`, as §3.1.
pub const MAX_TREE_VERTICES: usize = 1 << INDEX_BITS;
/// Mask of one 9-bit field.
pub const INDEX_MASK: u32 = (1 << INDEX_BITS) - 1;
/// Bits of a node position inside a low-level tree (inter-connections).
pub const POSITION_BITS: u32 = 13;
/// Nodes a low-level tree may hold.
pub const MAX_TREE_NODES: usize = 1 << POSITION_BITS;
/// Bits of a low-level tree's index in a node handle (the rest of its
/// word holds the node's type, template and place in the template).
pub const TREE_INDEX_BITS: u32 = 20;
/// Low-level trees a model may hold: about 600 M triangles at the
/// 500–700 triangles a tree the decomposition makes.
pub const MAX_TREES: usize = 1 << TREE_INDEX_BITS;
/// Inter-connections a low-level tree may hold (a 9-bit index).
pub const MAX_TREE_INTERCONNECTIONS: usize = 1 << INDEX_BITS;

/// Node type: an inner node whose children are in the same template.
pub const TYPE_INNER: u32 = 0;
/// Node type: an inner node whose children start new templates.
pub const TYPE_TEMPLATE_LEAF: u32 = 1;
/// Node type: a leaf of the original tree.
pub const TYPE_LEAF: u32 = 2;

/// Shift of the 3-bit reuse-mask half.
pub const MASK_SHIFT: u32 = 27;
/// Shift of the 2-bit node type.
pub const TYPE_SHIFT: u32 = 30;

/// Bits of a multi-triangle leaf's block offset (in its tree's stream).
pub const MULTI_OFFSET_BITS: u32 = 21;
/// Shift of a multi-triangle leaf's triangle count − 1 (6 bits).
pub const MULTI_COUNT_SHIFT: u32 = MULTI_OFFSET_BITS;
/// The most triangles a multi-triangle leaf may hold (a 6-bit count − 1).
pub const MULTI_COUNT_LIMIT: usize = 1 << (3 * INDEX_BITS - MULTI_COUNT_SHIFT);
/// Triangles a low-level tree may hold (so that its blocks fit the offset
/// field: at most 2^14 · 27 + 2^12 · 27 bits).
pub const MAX_TREE_TRIANGLES: usize = 1 << 14;

/// The node type (bits 30–31).
#[inline(always)]
pub fn node_type(w: u32) -> u32 {
    w >> TYPE_SHIFT
}

/// The 9-bit field `j` (0, 1 or 2).
#[inline(always)]
pub fn field(w: u32, j: u32) -> u32 {
    w >> (INDEX_BITS * j) & INDEX_MASK
}

/// The reuse-mask half (bits 27–29).
#[inline(always)]
pub fn mask_half(w: u32) -> u32 {
    w >> MASK_SHIFT & 7
}

/// A node word from its parts. Fields must fit 9 bits, the mask 3.
#[inline]
pub fn pack_node(fields: [u32; 3], mask: u32, ty: u32) -> u32 {
    debug_assert!(fields.iter().all(|&f| f <= INDEX_MASK) && mask < 8 && ty < 3);
    fields[0]
        | fields[1] << INDEX_BITS
        | fields[2] << (2 * INDEX_BITS)
        | mask << MASK_SHIFT
        | ty << TYPE_SHIFT
}

/// A multi-triangle leaf's `(block bit offset, triangle count)` in its
/// tree.
#[inline(always)]
pub fn multi_leaf(w: u32) -> (u32, u32) {
    (
        w & ((1 << MULTI_OFFSET_BITS) - 1),
        (w >> MULTI_COUNT_SHIFT & 63) + 1,
    )
}

/// An inter-connection's parts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Interconnection {
    /// The vertex index displaced from the template leaf's third field.
    pub vertex: u32,
    /// Template id of the left child's template.
    pub left_template: u8,
    /// Template id of the right child's template.
    pub right_template: u8,
    /// Node index, in the low-level tree, of the left child's template.
    pub left_start: u32,
}

impl Interconnection {
    /// The packed word.
    #[inline]
    pub fn pack(&self) -> u32 {
        debug_assert!(self.vertex <= INDEX_MASK);
        debug_assert!((self.left_start as usize) < MAX_TREE_NODES);
        self.vertex
            | (self.left_template as u32) << 9
            | (self.right_template as u32) << 14
            | self.left_start << 19
    }

    /// Unpacks a word.
    #[inline(always)]
    pub fn unpack(w: u32) -> Self {
        Self {
            vertex: w & INDEX_MASK,
            left_template: (w >> 9 & 31) as u8,
            right_template: (w >> 14 & 31) as u8,
            left_start: w >> 19,
        }
    }
}

/// The header of one low-level tree: where its parts start in the shared
/// arrays. Counts are the differences to the next header's starts (the
/// paper stores counts; starts give the same in the same bytes and need no
/// prefix sum at runtime).
///
/// # Layout
/// | bytes | field | meaning |
/// |---|---|---|
/// | 0–3   | `node_start`   | first node word of the tree |
/// | 4–7   | `ic_start`     | first inter-connection of the tree |
/// | 8–11  | `vertex_start` | first vertex of the tree |
/// | 12–15 | `first_triangle` | storage rank of the tree's first triangle |
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct TreeHeader {
    /// First node word of the tree.
    pub node_start: u32,
    /// First inter-connection of the tree.
    pub ic_start: u32,
    /// First vertex of the tree's vertex array.
    pub vertex_start: u32,
    /// Storage rank of the tree's first triangle (ranks are dense, tree by
    /// tree; the id map turns a rank into the input id).
    pub first_triangle: u32,
}

const _: () = assert!(size_of::<TreeHeader>() == 16);

/// Flag in [`HighNode::b`] marking a high-level leaf (a low-level tree).
pub const HIGH_LEAF: u32 = 0x8000_0000;

/// A node of the uncompressed high-level tree (§3.2: "we do not compress
/// the high-level BVH"): the plain 32-byte node.
///
/// # Layout
/// | bytes | field | meaning |
/// |---|---|---|
/// | 0–11  | `min` | box minimum, 3 × f32 |
/// | 12–23 | `max` | box maximum, 3 × f32 |
/// | 24–27 | `a`   | inner: left child; leaf: low-level tree index |
/// | 28–31 | `b`   | inner: right child; leaf: [`HIGH_LEAF`] |
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct HighNode {
    /// Box minimum.
    pub min: [f32; 3],
    /// Box maximum.
    pub max: [f32; 3],
    /// Left child or low-level tree index.
    pub a: u32,
    /// Right child or [`HIGH_LEAF`].
    pub b: u32,
}

const _: () = assert!(size_of::<HighNode>() == 32);

impl HighNode {
    /// Whether this node is a low-level tree.
    #[inline(always)]
    pub fn is_leaf(&self) -> bool {
        self.b & HIGH_LEAF != 0
    }
}

// ---------------------------------------------------------------------------
// The cursor's node handle. It lives with the words it decodes, not in
// `cursor.rs`, so that `cursor.rs` and `trace.rs` both depend on it and not
// on each other.

use super::template::{MAX_TEMPLATE_NODES, TEMPLATE_COUNT};
use crate::geom::Aabb;
pub(super) const KIND_HIGH: u8 = 3;
pub(super) const KIND_EMPTY: u8 = 4;
/// The root of a low-level tree not yet opened (out of core: its box is
/// the high-level leaf's; its word is read when the tree is entered).
pub(super) const KIND_UNOPENED: u8 = 5;

/// A node handle: the node's decoded box (the parent box its children are
/// decoded against), where it is, and which template it sits in. 32 bytes,
/// two 16-byte rows, so that the two-tree traversal's node pairs (two
/// handles and two boxes) stay small.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub struct HccNode {
    min: [f32; 3],
    /// Node word index, or high-level node index.
    pos: u32,
    max: [f32; 3],
    /// The low-level tree (unused for high-level nodes) above
    /// [`META_TREE_SHIFT`], the node's offset from its template's first
    /// word (4 bits), the template's id (5 bits) and the node type
    /// (`TYPE_*`, [`KIND_HIGH`], [`KIND_EMPTY`], [`KIND_UNOPENED`]; 3 bits).
    meta: u32,
}

/// Where the tree index starts in [`HccNode`]'s meta word.
const META_TREE_SHIFT: u32 = 32 - TREE_INDEX_BITS;
// The type, the template and the place in it below the tree index.
const _: () = assert!(META_TREE_SHIFT >= 3 + 5 + 4);
const _: () = assert!(MAX_TEMPLATE_NODES <= 16 && TEMPLATE_COUNT <= 32);
const _: () = assert!(std::mem::size_of::<HccNode>() == 32);

impl HccNode {
    #[inline(always)]
    pub(super) fn new(
        bounds: Aabb,
        tree: u32,
        pos: u32,
        block: u32,
        template: u8,
        kind: u8,
    ) -> Self {
        debug_assert!(tree >> TREE_INDEX_BITS == 0 && pos - block < 16);
        Self {
            min: bounds.min.to_array(),
            pos,
            max: bounds.max.to_array(),
            meta: tree << META_TREE_SHIFT
                | (pos - block) << 8
                | u32::from(template) << 3
                | u32::from(kind),
        }
    }

    /// The node's decoded box.
    #[inline(always)]
    pub fn bounds(&self) -> Aabb {
        Aabb::from_arrays(self.min, self.max)
    }

    /// The node word index (low-level nodes).
    #[inline(always)]
    pub(super) fn pos(&self) -> u32 {
        self.pos
    }

    /// The node word index of the first node of the node's template.
    #[inline(always)]
    pub(super) fn block(&self) -> u32 {
        self.pos - (self.meta >> 8 & 15)
    }

    #[inline(always)]
    pub(super) fn kind(&self) -> u8 {
        (self.meta & 7) as u8
    }

    #[inline(always)]
    pub(super) fn template_id(&self) -> u8 {
        (self.meta >> 3 & 31) as u8
    }

    /// The low-level tree the node is in (low-level nodes).
    #[inline(always)]
    pub(super) fn tree(&self) -> u32 {
        self.meta >> META_TREE_SHIFT
    }

    /// The same node, said to be in low-level tree `tree` (a one-tree
    /// i-HCCMesh's node as a node of the whole model, and back).
    #[inline(always)]
    pub(super) fn in_tree(mut self, tree: u32) -> Self {
        self.meta = self.meta & ((1 << META_TREE_SHIFT) - 1) | tree << META_TREE_SHIFT;
        self
    }

    /// The high-level node `i` with box `bounds`.
    #[inline(always)]
    pub(super) fn high(i: u32, bounds: Aabb) -> Self {
        Self::new(bounds, 0, i, i, 0, KIND_HIGH)
    }

    /// The root of low-level tree `tree`, box `bounds`, before the tree is
    /// read (see [`HccNode::is_unopened`]).
    #[inline(always)]
    pub(super) fn unopened(tree: u32, bounds: Aabb) -> Self {
        Self::new(bounds, tree, 0, 0, 0, KIND_UNOPENED)
    }

    /// Whether this is a low-level tree's root not yet read: only the
    /// out-of-core mode makes them, so that a traversal decodes a tree
    /// when it enters the tree's box, not when it meets the box.
    #[inline(always)]
    pub(super) fn is_unopened(&self) -> bool {
        self.kind() == KIND_UNOPENED
    }

    /// The root of an empty model.
    pub(super) fn empty() -> Self {
        Self::new(Aabb::EMPTY, 0, 0, 0, 0, KIND_EMPTY)
    }

    /// Whether this is a high-level node (a high-level leaf is the root of
    /// its low-level tree, not a high-level node).
    #[inline(always)]
    pub(super) fn is_high(&self) -> bool {
        self.kind() == KIND_HIGH
    }

    /// Whether this is a leaf of a low-level tree, or an empty model's
    /// root.
    #[inline(always)]
    pub(super) fn is_leaf(&self) -> bool {
        self.kind() == TYPE_LEAF as u8 || self.kind() == KIND_EMPTY
    }

    /// Whether this is an empty model's root.
    #[inline(always)]
    pub(super) fn is_empty(&self) -> bool {
        self.kind() == KIND_EMPTY
    }

    /// The template id of the template the node sits in (low-level nodes;
    /// `None` for high-level nodes).
    pub fn template(&self) -> Option<u8> {
        (self.kind() <= TYPE_LEAF as u8).then_some(self.template_id())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_round_trip() {
        let w = pack_node([511, 3, 257], 5, TYPE_TEMPLATE_LEAF);
        assert_eq!(
            [
                field(w, 0),
                field(w, 1),
                field(w, 2),
                mask_half(w),
                node_type(w)
            ],
            [511, 3, 257, 5, 1]
        );
        let ic = Interconnection {
            vertex: 300,
            left_template: 25,
            right_template: 17,
            left_start: 8191,
        };
        assert_eq!(Interconnection::unpack(ic.pack()), ic);
    }
}
