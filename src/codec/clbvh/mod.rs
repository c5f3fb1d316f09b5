//! CLBVH: compressed-leaf BVHs (Benthin, Wald, Woop, Áfra, HPG 2018, §3–4).
//!
//! The binary canonical tree is collapsed into an 8-wide tree (module
//! `collapse`) with two multi-node types:
//!
//! - **regular inner multi-nodes** ([`InnerNode`]): eight `f32` child boxes
//!   and eight tagged child references; a child is another inner node, an
//!   isolated leaf, or a compressed multi-leaf node;
//! - **compressed multi-leaf nodes** ([`MultiLeafNode`], 72 bytes): the
//!   dequantization frame and eight 8-bit child boxes rounded outward; every
//!   child is a leaf, and the leaves' data (the *leaf block*, see
//!   `encode.rs` docs) is stored right behind the node, so the
//!   node needs no child pointers.
//!
//! The builder's threshold is the paper's `N × M`: a subtree of at most
//! `8 · M` triangles ([`ClOptions::leaf_size`] is `M`) that the SAH does not
//! make a single leaf becomes one multi-leaf node, its children chosen by
//! the same greedy SAH collapse as the inner nodes'; larger subtrees become
//! regular inner nodes, some of whose children may be isolated leaves.
//!
//! Two leaf variants ([`LeafKind`]): *fast* leaves hold the triangles'
//! corners pre-gathered (the paper's `triangle4`-style "best speed" leaves)
//! and their ids; *compact* leaves hold each vertex index used in the leaf
//! block once (u32) and three 8-bit indices into that list per triangle
//! (the paper's §4.5 proof of concept), and the mesh keeps only its
//! vertices.
//!
//! # Choices where the paper leaves them open
//!
//! - **Collapse**: the canonical builder makes one triangle a leaf; a
//!   bottom-up SAH pass (leaf cost `1 · A · n` against split cost
//!   `1 · A + children`) merges subtrees of at most `M` triangles into
//!   leaves, and a wide node's children are found by opening the largest
//!   child the SAH wants split until there are eight. Embree's BVH8 builder
//!   splits top-down with the SAH directly; collapsing the one canonical
//!   tree keeps every codec on the same tree.
//! - **Per-lane triangle counts**: the paper drops the 8-bit offsets when
//!   each leaf is exactly one `triangle4`. Leaves here hold 1 to `8 · M`
//!   triangles, so the 8 bytes of *leaf ends* (cumulative counts) stay, as
//!   the first part of the leaf data, not of the 72-byte node. A lane with
//!   no triangles is unused.
//! - **Frame**: the node's float box minimum and one quantum per axis
//!   (`extent / 255` grown by ulps until `start + 255 · step` reaches the
//!   maximum), so that decoding is one multiply and one add per bound.
//! - **32-bit child references** (index or arena word offset, 30 bits, and
//!   a 2-bit tag) instead of Embree's 64-bit pointers: 224-byte inner
//!   nodes; a tree that does not fit is an error.
//! - **Triangle ids** stay the mesh's original ids; the compact variant
//!   finds a triangle by id through a slot table (4 bytes a triangle plus 8
//!   a leaf block), the fast one through the mesh's index array, which it
//!   keeps for smooth shading.
//! - **Traversal**: the cursor's `children` hands a node's up to eight
//!   child boxes to the queries as one batch: an inner node's rows are
//!   loaded as stored, a multi-leaf node's 8-bit boxes are dequantized all
//!   at once ([`simd`]) into the lanes. Against the default (child by
//!   child through `for_each_child`) this took 15–45 % off every query of
//!   `examples/cursor_bench.rs` but packets (the same), on a 300 k-triangle
//!   statue.
//! - **Rays** (closest and any hit) have a traversal of their own
//!   (module `trace`, through the cursor's
//!   [`closest_hit`](crate::query::RayCursor::closest_hit) and
//!   [`any_hit`](crate::query::RayCursor::any_hit)): eight stored boxes
//!   an AVX2 instruction (a multi-leaf node's dequantized in registers),
//!   nearest child first (one comparison for two), a single hit child
//!   entered without the stack, a multi-leaf node's lanes tested right
//!   away, its leaf block's first kilobyte asked for from memory together
//!   with the node (without that, the block was a second cache miss after
//!   the node's: +14 % camera rays/s on the 1 M statue, +19 % on the
//!   10 M), and four triangles of a lane at once with the watertight
//!   test's own operations. The same hits, bit for bit, as the generic
//!   traversal (tested); 1.05–1.07× Embree's camera rays/s on the 1 M
//!   statue (`peers`, one thread; 0.95× without the prefetch). Without
//!   AVX2 the generic traversal runs.
//! - **Huge pages**: the node arrays, the vertices and the triangles are
//!   moved into memory advised for transparent huge pages
//!   ([`huge`](crate::codec::common::huge)) when the tree is encoded or
//!   read, as Embree does with its own; see that module for the figures.
//! - **Uncompressed reference**: [`ClOptions::multi_leaf`] `= false` gives
//!   the same 8-wide tree with regular nodes only (the paper's BVH8), for
//!   the figures.

