//! The i-HCCMesh file: [`HccBvh::to_bytes`] and [`HccBvh::from_bytes`]
//! (the [`Codec`](crate::codec::Codec) contract's default `save` and `open`
//! write and read them); [`HccBvh::verify`] is in `verify.rs`.
//!
//! # Layout
//! All integers little-endian; the frame (section table, checksums) is the
//! shared one of [`container`]. A 408-byte header, then eleven sections
//! back to back, ending the file.
//!
//! | bytes | field |
//! |---|---|
//! | 0–7 | magic `CBVHHCC\0` |
//! | 8–11 | version (3; version 2 had no edge flags) |
//! | 12–15 | flags: bit 0 multi-triangle leaves, bit 1 quantized vertices, bit 2 vertex ids kept, bit 3 tree order (no triangle id map; the `ids` section empty); others 0 |
//! | 16–35 | counts: high-level nodes, low-level trees, node words, inter-connections, stored vertices |
//! | 36–39 | triangle count |
//! | 40–43 | input mesh's vertex count |
//! | 44–47 | bits per quantized coordinate (0 for `f32` vertices) |
//! | 48–83 | quantization grid origin, step and measured error, 3 × f32 each (zeros for `f32` vertices) |
//! | 84–135 | mass properties at density 1 ([`MassProps`]) |
//! | 136–399 | section table (offset, length, checksum) of the eleven sections below |
//! | 400–407 | checksum of bytes 0–399 |
//!
//! Sections, in order: high-level nodes ([`HighNode`], 32 bytes each),
//! low-level headers ([`TreeHeader`], 16 bytes), node words (`u32`),
//! inter-connections (`u32`), vertices (3 × `f32` each, or the packed
//! runs), packed runs' [`VertexTree`]s (16 bytes per tree; quantized
//! only), triangle blocks (multi-triangle leaves only), each tree's first
//! block byte (`u32`; multi only), the `ids` section and the `vertex ids`
//! section (when kept; layouts in `ids.rs`), and the edge flags, the
//! section every codec file ends with
//! ([`edges`]), by triangle id (the ids the
//! cursor reports: the input's, or tree order without the id map). The
//! leaf rank/select bits and the id map's running counts are rebuilt on
//! load, in one pass.
//!
//! # Validation
//! [`from_bytes`](HccBvh::from_bytes) checks the header, the section
//! table, every checksum and the frames of the variable-length sections,
//! and decodes the edge flags;
//! [`verify`](HccBvh::verify) walks every low-level tree with checked
//! reads and proves what queries rely on.

use super::ids::{IdMap, VertexIds};
use super::node::{HighNode, MAX_TREES, TreeHeader};
use super::vertices::{Quantized, VertexTree, Vertices};
use super::{HccBvh, HccError, HccStats};
use crate::codec::common::container::{self, Frame};
use crate::codec::common::edges;
use crate::codec::common::le::{f32x3_at, u32_at, word_bytes, words};
use crate::codec::common::{FormatError, MASS_BYTES, MassProps};

/// The file version this build writes and reads.
pub const VERSION: u32 = 3;
/// The i-HCCMesh file's magic.
pub const MAGIC: [u8; 8] = *b"CBVHHCC\0";
const MASS_AT: usize = 84;
const TABLE: usize = MASS_AT + MASS_BYTES;
const SECTIONS: usize = 11;
const HEADER_LEN: usize = TABLE + 24 * SECTIONS + 8;
const _: () = assert!(HEADER_LEN == 408);
const NAMES: [&str; SECTIONS] = [
    "high-level nodes",
    "headers",
    "node words",
    "inter-connections",
    "vertices",
    "vertex runs",
    "triangle blocks",
    "block starts",
    "ids",
    "vertex ids",
    edges::SECTION,
];
/// The file's frame: where its section table lies, its sections' names.
pub(super) const FRAME: Frame = Frame {
    table: TABLE,
    sections: &NAMES,
};
const FLAG_MULTI: u32 = 1;
const FLAG_QUANTIZED: u32 = 2;
const FLAG_VERTEX_IDS: u32 = 4;
const FLAG_TREE_ORDER: u32 = 8;

