//! The i-HCCMesh file: [`HccBvh::to_bytes`], [`HccBvh::from_bytes`],
//! [`HccBvh::save`], [`HccBvh::open`] and [`HccBvh::verify`].
//!
//! # Layout
//! All integers little-endian; the frame (section table, checksums) is the
//! shared one of [`container`]. A 248-byte header, then six sections back
//! to back, ending the file.
//!
//! | bytes | field |
//! |---|---|
//! | 0–7 | magic `CBVHHCC\0` |
//! | 8–11 | version (1) |
//! | 12–15 | flags: bit 0 set for multi-triangle leaves, others 0 |
//! | 16–39 | counts: high-level nodes, low-level trees, node words, inter-connections, vertices, leaf triangles (0 unless multi) |
//! | 40–43 | triangle count |
//! | 44–95 | mass properties at density 1 ([`MassProps`]) |
//! | 96–239 | section table (offset, length, checksum) for high-level nodes, headers, node words, inter-connections, vertices, leaf triangles |
//! | 240–247 | checksum of bytes 0–239 |
//!
//! High-level nodes are [`HighNode`]s (32 bytes), headers
//! [`TreeHeader`]s (16 bytes), node words, inter-connections and leaf
//! triangles `u32`, vertices 3 × f32. The leaf rank/select bits (one
//! triangle a leaf) are not stored: they are rebuilt from the node words
//! on load, in one pass.
//!
//! # Validation
//! [`from_bytes`](HccBvh::from_bytes) checks the header, the section table
//! and every checksum; [`verify`](HccBvh::verify) walks every low-level
//! tree with checked reads and proves what queries rely on.

use std::path::Path;

use xxhash_rust::xxh3::xxh3_64;

use super::node::{
    HIGH_LEAF, HighNode, INDEX_MASK, Interconnection, MAX_TREE_VERTICES, TYPE_LEAF,
    TYPE_TEMPLATE_LEAF, TreeHeader, field, mask_half, multi_range, node_type,
};
use super::template::{TEMPLATE_COUNT, TEMPLATES};
use super::{HccBvh, HccError, HccStats};
use crate::codec::common::container;
use crate::codec::common::le::u32_at;
use crate::codec::common::{FormatError, MASS_BYTES, MassProps, atomic_write};
use crate::cursor::NodeCursor;
use crate::geom::Aabb;

/// The file version this build writes and reads.
pub const VERSION: u32 = 1;
/// The i-HCCMesh file's magic.
pub const MAGIC: [u8; 8] = *b"CBVHHCC\0";
const TABLE: usize = 96;
const SECTIONS: usize = 6;
const HEADER_LEN: usize = TABLE + 24 * SECTIONS + 8;
const _: () = assert!(HEADER_LEN == 248);
const NAMES: [&str; SECTIONS] = [
    "high-level nodes",
    "headers",
    "node words",
    "inter-connections",
    "vertices",
    "leaf triangles",
];
const ELEM: [u64; SECTIONS] = [32, 16, 4, 4, 12, 4];

fn words(b: &[u8]) -> impl Iterator<Item = u32> + '_ {
    b.chunks_exact(4)
        .map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]))
}

fn header_err(field: &'static str, why: impl Into<String>) -> HccError {
    FormatError::header(field, why).into()
}

impl HccBvh {
    /// The file bytes (see the module docs for the layout).
    pub fn to_bytes(&self) -> Vec<u8> {
        let le =
            |it: &mut dyn Iterator<Item = u32>| it.flat_map(u32::to_le_bytes).collect::<Vec<u8>>();
        let high = le(&mut self.high.iter().flat_map(|n| {
            n.min
                .into_iter()
                .chain(n.max)
                .map(f32::to_bits)
                .chain([n.a, n.b])
        }));
        let headers = le(&mut self
            .headers
            .iter()
            .flat_map(|h| [h.node_start, h.ic_start, h.vertex_start, h.first_triangle]));
        let nodes = le(&mut self.nodes.iter().copied());
        let ics = le(&mut self.ics.iter().copied());
        let verts = le(&mut self.vertices.iter().flatten().map(|v| v.to_bits()));
        let tris = le(&mut self.triangles.iter().copied());
        let mut out = Vec::with_capacity(HEADER_LEN + nodes.len() + verts.len());
        out.extend_from_slice(&MAGIC);
        for v in [
            VERSION,
            u32::from(self.multi),
            self.high.len() as u32,
            self.headers.len() as u32,
            self.nodes.len() as u32,
            self.ics.len() as u32,
            self.vertices.len() as u32,
            self.triangles.len() as u32,
            self.triangle_count,
        ] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out.extend_from_slice(&self.mass.to_bytes());
        debug_assert_eq!(out.len(), TABLE);
        let sections: [&[u8]; SECTIONS] = [&high, &headers, &nodes, &ics, &verts, &tris];
        container::write_sections(&mut out, HEADER_LEN, &sections);
        out
    }

