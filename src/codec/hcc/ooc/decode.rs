//! o-HCCMesh decoding: the file's bytes into the i-HCCMesh the i-HCCMesh
//! encoder builds from the same tree and options, byte for byte
//! ([`HccBvh::from_ooc`]).

use super::super::MAX_LEAF_TRIANGLES;
#[cfg(target_arch = "x86_64")]
use super::super::grid16::Box16;
use super::super::ids::{IdMap, VertexIds};
use super::super::node::{HIGH_LEAF, HighNode, MAX_TREE_TRIANGLES, MAX_TREE_VERTICES, TreeHeader};
use super::super::pair::{Extents, Lanes, outer};
use super::super::vertices::{MAX_VERTEX_BITS, Quantized, Vertices};
use super::super::{HccBvh, HccStats};
use super::OocError;
use super::encode;
use super::file::{
    self, Header, SEC_BOXES, SEC_DICTS, SEC_EDGES, SEC_FIRSTS, SEC_HIGH, SEC_IDS, SEC_STARTS,
    SEC_TREES, SEC_VIDS, SECTIONS,
};
use super::model::{
    Adjacency, CONTEXTS, CTX_CORNER, CTX_LEAF, CTX_TEMPLATE, Layout, MAX_CORNER_SYM,
    MAX_TEMPLATE_SYM, RankCache, SYM_NEW, centre, plan, predicted,
};
use super::rebuild::Rebuild;
use crate::codec::common::bits::{BitReader, unzigzag};
use crate::codec::common::static_dict::{StaticDecoder, StaticDict};
use crate::codec::common::{FormatError, edges};
use crate::contact::EdgeFlags;

/// Everything reused from tree to tree.
#[derive(Default)]
struct Scratch {
    lay: Layout,
    adj: Adjacency,
    /// Per leaf (in `lay.leaves()`), its first triangle in `tris` and its
    /// count; empty without multi-triangle leaves (leaf `i` holds triangle
    /// `i`).
    spans: Vec<(u32, u32)>,
    tris: Vec<[u32; 3]>,
    /// Per vertex, its first triangle (times 4) and corner slot.
    first_use: Vec<u32>,
    /// Per vertex, its residuals' contexts and prediction (see `plan`).
    plans: Vec<(usize, [u32; 3])>,
    /// The grid slots of `plan`: the centre, then the vertices.
    grid: Vec<[u32; 3]>,
    /// The rebuild on [`Lanes`] (any grid), and on 16-bit lanes (grids of
    /// at most 16 bits).
    rebuild: Rebuild<Lanes>,
    #[cfg(target_arch = "x86_64")]
    rebuild16: Rebuild<Box16>,
}

/// The i-HCCMesh being rebuilt.
struct Out {
    headers: Vec<TreeHeader>,
    nodes: Vec<u32>,
    ics: Vec<u32>,
    q: Quantized,
    blocks: Vec<u8>,
    block_start: Vec<u32>,
    stored: u32,
    triangles: u32,
    stats: HccStats,
    roots: Vec<Extents>,
    /// The i-HCCMesh's leaf bits (bit `p` set when node word `p` is a
    /// leaf), set from the layouts rather than read back from the words.
    leaf_bits: Vec<u64>,
}

/// The largest raw symbol of each context, in bits.
fn raw_bits_limit(ctx: usize, bits: u32) -> u32 {
    let max = match ctx {
        CTX_TEMPLATE => MAX_TEMPLATE_SYM,
        1..=3 => MAX_CORNER_SYM,
        CTX_LEAF => MAX_LEAF_TRIANGLES as u32 - 1,
        // Zig-zagged residuals of coordinates and predictions in
        // 0..2^bits: below 2^(bits + 1).
        _ => (1u32 << (bits + 1)) - 1,
    };
    32 - max.leading_zeros()
}

/// What decoding any one tree needs: the header, the contexts' decoders
/// and the grid (without trees).
#[derive(Clone, Debug)]
pub(super) struct Coder {
    pub(super) h: Header,
    decs: Vec<StaticDecoder>,
    grid: Quantized,
}

