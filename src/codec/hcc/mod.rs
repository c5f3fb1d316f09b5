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
//! **A low-level tree** is a [`node::TreeHeader`], a run of
//! 4-byte node words, a run of inter-connections and the tree's own vertex
//! array. Vertices used by several low-level trees are stored once in each
//! ([`HccStats::duplicated_fraction`]).
//!
//! **Vertices** ([`HccOptions::vertex_bits`], module `vertices`): `f32`
//! coordinates (the default: lossless, the decoded triangles equal the
//! input bit for bit), or quantized on one grid over the mesh (16 bits
//! gives the paper's precision) and bit-packed per tree as offsets from
//! the tree's smallest grid point, so a vertex costs about 4 bytes instead
//! of 12 or 6. The grid is the mesh's, not each tree's, so that copies of a
//! vertex in several trees decode alike; the error bound is half a grid
//! step per axis ([`HccBvh::vertex_error`] gives the largest error
//! measured). Boxes are built from the decoded vertices, so a decoded box
//! contains its subtree's decoded triangles without any rounding of its
//! own.
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
//! # Triangle and vertex ids
//!
//! Leaves store triangles implicitly, so a triangle's place in storage (its
//! *rank*: leaves in node-word order, low-level tree by low-level tree) is
//! not its input id, and the template layout cannot be bent to make it so.
//! The cursor reports input ids, as every codec does (module `ids`): a
//! rank → id array read at every leaf, and the inverse found through cycle
//! shortcuts for [`NodeCursor::triangle`](crate::cursor::NodeCursor::triangle),
//! part `ids` (about 2–2.5 bytes a triangle). A leaf word's rank comes from
//! rank/select over a bit per node word (part `leaf-ranks`); a
//! multi-triangle leaf's block holds its first slot in its tree.
//!
//! **Tree order** ([`HccOptions::triangle_ids`] off,
//! [`HccOptions::tree_order`]): the map is not stored and a triangle's id
//! *is* its rank. The cursor, `triangle(id)`, `triangle_vertices(id)` and
//! [`HccBvh::decoded_mesh`] then all number triangles in storage order, so
//! the shape is self-consistent (the parry shape, the renderer and the sims
//! only ever pass back ids a leaf reported) but its ids are not the input's:
//! a caller that keeps per-triangle data of its own must reorder it by the
//! decoded mesh. Ties in queries still go to the smaller id, now the
//! smaller rank, so an answer can differ from another codec's only in
//! which of two equally near triangles it names.
//!
//! With [`HccOptions::vertex_ids`] (the default) each stored vertex keeps
//! its input index (part `vertex-ids`, about 1 byte a triangle) and the
//! input vertices no triangle uses are kept aside, so that
//! [`HccBvh::decoded_mesh`] is the input mesh itself (with `f32` vertices)
//! and [`HccBvh::triangle_vertex_indices`] gives input vertex indices
//! (smooth shading across low-level trees). Without it the decoded mesh's
//! vertices are the trees' arrays one after the other, copies included.
//!
//! # Multi-triangle leaves
//!
//! A tree built with up to [`MAX_LEAF_TRIANGLES`] triangles a leaf gives
//! leaves whose word holds the bit offset of a triangle block and the
//! triangle count; a block (module `block`) holds the leaf's first slot
//! and its corners as offsets from the leaf's smallest local vertex index
//! in as few bits as the leaf needs (the tree's vertices are numbered by
//! first use, so a leaf's corners are close). The leaf's box is its
//! triangles' box.
//!
//! See [`node`] for the bit layouts.

mod block;
mod canonical;
mod contract;
mod cursor;
mod decompose;
mod encode;
mod error;
mod file;
#[cfg(target_arch = "x86_64")]
mod grid16;
mod ids;
pub mod node;
pub mod ooc;
mod pair;
pub mod template;
mod trace;
mod verify;
mod vertices;

pub use error::HccError;
pub use node::HccNode;

