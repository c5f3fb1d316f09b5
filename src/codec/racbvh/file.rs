//! The RACBVH container: [`RacBvh::to_bytes`] and [`RacBvh::from_bytes`].
//!
//! # Layout
//! All integers little-endian. A 312-byte header, then five sections.
//! Checksums are xxh3-64.
//!
//! | bytes | field |
//! |---|---|
//! | 0–7 | magic `CBVHRAC\0` |
//! | 8–11 | version (4; version 3 had no edge flags) |
//! | 12–15 | flags: bit 0 empty tree, bit 1 lossless vertices |
//! | 16–19 | cluster bits `k` (clusters of `2^k` nodes, 8..=14) |
//! | 20–23 | box quantization bits (8..=24) |
//! | 24–27 | node count |
//! | 28–31 | triangle count |
//! | 32–35 | most triangles per leaf |
//! | 36–39 | triangle-delta threshold |
//! | 40–63 | grid origin, grid step: 6 × f32 |
//! | 64–79 | tree bits, box bits: 2 × u64 (statistics) |
//! | 80–87 | compression seconds: f64 (statistics) |
//! | 88–99 | vertex bits (8..=24, or 32 when lossless), vertex count, vertex-index bits |
//! | 100–123 | vertex quantization origin and step: 6 × f32 |
//! | 124–127 | zero |
//! | 128–179 | mass properties at density 1 ([`MassProps`]), so that a shape needs no mesh |
//! | 180–183 | zero |
//! | 184–303 | section table: (offset u64, length u64, checksum u64) for meta, clusters, vertices, triangles, edge flags |
//! | 304–311 | checksum of bytes 0–303 |
//!
//! The meta section holds one 20-byte entry per cluster: the cluster's
//! offset in the clusters section (u64), its node count (u32) and the
//! checksum of its bytes (u64). The vertices section holds three
//! frame-of-reference arrays (x, y, z), the triangles section one (three
//! vertex indices per triangle); see [`super::mesh`]. The mesh's checksum (checked by
//! [`RacBvh::verify`]) is the checksum of the vertices section's checksum
//! followed by the triangles section's. The edge flags are the section
//! every codec file ends with ([`edges`]), by
//! triangle id; unlike the mesh's, their checksum is checked and they are
//! decoded when the file is opened (they are read whole anyway).

use std::ops::Range;
use std::path::Path;
use std::sync::Arc;

use glam::Vec3A;
use xxhash_rust::xxh3::xxh3_64;

use super::mesh::{MeshParams, PackedMesh};
use super::{ClusterMeta, Header, RacBvh, RacError};
use crate::codec::common::container::{self, Frame};
use crate::codec::common::edges;
use crate::codec::common::le::{f32x3_at, u32_at, u64_at};
use crate::codec::common::packed::bits_for;
use crate::codec::common::quant::Grid;
use crate::codec::common::{FormatError, MASS_BYTES, MassProps, Store};
use crate::files::IoError;

/// The container version this build writes and reads.
pub const VERSION: u32 = 4;
/// The RACBVH file's magic.
pub const MAGIC: [u8; 8] = *b"CBVHRAC\0";
/// Where the section table starts.
const TABLE: usize = 184;
pub(super) const SECTIONS: usize = 5;
const HEADER_LEN: usize = TABLE + 24 * SECTIONS + 8;
const _: () = assert!(HEADER_LEN == 312);
const NAMES: [&str; SECTIONS] = ["meta", "clusters", "vertices", "triangles", edges::SECTION];
/// The file's frame: where its section table lies, its sections' names.
pub(super) const FRAME: Frame = Frame {
    table: TABLE,
    sections: &NAMES,
};
/// Bytes of one meta-table entry.
pub(super) const META_ENTRY: usize = 20;

/// A meta-table entry's bytes.
pub(super) fn meta_entry(e: &ClusterMeta, out: &mut Vec<u8>) {
    out.extend_from_slice(&e.offset.to_le_bytes());
    out.extend_from_slice(&e.nodes.to_le_bytes());
    out.extend_from_slice(&e.hash.to_le_bytes());
}

/// The checksum of the two mesh sections.
pub(super) fn mesh_hash(m: &PackedMesh) -> u64 {
    combine(xxh3_64(&m.vertices), xxh3_64(&m.triangles))
}

fn combine(a: u64, b: u64) -> u64 {
    let mut x = [0u8; 16];
    x[..8].copy_from_slice(&a.to_le_bytes());
    x[8..].copy_from_slice(&b.to_le_bytes());
    xxh3_64(&x)
}

fn header_err(field: &'static str, why: impl Into<String>) -> RacError {
    FormatError::header(field, why).into()
}