impl Coder {
    /// Checks the header's grid and reads the dictionaries.
    pub(super) fn new(h: &Header, dicts: &[u8]) -> Result<Self, OocError> {
        if !(1..=MAX_VERTEX_BITS).contains(&h.bits) {
            return Err(FormatError::header(
                "vertex bits",
                format!("{} is not in 1..={MAX_VERTEX_BITS}", h.bits),
            )
            .into());
        }
        let grid = Quantized {
            bits: h.bits,
            origin: h.grid[0],
            step: h.grid[1],
            error: h.grid[2],
            trees: Vec::new(),
            data: Vec::new(),
        };
        grid.check_grid()?;
        let mut r = BitReader::new(dicts);
        let mut decs = Vec::with_capacity(CONTEXTS);
        for ctx in 0..CONTEXTS {
            let bits = raw_bits_limit(ctx, h.bits);
            decs.push(StaticDict::read(&mut r, 1 << bits, bits)?.decoder(bits));
        }
        if r.overran() {
            return Err(corrupt_file("the dictionaries run past their section"));
        }
        Ok(Self {
            h: h.clone(),
            decs,
            grid,
        })
    }

    /// An empty i-HCCMesh being rebuilt, with room for `trees` trees.
    fn out(&self, trees: usize) -> Out {
        let mut q = self.grid.clone();
        q.trees.reserve(trees);
        Out {
            headers: Vec::with_capacity(trees),
            nodes: Vec::new(),
            ics: Vec::new(),
            q,
            blocks: Vec::new(),
            block_start: Vec::new(),
            stored: 0,
            triangles: 0,
            stats: HccStats::default(),
            roots: Vec::with_capacity(trees),
            leaf_bits: Vec::new(),
        }
    }

    /// Decodes tree `k` (its stream `bytes`) alone, as a one-tree
    /// i-HCCMesh whose triangles are numbered from 0 (their ranks less the
    /// tree's first rank) and whose vertices are the tree's own; returns
    /// it with its root box.
    pub(super) fn tree(&self, k: u32, bytes: &[u8]) -> Result<(HccBvh, Extents), OocError> {
        thread_local!(static SCRATCH: std::cell::RefCell<Scratch> = std::cell::RefCell::default());
        let mut out = self.out(1);
        SCRATCH.with(|s| match s.try_borrow_mut() {
            Ok(mut s) => decode_tree(k, bytes, &self.decs, &self.h, &mut s, &mut out),
            Err(_) => decode_tree(
                k,
                bytes,
                &self.decs,
                &self.h,
                &mut Scratch::default(),
                &mut out,
            ),
        })?;
        let root = out.roots[0];
        let high = vec![HighNode {
            min: [root[0], root[1], root[2]],
            max: [root[3], root[4], root[5]],
            a: 0,
            b: HIGH_LEAF,
        }];
        // A tree alone: its own vertices are the mesh's, none of them
        // counted as input vertices.
        let vertices = out.stored;
        let hcc = out.into_hcc(high, (None, None), &self.h, (vertices, 0));
        Ok((hcc, root))
    }
}

/// The id maps the file keeps (see the flags).
pub(super) fn id_maps(
    h: &Header,
    sec: &[&[u8]; SECTIONS],
) -> Result<(Option<IdMap>, Option<VertexIds>), OocError> {
    let ids = if h.tree_order {
        None
    } else {
        Some(IdMap::parse(sec[SEC_IDS], h.triangles)?)
    };
    let vertex_ids = if h.vertex_ids {
        Some(VertexIds::parse(sec[SEC_VIDS], h.stored_vertices)?)
    } else {
        None
    };
    Ok((ids, vertex_ids))
}

