//! The CLBVH file: [`ClBvh::to_bytes`] and [`ClBvh::from_bytes`] (the
//! [`Codec`](crate::codec::Codec) contract's default `save` and `open`
//! write and read them); [`ClBvh::verify`] is in `verify.rs`.
//!
//! # Layout
//! All integers little-endian. A 288-byte header, then seven sections
//! back to back in this order, ending the file. Checksums are xxh3-64.
//!
//! | bytes | field |
//! |---|---|
//! | 0–7 | magic: `CBVHCLB\0` fast leaves, `CBVHCLC\0` compact leaves |
//! | 8–11 | version (2; version 1 had no edge flags) |
//! | 12–15 | flags: bit 1 multi-leaf nodes; others 0 |
//! | 16–19 | leaf size `M` |
//! | 20–23 | root [`ChildRef`](super::ChildRef) |
//! | 24–47 | root box (min xyz, max xyz; f32) |
//! | 48–51 | multi-leaf node count |
//! | 52–55 | triangle count |
//! | 56–107 | mass properties at density 1 ([`MassProps`]) |
//! | 108–111 | zero |
//! | 112–279 | section table: (offset u64, length u64, checksum u64) for inner nodes (224 B each), arena (u32 words), vertices (12 B), triangles (12 B; fast), slots (u32; compact), blocks (2 × u32; compact), edge flags |
//! | 280–287 | checksum of bytes 0–279 |
//!
//! A section length that is not a whole number of its entries is an error;
//! the triangle and slot sections hold one entry a triangle (the one the
//! variant does not use is empty). The edge flags are the section every
//! codec file ends with ([`edges`]), by
//! triangle id, decoded by [`from_bytes`](ClBvh::from_bytes).

use super::node::InnerNode;
use super::{ClBvh, ClError, ClOptions, LeafKind};
use crate::codec::common::container::{Frame, version};
use crate::codec::common::edges;
use crate::codec::common::huge::huge;
use crate::codec::common::le::{u32_at, word_bytes, words};
use crate::codec::common::{FormatError, MASS_BYTES, MassProps};
use crate::geom::Aabb;

/// The file version this build writes and reads.
pub const VERSION: u32 = 2;
/// The magic of a CLBVH file with fast leaves.
pub const MAGIC: [u8; 8] = *b"CBVHCLB\0";
/// The magic of a CLBVH file with compact leaves.
pub const MAGIC_COMPACT: [u8; 8] = *b"CBVHCLC\0";
const TABLE: usize = 112;
const SECTIONS: usize = 7;
const HEADER_LEN: usize = TABLE + 24 * SECTIONS + 8;
const _: () = assert!(HEADER_LEN == 288);
const NAMES: [&str; SECTIONS] = [
    "inner nodes",
    "arena",
    "vertices",
    "triangles",
    "slots",
    "blocks",
    edges::SECTION,
];
/// The file's frame: where its section table lies, its sections' names.
pub(super) const FRAME: Frame = Frame {
    table: TABLE,
    sections: &NAMES,
};
/// Bytes of a section's entries (the edge flags are a byte stream).
const ELEM: [u64; SECTIONS] = [224, 4, 12, 12, 4, 8, 1];

fn header_err(field: &'static str, why: impl Into<String>) -> ClError {
    FormatError::header(field, why).into()
}

impl ClBvh {
    /// The file bytes (see the module docs for the layout).
    pub fn to_bytes(&self) -> Vec<u8> {
        let inner: &[u32] = bytemuck::cast_slice(&self.inner);
        let sections: [Vec<u8>; SECTIONS] = [
            word_bytes(inner.iter().copied()),
            word_bytes(self.arena.iter().copied()),
            word_bytes(self.vertices.iter().flatten().map(|f| f.to_bits())),
            word_bytes(self.triangles.iter().flatten().copied()),
            word_bytes(self.slot_of.iter().copied()),
            word_bytes(self.blocks.iter().flatten().copied()),
            edges::encode(&self.edges),
        ];
        let mut out = Vec::with_capacity(HEADER_LEN + sections.iter().map(Vec::len).sum::<usize>());
        out.extend_from_slice(match self.options.leaves {
            LeafKind::Fast => &MAGIC,
            LeafKind::Compact => &MAGIC_COMPACT,
        });
        let flags = u32::from(self.options.multi_leaf) << 1;
        for v in [VERSION, flags, self.options.leaf_size as u32, self.root] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        for f in self
            .root_box
            .min
            .to_array()
            .into_iter()
            .chain(self.root_box.max.to_array())
        {
            out.extend_from_slice(&f.to_le_bytes());
        }
        for v in [
            self.multi_nodes as u32,
            crate::cursor::NodeCursor::triangle_count(self) as u32,
        ] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out.extend_from_slice(&self.mass.to_bytes());
        out.extend_from_slice(&0u32.to_le_bytes());
        debug_assert_eq!(out.len(), TABLE);
        let refs: Vec<&[u8]> = sections.iter().map(Vec::as_slice).collect();
        FRAME.write(&mut out, &refs);
        out
    }