/// The header's fields, up to the section table (bytes 0–183).
pub(super) fn fields(h: &Header, m: &MeshParams, mass: &MassProps) -> Vec<u8> {
    let mut out = Vec::with_capacity(HEADER_LEN);
    out.extend_from_slice(&MAGIC);
    let flags = u32::from(h.empty) | (u32::from(m.lossless) << 1);
    for v in [
        VERSION,
        flags,
        h.cluster_bits,
        h.bits,
        h.node_count,
        h.triangle_count,
        h.max_leaf,
        h.tri_threshold,
    ] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for v in h
        .grid
        .origin
        .to_array()
        .into_iter()
        .chain(h.grid.step.to_array())
    {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&h.tree_bits.to_le_bytes());
    out.extend_from_slice(&h.bv_bits.to_le_bytes());
    out.extend_from_slice(&h.compression_seconds.to_le_bytes());
    for v in [m.vertex_bits, m.vertex_count, m.index_bits] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for v in m.origin.into_iter().chain(m.step) {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&0u32.to_le_bytes());
    debug_assert_eq!(out.len(), 128);
    out.extend_from_slice(&mass.to_bytes());
    out.extend_from_slice(&0u32.to_le_bytes());
    debug_assert_eq!(out.len(), TABLE);
    out
}