mod collapse;
mod contract;
mod cursor;
mod encode;
mod error;
pub mod file;
mod node;
pub mod simd;
mod trace;
mod verify;

use glam::Vec3A;

use crate::codec::ByteSize;
use crate::codec::common::MassProps;
use crate::codec::settings::{CodecOptions, Setting, Settings, SettingsError};
use crate::contact::EdgeFlags;
use crate::geom::Aabb;
use crate::mesh::Mesh;

pub use collapse::{NODE_COST, TRIANGLE_COST};
pub use cursor::{ClNode, NodeKind};
pub use encode::MAX_LEAF_SIZE;
pub use error::ClError;
pub use node::{
    ChildRef, ENDS_WORDS, InnerNode, MAX_REF_INDEX, MULTI_WORDS, MultiLeafNode, TAG_EMPTY,
    TAG_INNER, TAG_LEAF, TAG_MULTI, child_ref, ref_index, ref_tag,
};

/// What a leaf block stores per triangle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum LeafKind {
    /// Pre-gathered corners (36 bytes) and the id (4 bytes).
    #[default]
    Fast,
    /// De-duplicated vertex indices, 8-bit local corner indices, the id.
    Compact,
}

/// Encoder settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ClOptions {
    /// `M`, the most triangles the SAH may merge into one leaf (1 to
    /// [`MAX_LEAF_SIZE`]); the multi-leaf threshold is `8 · M`.
    pub leaf_size: usize,
    /// Leaf data variant.
    pub leaves: LeafKind,
    /// Whether to make compressed multi-leaf nodes (`false`: the
    /// uncompressed 8-wide reference tree).
    pub multi_leaf: bool,
}

impl Default for ClOptions {
    fn default() -> Self {
        Self {
            leaf_size: 4,
            leaves: LeafKind::Fast,
            multi_leaf: true,
        }
    }
}

/// The compact variant's default `M` ([`ClOptions::leaf_size`]): 6, not
/// the fast variant's 4. On the 1 M statue `M = 6` takes compact CLBVH from
/// 32.1 to 28.3 bytes a triangle (fewer multi-leaf nodes, more vertices
/// shared in a leaf block) at the same camera rays/s within the noise of
/// `examples/clbvh_stats.rs` (two alternating runs each, against plain in
/// the same run); the fast variant lost 3–4 % at `M = 6`, so it keeps 4.
pub const COMPACT_LEAF_SIZE: usize = 6;

impl ClOptions {
    /// These settings with `M` raised, if need be, to hold the leaves of a
    /// canonical tree built with up to `leaf` triangles a leaf (the encoder
    /// rejects a tree whose leaves exceed `M`).
    pub fn holding(self, leaf: usize) -> Self {
        Self {
            leaf_size: self.leaf_size.max(leaf),
            ..self
        }
    }

    /// The compact variant with its default leaf size
    /// ([`COMPACT_LEAF_SIZE`]) and otherwise default settings.
    pub fn compact() -> Self {
        Self {
            leaf_size: COMPACT_LEAF_SIZE,
            leaves: LeafKind::Compact,
            ..Self::default()
        }
    }
}