impl Out {
    /// The i-HCCMesh of these trees under the high-level tree `high`, with
    /// the id maps `maps`, the input mesh's vertex count and the input
    /// vertices the triangles use (`vertices`).
    fn into_hcc(
        self,
        high: Vec<HighNode>,
        (ids, vertex_ids): (Option<IdMap>, Option<VertexIds>),
        h: &Header,
        vertices: (u32, u32),
    ) -> HccBvh {
        let mut stats = self.stats;
        stats.trees = self.headers.len();
        stats.high_nodes = high.len();
        stats.tree_vertices = self.stored as usize;
        stats.mesh_vertices = vertices.1 as usize;
        let mut hcc = HccBvh {
            high,
            headers: self.headers,
            nodes: self.nodes,
            ics: self.ics,
            vertices: Vertices::Packed(self.q),
            blocks: self.blocks,
            block_start: self.block_start,
            leaf_bits: self.leaf_bits,
            leaf_rank: Vec::new(),
            ids,
            vertex_ids,
            multi: h.multi,
            triangle_count: self.triangles,
            mesh_vertices: vertices.0,
            mass: h.mass,
            edges: EdgeFlags::default(),
            stats,
        };
        hcc.rank_leaf_bits();
        hcc
    }
}

/// Tree `k`'s stream: its bytes in `streams` between its start and the
/// next tree's (`starts` as [`tree_table`] reads them).
pub(super) fn tree_stream<'a>(
    starts: &[u32],
    streams: &'a [u8],
    k: u32,
) -> Result<&'a [u8], OocError> {
    let k = k as usize;
    let range = starts.get(k).zip(starts.get(k + 1));
    range
        .and_then(|(&s, &e)| streams.get(s as usize..e as usize))
        .ok_or(OocError::Corrupt {
            tree: k as u32,
            what: "the tree's stream lies outside the streams section",
        })
}

/// Per tree, where its stream starts, and its first triangle rank and
/// first stored vertex, each with one more entry for the totals: the
/// prefix sums of the counts the sections `tree starts` and `tree firsts`
/// store (layout in the module docs of [`ooc`](super)), checked against
/// the header and the streams' length.
pub(super) fn tree_table(
    h: &Header,
    sec: &[&[u8]; SECTIONS],
) -> Result<(Vec<u32>, Vec<[u32; 2]>), OocError> {
    let bad = |what| Err(corrupt_file(what));
    let trees = h.trees as usize;
    // Fields of `w` bits per tree (`w` read first, 6 bits each), summed.
    let column_sums = |bytes: &[u8], columns: usize| -> Option<Vec<Vec<u64>>> {
        let mut r = BitReader::new(bytes);
        let widths: Vec<u32> = (0..columns).map(|_| r.get(6) as u32).collect();
        if widths.iter().any(|&w| w > 32) {
            return None;
        }
        let bits =
            6 * columns as u64 + widths.iter().map(|&w| u64::from(w)).sum::<u64>() * trees as u64;
        if bits.div_ceil(8) != bytes.len() as u64 {
            return None;
        }
        let mut sums = vec![Vec::with_capacity(trees + 1); columns];
        let mut acc = vec![0u64; columns];
        for _ in 0..trees {
            for c in 0..columns {
                sums[c].push(acc[c]);
                acc[c] += r.get(widths[c]);
            }
        }
        for c in 0..columns {
            sums[c].push(acc[c]);
        }
        (!r.overran()).then_some(sums)
    };
    let Some(starts) = column_sums(sec[SEC_STARTS], 1) else {
        return bad("the tree starts are malformed");
    };
    let Some(firsts) = column_sums(sec[SEC_FIRSTS], 2) else {
        return bad("the tree firsts are malformed");
    };
    if starts[0][trees] != sec[SEC_TREES].len() as u64 {
        return bad("the trees' stream lengths do not add up to the streams section");
    }
    if firsts[0][trees] != u64::from(h.triangles)
        || firsts[1][trees] != u64::from(h.stored_vertices)
    {
        return bad("the trees' triangles or vertices do not add up to the header's totals");
    }
    // Every sum is at most its total, a `u32`.
    let starts = starts[0].iter().map(|&s| s as u32).collect();
    let firsts = (0..=trees)
        .map(|k| [firsts[0][k] as u32, firsts[1][k] as u32])
        .collect();
    Ok((starts, firsts))
}

