//! The one builder: a mesh in, a [`CanonicalBvh`] out.
//!
//! The builder knows no codec. It produces a binary tree with `f32` boxes
//! (binned SAH, module `sah`), one triangle per leaf by default (the setting all
//! three papers assume) or up to [`BuildOptions::max_leaf_triangles`], and
//! puts the nodes in the order the [`Layout`] asks for (module `layout`). Every
//! codec consumes the result.
//!
//! It takes any finite mesh at any scale: nothing recurses over the tree (a
//! build needs the same stack for a collinear mesh as for a statue), a node
//! the SAH cannot split (flat or collinear boxes, identical centroids) is
//! split at a median, and no tree is taller than `2⌊log2 n⌋ + 16` over `n`
//! triangles ([`CanonicalBvh::height`]). The tree is the same whatever the
//! number of threads.
//!
//! A model larger than memory is split first ([`chunked`]): read from its
//! file as it is parsed, partitioned into spatial chunks on disk, each
//! small enough for this builder; a codec's out-of-core encoder builds the
//! chunks one at a time and joins them under the tree over the chunks
//! (o-HCCMesh's [`encode_streamed`](crate::codec::hcc::ooc::encode_streamed)).
//! The builder itself stays in-memory and format-blind.

pub mod chunked;
mod layout;
mod sah;

use std::str::FromStr;

use crate::geom::Aabb;
use crate::mesh::Mesh;

pub use layout::CACHE_EFFICIENT_BLOCKS;

/// The node order of a [`CanonicalBvh`]. The root is node 0 in every layout.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "kebab-case"))]
pub enum Layout {
    /// Pre-order, left child right after its parent.
    #[default]
    DepthFirst,
    /// The van Emde Boas layout: the top half of the tree by height, then
    /// each bottom subtree, recursively.
    VanEmdeBoas,
    /// Probability-driven clusters after Yoon & Manocha 2006 (see
    /// the `build::layout` module docs for the exact variant).
    CacheEfficient,
}

impl Layout {
    /// Every layout, in command-line order.
    pub const ALL: [Layout; 3] = [
        Layout::DepthFirst,
        Layout::VanEmdeBoas,
        Layout::CacheEfficient,
    ];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Layout::DepthFirst => "depth-first",
            Layout::VanEmdeBoas => "van-emde-boas",
            Layout::CacheEfficient => "cache-efficient",
        }
    }
}

impl std::fmt::Display for Layout {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Layout {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Layout::ALL
            .into_iter()
            .find(|l| l.name() == s)
            .ok_or_else(|| {
                format!("unknown layout {s:?}; use depth-first, van-emde-boas or cache-efficient")
            })
    }
}

/// Builder settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BuildOptions {
    /// The most triangles a leaf may hold (1 by default, as in the papers).
    pub max_leaf_triangles: usize,
    /// The node order.
    pub layout: Layout,
    /// SAH bins per axis (2–255; 32 by default).
    pub bins: usize,
}

impl Default for BuildOptions {
    fn default() -> Self {
        Self {
            max_leaf_triangles: 1,
            layout: Layout::DepthFirst,
            bins: 32,
        }
    }
}

/// What can stop a build.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum BuildError {
    /// `max_leaf_triangles` must be at least 1 and at most 2^16.
    #[error("max_leaf_triangles must be between 1 and 65536, got {0}")]
    LeafSize(usize),
    /// The SAH needs between 2 and 255 bins.
    #[error("bins must be between 2 and 255, got {0}")]
    Bins(usize),
    /// Node indices are 32-bit.
    #[error("{0} triangles is more than a 32-bit BVH can index (at most 2^31 - 1)")]
    TooManyTriangles(usize),
    /// A triangle refers to a vertex that does not exist or a coordinate
    /// is not finite: validate the mesh first.
    #[error("the mesh is invalid: {0}")]
    InvalidMesh(String),
}

/// Flag in [`CanonicalNode::b`] marking a leaf; the low bits hold the count.
pub const LEAF_FLAG: u32 = 0x8000_0000;