fn header_err(field: &'static str, why: impl Into<String>) -> HccError {
    FormatError::header(field, why).into()
}

impl HccBvh {
    /// The file bytes (see the module docs for the layout).
    pub fn to_bytes(&self) -> Vec<u8> {
        let high = word_bytes(self.high.iter().flat_map(|n| {
            n.min
                .into_iter()
                .chain(n.max)
                .map(f32::to_bits)
                .chain([n.a, n.b])
        }));
        let headers = word_bytes(
            self.headers
                .iter()
                .flat_map(|h| [h.node_start, h.ic_start, h.vertex_start, h.first_triangle]),
        );
        let nodes = word_bytes(self.nodes.iter().copied());
        let ics = word_bytes(self.ics.iter().copied());
        let (verts, runs) = match &self.vertices {
            Vertices::F32(v) => (
                word_bytes(v.iter().flatten().map(|c| c.to_bits())),
                Vec::new(),
            ),
            Vertices::Packed(q) => (
                q.data.clone(),
                word_bytes(
                    q.trees
                        .iter()
                        .flat_map(|t| [t.axes[0], t.axes[1], t.axes[2], t.byte]),
                ),
            ),
        };
        let starts = word_bytes(self.block_start.iter().copied());
        let ids = self.ids.as_ref().map_or(Vec::new(), IdMap::to_bytes);
        let vids = self
            .vertex_ids
            .as_ref()
            .map_or(Vec::new(), VertexIds::to_bytes);
        let q = self.vertices.quantized();
        let flags = u32::from(self.multi) * FLAG_MULTI
            + u32::from(q.is_some()) * FLAG_QUANTIZED
            + u32::from(self.vertex_ids.is_some()) * FLAG_VERTEX_IDS
            + u32::from(self.ids.is_none()) * FLAG_TREE_ORDER;
        let mut out = Vec::with_capacity(HEADER_LEN + nodes.len() + verts.len() + ids.len());
        out.extend_from_slice(&MAGIC);
        for v in [
            VERSION,
            flags,
            self.high.len() as u32,
            self.headers.len() as u32,
            self.nodes.len() as u32,
            self.ics.len() as u32,
            self.stats.tree_vertices as u32,
            self.triangle_count,
            self.mesh_vertices,
            q.map_or(0, |q| q.bits),
        ] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        let grid = q.map_or([[0f32; 3]; 3], |q| [q.origin, q.step, q.error]);
        for c in grid.iter().flatten() {
            out.extend_from_slice(&c.to_le_bytes());
        }
        debug_assert_eq!(out.len(), MASS_AT);
        out.extend_from_slice(&self.mass.to_bytes());
        debug_assert_eq!(out.len(), TABLE);
        let sections: [&[u8]; SECTIONS] = [
            &high,
            &headers,
            &nodes,
            &ics,
            &verts,
            &runs,
            &self.blocks,
            &starts,
            &ids,
            &vids,
            &edges::encode(&self.edges),
        ];
        FRAME.write(&mut out, &sections);
        out
    }