/// A compressed-leaf 8-wide BVH with its mesh.
#[derive(Clone, Debug)]
pub struct ClBvh {
    options: ClOptions,
    inner: Vec<InnerNode>,
    /// Multi-leaf nodes with their leaf data, and isolated leaf blocks.
    arena: Vec<u32>,
    multi_nodes: usize,
    root: ChildRef,
    root_box: Aabb,
    vertices: Vec<[f32; 3]>,
    /// The mesh's triangles (fast variant; empty for compact).
    triangles: Vec<[u32; 3]>,
    /// Compact: each triangle id's slot (its position in leaf order).
    slot_of: Vec<u32>,
    /// Compact: `(first slot, word offset)` of each leaf block, by slot.
    blocks: Vec<[u32; 2]>,
    mass: MassProps,
    /// Active edges by triangle id, computed when encoded.
    edges: EdgeFlags,
}

impl ClBvh {
    /// The options the tree was encoded with.
    pub fn options(&self) -> &ClOptions {
        &self.options
    }

    /// Mass properties at density 1 (computed from the mesh when built).
    pub fn mass(&self) -> MassProps {
        self.mass
    }

    /// Active edges by triangle id (stored in the file).
    pub fn edge_flags(&self) -> &EdgeFlags {
        &self.edges
    }

    /// The regular inner multi-nodes.
    pub fn inner_nodes(&self) -> &[InnerNode] {
        &self.inner
    }

    /// Number of compressed multi-leaf nodes.
    pub fn multi_leaf_count(&self) -> usize {
        self.multi_nodes
    }

    /// The mesh's vertices.
    pub fn vertices(&self) -> &[[f32; 3]] {
        &self.vertices
    }

    /// The root's box.
    pub fn root_box(&self) -> Aabb {
        self.root_box
    }

    /// The three vertex indices of triangle `id` (for smooth shading).
    pub fn vertex_indices(&self, id: u32) -> [u32; 3] {
        match self.options.leaves {
            LeafKind::Fast => self.triangles[id as usize],
            LeafKind::Compact => {
                let slot = self.slot_of[id as usize];
                let b = self.blocks.partition_point(|bl| bl[0] <= slot) - 1;
                let [first, at] = self.blocks[b];
                let at = at as usize;
                let hdr = self.arena[at];
                let (n, u) = ((hdr & 0xFFFF) as usize, (hdr >> 16) as usize);
                let local: &[u8] = bytemuck::cast_slice(&self.arena[at + 1 + u + n..]);
                let j = (slot - first) as usize;
                [0, 1, 2].map(|k| self.arena[at + 1 + local[3 * j + k] as usize])
            }
        }
    }

    /// The mesh back (vertices and triangles in original order).
    pub fn decoded_mesh(&self) -> Mesh {
        let n = match self.options.leaves {
            LeafKind::Fast => self.triangles.len(),
            LeafKind::Compact => self.slot_of.len(),
        };
        Mesh::new(
            self.vertices.clone(),
            (0..n as u32).map(|id| self.vertex_indices(id)).collect(),
        )
    }

    /// The corners of a triangle from its vertex indices.
    #[inline]
    fn corners(&self, v: [u32; 3]) -> crate::geom::Triangle {
        v.map(|i| Vec3A::from(self.vertices[i as usize]))
    }
}

impl ByteSize for ClBvh {
    fn bytes_by_part(&self) -> Vec<(&'static str, usize)> {
        let multi = self.multi_nodes * MULTI_WORDS * 4;
        vec![
            ("inner nodes", self.inner.len() * size_of::<InnerNode>()),
            ("multi-leaf nodes", multi),
            // Leaf ends and leaf blocks.
            ("leaf data", self.arena.len() * 4 - multi),
            ("vertices", self.vertices.len() * 12),
            ("triangles", self.triangles.len() * 12),
            (
                "triangle slots",
                self.slot_of.len() * 4 + self.blocks.len() * 8,
            ),
            ("edge-flags", self.edges.bytes()),
        ]
    }
}