use crate::codec::ByteSize;
use crate::codec::common::MassProps;
use crate::codec::settings::{CodecOptions, Setting, Settings, SettingsError, Values};
use crate::contact::EdgeFlags;
use crate::mesh::Mesh;
use ids::{IdMap, VertexIds};
use node::{HighNode, TreeHeader};
use vertices::Vertices;

/// The most triangles a multi-triangle leaf may hold (a 6-bit count in the
/// leaf word; a leaf's corners must also fit one low-level tree's 511
/// vertices).
pub const MAX_LEAF_TRIANGLES: usize = node::MULTI_COUNT_LIMIT;

/// An i-HCCMesh: the high-level tree and every low-level tree's header,
/// node words, inter-connections, vertices and (multi-triangle leaves)
/// triangle blocks, with the maps to the input's numbering (see the module
/// docs).
#[derive(Clone, Debug)]
pub struct HccBvh {
    high: Vec<HighNode>,
    headers: Vec<TreeHeader>,
    nodes: Vec<u32>,
    ics: Vec<u32>,
    vertices: Vertices,
    /// Multi-triangle leaves: every tree's block stream (see `block`).
    blocks: Vec<u8>,
    /// Multi-triangle leaves: each tree's first byte in `blocks`.
    block_start: Vec<u32>,
    /// Bit `p` set when node word `p` is a leaf.
    leaf_bits: Vec<u64>,
    /// Leaves before each word of `leaf_bits`.
    leaf_rank: Vec<u32>,
    /// Storage rank ↔ input triangle id (`None`: the triangles are
    /// numbered in storage order, [`HccOptions::triangle_ids`] off).
    ids: Option<IdMap>,
    /// Each stored vertex's input index (when kept).
    vertex_ids: Option<VertexIds>,
    multi: bool,
    triangle_count: u32,
    /// Vertices of the input mesh.
    mesh_vertices: u32,
    mass: MassProps,
    /// Active edges by triangle id (the ids the cursor reports): computed
    /// when encoded, read from the file (or the o-HCCMesh's) when opened;
    /// empty in a one-tree page of the out-of-core o-HCCMesh.
    edges: EdgeFlags,
    stats: HccStats,
}

/// Figures of one encode.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
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

/// Encoding options of the i-HCCMesh ([`HccBvh::encode_with`]). The leaf
/// size is the canonical tree's: one triangle a leaf gives the paper's
/// form, more gives multi-triangle leaves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HccOptions {
    /// `None` (the default): `f32` vertices, lossless. `Some(bits)`: each
    /// coordinate quantized to `bits` (1 to 24; 16 as the paper) on one
    /// grid over the mesh, rounded to nearest.
    pub vertex_bits: Option<u32>,
    /// Keep each stored vertex's input index and the unused input
    /// vertices (part `vertex-ids`), so that the decoded mesh is the
    /// input's, vertex numbering included (default: on).
    pub vertex_ids: bool,
    /// Keep the input's triangle ids (part `ids`, about 2.5 bytes a
    /// triangle; default: on). Off, the triangles are numbered in the
    /// tree's order (storage rank: leaves in node-word order, low-level
    /// tree by low-level tree) and no map is stored: leaves,
    /// [`NodeCursor::triangle`](crate::cursor::NodeCursor::triangle) and
    /// [`HccBvh::decoded_mesh`] all use that numbering, so the decoded
    /// mesh's triangles are the input's, permuted.
    pub triangle_ids: bool,
}

impl Default for HccOptions {
    fn default() -> Self {
        Self {
            vertex_bits: None,
            vertex_ids: true,
            triangle_ids: true,
        }
    }
}

impl HccOptions {
    /// Everything in the tree's order: neither triangle nor vertex ids
    /// kept (the smallest form). The decoded mesh is the input's triangles
    /// in storage order, over the low-level trees' vertex arrays one after
    /// the other (shared vertices repeated).
    pub fn tree_order(vertex_bits: Option<u32>) -> Self {
        Self {
            vertex_bits,
            vertex_ids: false,
            triangle_ids: false,
        }
    }
}