/// The high-level boxes as the file stores them (section `bytes`; see
/// `high_boxes` in the encoder), for the high-level tree `high` (shape
/// only, as [`high_tree`] reads it).
pub(super) fn stored_boxes(
    coder: &Coder,
    high: &[HighNode],
    bytes: &[u8],
) -> Result<Vec<[f32; 6]>, OocError> {
    let bad = || corrupt_file("the high-level boxes are malformed");
    let mut gs = vec![[0u32; 6]; high.len()];
    let empty = |g: &[u32; 6]| (0..3).any(|a| g[a] > g[a + 3]);
    let mut r = BitReader::new(bytes);
    let mut bits = 0u64;
    if let Some(root) = gs.first_mut() {
        let b = coder.h.bits;
        for c in root.iter_mut() {
            *c = r.get(b) as u32;
        }
        bits += 6 * u64::from(b);
        if empty(root) {
            return Err(bad());
        }
    }
    for (i, n) in high.iter().enumerate() {
        if n.is_leaf() {
            continue;
        }
        // Not empty: checked when it was read.
        let p = gs[i];
        let mut kids = [p, p];
        for e in 0..6 {
            let range = p[e % 3 + 3] - p[e % 3];
            let w = encode::bits_for(range);
            let side = r.get(1) as usize;
            let off = r.get(w) as u32;
            bits += 1 + u64::from(w);
            if off > range {
                return Err(bad());
            }
            // The child that does not share the parent's value.
            kids[1 - side][e] = if e < 3 { p[e] + off } else { p[e] - off };
        }
        // Children follow their parent (`high_tree` numbers them so).
        for (c, kid) in [n.a, n.b].into_iter().zip(kids) {
            if empty(&kid) {
                return Err(bad());
            }
            *gs.get_mut(c as usize).ok_or_else(bad)? = kid;
        }
    }
    if r.overran() || bits.div_ceil(8) != bytes.len() as u64 {
        return Err(bad());
    }
    let q = &coder.grid;
    Ok(gs
        .iter()
        .map(|g| std::array::from_fn(|e| q.value(e % 3, g[e])))
        .collect())
}

/// Decodes an o-HCCMesh file into its i-HCCMesh.
pub fn decode(b: &[u8]) -> Result<HccBvh, OocError> {
    let (h, sec) = file::parse(b)?;
    let coder = Coder::new(&h, sec[SEC_DICTS])?;
    let (mut high, leaf_of_tree) = high_tree(&h, sec[SEC_HIGH])?;
    // Capacities from the header, bounded by what the file can hold.
    let cap = |n: u32| (n as usize).min(b.len().saturating_mul(16));
    let mut out = coder.out(cap(h.trees));
    out.nodes.reserve(cap(h.node_words));
    out.ics.reserve(cap(h.interconnections));
    // At most the grid's bits per coordinate, and a byte of padding a tree.
    let vertex_bytes = (h.stored_vertices as u64 * 3 * u64::from(h.bits)).div_ceil(8);
    out.q
        .data
        .reserve(cap(u32::try_from(vertex_bytes).unwrap_or(u32::MAX)) + cap(h.trees));
    let (starts, firsts) = tree_table(&h, &sec)?;
    let streams = sec[SEC_TREES];
    let mut s = Scratch::default();
    for k in 0..h.trees {
        let bytes = tree_stream(&starts, streams, k)?;
        decode_tree(k, bytes, &coder.decs, &h, &mut s, &mut out)?;
    }
    let count = |what: &'static str, got: usize, want: u32| {
        if got == want as usize {
            Ok(())
        } else {
            Err(corrupt_file(what))
        }
    };
    count(
        "the trees hold another number of node words than the header says",
        out.nodes.len(),
        h.node_words,
    )?;
    count(
        "the trees hold another number of inter-connections than the header says",
        out.ics.len(),
        h.interconnections,
    )?;
    count(
        "the trees hold another number of vertices than the header says",
        out.stored as usize,
        h.stored_vertices,
    )?;
    count(
        "the trees hold another number of triangles than the header says",
        out.triangles as usize,
        h.triangles,
    )?;
    // High-level boxes bottom-up (children sit behind their parent).
    let mut boxes = vec![[0f32; 6]; high.len()];
    for (k, &hi) in leaf_of_tree.iter().enumerate() {
        boxes[hi as usize] = out.roots[k];
    }
    for i in (0..high.len()).rev() {
        let n = high[i];
        if !n.is_leaf() {
            let (l, r) = (boxes[n.a as usize], boxes[n.b as usize]);
            boxes[i] = std::array::from_fn(|e| if outer(e, r[e], l[e]) { r[e] } else { l[e] });
        }
        let bx = boxes[i];
        high[i].min = [bx[0], bx[1], bx[2]];
        high[i].max = [bx[3], bx[4], bx[5]];
    }
    let stored = stored_boxes(&coder, &high, sec[SEC_BOXES])?;
    if high.iter().zip(&stored).any(|(n, b)| {
        n.min
            .into_iter()
            .chain(n.max)
            .zip(b)
            .any(|(x, y)| x.to_bits() != y.to_bits())
    }) {
        return Err(corrupt_file(
            "the stored high-level boxes disagree with the boxes the trees rebuild",
        ));
    }
    if out
        .headers
        .iter()
        .zip(&firsts)
        .any(|(t, f)| [t.first_triangle, t.vertex_start] != *f)
    {
        return Err(corrupt_file(
            "the stored first triangles or vertices of the trees disagree with the trees",
        ));
    }
    let maps = id_maps(&h, &sec)?;
    let edges = edges::decode(sec[SEC_EDGES], u64::from(h.triangles))?;
    let mut hcc = out.into_hcc(high, maps, &h, (h.mesh_vertices, h.used_vertices));
    hcc.edges = edges;
    Ok(hcc)
}

