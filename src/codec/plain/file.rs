//! The plain BVH file: [`PlainBvh::to_bytes`] and [`PlainBvh::from_bytes`]
//! (the [`Codec`](crate::codec::Codec) contract's default `save` and `open`
//! write and read them); [`PlainBvh::verify`] is in `verify.rs`.
//!
//! # Layout
//! All integers little-endian. A 216-byte header, then five sections back
//! to back in this order, ending the file. Checksums are xxh3-64.
//!
//! | bytes | field |
//! |---|---|
//! | 0–7 | magic `CBVHPLN\0` |
//! | 8–11 | version (2; version 1 had no edge flags) |
//! | 12–15 | flags (0) |
//! | 16–19 | node count (≥ 1) |
//! | 20–23 | vertex count |
//! | 24–27 | triangle count |
//! | 28–31 | leaf-id count (0: one triangle per leaf, stored in the leaf) |
//! | 32–83 | mass properties at density 1 ([`MassProps`]) |
//! | 84–87 | zero |
//! | 88–207 | section table: (offset u64, length u64, checksum u64) for nodes, vertices, triangles, leaf ids, edge flags |
//! | 208–215 | checksum of bytes 0–207 |
//!
//! Nodes are [`PlainNode`]s (32 bytes), vertices 3 × f32, triangles
//! 3 × u32, leaf ids u32; the edge flags are the section every codec file
//! ends with ([`edges`]), by triangle id.
//!
//! # Validation
//! [`from_bytes`](PlainBvh::from_bytes) checks the header, the section
//! table and every checksum (the bytes are copied into memory anyway), and
//! decodes the edge flags;
//! [`verify`](PlainBvh::verify) proves what queries rely on. A tree that
//! was not verified may make a query panic or loop; the CLI, the sims and
//! [`crate::codec::AnyCodec::open`] verify by default.

use super::node::PlainNode;
use super::{PlainBvh, PlainError};
use crate::codec::common::container::{self, Frame};
use crate::codec::common::edges;
use crate::codec::common::huge::huge;
use crate::codec::common::le::{u32_at, words};
use crate::codec::common::{FormatError, MASS_BYTES, MassProps};

/// The file version this build writes and reads.
pub const VERSION: u32 = 2;
/// The plain file's magic.
pub const MAGIC: [u8; 8] = *b"CBVHPLN\0";
const SECTIONS: usize = 5;
const TABLE: usize = 88;
const HEADER_LEN: usize = TABLE + 24 * SECTIONS + 8;
const _: () = assert!(HEADER_LEN == 216);
const NAMES: [&str; SECTIONS] = ["nodes", "vertices", "triangles", "leaf ids", edges::SECTION];
/// The file's frame: where its section table lies, its sections' names.
pub(super) const FRAME: Frame = Frame {
    table: TABLE,
    sections: &NAMES,
};

fn header_err(field: &'static str, why: impl Into<String>) -> PlainError {
    FormatError::header(field, why).into()
}

impl PlainBvh {
    /// The file bytes (see the module docs for the layout).
    pub fn to_bytes(&self) -> Vec<u8> {
        let nodes: Vec<u8> = self
            .nodes
            .iter()
            .flat_map(|n| {
                n.min
                    .into_iter()
                    .chain(n.max)
                    .map(f32::to_bits)
                    .chain([n.left, n.right])
            })
            .flat_map(u32::to_le_bytes)
            .collect();
        let verts: Vec<u8> = self
            .vertices
            .iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let tris: Vec<u8> = self
            .triangles
            .iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let ids: Vec<u8> = self.leaf_ids.iter().flat_map(|v| v.to_le_bytes()).collect();
        let flags = edges::encode(&self.edges);
        let mut out = Vec::with_capacity(HEADER_LEN + nodes.len() + verts.len() + tris.len());
        out.extend_from_slice(&MAGIC);
        for v in [
            VERSION,
            0,
            self.nodes.len() as u32,
            self.vertices.len() as u32,
            self.triangles.len() as u32,
            self.leaf_ids.len() as u32,
        ] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out.extend_from_slice(&self.mass.to_bytes());
        out.extend_from_slice(&0u32.to_le_bytes());
        debug_assert_eq!(out.len(), TABLE);
        let sections: [&[u8]; SECTIONS] = [&nodes, &verts, &tris, &ids, &flags];
        FRAME.write(&mut out, &sections);
        out
    }

    /// Reads a file written by [`to_bytes`](Self::to_bytes): checks the
    /// header, the section table (sections back to back, sized by the
    /// counts, ending the file) and every checksum. Never panics and never
    /// allocates more than the bytes given. Call [`verify`](Self::verify)
    /// before querying bytes you did not write yourself.
    pub fn from_bytes(b: &[u8]) -> Result<PlainBvh, PlainError> {
        if let Some(found) = container::version(b, &MAGIC)
            && found != VERSION
        {
            return Err(PlainError::Version {
                found,
                supported: VERSION,
            });
        }
        FRAME.check_header(b, &MAGIC, "plain BVH")?;
        if u32_at(b, 12) != 0 || u32_at(b, 84) != 0 {
            return Err(header_err("flags", "reserved bits are set"));
        }
        let counts = [u32_at(b, 16), u32_at(b, 20), u32_at(b, 24), u32_at(b, 28)];
        if counts[0] == 0 {
            return Err(header_err("node count", "a tree has at least one node"));
        }
        let mass = MassProps::from_bytes(&b[32..32 + MASS_BYTES])
            .map_err(|why| header_err("mass properties", why))?;
        let elem = [32u64, 12, 12, 4];
        // The edge flags are variable-length: bounded by the file.
        let ranges = FRAME.sections(
            b,
            |k, len| match elem.get(k) {
                Some(e) if len != u64::from(counts[k]) * e => {
                    Err(format!("{len} bytes for {} entries", counts[k]))
                }
                _ => Ok(()),
            },
            |_| false,
        )?;
        // Fixed-size reads (no per-record allocation): the word `k` of a
        // record `c`.
        let w = |c: &[u8], k: usize| u32_at(c, 4 * k);
        let nodes = b[ranges[0].clone()].chunks_exact(32).map(|c| PlainNode {
            min: [w(c, 0), w(c, 1), w(c, 2)].map(f32::from_bits),
            max: [w(c, 3), w(c, 4), w(c, 5)].map(f32::from_bits),
            left: w(c, 6),
            right: w(c, 7),
        });
        let vertices = b[ranges[1].clone()]
            .chunks_exact(12)
            .map(|c| [w(c, 0), w(c, 1), w(c, 2)].map(f32::from_bits));
        let triangles = b[ranges[2].clone()]
            .chunks_exact(12)
            .map(|c| [w(c, 0), w(c, 1), w(c, 2)]);
        let edges = edges::decode(&b[ranges[4].clone()], u64::from(counts[2]))?;
        Ok(PlainBvh {
            nodes: huge(nodes),
            vertices: huge(vertices),
            triangles: huge(triangles),
            leaf_ids: huge(words(&b[ranges[3].clone()])),
            mass,
            edges,
        })
    }
}
