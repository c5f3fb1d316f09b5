//! o-HCCMesh encoding: an i-HCCMesh (quantized vertices, one triangle a
//! leaf) into the coded file, in two passes over the model (the first
//! counts each context's symbols for its dictionary, the second writes);
//! [`HccBvh::to_ooc`], and [`HccOocBvh::encode_with`] from the canonical
//! tree.

use super::super::HccBvh;
use super::super::ids::{IdMap, VertexIds};
use super::super::node::{HighNode, Interconnection, TYPE_LEAF, node_type};
use super::super::template::TEMPLATES;
use super::super::vertices::Quantized;
use super::file::{self, Header, SECTIONS};
use super::model::{
    Adjacency, CONTEXTS, CTX_CORNER, CTX_LEAF, CTX_TEMPLATE, CornerCache, Layout, PART_VERTICES,
    centre, part_of, plan, predicted, template_symbol,
};
use super::paged::Paged;
use super::{HccOocBvh, Mode, OocError, OocOptions};
use crate::build::CanonicalBvh;
use crate::codec::ByteSize;
use crate::codec::common::Store;
use crate::codec::common::bits::{BitWriter, zigzag};
use crate::codec::common::edges;
use crate::codec::common::static_dict::{StaticDict, StaticEncoder};
use crate::hash::FastMap;
use crate::mesh::Mesh;

/// Bytes of an o-HCCMesh file by part.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct OocSizes {
    /// Header and section table.
    pub header: usize,
    /// The contexts' dictionaries.
    pub dictionaries: usize,
    /// The high-level tree: its shape (a bit a node) and its boxes (on the
    /// vertex grid, children against their parent: a few bytes a node).
    pub high_level: usize,
    /// Per low-level tree its stream's length, triangle count and stored
    /// vertex count (summed at open for random access; a few bits each).
    pub tree_starts: usize,
    /// Template symbols (tree structure and inter-connections), in bits/8.
    pub templates: f64,
    /// Corner symbols (vertex indices), in bits/8.
    pub corners: f64,
    /// Vertex residuals, in bits/8.
    pub vertices: f64,
    /// Bits that pad each tree's stream to a byte, in bits/8.
    pub padding: f64,
    /// The triangle id map (when kept).
    pub ids: usize,
    /// The vertex id map (when kept).
    pub vertex_ids: usize,
    /// The edge flags ([`edges`](crate::codec::common::edges)).
    pub edge_flags: usize,
}

impl OocSizes {
    /// The sizes of a file whose sections are `section_lens` bytes long
    /// (in file order, [`SECTIONS`] of them) and whose trees' streams hold
    /// `part_bits` bits of templates, corners and vertices (the rest of
    /// the streams' bytes is padding). What [`encode`] and the
    /// out-of-core builder both report.
    pub(super) fn from_sections(section_lens: &[u64; SECTIONS], part_bits: &[u64; 3]) -> Self {
        let len = |k: usize| section_lens[k] as usize;
        let coded: u64 = part_bits.iter().sum();
        Self {
            header: file::HEADER_LEN,
            dictionaries: len(file::SEC_DICTS),
            high_level: len(file::SEC_HIGH) + len(file::SEC_BOXES),
            tree_starts: len(file::SEC_STARTS) + len(file::SEC_FIRSTS),
            templates: part_bits[0] as f64 / 8.0,
            corners: part_bits[1] as f64 / 8.0,
            vertices: part_bits[2] as f64 / 8.0,
            padding: (section_lens[file::SEC_TREES] * 8 - coded) as f64 / 8.0,
            ids: len(file::SEC_IDS),
            vertex_ids: len(file::SEC_VIDS),
            edge_flags: len(file::SEC_EDGES),
        }
    }

    /// The parts as `(name, bytes)`.
    pub fn parts(&self) -> Vec<(&'static str, f64)> {
        vec![
            ("header", self.header as f64),
            ("dictionaries", self.dictionaries as f64),
            ("high-level", self.high_level as f64),
            ("tree-starts", self.tree_starts as f64),
            ("templates", self.templates),
            ("corners", self.corners),
            ("vertices", self.vertices),
            ("padding", self.padding),
            ("ids", self.ids as f64),
            ("vertex-ids", self.vertex_ids as f64),
            ("edge-flags", self.edge_flags as f64),
        ]
    }

    /// Every part summed: the file's length.
    pub fn total(&self) -> f64 {
        self.parts().iter().map(|p| p.1).sum()
    }
}