impl HccBvh {
    /// The i-HCCMesh an o-HCCMesh file codes (checked as
    /// [`HccOocBvh::from_bytes`](super::HccOocBvh::from_bytes) does; run
    /// [`HccBvh::verify`] before querying bytes you did not write).
    pub fn from_ooc(bytes: &[u8]) -> Result<HccBvh, OocError> {
        decode(bytes)
    }
}

/// The next symbol of context `ctx` in tree `k`'s stream.
#[inline(always)]
fn read_symbol(
    decs: &[StaticDecoder],
    ctx: usize,
    r: &mut BitReader<'_>,
    k: u32,
) -> Result<u32, OocError> {
    r.refill();
    read_refilled(decs, ctx, r, k)
}

/// [`read_symbol`] without a refill: one of at most
/// [`READS_PER_REFILL`](crate::codec::common::static_dict::READS_PER_REFILL)
/// reads after [`BitReader::refill`].
#[inline(always)]
fn read_refilled(
    decs: &[StaticDecoder],
    ctx: usize,
    r: &mut BitReader<'_>,
    k: u32,
) -> Result<u32, OocError> {
    match decs[ctx].get_refilled(r) {
        Ok(v) => Ok(v),
        Err(e) => Err(symbol_error(k, e)),
    }
}

/// A symbol that could not be read, in tree `k`.
#[cold]
fn symbol_error(k: u32, e: FormatError) -> OocError {
    match e {
        FormatError::Corrupt { what } => OocError::Corrupt { tree: k, what },
        e => e.into(),
    }
}

fn corrupt_file(what: &'static str) -> OocError {
    OocError::Corrupt {
        tree: u32::MAX,
        what,
    }
}

