//! o-HCCMesh (HCCMesh §5): the out-of-core form of the i-HCCMesh. Each
//! low-level tree's structure, vertex indices and quantized vertices are
//! coded through static dictionaries of optimal size
//! ([`static_dict`](crate::codec::common::static_dict), §5.2); no box is
//! stored: decoding rebuilds every box bottom-up from the vertices and
//! produces the i-HCCMesh that [`HccBvh::encode_with`] builds from the same
//! tree and options, byte for byte.
//!
//! ```
//! use cbvh::codec::hcc::ooc::{HccOocBvh, OocOptions};
//! # fn demo(mesh: &cbvh::Mesh) -> Result<(), Box<dyn std::error::Error>> {
//! let tree = cbvh::build::build_default(mesh)?;
//! let ooc = HccOocBvh::encode_with(&tree, mesh, &OocOptions::default())?;
//! let bytes = ooc.file_bytes(); // ~3–4 bytes a triangle
//! let back = HccOocBvh::from_bytes(bytes)?; // o → i at open
//! assert_eq!(back.hcc().map(|h| h.to_bytes()), ooc.hcc().map(|h| h.to_bytes()));
//! // Out of core: trees decoded on demand into a 64 KB cache.
//! let paged = HccOocBvh::from_bytes_with_budget(bytes, 64 << 10)?;
//! # let _ = paged;
//! # Ok(()) }
//! ```
//!
//! # Two modes (§3.1)
//!
//! [`HccOocBvh`] decodes the whole file when it is opened if the
//! i-HCCMesh it decodes to fits the cache budget (the default budget is
//! unlimited); otherwise it keeps the file (memory-mapped when opened from
//! a path) and decodes each low-level tree into a one-tree i-HCCMesh in a
//! [`PageCache`](crate::codec::common::page_cache::PageCache) the first
//! time a traversal enters it (module `paged`). The high-level tree and
//! its boxes are stored apart from the trees for that reason, and read
//! whole when the file is opened. The paper keeps them uncompressed (“we
//! do not compress the high-level BVH since it is frequently used and is
//! relatively small”); here the boxes are on the vertex grid, each
//! child's against its parent, decoded in one pass over the nodes at
//! open: about 6 bytes a node rather than 24 (on the 75 k-triangle bunny,
//! 0.075 → 0.018 bytes a triangle for the high-level tree).
//!
//! # Built out of core
//!
//! A model too large to build in memory is built chunk by chunk
//! ([`encode_streamed`], over a [`ChunkedMesh`](crate::build::chunked::ChunkedMesh)):
//! every chunk's trees on the whole model's grid, one set of dictionaries
//! for all, the chunks' high-level trees joined under the tree over the
//! chunks, edge flags paired across chunks. The file is an ordinary
//! o-HCCMesh file (module `stream`); `cbvh build FILE --codec hcc-ooc`
//! takes that path when the model is over its memory budget.
//!
//! # Why a sub-module of `hcc`
//!
//! o-HCCMesh is not a traversable structure of its own: it is a coding of
//! the i-HCCMesh, and decodes into one. Living under `hcc` it builds the
//! [`HccBvh`] directly, shares the pair coding of the boxes with the
//! i-HCCMesh encoder (module `pair`, so the rebuilt words cannot drift from
//! the encoder's) and reads the template table, without widening what
//! `hcc` exposes.
//!
//! # What is coded, and in which order
//!
//! Per low-level tree, one bit stream starting on a byte, in three parts
//! one after the other:
//!
//! 1. **Templates** (structure and inter-connections, §4.3): the template
//!    symbols in the order the i-HCCMesh allocates templates, which is a
//!    depth-first order of the template tree (root template, then for the
//!    template leaf on top of a stack its two child templates, left then
//!    right; the stack takes a template's leaves in breadth-first order,
//!    so the last one is expanded first). A symbol is the template id
//!    (5 bits) and one bit per node at template depth 3 without children
//!    inside the template: a template leaf or a leaf of the tree. Node
//!    types, child positions, inter-connections (child template ids, left
//!    start, index) all follow from the symbols; nothing else is stored.
//! 2. **Vertex indices**, streaming-mesh style (§5.1, \[ILS05\]): the leaves
//!    in node-word order, which is the same depth-first order of the
//!    templates; each corner is one symbol (context by corner slot): 0 for
//!    a vertex never seen in this tree (it takes the next local index,
//!    which is how the i-HCCMesh numbers a tree's vertices: by first use),
//!    `1 + r` for the vertex at rank `r` of a cache of the 16 most recently
//!    used ones, else `17 + d` for the vertex `d + 1` below the next index.
//! 3. **Vertices**, in the order of their local indices (the order of
//!    first use), as grid coordinates on the i-HCCMesh's mesh-wide
//!    quantization grid (16 bits by default, §5.1), predicted and sent as
//!    zig-zagged residuals, one context per axis and kind of prediction,
//!    from the corners of the vertex's first triangle that have smaller
//!    indices and the triangles before it: the parallelogram `a + b − c`
//!    \[AG04\] when the other two corners are known and an earlier triangle
//!    of the tree shares their edge (`c` its third corner; found through
//!    each vertex's last 16 triangles); their midpoint or the one known
//!    corner otherwise; the tree's last decoded vertex when no corner is
//!    known.
//!
//! The order is the decoder's (version 6; version 5 sent each new vertex
//! right after its triangle's corners, the same symbols interleaved): it
//! reads every corner first, in a loop that only reads symbols and keeps
//! the corner cache, then plans every vertex's prediction from the
//! connectivity alone, then reads the residuals, whose contexts are known
//! by then, so that no symbol read waits for the modelling of another
//! part. The file's size is the same. A triangle's three corners, a
//! vertex's three residuals and a template leaf's two templates are each
//! read after one refill of the bit reader.
//!
//! Every context has its own static dictionary, one for the whole file
//! (so that a tree decodes alone, for on-demand decoding), sized by §5.2's
//! rule. Unlike the paper's, a dictionary may split its values: a large
//! value is coded as its bit length and the bits below its leading one
//! through the dictionary, its lower bits raw (the encoder chooses the
//! split per context, never worse than the paper's coding; see
//! [`static_dict`](crate::codec::common::static_dict)). On a scanned model
//! (the Stanford bunny) the residuals spread over thousands of values, and
//! the split coding of them takes about a fifth less than the plain.
//!
//! **Boxes** are not stored (§5.1): the decoder computes each node's tight
//! box bottom-up from the decoded vertices (ties: first corner, left
//! child, as the i-HCCMesh encoder) and then codes each sibling pair's
//! reuse mask and vertex fields top-down exactly as the i-HCCMesh encoder
//! does; the high-level tree's boxes are combined from the low-level
//! trees' root boxes the same way. All of it linear in the nodes.
//!
//! **Multi-triangle leaves** (the i-HCCMesh's §7 extension) code a
//! leaf's triangle count − 1 (its own context) before its triangles; the
//! decoder rebuilds the leaf's block as the i-HCCMesh encoder writes it.
//!
//! **Scope**: quantized vertices only (f32 vertices are an error). The id maps (input triangle
//! and vertex numbering), when the options keep them, are stored as the
//! i-HCCMesh stores them, not coded further: the default is the paper's
//! form, tree order, no maps.
//!
//! # Layout
//!
//! All integers little-endian; the frame is the shared one of
//! [`container`](crate::codec::common::container). A 364-byte header, then
//! nine sections back to back, ending the file.
//!
//! | bytes | field |
//! |---|---|
//! | 0–7 | magic `CBVHHCO\0` |
//! | 8–11 | version (7: version 6 had no edge flags, version 5 interleaved each new vertex's residuals with its triangle's corners, version 4 stored the trees' starts and firsts as `u32`, version 3 also the high-level boxes as `f32`, version 2's dictionaries had no split, version 1 had no high-level boxes nor tree firsts) |
//! | 12–15 | flags: bit 0 vertex ids kept, bit 1 tree order (no triangle id map), bit 2 multi-triangle leaves; others 0 |
//! | 16–35 | counts of the i-HCCMesh: high-level nodes, low-level trees, node words, inter-connections, stored vertices |
//! | 36–39 | triangle count |
//! | 40–43 | input mesh's vertex count |
//! | 44–47 | distinct input vertices the triangles use |
//! | 48–51 | bits per grid coordinate (1–24) |
//! | 52–87 | grid origin, step and measured error, 3 × f32 each |
//! | 88–139 | mass properties at density 1 |
//! | 140–355 | section table (offset, length, checksum) of the nine sections |
//! | 356–363 | checksum of bytes 0–355 |
//!
//! Sections, in order:
//! - *dictionaries*: the 14 contexts' dictionaries back to back in one bit
//!   stream (templates; corners 0, 1, 2; parallelogram x, y, z; near x,
//!   y, z; far x, y, z; leaf sizes), each as [`StaticDict`](crate::codec::common::static_dict::StaticDict) writes it;
//! - *high-level shape*: one bit per high-level node (1 inner, 0 a
//!   low-level tree) in depth-first order, left first (the order the
//!   i-HCCMesh numbers them);
//! - *tree starts*: per low-level tree, the length of its stream in
//!   bytes (opening sums them into where each tree's stream starts in the
//!   next section, for random access), in one bit stream,
//!   least-significant bit first: the width of the lengths (6 bits), then
//!   the lengths in that many bits each, the last byte zero-padded; the
//!   lengths add up to the streams section's;
//! - *tree streams*: the trees' streams, each starting on a byte;
//! - *ids*, *vertex ids*: the i-HCCMesh's sections of the same names,
//!   empty when not kept;
//! - *high-level boxes*: what the out-of-core mode traverses before any
//!   tree is decoded, as grid coordinates (the boxes are unions of grid
//!   points) in one bit stream, least-significant bit first: the root's
//!   six (minimum x, y, z, maximum x, y, z; the grid's bits each), then
//!   per inner node in node order (parents first) and per extent in the
//!   same order, a bit naming the child that does not share the parent's
//!   value (0 the right one, 1 the left one; one of them always does) and
//!   that child's distance inside the parent's value, in as many bits as
//!   the parent's extent on that axis (maximum − minimum) needs; the last
//!   byte zero-padded. The whole decode rebuilds the boxes from the trees
//!   and checks they are equal;
//! - *tree firsts*: per low-level tree, its triangle count and its stored
//!   vertex count, from which opening sums each tree's first triangle
//!   rank and first stored vertex, so that a tree decoded alone numbers
//!   its triangles and vertices as the whole model does. Laid out as the
//!   tree starts, with two columns: the two widths (6 bits each), then
//!   per tree its two counts;
//! - *edge flags*: the section every codec file ends with
//!   ([`edges`](crate::codec::common::edges)), by triangle id (tree order
//!   by default), computed by the i-HCCMesh encoder from its quantized
//!   triangles and decoded whole when the file is opened, in both modes.
//!
//! # Validation
//! [`HccOocBvh::from_bytes`] checks the frame and every checksum, then
//! decodes with checked reads: every symbol, count and index is checked
//! against what the structure allows (a tree's nodes, inter-connections
//! and vertices, the grid, the header's totals), so hostile bytes give an
//! [`OocError`], never a panic or a hang. The decoded i-HCCMesh is then
//! verified by [`HccBvh::verify`] like any i-HCCMesh file. Out of core,
//! opening checks the frame and every checksum but the tree streams' (the
//! whole file would be read), the high-level tree and the firsts; a tree
//! is checked when it is decoded, and a tree that does not decode panics
//! in the query that reaches it. `verify` (run by
//! [`AnyCodec::open`](crate::codec::AnyCodec::open) by default) decodes
//! every tree once and proves the file.

