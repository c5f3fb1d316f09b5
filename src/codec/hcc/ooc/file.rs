//! The o-HCCMesh file's frame: header fields and sections, written and
//! parsed (layout in the module docs of [`ooc`](super)); and
//! [`HccOocBvh::from_bytes`], [`HccOocBvh::open`] (either mode, by the
//! cache budget) and [`HccOocBvh::save`].

use std::path::Path;
use std::sync::Arc;

use super::super::node::MAX_TREES;
use super::paged::{self, Paged};
use super::{HccOocBvh, Mode, OocError, decode};
use crate::codec::common::container::{self, Frame};
use crate::codec::common::le::{f32x3_at, u32_at};
use crate::codec::common::{FormatError, MASS_BYTES, MassProps, Store, edges};
use crate::files::IoError;

/// The file version this build writes and reads.
pub const VERSION: u32 = 7;
/// The o-HCCMesh file's magic.
pub const MAGIC: [u8; 8] = *b"CBVHHCO\0";
const MASS_AT: usize = 88;
pub const TABLE: usize = MASS_AT + MASS_BYTES;
/// Number of sections.
pub const SECTIONS: usize = 9;
/// Bytes of the header.
pub const HEADER_LEN: usize = TABLE + 24 * SECTIONS + 8;
const _: () = assert!(HEADER_LEN == 364);
/// Section names, in file order.
pub const NAMES: [&str; SECTIONS] = [
    "dictionaries",
    "high-level shape",
    "tree starts",
    "tree streams",
    "ids",
    "vertex ids",
    "high-level boxes",
    "tree firsts",
    edges::SECTION,
];
/// The file's frame: where its section table lies, its sections' names.
pub(in crate::codec) const FRAME: Frame = Frame {
    table: TABLE,
    sections: &NAMES,
};
/// Section index of the dictionaries.
pub const SEC_DICTS: usize = 0;
/// Section index of the high-level tree's shape bits.
pub const SEC_HIGH: usize = 1;
/// Section index of the trees' first bytes.
pub const SEC_STARTS: usize = 2;
/// Section index of the trees' coded streams.
pub const SEC_TREES: usize = 3;
/// Section index of the triangle id map.
pub const SEC_IDS: usize = 4;
/// Section index of the vertex id map.
pub const SEC_VIDS: usize = 5;
/// Section index of the high-level tree's boxes.
pub const SEC_BOXES: usize = 6;
/// Section index of each tree's first triangle and first stored vertex.
pub const SEC_FIRSTS: usize = 7;
/// Section index of the edge flags.
pub const SEC_EDGES: usize = 8;
const FLAG_VERTEX_IDS: u32 = 1;
const FLAG_TREE_ORDER: u32 = 2;
const FLAG_MULTI: u32 = 4;

/// The header's fields.
#[derive(Clone, Debug, PartialEq)]
pub struct Header {
    /// Multi-triangle leaves.
    pub multi: bool,
    /// Input vertex ids kept (section `vertex ids`).
    pub vertex_ids: bool,
    /// Triangles in tree order (no `ids` section).
    pub tree_order: bool,
    /// High-level nodes.
    pub high_nodes: u32,
    /// Low-level trees.
    pub trees: u32,
    /// i-HCCMesh node words.
    pub node_words: u32,
    /// i-HCCMesh inter-connections.
    pub interconnections: u32,
    /// Vertices stored over all trees.
    pub stored_vertices: u32,
    /// Triangles.
    pub triangles: u32,
    /// The input mesh's vertices.
    pub mesh_vertices: u32,
    /// Distinct input vertices the triangles use.
    pub used_vertices: u32,
    /// Bits per grid coordinate.
    pub bits: u32,
    /// Grid origin, step and measured error.
    pub grid: [[f32; 3]; 3],
    /// Mass properties at density 1.
    pub mass: MassProps,
}

fn header_err(field: &'static str, why: impl Into<String>) -> OocError {
    FormatError::header(field, why).into()
}

/// Writes a whole file.
pub fn write(h: &Header, sections: &[&[u8]; SECTIONS]) -> Vec<u8> {
    let len: usize = sections.iter().map(|s| s.len()).sum();
    let mut out = Vec::with_capacity(HEADER_LEN + len);
    fields(h, &mut out);
    FRAME.write(&mut out, sections);
    out
}

/// The header of a file whose sections have these `(length, checksum)`:
/// a writer that streams the sections after it.
pub fn header(h: &Header, sections: &[(u64, u64); SECTIONS]) -> Vec<u8> {
    let mut out = Vec::with_capacity(HEADER_LEN);
    fields(h, &mut out);
    FRAME.write_table(&mut out, sections);
    out
}

/// The header's fields, up to the section table.
fn fields(h: &Header, out: &mut Vec<u8>) {
    out.extend_from_slice(&MAGIC);
    let flags = u32::from(h.vertex_ids) * FLAG_VERTEX_IDS
        + u32::from(h.tree_order) * FLAG_TREE_ORDER
        + u32::from(h.multi) * FLAG_MULTI;
    for v in [
        VERSION,
        flags,
        h.high_nodes,
        h.trees,
        h.node_words,
        h.interconnections,
        h.stored_vertices,
        h.triangles,
        h.mesh_vertices,
        h.used_vertices,
        h.bits,
    ] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for c in h.grid.iter().flatten() {
        out.extend_from_slice(&c.to_le_bytes());
    }
    debug_assert_eq!(out.len(), MASS_AT);
    out.extend_from_slice(&h.mass.to_bytes());
}