    /// Reads a file written by [`to_bytes`](Self::to_bytes): checks the
    /// header, the section table (sections back to back, whole elements,
    /// ending the file) and the checksums. Never panics and never allocates
    /// more than the bytes given. Call [`verify`](Self::verify) before
    /// querying bytes you did not write yourself.
    pub fn from_bytes(b: &[u8]) -> Result<ClBvh, ClError> {
        let (leaves, magic) = if b.starts_with(&MAGIC_COMPACT) {
            (LeafKind::Compact, &MAGIC_COMPACT)
        } else {
            (LeafKind::Fast, &MAGIC)
        };
        if let Some(found) = version(b, magic)
            && found != VERSION
        {
            return Err(ClError::Version {
                found,
                supported: VERSION,
            });
        }
        FRAME.check_header(b, magic, "CLBVH")?;
        let flags = u32_at(b, 12);
        if flags & !2 != 0 || u32_at(b, 108) != 0 {
            return Err(header_err("flags", "reserved bits are set"));
        }
        let options = ClOptions {
            leaf_size: u32_at(b, 16) as usize,
            leaves,
            multi_leaf: flags & 2 != 0,
        };
        if !(1..=super::MAX_LEAF_SIZE).contains(&options.leaf_size) {
            return Err(header_err("leaf size", format!("{}", options.leaf_size)));
        }
        let root = u32_at(b, 20);
        let f = |k: usize| f32::from_bits(u32_at(b, 24 + 4 * k));
        let root_box = Aabb::from_arrays([f(0), f(1), f(2)], [f(3), f(4), f(5)]);
        let multi_nodes = u32_at(b, 48) as usize;
        let tris = u32_at(b, 52) as usize;
        let mass = MassProps::from_bytes(&b[56..56 + MASS_BYTES])
            .map_err(|why| header_err("mass properties", why))?;
        let ranges = FRAME.sections(
            b,
            |k, len| {
                if len % ELEM[k] == 0 {
                    Ok(())
                } else {
                    Err(format!(
                        "{len} bytes is not a whole number of {}-byte entries",
                        ELEM[k]
                    ))
                }
            },
            |_| false,
        )?;
        let expect_tris = |k: usize, per: usize| {
            let n = ranges[k].len() / ELEM[k] as usize;
            if n == tris * per {
                Ok(())
            } else {
                Err(header_err(
                    NAMES[k],
                    format!("{n} entries for {tris} triangles"),
                ))
            }
        };
        match options.leaves {
            LeafKind::Fast => {
                expect_tris(3, 1)?;
                expect_tris(4, 0)?;
                if !ranges[5].is_empty() {
                    return Err(header_err("blocks", "a fast tree has no block table"));
                }
            }
            LeafKind::Compact => {
                expect_tris(3, 0)?;
                expect_tris(4, 1)?;
            }
        }
        let inner = b[ranges[0].clone()].chunks_exact(224).map(|c| {
            let mut n = InnerNode::EMPTY;
            let dst: &mut [u32] = bytemuck::cast_slice_mut(std::slice::from_mut(&mut n));
            for (d, w) in dst.iter_mut().zip(words(c)) {
                *d = w;
            }
            n
        });
        let w = |c: &[u8], k: usize| u32_at(c, 4 * k);
        let edges = edges::decode(&b[ranges[6].clone()], tris as u64)?;
        Ok(ClBvh {
            options,
            inner: huge(inner),
            arena: huge(words(&b[ranges[1].clone()])),
            multi_nodes,
            root,
            root_box,
            vertices: huge(
                b[ranges[2].clone()]
                    .chunks_exact(12)
                    .map(|c| [w(c, 0), w(c, 1), w(c, 2)].map(f32::from_bits)),
            ),
            triangles: huge(
                b[ranges[3].clone()]
                    .chunks_exact(12)
                    .map(|c| [w(c, 0), w(c, 1), w(c, 2)]),
            ),
            slot_of: words(&b[ranges[4].clone()]).collect(),
            blocks: b[ranges[5].clone()]
                .chunks_exact(8)
                .map(|c| [w(c, 0), w(c, 1)])
                .collect(),
            mass,
            edges,
        })
    }
}