    /// Reads a file written by [`to_bytes`](Self::to_bytes): checks the
    /// header, the section table, every checksum and the frames of the
    /// variable-length sections. Never panics. Call
    /// [`verify`](Self::verify) before querying bytes you did not write.
    pub fn from_bytes(b: &[u8]) -> Result<HccBvh, HccError> {
        if let Some(found) = container::version(b, &MAGIC)
            && found != VERSION
        {
            return Err(HccError::Version {
                found,
                supported: VERSION,
            });
        }
        FRAME.check_header(b, &MAGIC, "i-HCCMesh")?;
        let flags = u32_at(b, 12);
        if flags > FLAG_MULTI | FLAG_QUANTIZED | FLAG_VERTEX_IDS | FLAG_TREE_ORDER {
            return Err(header_err("flags", "reserved bits are set"));
        }
        let (multi, quantized, has_vids, tree_order) = (
            flags & FLAG_MULTI != 0,
            flags & FLAG_QUANTIZED != 0,
            flags & FLAG_VERTEX_IDS != 0,
            flags & FLAG_TREE_ORDER != 0,
        );
        let [
            n_high,
            n_trees,
            n_nodes,
            n_ics,
            n_verts,
            triangle_count,
            mesh_vertices,
            bits,
        ] = std::array::from_fn(|k| u32_at(b, 16 + 4 * k));
        let mass = MassProps::from_bytes(&b[MASS_AT..TABLE])
            .map_err(|why| header_err("mass properties", why))?;
        if n_trees as usize > MAX_TREES {
            return Err(header_err(
                "low-level trees",
                format!("{n_trees} is more than {MAX_TREES}"),
            ));
        }
        let (trees, verts) = (u64::from(n_trees), u64::from(n_verts));
        // Each section's length: exact, or `None` for a variable one.
        let fixed = |on: bool, n: u64| Some(if on { n } else { 0 });
        let want: [Option<u64>; SECTIONS] = [
            Some(32 * u64::from(n_high)),
            Some(16 * trees),
            Some(4 * u64::from(n_nodes)),
            Some(4 * u64::from(n_ics)),
            if quantized { None } else { Some(12 * verts) },
            fixed(quantized, 16 * trees),
            if multi { None } else { Some(0) },
            fixed(multi, 4 * trees),
            if tree_order { Some(0) } else { None },
            if has_vids { None } else { Some(0) },
            None,
        ];
        let ranges = FRAME.sections(
            b,
            |k, len| match want[k] {
                Some(w) if w != len => Err(format!("{len} bytes where the counts give {w}")),
                _ => Ok(()),
            },
            |_| false,
        )?;
        let sec = |k: usize| &b[ranges[k].clone()];
        let w = |c: &[u8], k: usize| u32_at(c, 4 * k);
        let high = sec(0)
            .chunks_exact(32)
            .map(|c| HighNode {
                min: [w(c, 0), w(c, 1), w(c, 2)].map(f32::from_bits),
                max: [w(c, 3), w(c, 4), w(c, 5)].map(f32::from_bits),
                a: w(c, 6),
                b: w(c, 7),
            })
            .collect();
        let headers = sec(1)
            .chunks_exact(16)
            .map(|c| TreeHeader {
                node_start: w(c, 0),
                ic_start: w(c, 1),
                vertex_start: w(c, 2),
                first_triangle: w(c, 3),
            })
            .collect();
        let vertices = if quantized {
            let q = Quantized {
                bits,
                origin: f32x3_at(b, 48),
                step: f32x3_at(b, 60),
                error: f32x3_at(b, 72),
                trees: sec(5)
                    .chunks_exact(16)
                    .map(|c| VertexTree {
                        axes: [w(c, 0), w(c, 1), w(c, 2)],
                        byte: w(c, 3),
                    })
                    .collect(),
                data: sec(4).to_vec(),
            };
            q.check_grid()?;
            Vertices::Packed(q)
        } else {
            if bits != 0 || b[48..84].iter().any(|&x| x != 0) {
                return Err(header_err(
                    "vertex grid",
                    "f32 vertices with quantization fields set",
                ));
            }
            Vertices::F32(
                sec(4)
                    .chunks_exact(12)
                    .map(|c| [w(c, 0), w(c, 1), w(c, 2)].map(f32::from_bits))
                    .collect(),
            )
        };
        let ids = if tree_order {
            None
        } else {
            Some(IdMap::parse(sec(8), triangle_count)?)
        };
        let vertex_ids = if has_vids {
            Some(VertexIds::parse(sec(9), n_verts)?)
        } else {
            None
        };
        let edges = edges::decode(sec(10), u64::from(triangle_count))?;
        let mut out = HccBvh {
            high,
            headers,
            nodes: words(sec(2)).collect(),
            ics: words(sec(3)).collect(),
            vertices,
            blocks: sec(6).to_vec(),
            block_start: words(sec(7)).collect(),
            leaf_bits: Vec::new(),
            leaf_rank: Vec::new(),
            ids,
            vertex_ids,
            multi,
            triangle_count,
            mesh_vertices,
            mass,
            edges,
            stats: HccStats::default(),
        };
        out.build_leaf_ranks();
        out.stats.trees = out.headers.len();
        out.stats.high_nodes = out.high.len();
        out.stats.tree_vertices = n_verts as usize;
        Ok(out)
    }
}