/// Settings of the compact variant ([`ClBvhCompact`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct CompactOptions {
    /// `M`, as [`ClOptions::leaf_size`].
    pub leaf_size: usize,
    /// As [`ClOptions::multi_leaf`].
    pub multi_leaf: bool,
}

impl CompactOptions {
    /// As [`ClOptions::holding`].
    pub fn holding(self, leaf: usize) -> Self {
        Self {
            leaf_size: self.leaf_size.max(leaf),
            ..self
        }
    }
}

impl Default for CompactOptions {
    fn default() -> Self {
        let o = ClOptions::compact();
        Self {
            leaf_size: o.leaf_size,
            multi_leaf: o.multi_leaf,
        }
    }
}

/// The compact variant as a codec of its own (registry name
/// `clbvh-compact`): a [`ClBvh`] with [`LeafKind::Compact`] leaves.
#[derive(Clone, Debug)]
pub struct ClBvhCompact(pub ClBvh);

impl crate::codec::ByteSize for ClBvhCompact {
    fn bytes_by_part(&self) -> Vec<(&'static str, usize)> {
        self.0.bytes_by_part()
    }
}

impl ClOptions {
    /// `leaf_size` as a setting (`clbvh.leaf-size`, and
    /// `clbvh-compact.leaf-size`): `M`, 1 to [`MAX_LEAF_SIZE`].
    pub const LEAF_SIZE: Setting = Setting::whole("leaf-size", 1, MAX_LEAF_SIZE as u64);
    /// `multi_leaf` as a setting (`clbvh.multi-leaf`, and
    /// `clbvh-compact.multi-leaf`): `false` for the uncompressed 8-wide
    /// reference.
    pub const MULTI_LEAF: Setting = Setting::flag("multi-leaf");
}

/// Both variants' own settings.
const LEAF_SETTINGS: &[Setting] = &[ClOptions::LEAF_SIZE, ClOptions::MULTI_LEAF];

impl CodecOptions for ClOptions {
    const SETTINGS: &'static [Setting] = LEAF_SETTINGS;

    /// The options from a front end's settings ([`crate::codec::settings`]):
    /// `clbvh.leaf-size` (`M`, 1 to [`MAX_LEAF_SIZE`]; unset: 4, or the
    /// common leaf size if larger) and `clbvh.multi-leaf` (`false`: the
    /// uncompressed 8-wide reference).
    fn from_settings(s: &Settings) -> Result<Self, SettingsError> {
        let (leaf_size, multi_leaf) = leaf_settings(s, "clbvh", Self::default().leaf_size)?;
        Ok(Self {
            leaf_size,
            multi_leaf,
            ..Self::default()
        })
    }
}

impl CodecOptions for CompactOptions {
    const SETTINGS: &'static [Setting] = LEAF_SETTINGS;

    /// As [`ClOptions`]' settings, with the keys under `clbvh-compact` and
    /// `M` 6 by default.
    fn from_settings(s: &Settings) -> Result<Self, SettingsError> {
        let (leaf_size, multi_leaf) = leaf_settings(s, "clbvh-compact", Self::default().leaf_size)?;
        Ok(Self {
            leaf_size,
            multi_leaf,
        })
    }
}

/// `M` and whether to make multi-leaf nodes, from `codec`'s `leaf-size`
/// and `multi-leaf` settings: `M` is the setting if given, else
/// `default_m` raised to the common leaf size (the encoder rejects a
/// canonical tree whose leaves exceed `M`).
fn leaf_settings(
    s: &Settings,
    codec: &str,
    default_m: usize,
) -> Result<(usize, bool), SettingsError> {
    let (size, multi) = (ClOptions::LEAF_SIZE, ClOptions::MULTI_LEAF);
    let m = s
        .get(codec, size.key)?
        .unwrap_or(default_m.max(s.leaf_size));
    if !size.values.allows(m as u64) {
        return Err(SettingsError::Invalid {
            codec: codec.into(),
            reason: format!("leaf size {m} is not allowed: use {}", size.values),
        });
    }
    Ok((m, s.get(codec, multi.key)?.unwrap_or(true)))
}