mod contract;
mod cursor;
mod decode;
mod encode;
mod error;
mod file;
mod model;
mod paged;
mod rebuild;
mod stream;

pub use encode::OocSizes;
pub use error::OocError;
pub use file::MAGIC;
pub use stream::{Progress, StreamedBuild, encode_streamed};

use super::{HccBvh, HccOptions};
use crate::codec::ByteSize;
use crate::codec::common::page_cache::CacheStats;
use crate::codec::settings::{CodecOptions, Setting, Settings, SettingsError, Values};
use crate::contact::EdgeFlags;
use paged::Paged;

/// Encoding options of the o-HCCMesh: the i-HCCMesh options it codes
/// (always quantized), and the cache budget it is traversed with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct OocOptions {
    /// Bits per grid coordinate (1 to 24; 16 as the paper).
    pub vertex_bits: u32,
    /// Keep the input's vertex ids (stored uncoded; default off).
    pub vertex_ids: bool,
    /// Keep the input's triangle ids (stored uncoded, about 2.5 bytes a
    /// triangle; default off: tree order, the paper's form).
    pub triangle_ids: bool,
    /// Bytes of decoded low-level trees to keep (see [`HccOocBvh`]'s
    /// modes): when the whole i-HCCMesh fits, it is decoded at once
    /// (the default, `usize::MAX`); otherwise trees are decoded on demand
    /// into a cache of this many bytes.
    pub cache_budget_bytes: usize,
}