/// The model's state while coding one tree.
#[derive(Default)]
struct Model {
    lay: Layout,
    types: Vec<u32>,
    cache: CornerCache,
    adj: Adjacency,
    grid: Vec<[u32; 3]>,
    tris: Vec<[u32; 3]>,
}

/// The coding of one tree's triangles.
struct TreeCoder {
    max_q: u32,
    next: u32,
    n_verts: u32,
}

impl TreeCoder {
    /// Codes triangle `c` (local corners) of tree `k`: its corner symbols,
    /// then each new vertex's residuals, in the order of their indices
    /// (the encoder's pass 2 moves the residuals behind every corner of
    /// the tree; see the module docs).
    fn triangle(
        &mut self,
        c: [u32; 3],
        q: &Quantized,
        k: usize,
        m: &mut Model,
        emit: &mut impl FnMut(usize, u32),
    ) -> Result<(), &'static str> {
        let first_new = self.next;
        for (slot, &v) in c.iter().enumerate() {
            if v > self.next {
                return Err("vertices are not numbered by first use");
            }
            emit(CTX_CORNER + slot, m.cache.symbol(v, self.next));
            if v == self.next {
                if self.next >= self.n_verts {
                    return Err("a leaf names a vertex past the tree's array");
                }
                m.adj.new_vertex(v);
                self.next += 1;
            }
            m.cache.touch(v);
        }
        // New vertices take increasing indices in corner order; a corner
        // repeating one already coded here is below `v`.
        let mut v = first_new;
        for slot in 0..3 {
            if c[slot] != v {
                continue;
            }
            let (ctx, slots) = plan(c, slot, v, &m.adj);
            let pred = predicted(ctx, slots, &m.grid, self.max_q);
            let g = q.grid_point(k, v);
            for x in 0..3 {
                emit(ctx + x, zigzag(i64::from(g[x]) - i64::from(pred[x])) as u32);
            }
            m.grid.push(g);
            v += 1;
        }
        m.adj.add(c);
        Ok(())
    }
}

/// Runs the model over low-level tree `k` of `hcc`, calling `emit(context,
/// symbol)` for every symbol in stream order.
fn model_tree(
    hcc: &HccBvh,
    q: &Quantized,
    k: usize,
    m: &mut Model,
    emit: &mut impl FnMut(usize, u32),
) -> Result<(), OocError> {
    let bad = |what| OocError::NotCanonical {
        tree: k as u32,
        what,
    };
    let h = hcc.headers[k];
    let (node_end, ic_end, vertex_end) = hcc.tree_ends(k);
    let words = hcc
        .nodes
        .get(h.node_start as usize..node_end as usize)
        .filter(|w| !w.is_empty())
        .ok_or(bad("the tree's node words are out of range"))?;
    let ics = hcc
        .ics
        .get(h.ic_start as usize..ic_end as usize)
        .ok_or(bad("the tree's inter-connections are out of range"))?;
    let n_verts = vertex_end
        .checked_sub(h.vertex_start)
        .ok_or(bad("the tree's vertices are out of range"))?;
    m.types.clear();
    m.types.extend(words.iter().map(|&w| node_type(w)));
    // Structure: the templates in the order the i-HCCMesh allocated them.
    let root = if m.types[0] == TYPE_LEAF {
        0
    } else {
        (words[0] & 31) as u8
    };
    let overrun = "a template runs past the tree's nodes";
    let sym = template_symbol(root, 0, &m.types).ok_or(bad(overrun))?;
    emit(CTX_TEMPLATE, sym);
    m.lay.root(sym).map_err(bad)?;
    while let Some(at) = m.lay.pending.pop() {
        let ic = ics
            .get(m.lay.ics.len())
            .map(|&w| Interconnection::unpack(w))
            .ok_or(bad("fewer inter-connections than template leaves"))?;
        let start = m.lay.positions();
        let left_nodes = TEMPLATES
            .get(ic.left_template as usize)
            .ok_or(bad("a template id is out of range"))?
            .nodes as usize;
        let l = template_symbol(ic.left_template, start, &m.types).ok_or(bad(overrun))?;
        let r =
            template_symbol(ic.right_template, start + left_nodes, &m.types).ok_or(bad(overrun))?;
        emit(CTX_TEMPLATE, l);
        emit(CTX_TEMPLATE, r);
        m.lay.expand(at, l, r).map_err(bad)?;
        if m.lay.ics.last().map(|i| i.2) != Some(ic.left_start) {
            return Err(bad("an inter-connection's position is not the layout's"));
        }
    }
    if m.lay.types() != m.types || m.lay.ics.len() != ics.len() {
        return Err(bad("the node types are not the templates'"));
    }
    // Leaves in node-word order: each triangle's corners, then its new
    // vertices.
    m.cache.clear();
    m.adj.clear();
    m.grid.clear();
    // Grid slot 0 (see `plan`).
    m.grid.push(centre(q.max_q()));
    let mut t = TreeCoder {
        max_q: q.max_q(),
        next: 0,
        n_verts,
    };
    for p in 0..words.len() {
        if m.types[p] != TYPE_LEAF {
            continue;
        }
        m.tris.clear();
        hcc.leaf_triangles(k as u32, h.node_start + p as u32, |_, c| m.tris.push(c));
        if hcc.multi {
            let count = m.tris.len() as u32;
            emit(
                CTX_LEAF,
                count
                    .checked_sub(1)
                    .ok_or(bad("a leaf holds no triangle"))?,
            );
        }
        for i in 0..m.tris.len() {
            let c = m.tris[i];
            t.triangle(c, q, k, m, emit).map_err(bad)?;
        }
    }
    let next = t.next;
    if next != n_verts {
        return Err(bad("a stored vertex is used by no leaf"));
    }
    Ok(())
}