impl HccOptions {
    /// `vertex_ids` as a setting (`hcc.vertex-ids`).
    pub const VERTEX_IDS: Setting = Setting::flag("vertex-ids");
    /// `triangle_ids` as a setting (`hcc.triangle-ids`).
    pub const TRIANGLE_IDS: Setting = Setting::flag("triangle-ids");
    /// [`HccOptions::tree_order`] as a setting (`hcc.tree-order`: `true`
    /// drops both id maps).
    pub const TREE_ORDER: Setting = Setting::flag("tree-order");
}

/// The bits per vertex coordinate both HCCMesh forms' grids take: 1 to 24.
pub const VERTEX_BIT_RANGE: Values = Values::whole(1, 24);

impl CodecOptions for HccOptions {
    const SETTINGS: &'static [Setting] = &[Self::VERTEX_IDS, Self::TRIANGLE_IDS, Self::TREE_ORDER];
    const VERTEX_BITS: Option<Values> = Some(VERTEX_BIT_RANGE);

    /// The options from a front end's settings ([`crate::codec::settings`]):
    /// `hcc.vertex-ids`, `hcc.triangle-ids` (`true`/`false`), `hcc.tree-order`
    /// (`true`: neither id map, as [`HccOptions::tree_order`]), and the
    /// common `vertex_bits` (`f32` by default; [`VERTEX_BIT_RANGE`]).
    fn from_settings(s: &Settings) -> Result<Self, SettingsError> {
        let d = Self::default();
        let tree_order = s.get::<bool>("hcc", Self::TREE_ORDER.key)?.unwrap_or(false);
        let o = Self {
            vertex_bits: s.vertex_bits_or(d.vertex_bits),
            vertex_ids: s.get("hcc", Self::VERTEX_IDS.key)?.unwrap_or(d.vertex_ids) && !tree_order,
            triangle_ids: s
                .get("hcc", Self::TRIANGLE_IDS.key)?
                .unwrap_or(d.triangle_ids)
                && !tree_order,
        };
        check_vertex_bits("hcc", o.vertex_bits)?;
        Ok(o)
    }
}

impl HccBvh {
    /// The mesh as stored, triangle `k` being the triangle the cursor
    /// reports as id `k`: input triangle `k`, or the triangle of storage
    /// rank `k` in tree order ([`HccOptions::triangle_ids`] off). With
    /// vertex ids kept, its vertices are the input's (decoded positions);
    /// without, the low-level trees' arrays one after the other (shared
    /// vertices repeated).
    pub fn decoded_mesh(&self) -> Mesh {
        let mut triangles = vec![[0u32; 3]; self.triangle_count as usize];
        let mut vertices = match &self.vertex_ids {
            Some(_) => vec![[0f32; 3]; self.mesh_vertices as usize],
            None => Vec::with_capacity(self.stats.tree_vertices),
        };
        for (tree, h) in self.headers.iter().enumerate() {
            let tree = tree as u32;
            let (node_end, _, vertex_end) = self.tree_ends(tree as usize);
            for pos in h.node_start..node_end {
                if node::node_type(self.nodes[pos as usize]) == node::TYPE_LEAF {
                    self.leaf_triangles(tree, pos, |rank, c| {
                        let id = self.id_of(rank) as usize;
                        triangles[id] = c.map(|l| self.vertex_index(h.vertex_start + l));
                    });
                }
            }
            for local in 0..vertex_end - h.vertex_start {
                let p = self.point(tree, h, local);
                match &self.vertex_ids {
                    Some(v) => vertices[v.get(h.vertex_start + local) as usize] = p,
                    None => vertices.push(p),
                }
            }
        }
        if let Some(v) = &self.vertex_ids {
            for &(i, p) in &v.unused {
                vertices[i as usize] = p;
            }
        }
        Mesh::new(vertices, triangles)
    }

    /// The index, in [`HccBvh::decoded_mesh`]'s vertices, of stored vertex
    /// `s` (the trees' arrays one after the other).
    #[inline]
    pub(super) fn vertex_index(&self, s: u32) -> u32 {
        match &self.vertex_ids {
            Some(v) => v.get(s),
            None => s,
        }
    }