impl Default for OocOptions {
    fn default() -> Self {
        Self {
            vertex_bits: 16,
            vertex_ids: false,
            triangle_ids: false,
            cache_budget_bytes: usize::MAX,
        }
    }
}

impl OocOptions {
    /// The i-HCCMesh options this o-HCCMesh codes.
    pub fn hcc(&self) -> HccOptions {
        HccOptions {
            vertex_bits: Some(self.vertex_bits),
            vertex_ids: self.vertex_ids,
            triangle_ids: self.triangle_ids,
        }
    }
}

impl CodecOptions for OocOptions {
    const SETTINGS: &'static [Setting] = &[HccOptions::VERTEX_IDS, HccOptions::TRIANGLE_IDS];
    const VERTEX_BITS: Option<Values> = Some(super::VERTEX_BIT_RANGE);

    /// The options from a front end's settings ([`crate::codec::settings`]):
    /// `hcc-ooc.vertex-ids`, `hcc-ooc.triangle-ids` (`true`/`false`, both off
    /// by default: the paper's tree order), and the common `vertex_bits`
    /// ([`VERTEX_BIT_RANGE`](super::VERTEX_BIT_RANGE); it always quantizes,
    /// so unset or 0 gives 16).
    fn from_settings(s: &Settings) -> Result<Self, SettingsError> {
        let d = Self::default();
        let vertex_bits = s
            .vertex_bits_or(Some(d.vertex_bits))
            .unwrap_or(d.vertex_bits);
        super::check_vertex_bits("hcc-ooc", Some(vertex_bits))?;
        Ok(Self {
            vertex_bits,
            vertex_ids: s
                .get("hcc-ooc", HccOptions::VERTEX_IDS.key)?
                .unwrap_or(d.vertex_ids),
            triangle_ids: s
                .get("hcc-ooc", HccOptions::TRIANGLE_IDS.key)?
                .unwrap_or(d.triangle_ids),
            ..d
        })
    }
}