/// Parses the header and the section table of `b`, checking every
/// checksum; returns the header and each section's bytes.
pub fn parse(b: &[u8]) -> Result<(Header, [&[u8]; SECTIONS]), OocError> {
    parse_with(b, true)
}

/// [`parse`], checking the tree streams' checksum only if `streams` is
/// set (on-demand decoding reads a tree's bytes only when it needs them;
/// the checksum of the whole section would read the whole file).
pub fn parse_with(b: &[u8], streams: bool) -> Result<(Header, [&[u8]; SECTIONS]), OocError> {
    if let Some(found) = container::version(b, &MAGIC)
        && found != VERSION
    {
        return Err(OocError::Version {
            found,
            supported: VERSION,
        });
    }
    FRAME.check_header(b, &MAGIC, "o-HCCMesh")?;
    let flags = u32_at(b, 12);
    if flags > FLAG_VERTEX_IDS | FLAG_TREE_ORDER | FLAG_MULTI {
        return Err(header_err("flags", "reserved bits are set"));
    }
    let f: [u32; 9] = std::array::from_fn(|k| u32_at(b, 16 + 4 * k));
    let mass = MassProps::from_bytes(&b[MASS_AT..TABLE])
        .map_err(|why| header_err("mass properties", why))?;
    let h = Header {
        multi: flags & FLAG_MULTI != 0,
        vertex_ids: flags & FLAG_VERTEX_IDS != 0,
        tree_order: flags & FLAG_TREE_ORDER != 0,
        high_nodes: f[0],
        trees: f[1],
        node_words: f[2],
        interconnections: f[3],
        stored_vertices: f[4],
        triangles: f[5],
        mesh_vertices: f[6],
        used_vertices: f[7],
        bits: f[8],
        grid: [f32x3_at(b, 52), f32x3_at(b, 64), f32x3_at(b, 76)],
        mass,
    };
    if h.trees as usize > MAX_TREES {
        return Err(header_err(
            "low-level trees",
            format!("{} is more than {MAX_TREES}", h.trees),
        ));
    }
    // Out of core (without `streams`), the trees are checked tree by tree
    // as they are paged in.
    let ranges = FRAME.sections(b, |_, _| Ok(()), |k| !streams && k == SEC_TREES)?;
    let mut out: [&[u8]; SECTIONS] = [&[]; SECTIONS];
    for (slot, r) in out.iter_mut().zip(ranges) {
        *slot = &b[r];
    }
    if (h.tree_order && !out[SEC_IDS].is_empty()) || (!h.vertex_ids && !out[SEC_VIDS].is_empty()) {
        return Err(header_err(
            "flags",
            "the id sections disagree with the flags",
        ));
    }
    Ok((h, out))
}

impl HccOocBvh {
    /// Decodes an o-HCCMesh file whole (pre-loaded; see the module docs'
    /// validation).
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, OocError> {
        Self::from_bytes_with_budget(bytes, usize::MAX)
    }

    /// Opens an o-HCCMesh file held in memory: pre-loaded if its
    /// i-HCCMesh fits `budget` bytes, else out of core with a cache of
    /// `budget` bytes.
    pub fn from_bytes_with_budget(bytes: &[u8], budget: usize) -> Result<Self, OocError> {
        Self::with_budget(Store::Owned(bytes.to_vec()), budget)
    }

    /// Reads the file at `path` and decodes it whole.
    pub fn open(path: &Path) -> Result<Self, OocError> {
        Self::open_with_budget(path, usize::MAX)
    }

    /// Opens the file at `path`: decoded whole if its i-HCCMesh fits
    /// `budget` bytes; else memory-mapped, its trees decoded on demand
    /// into a cache of `budget` bytes. The file must not be modified in
    /// place or truncated while it is open; cbvh's own saves replace a
    /// file atomically, which is safe.
    pub fn open_with_budget(path: &Path, budget: usize) -> Result<Self, OocError> {
        let io = IoError::at(path);
        let file = std::fs::File::open(path).map_err(io)?;
        // SAFETY: memmap2 requires the mapped file not to change while
        // mapped; `open_with_budget` documents that requirement. Every read
        // of the map goes through bounds-checked slices and checked
        // decoding, so bad contents give errors, not undefined behaviour.
        let map = Arc::new(unsafe { memmap2::Mmap::map(&file) }.map_err(io)?);
        let len = map.len();
        Self::with_budget(Store::Mapped(map, 0..len), budget)
    }

    /// Pre-loaded or paged, by the header's estimate of the i-HCCMesh's
    /// size against `budget`.
    pub(super) fn with_budget(file: Store, budget: usize) -> Result<Self, OocError> {
        let (h, _) = parse_with(&file, false)?;
        let mode = if paged::decoded_estimate(&h) <= budget {
            Mode::Whole {
                hcc: decode::decode(&file)?,
                file: file.to_vec(),
            }
        } else {
            Mode::Paged(Paged::new(file, budget)?)
        };
        Ok(Self { mode, sizes: None })
    }

    /// Writes the o-HCCMesh file to `path` atomically.
    pub fn save(&self, path: &Path) -> Result<(), OocError> {
        Ok(crate::files::save(path, self.file_bytes())?)
    }
}