/// The high-level tree's shape: a bit a node (1 inner, 0 a low-level
/// tree), in the order the i-HCCMesh encoder allocated them.
pub(super) fn high_shape(high: &[HighNode], trees_want: usize) -> Result<Vec<u8>, OocError> {
    let bad = |what| OocError::NotCanonical {
        tree: u32::MAX,
        what,
    };
    let mut w = BitWriter::default();
    if high.is_empty() {
        return Ok(Vec::new());
    }
    let (mut stack, mut len, mut trees) = (vec![0u32], 1u32, 0u32);
    while let Some(h) = stack.pop() {
        let n = high
            .get(h as usize)
            .ok_or(bad("a high-level child is out of range"))?;
        if n.is_leaf() {
            if n.a != trees {
                return Err(bad("low-level trees are not numbered depth-first"));
            }
            trees += 1;
            w.put(0, 1);
        } else {
            if n.a != len || n.b != len + 1 {
                return Err(bad("high-level nodes are not allocated depth-first"));
            }
            w.put(1, 1);
            stack.push(len + 1);
            stack.push(len);
            len += 2;
        }
    }
    if len as usize != high.len() || trees as usize != trees_want {
        return Err(bad(
            "the high-level tree has nodes or trees it does not reach",
        ));
    }
    Ok(w.finish())
}

/// The high-level tree's boxes on the vertex grid (layout in the module
/// docs of [`ooc`](super)): the root's grid coordinates, then per inner
/// node (in node order, parents first) and per extent which child shares
/// the parent's value and how far inside the parent the other child's is.
pub(super) fn high_boxes(high: &[HighNode], q: &Quantized) -> Result<Vec<u8>, OocError> {
    let bad = |what| OocError::NotCanonical {
        tree: u32::MAX,
        what,
    };
    let grid = |n: &HighNode| -> Result<[u32; 6], OocError> {
        let mut g = [0u32; 6];
        for (e, x) in n.min.into_iter().chain(n.max).enumerate() {
            let c = q.nearest(e % 3, x);
            if q.value(e % 3, c).to_bits() != x.to_bits() {
                return Err(bad("a high-level box is not on the vertex grid"));
            }
            g[e] = c;
        }
        Ok(g)
    };
    let gs = high.iter().map(grid).collect::<Result<Vec<_>, _>>()?;
    let mut w = BitWriter::default();
    let Some(root) = gs.first() else {
        return Ok(Vec::new());
    };
    for &c in root {
        w.put(u64::from(c), q.bits);
    }
    for (n, p) in high.iter().zip(&gs) {
        if n.is_leaf() {
            continue;
        }
        // `high_shape` checked the children's positions.
        let (l, r) = (gs[n.a as usize], gs[n.b as usize]);
        for e in 0..6 {
            let range = p[e % 3 + 3]
                .checked_sub(p[e % 3])
                .ok_or(bad("a high-level box is empty"))?;
            let (right, other) = if l[e] == p[e] {
                (0, r[e])
            } else if r[e] == p[e] {
                (1, l[e])
            } else {
                return Err(bad("a high-level box is not its children's union"));
            };
            let off = if e < 3 {
                other.checked_sub(p[e])
            } else {
                p[e].checked_sub(other)
            }
            .filter(|&o| o <= range)
            .ok_or(bad("a high-level box is not its children's union"))?;
            w.put(right, 1);
            w.put(u64::from(off), bits_for(range));
        }
    }
    Ok(w.finish())
}