    /// Writes the file to `path` atomically.
    pub fn save(&self, path: &Path) -> Result<(), HccError> {
        atomic_write(path, &self.to_bytes()).map_err(|e| HccError::Io {
            path: path.display().to_string(),
            message: e.to_string(),
        })
    }

    /// Reads the file at `path` (see [`from_bytes`](Self::from_bytes)).
    pub fn open(path: &Path) -> Result<HccBvh, HccError> {
        let bytes = std::fs::read(path).map_err(|e| HccError::Io {
            path: path.display().to_string(),
            message: e.to_string(),
        })?;
        Self::from_bytes(&bytes)
    }

    /// Reads a file written by [`to_bytes`](Self::to_bytes): checks the
    /// header, the section table and every checksum. Never panics. Call
    /// [`verify`](Self::verify) before querying bytes you did not write.
    pub fn from_bytes(b: &[u8]) -> Result<HccBvh, HccError> {
        container::check_header(b, HEADER_LEN, &MAGIC, "i-HCCMesh")?;
        let version = u32_at(b, 8);
        if version != VERSION {
            return Err(HccError::Version {
                found: version,
                supported: VERSION,
            });
        }
        let flags = u32_at(b, 12);
        if flags > 1 {
            return Err(header_err("flags", "reserved bits are set"));
        }
        let multi = flags == 1;
        let counts: [u32; SECTIONS] = std::array::from_fn(|k| u32_at(b, 16 + 4 * k));
        let triangle_count = u32_at(b, 40);
        let mass = MassProps::from_bytes(&b[44..44 + MASS_BYTES]).ok_or_else(|| {
            header_err(
                "mass properties",
                "a value is not finite or the mass is negative",
            )
        })?;
        let mut at = HEADER_LEN as u64;
        let mut ranges: [std::ops::Range<usize>; SECTIONS] = Default::default();
        for k in 0..SECTIONS {
            let (off, len, hash) = container::section_entry(b, TABLE, k);
            if off != at {
                return Err(header_err(
                    NAMES[k],
                    format!("the section starts at {off}, not at {at}"),
                ));
            }
            if len != u64::from(counts[k]) * ELEM[k] {
                return Err(header_err(
                    NAMES[k],
                    format!("{len} bytes for {} entries", counts[k]),
                ));
            }
            let end = off + len;
            if end > b.len() as u64 {
                return Err(FormatError::Truncated {
                    section: NAMES[k],
                    need: end,
                    have: b.len() as u64,
                }
                .into());
            }
            let r = off as usize..end as usize;
            if xxh3_64(&b[r.clone()]) != hash {
                return Err(FormatError::Checksum { section: NAMES[k] }.into());
            }
            ranges[k] = r;
            at = end;
        }
        if at != b.len() as u64 {
            return Err(header_err(
                "length",
                format!("{} bytes follow the last section", b.len() as u64 - at),
            ));
        }
        let w = |c: &[u8], k: usize| u32_at(c, 4 * k);
        let high = b[ranges[0].clone()]
            .chunks_exact(32)
            .map(|c| HighNode {
                min: [w(c, 0), w(c, 1), w(c, 2)].map(f32::from_bits),
                max: [w(c, 3), w(c, 4), w(c, 5)].map(f32::from_bits),
                a: w(c, 6),
                b: w(c, 7),
            })
            .collect();
        let headers = b[ranges[1].clone()]
            .chunks_exact(16)
            .map(|c| TreeHeader {
                node_start: w(c, 0),
                ic_start: w(c, 1),
                vertex_start: w(c, 2),
                first_triangle: w(c, 3),
            })
            .collect();
        let vertices = b[ranges[4].clone()]
            .chunks_exact(12)
            .map(|c| [w(c, 0), w(c, 1), w(c, 2)].map(f32::from_bits))
            .collect();
        let mut out = HccBvh {
            high,
            headers,
            nodes: words(&b[ranges[2].clone()]).collect(),
            ics: words(&b[ranges[3].clone()]).collect(),
            vertices,
            triangles: words(&b[ranges[5].clone()]).collect(),
            leaf_bits: Vec::new(),
            leaf_rank: Vec::new(),
            multi,
            triangle_count,
            mass,
            stats: HccStats::default(),
        };
        if !multi {
            out.build_leaf_ranks();
        }
        out.stats.trees = out.headers.len();
        out.stats.high_nodes = out.high.len();
        out.stats.tree_vertices = out.vertices.len();
        Ok(out)
    }