/// The high-level tree's nodes (boxes still empty) from its shape bits,
/// and the high-level leaf of each low-level tree.
pub(super) fn high_tree(h: &Header, bits: &[u8]) -> Result<(Vec<HighNode>, Vec<u32>), OocError> {
    let zero = HighNode {
        min: [0.0; 3],
        max: [0.0; 3],
        a: 0,
        b: 0,
    };
    if (h.triangles == 0) != (h.high_nodes == 0) || (h.high_nodes == 0) != (h.trees == 0) {
        return Err(corrupt_file(
            "the counts of triangles, high-level nodes and trees disagree",
        ));
    }
    let mut high = Vec::with_capacity((h.high_nodes as usize).min(bits.len() * 8));
    let mut leaf_of_tree = Vec::with_capacity((h.trees as usize).min(bits.len() * 8));
    if h.high_nodes == 0 {
        return Ok((high, leaf_of_tree));
    }
    let mut r = BitReader::new(bits);
    high.push(zero);
    let mut stack = vec![0u32];
    while let Some(i) = stack.pop() {
        if r.get(1) == 1 {
            let a = high.len() as u32;
            if a + 2 > h.high_nodes {
                return Err(corrupt_file(
                    "the high-level tree has more nodes than the header says",
                ));
            }
            high[i as usize].a = a;
            high[i as usize].b = a + 1;
            high.extend([zero, zero]);
            stack.push(a + 1);
            stack.push(a);
        } else {
            if leaf_of_tree.len() as u32 >= h.trees {
                return Err(corrupt_file(
                    "the high-level tree has more leaves than there are trees",
                ));
            }
            high[i as usize].a = leaf_of_tree.len() as u32;
            high[i as usize].b = HIGH_LEAF;
            leaf_of_tree.push(i);
        }
    }
    if r.overran() || high.len() != h.high_nodes as usize || leaf_of_tree.len() != h.trees as usize
    {
        return Err(corrupt_file(
            "the high-level shape disagrees with the header's counts",
        ));
    }
    Ok((high, leaf_of_tree))
}