/// Per tree, the differences of consecutive entries of each column of
/// prefix sums (one entry more than trees), each column in the fewest bits
/// that hold its largest difference (6 bits first, per column), the
/// columns interleaved tree by tree: the sections `tree starts` and `tree
/// firsts` (layout in the module docs of [`ooc`](super)).
pub(super) fn tree_columns(columns: &[&[u32]]) -> Vec<u8> {
    let diffs: Vec<Vec<u32>> = columns
        .iter()
        .map(|c| c.windows(2).map(|p| p[1] - p[0]).collect())
        .collect();
    let widths: Vec<u32> = diffs
        .iter()
        .map(|d| bits_for(d.iter().copied().max().unwrap_or(0)))
        .collect();
    let mut w = BitWriter::default();
    for &b in &widths {
        w.put(u64::from(b), 6);
    }
    for t in 0..diffs.first().map_or(0, Vec::len) {
        for (d, &b) in diffs.iter().zip(&widths) {
            w.put(u64::from(d[t]), b);
        }
    }
    w.finish()
}

/// Where the stream of tree `k` starts, `at` bytes into the streams: a
/// `u32`, or the error that the streams outgrow 4 GiB.
pub(super) fn stream_offset(at: u64, k: usize) -> Result<u32, OocError> {
    u32::try_from(at).map_err(|_| OocError::Corrupt {
        tree: k as u32,
        what: "the coded trees outgrow 4 GiB",
    })
}

/// Bits that hold `v` (0 for 0): an offset inside a range of `v`.
pub(super) fn bits_for(v: u32) -> u32 {
    32 - v.leading_zeros()
}

/// Each context's symbol counts, summed over trees (pass 1).
pub(super) struct SymbolCounts {
    counts: Vec<FastMap<u32, u64>>,
    m: Model,
}

impl SymbolCounts {
    pub(super) fn new() -> Self {
        Self {
            counts: vec![FastMap::default(); CONTEXTS],
            m: Model::default(),
        }
    }

    /// Adds every tree of `hcc` (quantized on `q`).
    pub(super) fn add(&mut self, hcc: &HccBvh, q: &Quantized) -> Result<(), OocError> {
        let counts = &mut self.counts;
        for k in 0..hcc.headers.len() {
            model_tree(hcc, q, k, &mut self.m, &mut |ctx, sym| {
                *counts[ctx].entry(sym).or_insert(0) += 1;
            })?;
        }
        Ok(())
    }

    /// The dictionaries of optimal size for these counts, and the
    /// section that stores them.
    pub(super) fn dictionaries(&self) -> (Vec<StaticDict>, Vec<u8>) {
        let dicts: Vec<StaticDict> = self
            .counts
            .iter()
            .map(|c| StaticDict::optimal(&c.iter().map(|(&s, &n)| (s, n)).collect::<Vec<_>>()))
            .collect();
        let mut w = BitWriter::default();
        for d in &dicts {
            d.write(&mut w);
        }
        (dicts, w.finish())
    }
}

/// Codes trees through the file's dictionaries (pass 2).
pub(super) struct StreamCoder {
    encs: Vec<StaticEncoder>,
    /// Bits of templates, corners and vertices coded so far.
    pub(super) part_bits: [u64; 3],
    residuals: Vec<(usize, u32)>,
    m: Model,
}

impl StreamCoder {
    pub(super) fn new(dicts: &[StaticDict]) -> Self {
        Self {
            encs: dicts.iter().map(StaticDict::encoder).collect(),
            part_bits: [0; 3],
            residuals: Vec::new(),
            m: Model::default(),
        }
    }

    /// Tree `k` of `hcc` (quantized on `q`), its stream starting on a
    /// byte, appended to `out`.
    pub(super) fn tree(
        &mut self,
        hcc: &HccBvh,
        q: &Quantized,
        k: usize,
        out: &mut Vec<u8>,
    ) -> Result<(), OocError> {
        let mut w = BitWriter::default();
        let (encs, part_bits) = (&mut self.encs, &mut self.part_bits);
        let mut put = |ctx: usize, sym: u32| {
            let before = w.bit_len();
            encs[ctx].put(&mut w, sym);
            part_bits[part_of(ctx)] += w.bit_len() - before;
        };
        // The templates and the corners as the model gives them, the
        // residuals after them (see the module docs).
        let residuals = &mut self.residuals;
        residuals.clear();
        model_tree(hcc, q, k, &mut self.m, &mut |ctx, sym| {
            if part_of(ctx) == PART_VERTICES {
                residuals.push((ctx, sym));
            } else {
                put(ctx, sym);
            }
        })?;
        for &(ctx, sym) in residuals.iter() {
            put(ctx, sym);
        }
        out.extend_from_slice(&w.finish());
        Ok(())
    }
}