/// How an [`HccOocBvh`] holds its model.
#[derive(Debug)]
enum Mode {
    /// Decoded whole when opened; the file's bytes (what it saves) kept
    /// beside the i-HCCMesh.
    Whole { hcc: HccBvh, file: Vec<u8> },
    /// Low-level trees decoded on demand into a cache.
    Paged(Paged),
}

/// The `hcc-ooc` codec: an o-HCCMesh file and the i-HCCMesh it decodes
/// to, in one of the paper's two modes (§3.1):
///
/// - **pre-loaded**: when the whole i-HCCMesh fits the cache budget (by
///   default it always does), every low-level tree is decoded when the
///   file is opened and the model is traversed as that i-HCCMesh;
/// - **out of core**: otherwise the file (memory-mapped by
///   [`HccOocBvh::open_with_budget`]) stays coded, and each low-level tree
///   is decoded into an LRU cache of the budget's bytes the first time a
///   traversal enters it, evicted when the cache needs the room. Only the
///   high-level tree with its boxes (stored uncoded, as the paper keeps
///   it), the trees' first triangles and vertices and the id maps stay in
///   memory besides the cache. See [`HccOocBvh::cache_stats`].
///
/// Both modes answer every query identically.
#[derive(Debug)]
pub struct HccOocBvh {
    mode: Mode,
    sizes: Option<OocSizes>,
}

impl HccOocBvh {
    /// The decoded i-HCCMesh (`None` out of core, where it is never whole).
    pub fn hcc(&self) -> Option<&HccBvh> {
        match &self.mode {
            Mode::Whole { hcc, .. } => Some(hcc),
            Mode::Paged(_) => None,
        }
    }

    /// Active edges by triangle id, read from the file when opened (in
    /// both modes: out of core, they stay in memory beside the high-level
    /// tree).
    pub fn edge_flags(&self) -> &EdgeFlags {
        match &self.mode {
            Mode::Whole { hcc, .. } => hcc.edge_flags(),
            Mode::Paged(p) => p.edge_flags(),
        }
    }

    /// Whether the model is out of core (trees decoded on demand).
    pub fn is_paged(&self) -> bool {
        matches!(self.mode, Mode::Paged(_))
    }

    /// The cache's counters out of core (`None` pre-loaded).
    pub fn cache_stats(&self) -> Option<CacheStats> {
        match &self.mode {
            Mode::Whole { .. } => None,
            Mode::Paged(p) => Some(p.cache_stats()),
        }
    }

    /// The bytes of the i-HCCMesh the file decodes to: exact pre-loaded,
    /// estimated from the header's counts out of core.
    pub fn decoded_bytes(&self) -> usize {
        match &self.mode {
            Mode::Whole { hcc, .. } => hcc.bytes_total(),
            Mode::Paged(p) => p.decoded_estimate(),
        }
    }

    /// The o-HCCMesh file's bytes.
    pub fn file_bytes(&self) -> &[u8] {
        match &self.mode {
            Mode::Whole { file, .. } => file,
            Mode::Paged(p) => p.file(),
        }
    }

    /// The file's bytes by part (known when this value was encoded, not
    /// when it was read from a file).
    pub fn sizes(&self) -> Option<&OocSizes> {
        self.sizes.as_ref()
    }
}

impl ByteSize for HccOocBvh {
    /// Pre-loaded: the decoded i-HCCMesh's parts and the file kept beside
    /// it. Out of core: what stays in memory besides the cache (the
    /// high-level tree, the trees' firsts, the id maps) and the file.
    fn bytes_by_part(&self) -> Vec<(&'static str, usize)> {
        match &self.mode {
            Mode::Whole { hcc, file } => {
                let mut parts = hcc.bytes_by_part();
                parts.push(("o-hccmesh-file", file.len()));
                parts
            }
            Mode::Paged(p) => p.parts(),
        }
    }
}
