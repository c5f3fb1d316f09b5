//! HCCMesh (Kim et al., EG 2010): the in-core i-HCCMesh (§3.1, §4), where
//! mesh and tree are one structure and a node costs 4 bytes, and a variant
//! with several triangles a leaf (the paper's §7 extension).
//!
//! ```
//! use cbvh::codec::hcc::HccBvh;
//! # fn demo(mesh: &cbvh::Mesh) -> Result<(), Box<dyn std::error::Error>> {
//! let tree = cbvh::build::build_default(mesh)?;
//! let hcc = HccBvh::encode(&tree, mesh)?;
//! let dup = hcc.stats().duplicated_fraction(); // the paper's 14 %
//! # let _ = dup; Ok(()) }
//! ```
//!
//! # Structure
//!
//! **Decomposition** (`decompose`): a high-level tree over low-level trees,
//! each the highest subtree of the canonical tree with fewer than 512
//! distinct vertices (and few enough nodes and template leaves for the
//! index fields; see the module for the exact limits). The high-level tree
//! is stored uncompressed, 32 bytes a node, with each node's exact box; a
//! high-level leaf names a low-level tree, whose root box is that leaf's.
//!
//! **A low-level tree** is a [`TreeHeader`](node::TreeHeader), a run of
//! 4-byte node words, a run of inter-connections and the tree's own vertex
//! array (`f32` coordinates: lossless, so the decoded triangles equal the
//! input bit for bit). Vertices used by several low-level trees are stored
//! once in each ([`HccStats::duplicated_fraction`]).
//!
//! **Boxes** (§4.2). By the inheritance property, for each of the six
//! extents one child of a node shares the parent's extent. Siblings are
//! always stored next to each other (or reached through one
//! inter-connection) and decoded as a pair: six reuse-mask bits (three in
//! each sibling's word) say, per extent `e` (0–2 minimum x, y, z; 3–5
//! maximum), whether the left child inherits (bit set: the right child
//! reads coordinate `e % 3` of a vertex) or the right child does (the left
//! child reads the vertex). The vertex for extent `e` is field `e % 3` of
//! the left word for minima and of the right word for maxima. When both
//! children share the parent's extent either may inherit: the other's
//! vertex attains the same value.
//!
//! Choices the paper leaves open, and why:
//! - *A leaf's box* is its triangle's box, computed from the three corners
//!   the leaf stores anyway, so a leaf's fields hold its corners (Fig. 5)
//!   and no box. When one child is a leaf, the six mask bits of the pair
//!   say which extents the *inner* child inherits, and its three fields give
//!   vertices for the others in extent order. An inner child that differs
//!   from its parent in more than three extents keeps the three that shrink
//!   it most and inherits the rest: looser, still conservative
//!   ([`HccStats::loose_extents`] counts them).
//! - *Parents decoded looser than tight*: the encoder codes every pair
//!   against the box its parent *decodes* to, never the tight one, so a
//!   loose box stays conservative all the way down.
//! - *Template order*: a template's nodes are stored breadth-first (a
//!   node's children by one popcount, siblings adjacent); the two child
//!   templates of a template leaf are stored back to back so one position
//!   in the inter-connection finds both; template leaves are expanded
//!   depth-first so a subtree's templates stay close in memory.
//! - *The root of a low-level tree* has no sibling; its box is the
//!   high-level leaf's, and an inner root's word holds its template id.
//!
//! **Structure** (§4.3): templates of height 1–4 (all 26 shapes, module
//! `template`) partition each low-level tree top-down; template leaves
//! (inner nodes at template depth 3) point through a 9-bit field to an
//! inter-connection that names the child templates.
//!
//! # Triangle ids
//!
//! The i-HCCMesh stores triangles implicitly (a leaf holds corners, not an
//! id), so cbvh numbers them by storage: a triangle's id is its rank among
//! the leaves in node-word order, low-level tree by low-level tree. The
//! ids are dense (`0..triangle_count`) and stable for a given encoding, and
//! they are *not* the input mesh's ids: [`HccBvh::decoded_mesh`] gives the
//! mesh with its triangles in id order. With one triangle a leaf,
//! [`NodeCursor::triangle`](crate::cursor::NodeCursor::triangle) finds a
//! triangle by rank/select over a bit per node word (a set bit marks a
//! leaf) and a running count every 64 words: part `leaf-ranks`, about 0.4
//! bytes a triangle. With several triangles a leaf, a leaf's word holds
//! the position of its first triangle in its tree's triangle run, and the
//! id is the tree's first id plus that position, so `triangle` is one
//! binary search over the trees.
//!
//! # Multi-triangle leaves (`hcc-multi`)
//!
//! A tree built with up to [`MAX_LEAF_TRIANGLES`] triangles a leaf gives
//! leaves whose word holds an 18-bit first triangle and a 9-bit count − 1
//! into the tree's triangle run, each triangle three 9-bit corners in a
//! `u32`; the leaf's box is its triangles' box.
//!
//! See [`node`] for the bit layouts.