/// Decodes low-level tree `k` from its stream `bytes` and appends its
/// i-HCCMesh to `out`.
fn decode_tree(
    k: u32,
    bytes: &[u8],
    decs: &[StaticDecoder],
    h: &Header,
    s: &mut Scratch,
    out: &mut Out,
) -> Result<(), OocError> {
    let bad = |what| OocError::Corrupt { tree: k, what };
    let mut r = BitReader::new(bytes);
    // Structure.
    s.lay
        .root(read_symbol(decs, CTX_TEMPLATE, &mut r, k)?)
        .map_err(bad)?;
    while let Some(at) = s.lay.pending.pop() {
        r.refill();
        let left = read_refilled(decs, CTX_TEMPLATE, &mut r, k)?;
        let right = read_refilled(decs, CTX_TEMPLATE, &mut r, k)?;
        s.lay.expand(at, left, right).map_err(bad)?;
    }
    let n = s.lay.positions();
    if out.nodes.len() + n > h.node_words as usize {
        return Err(bad("the trees hold more node words than the header says"));
    }
    // Pass 1, the corners: each leaf's triangles, and where each vertex
    // is first used (`first_use[v]`: its triangle, times 4, plus its
    // corner slot).
    // A local, so that its ranks stay in a register.
    let mut cache = RankCache::default();
    s.tris.clear();
    s.spans.clear();
    s.first_use.resize(MAX_TREE_VERTICES + 3, 0);
    let mut next = 0u32;
    for _ in 0..s.lay.leaves().len() {
        let count = if h.multi {
            read_symbol(decs, CTX_LEAF, &mut r, k)? + 1
        } else {
            1
        };
        if count as usize > MAX_LEAF_TRIANGLES || s.tris.len() + count as usize > MAX_TREE_TRIANGLES
        {
            return Err(bad(
                "a leaf or the tree holds more triangles than the format allows",
            ));
        }
        if h.multi {
            s.spans.push((s.tris.len() as u32, count));
        }
        for _ in 0..count {
            let t = (s.tris.len() as u32) << 2;
            let mut c = [0u32; 3];
            // One refill for the three corners.
            r.refill();
            for (slot, cs) in c.iter_mut().enumerate() {
                let sym = read_refilled(decs, CTX_CORNER + slot, &mut r, k)?;
                let v = cache.decode(sym, next).map_err(bad)?;
                // Written whether or not `next` is used here (no branch
                // on the symbol's kind): the entry stays once it is.
                s.first_use[next as usize] = t | slot as u32;
                // The symbol, not the vertex, says a vertex is new: the
                // count then does not wait for the cache.
                next += u32::from(sym == SYM_NEW);
                *cs = v;
            }
            if next as usize > MAX_TREE_VERTICES {
                return Err(bad("the tree has more vertices than 9-bit indices address"));
            }
            s.tris.push(c);
        }
    }
    // Pass 2, the plans: how each vertex is predicted, from the adjacency
    // of the triangles before the one that first uses it.
    s.adj.start(next as usize);
    s.plans.clear();
    let mut added = 0;
    for v in 0..next {
        let at = s.first_use[v as usize];
        let t = (at >> 2) as usize;
        while added < t {
            s.adj.add(s.tris[added]);
            added += 1;
        }
        s.plans.push(plan(s.tris[t], (at & 3) as usize, v, &s.adj));
    }
    // Pass 3, the vertices: their residuals, in the order of their
    // indices, against their plans' predictions.
    let max_q = out.q.max_q();
    s.grid.clear();
    s.grid.push(centre(max_q));
    let mut outside = false;
    for &(ctx, slots) in &s.plans {
        let pred = predicted(ctx, slots, &s.grid, max_q);
        // Axis by axis, written out (`array::from_fn` stays a call).
        let mut g = [0u32; 3];
        // One refill for the three residuals.
        r.refill();
        for (x, gx) in g.iter_mut().enumerate() {
            let d = unzigzag(u64::from(read_refilled(decs, ctx + x, &mut r, k)?));
            let q = i64::from(pred[x]) + d;
            outside |= !(0..=i64::from(max_q)).contains(&q);
            *gx = q as u32;
        }
        s.grid.push(g);
    }
    if outside {
        return Err(bad("a vertex decodes outside the grid"));
    }
    let triangles = s.tris.len() as u32;
    if r.overran() {
        return Err(bad("the tree's stream ends early"));
    }
    out.headers.push(TreeHeader {
        node_start: out.nodes.len() as u32,
        ic_start: out.ics.len() as u32,
        vertex_start: out.stored,
        first_triangle: out.triangles,
    });
    let multi = h.multi.then_some((&mut out.blocks, &mut out.block_start));
    // Boxes on the grid, as the i-HCCMesh encoder codes quantized ones:
    // in one 16-bit register each when the grid allows.
    let tree = (&s.spans[..], &s.tris[..]);
    let outs = (&mut out.nodes, &mut out.ics, multi);
    #[cfg(target_arch = "x86_64")]
    let root = if h.bits <= 16 {
        s.rebuild16
            .tree(&s.lay, tree, &s.grid[1..], outs, &mut out.stats)
    } else {
        s.rebuild
            .tree(&s.lay, tree, &s.grid[1..], outs, &mut out.stats)
    };
    #[cfg(not(target_arch = "x86_64"))]
    let root = s
        .rebuild
        .tree(&s.lay, tree, &s.grid[1..], outs, &mut out.stats);
    if u32::try_from(out.blocks.len()).is_err() {
        return Err(bad("the trees' triangle blocks outgrow 4 GiB"));
    }
    // The root box in world coordinates (the grid is monotone).
    out.roots
        .push(std::array::from_fn(|e| out.q.value(e % 3, root[e] as u32)));
    let base = out.nodes.len() - n;
    out.leaf_bits.resize(out.nodes.len().div_ceil(64), 0);
    for &p in s.lay.leaves() {
        let p = base + p as usize;
        out.leaf_bits[p / 64] |= 1 << (p % 64);
    }
    out.q.push_tree(&s.grid[1..]);
    out.stored = out
        .stored
        .checked_add(next)
        .ok_or(bad("the trees hold more vertices than 32 bits count"))?;
    out.triangles = out
        .triangles
        .checked_add(triangles)
        .ok_or(bad("the trees hold more triangles than 32 bits count"))?;
    if out.ics.len() > h.interconnections as usize {
        return Err(bad(
            "the trees hold more inter-connections than the header says",
        ));
    }
    Ok(())
}