/// One node of a [`CanonicalBvh`]: the same 32 bytes as RACBVH's Listing 1.
///
/// - inner node: `a` = left child index, `b` = right child index;
/// - leaf: `a` = first index into [`CanonicalBvh::leaf_triangles`],
///   `b` = [`LEAF_FLAG`] | triangle count.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct CanonicalNode {
    /// Box minimum.
    pub min: [f32; 3],
    /// Box maximum.
    pub max: [f32; 3],
    /// Left child, or first leaf-triangle slot.
    pub a: u32,
    /// Right child, or [`LEAF_FLAG`] | count.
    pub b: u32,
}

impl CanonicalNode {
    /// Whether this node is a leaf.
    #[inline]
    pub fn is_leaf(&self) -> bool {
        self.b & LEAF_FLAG != 0
    }

    /// The box.
    #[inline]
    pub fn aabb(&self) -> Aabb {
        Aabb::from_arrays(self.min, self.max)
    }

    /// Left and right child of an inner node.
    #[inline]
    pub fn children(&self) -> [u32; 2] {
        [self.a, self.b]
    }

    /// The range into [`CanonicalBvh::leaf_triangles`] of a leaf.
    #[inline]
    pub fn leaf_range(&self) -> std::ops::Range<usize> {
        let first = self.a as usize;
        first..first + (self.b & !LEAF_FLAG) as usize
    }
}

/// The codec-independent BVH: binary, `f32` boxes, nodes in layout order
/// with the root at index 0.
#[derive(Clone, Debug)]
pub struct CanonicalBvh {
    /// Nodes in layout order.
    pub nodes: Vec<CanonicalNode>,
    /// Parent of each node (`u32::MAX` for the root).
    pub parents: Vec<u32>,
    /// Original mesh triangle ids, in leaf order; leaves index ranges of it.
    pub leaf_triangles: Vec<u32>,
    /// The layout the nodes are in.
    pub layout: Layout,
    /// The leaf size the tree was built with.
    pub max_leaf_triangles: usize,
}

impl CanonicalBvh {
    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Number of triangles referenced by the leaves.
    pub fn triangle_count(&self) -> usize {
        self.leaf_triangles.len()
    }

    /// The root's box (empty for an empty tree).
    pub fn root_aabb(&self) -> Aabb {
        self.nodes.first().map(|n| n.aabb()).unwrap_or(Aabb::EMPTY)
    }

    /// Height of the tree (a single leaf has height 1).
    pub fn height(&self) -> usize {
        let mut best = 0;
        let mut stack = vec![(0u32, 1usize)];
        while let Some((i, d)) = stack.pop() {
            best = best.max(d);
            let n = &self.nodes[i as usize];
            if !n.is_leaf() {
                stack.push((n.a, d + 1));
                stack.push((n.b, d + 1));
            }
        }
        best
    }
}

/// Builds the canonical BVH of `mesh`. `progress(done, total)` is called
/// from any thread as triangles reach their leaves and as the layout runs.
pub fn build(
    mesh: &Mesh,
    options: &BuildOptions,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<CanonicalBvh, BuildError> {
    if options.max_leaf_triangles == 0 || options.max_leaf_triangles > 1 << 16 {
        return Err(BuildError::LeafSize(options.max_leaf_triangles));
    }
    if !(2..=255).contains(&options.bins) {
        return Err(BuildError::Bins(options.bins));
    }
    if mesh.triangles.len() >= (LEAF_FLAG as usize) / 2 {
        return Err(BuildError::TooManyTriangles(mesh.triangles.len()));
    }
    mesh.validate("mesh").or_else(|e| match e {
        // An empty mesh still gets a (single empty leaf) tree.
        crate::mesh::MeshError::NoFaces { .. } => Ok(()),
        e => Err(BuildError::InvalidMesh(e.to_string())),
    })?;
    let built = sah::build_tree(mesh, options, progress);
    Ok(layout::apply(built, options, progress))
}

/// Builds with default options and no progress reporting.
pub fn build_default(mesh: &Mesh) -> Result<CanonicalBvh, BuildError> {
    build(mesh, &BuildOptions::default(), &|_, _| {})
}