mod contract;
mod decode;
mod decompose;
mod encode;
mod error;
mod file;
pub mod node;
pub mod template;

pub use decode::HccNode;
pub use encode::HccBvh;
pub use error::HccError;

use crate::mesh::Mesh;

/// The most triangles a multi-triangle leaf may hold: a leaf's corners
/// (at most three each) must fit one low-level tree's 511 vertices, and a
/// tree's triangles an 18-bit first-triangle field.
pub const MAX_LEAF_TRIANGLES: usize = 64;

/// Figures of one encode.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct HccStats {
    /// Low-level trees.
    pub trees: usize,
    /// High-level nodes.
    pub high_nodes: usize,
    /// Vertices stored, summed over the low-level trees.
    pub tree_vertices: usize,
    /// Distinct vertices the mesh's triangles use.
    pub mesh_vertices: usize,
    /// Sibling pairs of two inner nodes.
    pub inner_pairs: usize,
    /// Sibling pairs of a leaf and an inner node.
    pub mixed_pairs: usize,
    /// Extents an inner node inherited from its parent although it did not
    /// attain them (more than three to code beside a leaf sibling).
    pub loose_extents: usize,
    /// How many times each template occurs.
    pub templates: [u64; template::TEMPLATE_COUNT],
}

impl HccStats {
    /// Share of stored vertices that are copies (a vertex used by several
    /// low-level trees): `(stored − distinct) / distinct`.
    pub fn duplicated_fraction(&self) -> f64 {
        if self.mesh_vertices == 0 {
            0.0
        } else {
            (self.tree_vertices - self.mesh_vertices) as f64 / self.mesh_vertices as f64
        }
    }
}

impl HccBvh {
    /// The mesh the structure stores, triangles in id order. Its vertex
    /// array is the low-level trees' arrays one after the other (shared
    /// vertices repeated); positions are the input's, bit for bit.
    pub fn decoded_mesh(&self) -> Mesh {
        let mut triangles = Vec::with_capacity(self.triangle_count as usize);
        for (t, h) in self.headers.iter().enumerate() {
            let end = self.headers.get(t + 1);
            let base = h.vertex_start;
            if self.multi {
                let last = end.map_or(self.triangle_count, |n| n.first_triangle);
                for id in h.first_triangle..last {
                    triangles.push(self.multi_corners(id).map(|c| base + c));
                }
            } else {
                let last = end.map_or(self.nodes.len() as u32, |n| n.node_start);
                for &w in &self.nodes[h.node_start as usize..last as usize] {
                    if node::node_type(w) == node::TYPE_LEAF {
                        triangles.push([0, 1, 2].map(|j| base + node::field(w, j)));
                    }
                }
            }
        }
        Mesh::new(self.vertices.clone(), triangles)
    }
}