    /// Statistics of the encode: trees, duplicated vertices, templates.
    pub fn stats(&self) -> &HccStats {
        &self.stats
    }

    /// Mass properties at density 1 (computed from the mesh when built).
    pub fn mass(&self) -> MassProps {
        self.mass
    }

    /// Active edges by triangle id (stored in the file).
    pub fn edge_flags(&self) -> &EdgeFlags {
        &self.edges
    }

    /// Whether leaves hold several triangles.
    pub fn is_multi(&self) -> bool {
        self.multi
    }

    /// Number of low-level trees.
    pub fn tree_count(&self) -> usize {
        self.headers.len()
    }

    /// Bits per quantized vertex coordinate (`None`: `f32` vertices).
    pub fn vertex_bits(&self) -> Option<u32> {
        self.vertices.quantized().map(|q| q.bits)
    }

    /// The largest distance per axis between an input vertex and its
    /// decoded position, measured when encoding (zero for `f32` vertices);
    /// at most half a grid step ([`HccBvh::vertex_step`]) per axis.
    pub fn vertex_error(&self) -> [f32; 3] {
        self.vertices.quantized().map_or([0.0; 3], |q| q.error)
    }

    /// The quantization grid's step per axis (zero for `f32` vertices).
    pub fn vertex_step(&self) -> [f32; 3] {
        self.vertices.quantized().map_or([0.0; 3], |q| q.step)
    }

    /// Whether triangles keep their input ids (otherwise they are numbered
    /// in storage order; see [`HccOptions::triangle_ids`]).
    pub fn has_triangle_ids(&self) -> bool {
        self.ids.is_some()
    }

    /// Whether each stored vertex keeps its input index.
    pub fn has_vertex_ids(&self) -> bool {
        self.vertex_ids.is_some()
    }

    /// Where low-level tree `k`'s node words, inter-connections and
    /// vertices end (the next tree's starts).
    pub(super) fn tree_ends(&self, k: usize) -> (u32, u32, u32) {
        self.headers.get(k + 1).map_or(
            (
                self.nodes.len() as u32,
                self.ics.len() as u32,
                self.stats.tree_vertices as u32,
            ),
            |h| (h.node_start, h.ic_start, h.vertex_start),
        )
    }

    /// Triangles of low-level tree `k`.
    #[inline(always)]
    pub(super) fn tree_triangles(&self, k: usize) -> u32 {
        self.headers
            .get(k + 1)
            .map_or(self.triangle_count, |h| h.first_triangle)
            - self.headers[k].first_triangle
    }
}

impl ByteSize for HccBvh {
    fn bytes_by_part(&self) -> Vec<(&'static str, usize)> {
        let mut parts = vec![
            ("high-level", self.high.len() * size_of::<HighNode>()),
            ("headers", self.headers.len() * size_of::<TreeHeader>()),
            ("nodes", self.nodes.len() * 4),
            ("interconnections", self.ics.len() * 4),
            ("vertices", self.vertices.bytes()),
        ];
        if self.multi {
            parts.push(("triangles", self.blocks.len() + self.block_start.len() * 4));
        }
        parts.push((
            "leaf-ranks",
            self.leaf_bits.len() * 8 + self.leaf_rank.len() * 4,
        ));
        if let Some(ids) = &self.ids {
            parts.push(("ids", ids.bytes()));
        }
        if let Some(v) = &self.vertex_ids {
            parts.push(("vertex-ids", v.bytes()));
        }
        parts.push(("edge-flags", self.edges.bytes()));
        parts
    }
}

/// Bits per quantized vertex coordinate, where given: [`VERTEX_BIT_RANGE`]
/// (both HCCMesh forms' grids).
fn check_vertex_bits(codec: &str, bits: Option<u32>) -> Result<(), SettingsError> {
    match bits {
        Some(b) if !VERTEX_BIT_RANGE.allows(u64::from(b)) => Err(SettingsError::Invalid {
            codec: codec.into(),
            reason: format!(
                "vertex bits {b} is not allowed: use {VERTEX_BIT_RANGE} (0 for f32 vertices)"
            ),
        }),
        _ => Ok(()),
    }
}