    /// Proves everything a query relies on: the high-level tree is a tree
    /// over every low-level tree once; each low-level tree's runs lie in
    /// the arrays; every node word, template id, inter-connection, vertex
    /// index and triangle range is in range; every node is reached once;
    /// every decoded box is finite and inside its parent's; the leaves hold
    /// `triangle_count` triangles, ids dense.
    pub fn verify(&self) -> Result<(), HccError> {
        let bad = |tree: usize, node: usize, what: &'static str| HccError::Corrupt {
            tree: tree as u32,
            node: node as u32,
            what,
        };
        if self
            .vertices
            .iter()
            .any(|v| v.iter().any(|c| !c.is_finite()))
        {
            return Err(bad(0, 0, "a vertex has a non-finite coordinate"));
        }
        let nt = self.headers.len();
        if nt == 0 {
            return if self.high.is_empty() && self.nodes.is_empty() && self.triangle_count == 0 {
                Ok(())
            } else {
                Err(bad(
                    0,
                    0,
                    "a structure without low-level trees must be empty",
                ))
            };
        }
        // High-level tree: children after parents, each node and tree once.
        let mut tree_seen = vec![false; nt];
        let mut high_seen = vec![false; self.high.len()];
        let mut stack = vec![0usize];
        let inside = |c: &HighNode, p: &HighNode| {
            (0..3).all(|k| c.min[k] >= p.min[k] && c.max[k] <= p.max[k] && c.min[k] <= c.max[k])
        };
        while let Some(i) = stack.pop() {
            let Some(n) = self.high.get(i) else {
                return Err(bad(0, i, "a high-level child index is out of range"));
            };
            if std::mem::replace(&mut high_seen[i], true) {
                return Err(bad(0, i, "a high-level node is reached twice"));
            }
            if n.min.iter().chain(&n.max).any(|c| !c.is_finite()) {
                return Err(bad(0, i, "a high-level box is not finite"));
            }
            if n.is_leaf() {
                if n.b != HIGH_LEAF
                    || n.a as usize >= nt
                    || std::mem::replace(&mut tree_seen[n.a as usize], true)
                {
                    return Err(bad(
                        0,
                        i,
                        "a high-level leaf names a missing or repeated tree",
                    ));
                }
            } else {
                for c in [n.a as usize, n.b as usize] {
                    if c <= i || c >= self.high.len() || !inside(&self.high[c], n) {
                        return Err(bad(
                            0,
                            i,
                            "a high-level child is out of range or outside its parent",
                        ));
                    }
                    stack.push(c);
                }
            }
        }
        let mut tree_box = vec![Aabb::EMPTY; nt];
        for n in self.high.iter().filter(|n| n.is_leaf()) {
            tree_box[n.a as usize] = Aabb::from_arrays(n.min, n.max);
        }
        if !tree_seen.iter().all(|&s| s) {
            return Err(bad(
                0,
                0,
                "a low-level tree is not under the high-level tree",
            ));
        }
        // Low-level runs: increasing starts inside the arrays.
        let ends = |k: usize| {
            self.headers.get(k + 1).map_or(
                (
                    self.nodes.len() as u32,
                    self.ics.len() as u32,
                    self.vertices.len() as u32,
                ),
                |h| (h.node_start, h.ic_start, h.vertex_start),
            )
        };
        let mut triangles = 0u64;
        for (k, h) in self.headers.iter().enumerate() {
            let (ne, ie, ve) = ends(k);
            if h.node_start >= ne
                || h.ic_start > ie
                || h.vertex_start > ve
                || ne as usize > self.nodes.len()
                || ie as usize > self.ics.len()
                || ve as usize > self.vertices.len()
                || (ve - h.vertex_start) as usize > MAX_TREE_VERTICES
                || u64::from(h.first_triangle) != triangles
            {
                return Err(bad(
                    k,
                    0,
                    "the tree's header is out of order or out of range",
                ));
            }
            triangles += self.verify_tree(k, tree_box[k], (ne, ie, ve))?;
        }
        if triangles != u64::from(self.triangle_count)
            || (self.multi && self.triangles.len() as u64 != triangles)
        {
            return Err(bad(0, 0, "the leaves do not hold the triangle count"));
        }
        Ok(())
    }

    /// Walks low-level tree `k` (runs ending at `ne`, `ie`, `ve`) with
    /// checked reads; returns its triangle count.
    fn verify_tree(
        &self,
        k: usize,
        hl: Aabb,
        (ne, ie, ve): (u32, u32, u32),
    ) -> Result<u64, HccError> {
        let bad = |node: u32, what: &'static str| HccError::Corrupt {
            tree: k as u32,
            node,
            what,
        };
        let h = self.headers[k];
        let nv = ve - h.vertex_start;
        let ni = ie - h.ic_start;
        let mut seen = vec![false; (ne - h.node_start) as usize];
        let mut triangles = 0u64;
        // Check a word's vertex fields (and its inter-connection) first.
        let check_word = |pos: u32| -> Result<(), HccError> {
            let w = self.nodes[pos as usize];
            let ty = node_type(w);
            if ty > TYPE_LEAF {
                return Err(bad(pos, "a node word has an unknown type"));
            }
            if ty == TYPE_LEAF && self.multi {
                let (start, count) = multi_range(w);
                let end = u64::from(h.first_triangle) + u64::from(start) + u64::from(count);
                if end > self.triangles.len() as u64 {
                    return Err(bad(pos, "a leaf's triangles are out of range"));
                }
                for t in h.first_triangle + start..end as u32 {
                    let c = self.triangles[t as usize];
                    if c >> 27 != 0 || (0..3).any(|j| field(c, j) >= nv) {
                        return Err(bad(pos, "a triangle's corner is out of range"));
                    }
                }
                return Ok(());
            }
            for j in 0..3 {
                let v = if j == 2 && ty == TYPE_TEMPLATE_LEAF {
                    if field(w, 2) >= ni {
                        return Err(bad(pos, "an inter-connection index is out of range"));
                    }
                    self.ics[(h.ic_start + field(w, 2)) as usize] & INDEX_MASK
                } else {
                    field(w, j)
                };
                if v >= nv {
                    return Err(bad(pos, "a vertex index is out of range"));
                }
            }
            Ok(())
        };
        let rw = self.nodes[h.node_start as usize];
        if node_type(rw) != TYPE_LEAF && (rw & 31) as usize >= TEMPLATE_COUNT {
            return Err(bad(h.node_start, "the root's template id is out of range"));
        }
        check_word(h.node_start)?;
        let start = self.low_root(k as u32, hl);
        let mut stack = vec![start];
        while let Some(n) = stack.pop() {
            let local = (n.pos() - h.node_start) as usize;
            if std::mem::replace(&mut seen[local], true) {
                return Err(bad(n.pos(), "a node is reached twice"));
            }
            if self.is_leaf(&n) {
                let mut inside = true;
                let b = n.bounds();
                self.for_each_triangle(&n, |_, t| {
                    triangles += 1;
                    inside &= b.contains(&Aabb::of_triangle(t));
                });
                if !inside {
                    return Err(bad(n.pos(), "a leaf's box does not contain its triangles"));
                }
                continue;
            }
            // Children's positions, checked before any decode reads them.
            let w = self.nodes[n.pos() as usize];
            let (l, r) = if node_type(w) == TYPE_TEMPLATE_LEAF {
                let ic = Interconnection::unpack(self.ics[(h.ic_start + field(w, 2)) as usize]);
                if ic.left_template as usize >= TEMPLATE_COUNT
                    || ic.right_template as usize >= TEMPLATE_COUNT
                {
                    return Err(bad(
                        n.pos(),
                        "an inter-connection's template id is out of range",
                    ));
                }
                let l = h.node_start + ic.left_start;
                let r = l + u32::from(TEMPLATES[ic.left_template as usize].nodes);
                let rend = r + u32::from(TEMPLATES[ic.right_template as usize].nodes);
                if rend > ne {
                    return Err(bad(n.pos(), "an inter-connection points past the tree"));
                }
                (l, r)
            } else {
                let t = &TEMPLATES[n.template().unwrap_or(0) as usize];
                let local = n.pos() - n.block();
                if !t.has_children(local) || n.block() + u32::from(t.nodes) > ne {
                    return Err(bad(
                        n.pos(),
                        "a template node has no children or lies past the tree",
                    ));
                }
                let l = n.block() + t.children(local);
                (l, l + 1)
            };
            check_word(l)?;
            check_word(r)?;
            let (wl, wr) = (self.nodes[l as usize], self.nodes[r as usize]);
            let mask = mask_half(wl) | mask_half(wr) << 3;
            if (node_type(wl) == TYPE_LEAF) != (node_type(wr) == TYPE_LEAF) && mask.count_ones() < 3
            {
                return Err(bad(
                    n.pos(),
                    "an inner child beside a leaf codes more than three extents",
                ));
            }
            let parent = n.bounds();
            let mut ok = true;
            self.for_each_child(&n, |c, b| {
                let finite = b.min.is_finite() && b.max.is_finite();
                ok &= finite && parent.contains(&b);
                stack.push(c);
            });
            if !ok {
                return Err(bad(
                    n.pos(),
                    "a child's box is not finite or not inside its parent's",
                ));
            }
        }
        Ok(triangles)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::build::build_default;
    use crate::scene::{Kind, generate};

    /// Random corruptions of every array: `verify` never panics, rejects
    /// most, and whatever it accepts traverses without panicking.
    #[test]
    fn verify_never_panics_on_corrupted_structures() {
        let mesh = generate(Kind::Statue, 1500, 3, &mut |_, _| {}).unwrap();
        let good = HccBvh::encode(&build_default(&mesh).unwrap(), &mesh).unwrap();
        good.verify().unwrap();
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let mut rejected = 0;
        for round in 0..400 {
            let mut h = good.clone();
            let r = next();
            let bit = 1u32 << (r % 32);
            match round % 5 {
                0 => {
                    let i = (r >> 8) as usize % h.nodes.len();
                    h.nodes[i] ^= bit;
                }
                1 => {
                    let i = (r >> 8) as usize % h.ics.len();
                    h.ics[i] ^= bit;
                }
                2 => {
                    let i = (r >> 8) as usize % h.headers.len();
                    h.headers[i].node_start ^= bit;
                }
                3 => {
                    let i = (r >> 8) as usize % h.high.len();
                    h.high[i].a ^= bit;
                }
                _ => {
                    let i = (r >> 8) as usize % h.vertices.len();
                    h.vertices[i][(r >> 40) as usize % 3] =
                        f32::from_bits(h.vertices[i][0].to_bits() ^ bit);
                }
            }
            h.build_leaf_ranks();
            match h.verify() {
                Err(_) => rejected += 1,
                Ok(()) => {
                    // Accepted: a full traversal must not panic.
                    let (root, _) = h.root();
                    let mut stack = vec![root];
                    while let Some(n) = stack.pop() {
                        if h.is_leaf(&n) {
                            h.for_each_triangle(&n, |id, _| {
                                let _ = h.triangle(id);
                            });
                        } else {
                            h.for_each_child(&n, |c, _| stack.push(c));
                        }
                    }
                }
            }
        }
        assert!(
            rejected > 200,
            "only {rejected} of 400 corruptions rejected"
        );
    }
}