/// Encodes `hcc` as an o-HCCMesh file; returns the bytes and their sizes
/// by part.
pub fn encode(hcc: &HccBvh) -> Result<(Vec<u8>, OocSizes), OocError> {
    let q = hcc.vertices.quantized().ok_or(OocError::NotQuantized)?;
    // Pass 1: each context's symbol counts.
    let mut counts = SymbolCounts::new();
    counts.add(hcc, q)?;
    let (dicts, dict_bytes) = counts.dictionaries();
    // Pass 2: the trees' streams, each starting on a byte.
    let mut coder = StreamCoder::new(&dicts);
    let mut streams = Vec::new();
    let mut starts = Vec::with_capacity(hcc.headers.len() + 1);
    for k in 0..hcc.headers.len() {
        starts.push(stream_offset(streams.len() as u64, k)?);
        coder.tree(hcc, q, k, &mut streams)?;
    }
    starts.push(stream_offset(streams.len() as u64, hcc.headers.len())?);
    let part_bits = coder.part_bits;
    let starts = tree_columns(&[&starts]);
    let high = high_shape(&hcc.high, hcc.headers.len())?;
    let boxes = high_boxes(&hcc.high, q)?;
    let firsts = tree_columns(&[
        &hcc.headers
            .iter()
            .map(|t| t.first_triangle)
            .chain([hcc.triangle_count])
            .collect::<Vec<_>>(),
        &hcc.headers
            .iter()
            .map(|t| t.vertex_start)
            .chain([hcc.stats.tree_vertices as u32])
            .collect::<Vec<_>>(),
    ]);
    let ids = hcc.ids.as_ref().map_or(Vec::new(), IdMap::to_bytes);
    let vids = hcc
        .vertex_ids
        .as_ref()
        .map_or(Vec::new(), VertexIds::to_bytes);
    let header = Header {
        multi: hcc.multi,
        vertex_ids: hcc.vertex_ids.is_some(),
        tree_order: hcc.ids.is_none(),
        high_nodes: hcc.high.len() as u32,
        trees: hcc.headers.len() as u32,
        node_words: hcc.nodes.len() as u32,
        interconnections: hcc.ics.len() as u32,
        stored_vertices: hcc.stats.tree_vertices as u32,
        triangles: hcc.triangle_count,
        mesh_vertices: hcc.mesh_vertices,
        used_vertices: hcc.stats.mesh_vertices as u32,
        bits: q.bits,
        grid: [q.origin, q.step, q.error],
        mass: hcc.mass,
    };
    let flags = edges::encode(&hcc.edges);
    let sections: [&[u8]; SECTIONS] = [
        &dict_bytes,
        &high,
        &starts,
        &streams,
        &ids,
        &vids,
        &boxes,
        &firsts,
        &flags,
    ];
    let bytes = file::write(&header, &sections);
    let sizes = OocSizes::from_sections(&sections.map(|s| s.len() as u64), &part_bits);
    debug_assert_eq!(sizes.total() as usize, bytes.len());
    Ok((bytes, sizes))
}

impl HccBvh {
    /// This i-HCCMesh as an o-HCCMesh file, and its bytes by part.
    /// Quantized vertices only.
    pub fn to_ooc(&self) -> Result<(Vec<u8>, OocSizes), OocError> {
        encode(self)
    }
}

impl HccOocBvh {
    /// Encodes `bvh` (built over `mesh`) as an i-HCCMesh with `options`
    /// and codes it; out of core when the i-HCCMesh does not fit
    /// `options.cache_budget_bytes`.
    pub fn encode_with(
        bvh: &CanonicalBvh,
        mesh: &Mesh,
        options: &OocOptions,
    ) -> Result<Self, OocError> {
        let hcc = HccBvh::encode_with(bvh, mesh, &options.hcc())?;
        let (file, sizes) = encode(&hcc)?;
        let mode = if hcc.bytes_total() <= options.cache_budget_bytes {
            Mode::Whole { hcc, file }
        } else {
            drop(hcc);
            Mode::Paged(Paged::new(Store::Owned(file), options.cache_budget_bytes)?)
        };
        Ok(Self {
            mode,
            sizes: Some(sizes),
        })
    }

    /// Codes an i-HCCMesh (quantized vertices); pre-loaded.
    pub fn from_hcc(hcc: HccBvh) -> Result<Self, OocError> {
        let (file, sizes) = encode(&hcc)?;
        Ok(Self {
            mode: Mode::Whole { hcc, file },
            sizes: Some(sizes),
        })
    }
}