impl RacBvh {
    /// The container bytes (see [`file`](super::file) for the layout).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = fields(&self.header, &self.mesh.params(), &self.mass);
        out.reserve(self.data.len() + self.mesh.bytes() + 24 * SECTIONS + 8);
        let mut meta = Vec::with_capacity(self.meta.len() * META_ENTRY);
        for e in &self.meta {
            meta_entry(e, &mut meta);
        }
        let flags = edges::encode(&self.edges);
        let sections: [&[u8]; SECTIONS] = [
            &meta,
            &self.data,
            &self.mesh.vertices,
            &self.mesh.triangles,
            &flags,
        ];
        FRAME.write(&mut out, &sections);
        out
    }

    /// Reads a container written by [`to_bytes`](Self::to_bytes), with a
    /// cache of `cache_budget_bytes`. Checks the header, the section table
    /// and the meta table; clusters are checked when decoded (or all at once
    /// by [`verify`](Self::verify)). Never panics on bad bytes.
    pub fn from_bytes(b: &[u8], cache_budget_bytes: usize) -> Result<RacBvh, RacError> {
        Self::parse(b, &|r| Store::Owned(b[r].to_vec()), cache_budget_bytes)
    }

    /// Opens a container file out of core: the file is memory-mapped and
    /// clusters are read from it on demand (checked as
    /// [`from_bytes`](Self::from_bytes) does). The file must not be modified
    /// in place or truncated while the tree is alive; cbvh's own saves
    /// replace a file atomically, which is safe.
    pub fn open(path: &Path, cache_budget_bytes: usize) -> Result<RacBvh, RacError> {
        let io = IoError::at(path);
        let file = std::fs::File::open(path).map_err(io)?;
        // SAFETY: memmap2 requires the mapped file not to change while
        // mapped; `open` documents that requirement. Every read of the map
        // goes through bounds-checked slices and checksums, so bad contents
        // give errors, not undefined behaviour.
        let map = Arc::new(unsafe { memmap2::Mmap::map(&file) }.map_err(io)?);
        Self::parse(&map, &|r| Store::Mapped(map.clone(), r), cache_budget_bytes)
    }

    fn parse(
        b: &[u8],
        make: &dyn Fn(Range<usize>) -> Store,
        cache_budget_bytes: usize,
    ) -> Result<RacBvh, RacError> {
        if let Some(version) = container::version(b, &MAGIC)
            && version != VERSION
        {
            return Err(RacError::Version(version));
        }
        FRAME.check_header(b, &MAGIC, "RACBVH")?;
        let flags = u32_at(b, 12);
        if flags & !3 != 0 {
            return Err(header_err("flags", format!("unknown flags {flags:#x}")));
        }
        let (empty, lossless) = (flags & 1 != 0, flags & 2 != 0);
        let cluster_bits = u32_at(b, 16);
        if !(8..=14).contains(&cluster_bits) {
            return Err(header_err(
                "cluster bits",
                format!("{cluster_bits} is not in 8..=14"),
            ));
        }
        let bits = u32_at(b, 20);
        if !(8..=24).contains(&bits) {
            return Err(header_err("bits", format!("{bits} is not in 8..=24")));
        }
        let node_count = u32_at(b, 24);
        let triangle_count = u32_at(b, 28);
        if node_count == 0 || node_count >= 1 << 31 {
            return Err(header_err(
                "node count",
                format!("{node_count} is not in 1..2^31"),
            ));
        }
        if empty != (triangle_count == 0) || (empty && node_count != 1) {
            return Err(header_err(
                "flags",
                "the empty flag disagrees with the counts",
            ));
        }
        let max_leaf = u32_at(b, 32);
        let tri_threshold = u32_at(b, 36);
        if !(1..=65536).contains(&max_leaf) || !(1..=4096).contains(&tri_threshold) {
            return Err(header_err(
                "leaf size",
                "max leaf or triangle threshold out of range",
            ));
        }
        let (origin, step) = (f32x3_at(b, 40), f32x3_at(b, 52));
        if origin.iter().chain(&step).any(|v| !v.is_finite()) || step.iter().any(|&s| s < 0.0) {
            return Err(header_err(
                "grid",
                "origin or step not finite, or a negative step",
            ));
        }
        let grid = Grid {
            origin: Vec3A::from(origin),
            step: Vec3A::from(step),
            max_q: ((1u64 << bits) - 1) as u32,
        };
        let seconds = f64::from_bits(u64_at(b, 80));
        if !(seconds.is_finite() && seconds >= 0.0) {
            return Err(header_err("compression seconds", format!("{seconds}")));
        }
        let header = Header {
            cluster_bits,
            bits,
            node_count,
            triangle_count,
            max_leaf,
            tri_threshold,
            grid,
            empty,
            tree_bits: u64_at(b, 64),
            bv_bits: u64_at(b, 72),
            compression_seconds: seconds,
        };
        let (vertex_bits, vertex_count, index_bits) = (u32_at(b, 88), u32_at(b, 92), u32_at(b, 96));
        if !(lossless && vertex_bits == 32 || !lossless && (8..=24).contains(&vertex_bits)) {
            return Err(header_err(
                "vertex bits",
                format!("{vertex_bits} with lossless = {lossless}"),
            ));
        }
        if index_bits != bits_for(u64::from(vertex_count)) {
            return Err(header_err(
                "vertex-index bits",
                format!("{index_bits} for {vertex_count} vertices"),
            ));
        }
        if u32_at(b, 124) != 0 || u32_at(b, 180) != 0 {
            return Err(header_err(
                "reserved words",
                "bytes 124–127 or 180–183 are not zero",
            ));
        }
        let (morigin, mstep) = (f32x3_at(b, 100), f32x3_at(b, 112));
        if morigin.iter().chain(&mstep).any(|v| !v.is_finite()) {
            return Err(header_err("vertex grid", "not finite"));
        }
        let mass = MassProps::from_bytes(&b[128..128 + MASS_BYTES])
            .map_err(|why| header_err("mass properties", why))?;
        // The clusters are checked cluster by cluster as they are decoded
        // (the meta table holds their checksums), the mesh's two sections
        // when the mesh is unpacked; the meta table and the edge flags here.
        let (ranges, hashes) =
            FRAME.sections_with_checksums(b, |_, _| Ok(()), |k| (1..=3).contains(&k))?;
        let sections: [&[u8]; SECTIONS] = std::array::from_fn(|k| &b[ranges[k].clone()]);
        let hashes: [u64; SECTIONS] = std::array::from_fn(|k| hashes[k]);
        let csize = 1u64 << cluster_bits;
        let clusters = u64::from(node_count).div_ceil(csize);
        let need = clusters * META_ENTRY as u64;
        if (sections[0].len() as u64) < need {
            return Err(FormatError::Truncated {
                section: "meta",
                need,
                have: sections[0].len() as u64,
            }
            .into());
        }
        let data = sections[1];
        // Every node codes at least one bit (its structure symbol), so a
        // node count the clusters cannot hold is a forgery; this also bounds
        // what `verify` allocates per node by the file's size.
        if (data.len() as u64) * 8 < u64::from(node_count) {
            return Err(FormatError::Truncated {
                section: "clusters",
                need: u64::from(node_count).div_ceil(8),
                have: data.len() as u64,
            }
            .into());
        }
        let mut meta = Vec::with_capacity(clusters as usize);
        let mut prev = 0u64;
        for c in 0..clusters {
            let at = (c as usize) * META_ENTRY;
            let offset = u64_at(sections[0], at);
            let nodes = u32_at(sections[0], at + 8);
            let hash = u64_at(sections[0], at + 12);
            let want = csize.min(u64::from(node_count) - c * csize);
            if offset < prev || offset > data.len() as u64 || u64::from(nodes) != want {
                return Err(RacError::Corrupt(
                    "a meta-table entry is out of order, out of range or has the wrong node count",
                ));
            }
            prev = offset;
            meta.push(ClusterMeta {
                offset,
                nodes,
                hash,
            });
        }
        let mesh = PackedMesh::from_parts(
            MeshParams {
                vertex_bits,
                lossless,
                origin: morigin,
                step: mstep,
                vertex_count,
                triangle_count,
                index_bits,
            },
            make(ranges[2].clone()),
            make(ranges[3].clone()),
        )?;
        let mesh_hash = combine(hashes[2], hashes[3]);
        let edges = edges::decode(sections[4], u64::from(triangle_count))?;
        let mut rac = RacBvh::assemble(
            header,
            make(ranges[1].clone()),
            meta,
            mesh,
            mesh_hash,
            mass,
            cache_budget_bytes,
        );
        rac.edges = edges;
        Ok(rac)
    }
}
