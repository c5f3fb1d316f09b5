//! Compression (§4): clusters, front-based structure coding, quantized and
//! predicted boxes, delta-coded triangle and child indices.

use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use rayon::prelude::*;

use super::mesh::PackedMesh;
use super::node::residuals;
use super::{
    CTX_CHILD, CTX_COUNT, CTX_PCLUSTER, CTX_STRUCT, CTX_TRI, CTX_TRI_FAR, ClusterMeta, Header,
    NCTX, RacBvh, RacError, RacOptions, STREAM_MASK, STREAM_RES, STREAMS, bucket, mask_context,
    raw_bits, value_context, zero_mask,
};
use crate::build::CanonicalBvh;
use crate::codec::common::Store;
use crate::codec::common::bits::{BitWriter, golomb_len, zigzag};
use crate::codec::common::dict::{DictEncoder, MAX_K, SymbolEncoder};
use crate::codec::common::quant::{Grid, QBox};
use crate::geom::Aabb;
use crate::mesh::Mesh;

/// One coded item of a cluster, before the rank codes' parameters are known.
enum Item {
    Sym {
        ctx: usize,
        rank: u32,
        raw: Option<u32>,
        stream: usize,
    },
    Raw {
        v: u64,
        bits: u32,
        stream: usize,
    },
}

/// What [`encode_cluster`] reads of the tree, by global node index in
/// layout order: the in-memory encoder's whole tree, or the out-of-core
/// encoder's window of it ([`super::stream`]). It asks only for the
/// cluster's nodes, their parents and, for a node whose sibling comes
/// earlier in the cluster, the sibling.
pub(super) trait TreeSource: Sync {
    /// The parent of node `g` (not the root).
    fn parent(&self, g: usize) -> usize;
    /// The children of inner node `g`, `None` for a leaf.
    fn children(&self, g: usize) -> Option<[u32; 2]>;
    /// The triangle ids of leaf `g`.
    fn leaf_ids(&self, g: usize) -> &[u32];
    /// The quantized box of node `g` (inside its parent's).
    fn qbox(&self, g: usize) -> &QBox;
}

/// The in-memory tree with its quantized boxes.
struct Whole<'a> {
    bvh: &'a CanonicalBvh,
    q: &'a [QBox],
}

impl TreeSource for Whole<'_> {
    #[inline]
    fn parent(&self, g: usize) -> usize {
        self.bvh.parents[g] as usize
    }
    #[inline]
    fn children(&self, g: usize) -> Option<[u32; 2]> {
        let n = &self.bvh.nodes[g];
        (!n.is_leaf()).then(|| n.children())
    }
    #[inline]
    fn leaf_ids(&self, g: usize) -> &[u32] {
        &self.bvh.leaf_triangles[self.bvh.nodes[g].leaf_range()]
    }
    #[inline]
    fn qbox(&self, g: usize) -> &QBox {
        &self.q[g]
    }
}

/// Node boxes of `bvh` from its triangles as `tri` gives them (the stored
/// mesh's, so that the boxes contain the triangles the cursor reports:
/// quantized vertices move), bottom-up.
pub(super) fn node_boxes(
    bvh: &CanonicalBvh,
    tri: &dyn Fn(u32) -> crate::geom::Triangle,
) -> Vec<Aabb> {
    let mut boxes = vec![Aabb::EMPTY; bvh.nodes.len()];
    for i in (0..bvh.nodes.len()).rev() {
        let n = &bvh.nodes[i];
        boxes[i] = if n.is_leaf() {
            bvh.leaf_triangles[n.leaf_range()]
                .iter()
                .fold(Aabb::EMPTY, |b, &t| b.union(&Aabb::of_triangle(&tri(t))))
        } else {
            boxes[n.a as usize].union(&boxes[n.b as usize])
        };
    }
    boxes
}

/// Clamps `c` into its parent's quantized box `pq` (see the encoder for
/// why: far from the origin neighbouring grid points can coincide).
pub(super) fn clamp_into(c: &mut QBox, pq: &QBox) {
    for a in 0..3 {
        let lo = c.min[a].clamp(pq.min[a], pq.max[a]);
        let hi = c.max[a].clamp(pq.min[a], pq.max[a]);
        c.min[a] = lo.min(hi);
        c.max[a] = lo.max(hi);
    }
}

/// Checks what the codec relies on: parents before children, consistent
/// parent links, leaf ranges in bounds.
pub(super) fn check_tree(bvh: &CanonicalBvh, tri_count: usize) -> Result<(), RacError> {
    let n = bvh.nodes.len();
    if n == 0 || bvh.parents.len() != n {
        return Err(RacError::InvalidTree(
            "the tree has no nodes or its parent array has the wrong length".into(),
        ));
    }
    if n >= (1usize << 31) {
        return Err(RacError::InvalidTree(format!(
            "{n} nodes is more than 2^31 - 1"
        )));
    }
    for (i, node) in bvh.nodes.iter().enumerate() {
        if node.is_leaf() {
            let r = node.leaf_range();
            if r.end > bvh.leaf_triangles.len() || r.len() > bvh.max_leaf_triangles.max(1) {
                return Err(RacError::InvalidTree(format!(
                    "leaf {i} has a bad triangle range {r:?}"
                )));
            }
            if r.is_empty() && n > 1 {
                return Err(RacError::InvalidTree(format!("leaf {i} has no triangles")));
            }
        } else {
            for c in node.children() {
                if c as usize >= n || c as usize <= i || bvh.parents[c as usize] != i as u32 {
                    return Err(RacError::InvalidTree(format!(
                        "node {i}'s child {c} does not come after it or does not name it as parent \
                         (RACBVH needs parents before children in the layout)"
                    )));
                }
            }
        }
    }
    if bvh.leaf_triangles.iter().any(|&t| t as usize >= tri_count) {
        return Err(RacError::InvalidTree(
            "a leaf refers to a triangle the mesh does not have".into(),
        ));
    }
    Ok(())
}

impl RacBvh {
    /// Compresses `bvh`, built over `mesh`.
    pub fn encode(
        bvh: &CanonicalBvh,
        mesh: &Mesh,
        options: &RacOptions,
    ) -> Result<RacBvh, RacError> {
        Self::encode_with_progress(bvh, mesh, options, &|_, _| {})
    }

    /// [`encode`](Self::encode), calling `progress(clusters done, clusters)`
    /// as clusters finish. Clusters are compressed in parallel on rayon's
    /// threads; the result does not depend on the thread count.
    pub fn encode_with_progress(
        bvh: &CanonicalBvh,
        mesh: &Mesh,
        options: &RacOptions,
        progress: &(dyn Fn(u64, u64) + Sync),
    ) -> Result<RacBvh, RacError> {
        let start = Instant::now();
        options.validate()?;
        check_tree(bvh, mesh.triangles.len())?;
        let pmesh = PackedMesh::encode(mesh, options.vertex_bits)?;
        let boxes = node_boxes(bvh, &|t| pmesh.triangle(t));
        let empty = bvh.leaf_triangles.is_empty();
        let root_box = boxes[0];
        let finite =
            root_box.min.is_finite() && root_box.max.is_finite() && root_box.extent().is_finite();
        if !empty && !finite {
            return Err(RacError::InvalidMesh(
                "the mesh's bounding box is not finite in f32".into(),
            ));
        }
        let grid = if empty {
            Grid::new(&Aabb::from_arrays([0.0; 3], [0.0; 3]), options.bits)
        } else {
            Grid::new(&root_box, options.bits)
        };
        let mut q: Vec<QBox> = boxes
            .par_iter()
            .map(|b| {
                if empty {
                    QBox::default()
                } else {
                    grid.quantize(b)
                }
            })
            .collect();
        q[0] = Header::root_qbox(&grid);
        // Far from the origin the grid step can be below the f32 spacing
        // there, so neighbouring grid points coincide and a flat child's
        // rounded-down min can land past its parent's rounded-up max. Grid
        // points are monotone in q, so clamping a child into its parent's
        // quantized box (and swapping an inverted pair) keeps it
        // conservative: the parent's points already bound the child's box.
        // Parents come before children (checked above).
        for g in 1..q.len() {
            let pq = q[bvh.parents[g] as usize];
            clamp_into(&mut q[g], &pq);
        }
        let cluster_nodes = options.cluster_nodes;
        let cluster_bits = cluster_nodes.trailing_zeros();
        let header = Header {
            cluster_bits,
            bits: options.bits,
            node_count: bvh.nodes.len() as u32,
            triangle_count: mesh.triangles.len() as u32,
            max_leaf: bvh.max_leaf_triangles.max(1) as u32,
            tri_threshold: options.tri_delta_threshold,
            grid,
            empty,
            tree_bits: 0,
            bv_bits: 0,
            compression_seconds: 0.0,
        };
        let mut data = Vec::new();
        let mut meta = Vec::new();
        let (mut tree_bits, mut bv_bits) = (0u64, 0u64);
        let csize = cluster_nodes as usize;
        let clusters = bvh.nodes.len().div_ceil(csize);
        let done = AtomicU64::new(0);
        progress(0, clusters as u64);
        let whole = Whole { bvh, q: &q };
        let coded: Vec<(Vec<u8>, u64, u64)> = (0..clusters)
            .into_par_iter()
            .map(|c| {
                let s = c * csize;
                let e = (s + csize).min(bvh.nodes.len());
                let r = code_cluster(&whole, &header, c as u32, s, e)?;
                progress(done.fetch_add(1, Ordering::Relaxed) + 1, clusters as u64);
                Ok(r)
            })
            .collect::<Result<_, RacError>>()?;
        for (c, (bytes, tb, bb)) in coded.into_iter().enumerate() {
            let s = c * csize;
            let e = (s + csize).min(bvh.nodes.len());
            meta.push(ClusterMeta {
                offset: data.len() as u64,
                nodes: (e - s) as u32,
                hash: xxhash_rust::xxh3::xxh3_64(&bytes),
            });
            data.extend_from_slice(&bytes);
            tree_bits += tb;
            bv_bits += bb;
        }
        let mut header = header;
        header.tree_bits = tree_bits;
        header.bv_bits = bv_bits;
        header.compression_seconds = start.elapsed().as_secs_f64();
        let mesh_hash = super::file::mesh_hash(&pmesh);
        let mut rac = RacBvh::assemble(
            header,
            Store::Owned(data),
            meta,
            pmesh,
            mesh_hash,
            crate::codec::common::MassProps::of_mesh(mesh),
            options.cache_budget_bytes,
        );
        // Packed here, in memory: nothing to check before the first query.
        let _ = rac.mesh_ok.set(Ok(()));
        // From the tree as stored (quantized vertices); the traversal's
        // clusters are not kept, so the tree starts with a cold cache.
        rac.edges = crate::codec::common::edges::of_cursor(&rac);
        rac.clear_cache();
        Ok(rac)
    }
}

/// Codes nodes `s..e` (cluster `c`) both ways (front positions counted
/// from the newest node suit depth-first orders, from the oldest
/// breadth-first ones) and keeps the shorter. Returns the bytes and the
/// bits spent on the tree and on the boxes.
pub(super) fn code_cluster<T: TreeSource>(
    t: &T,
    h: &Header,
    c: u32,
    s: usize,
    e: usize,
) -> Result<(Vec<u8>, u64, u64), RacError> {
    let newest = encode_cluster(t, h, c, s, e, false)?;
    let oldest = encode_cluster(t, h, c, s, e, true)?;
    Ok(if oldest.0.len() < newest.0.len() {
        oldest
    } else {
        newest
    })
}

/// Codes nodes `s..e` (cluster `c`). Returns the bytes and the bits spent
/// on the tree and on the boxes.
fn encode_cluster<T: TreeSource>(
    t: &T,
    h: &Header,
    c: u32,
    s: usize,
    e: usize,
    from_oldest: bool,
) -> Result<(Vec<u8>, u64, u64), RacError> {
    let mut items = Vec::with_capacity((e - s) * 9);
    let mut dicts: Vec<DictEncoder> = (0..NCTX).map(|_| DictEncoder::new()).collect();
    let mut sym = |items: &mut Vec<Item>, ctx: usize, v: u32, stream: usize| {
        let st = dicts[ctx].encode(v);
        items.push(Item::Sym {
            ctx,
            rank: st.rank,
            raw: st.raw,
            stream,
        });
    };
    // The parent clusters, in order of first use.
    let mut pclusters: Vec<u32> = Vec::new();
    let mut pindex: HashMap<u32, u32> = HashMap::new();
    for g in s.max(1)..e {
        let p = t.parent(g);
        if p < s {
            let pc = (p >> h.cluster_bits) as u32;
            pindex.entry(pc).or_insert_with(|| {
                pclusters.push(pc);
                pclusters.len() as u32 - 1
            });
        }
    }
    let mut front: Vec<u32> = Vec::new();
    let mut got = vec![0u8; e - s];
    let mut res = vec![[0u32; 6]; e - s];
    let mut last_tri: i64 = 0;
    let threshold = i64::from(h.tri_threshold);
    for g in s..e {
        let kids = t.children(g);
        let leaf = u32::from(kids.is_none());
        let mut sib_tri: Option<i64> = None;
        if g == 0 {
            sym(&mut items, CTX_STRUCT, leaf, 0);
        } else {
            let p = t.parent(g);
            let pk = t.children(p).ok_or_else(|| {
                RacError::InvalidTree(format!("the parent {p} of node {g} is a leaf"))
            })?;
            let right = pk[1] as usize == g;
            let side = u32::from(right);
            if p >= s {
                let at = front
                    .iter()
                    .rposition(|&f| f as usize == p)
                    .ok_or_else(|| {
                        RacError::InvalidTree(format!("parent {p} of node {g} is not open"))
                    })?;
                let pos = if from_oldest {
                    at
                } else {
                    front.len() - 1 - at
                } as u32;
                // The second child's side is implied: sent as 0.
                let coded_side = if got[p - s] != 0 { 0 } else { side };
                sym(
                    &mut items,
                    CTX_STRUCT,
                    ((pos + 1) << 2) | (coded_side << 1) | leaf,
                    0,
                );
                got[p - s] |= 1 << side;
                if got[p - s] == 3 {
                    front.remove(at);
                }
            } else {
                sym(&mut items, CTX_STRUCT, (side << 1) | leaf, 0);
                let pc = (p >> h.cluster_bits) as u32;
                sym(&mut items, CTX_PCLUSTER, pindex[&pc], 0);
                items.push(Item::Raw {
                    v: (p & ((1 << h.cluster_bits) - 1)) as u64,
                    bits: h.cluster_bits,
                    stream: 0,
                });
            }
            let (pq, cq) = (t.qbox(p), t.qbox(g));
            let inside = (0..3).all(|a| pq.min[a] <= cq.min[a] && cq.max[a] <= pq.max[a]);
            if !inside {
                return Err(RacError::InvalidTree(format!(
                    "node {g}'s box is not inside its parent's"
                )));
            }
            let r = residuals(pq, right, cq).map(|v| v as u32);
            let sibg = pk[usize::from(!right)] as usize;
            let known = p >= s && (s..g).contains(&sibg);
            if known
                && t.children(sibg).is_none()
                && let &[id] = t.leaf_ids(sibg)
            {
                sib_tri = Some(i64::from(id));
            }
            let sib = known.then(|| &res[sibg - s]);
            let has_sib = sib.is_some();
            sym(
                &mut items,
                mask_context(leaf == 1, right, has_sib),
                zero_mask(&r, sib),
                STREAM_MASK,
            );
            for (k, &v) in r.iter().enumerate() {
                if v == 0 {
                    continue;
                }
                let b = bucket(u64::from(v));
                sym(
                    &mut items,
                    value_context(leaf == 1, right, k, has_sib),
                    b,
                    STREAM_RES + k,
                );
                if b > 1 {
                    items.push(Item::Raw {
                        v: u64::from(v),
                        bits: b - 1,
                        stream: STREAM_RES + k,
                    });
                }
            }
            res[g - s] = r;
        }
        if kids.is_none() {
            let ids = t.leaf_ids(g);
            // A sibling leaf's triangle is a better reference than the
            // previous leaf's when the layout is not depth-first.
            last_tri = sib_tri.unwrap_or(last_tri);
            if h.max_leaf > 1 {
                sym(&mut items, CTX_COUNT, ids.len() as u32, 0);
            }
            for &id in ids {
                let d = i64::from(id) - last_tri;
                if d.abs() < threshold {
                    sym(&mut items, CTX_TRI, zigzag(d) as u32 + 1, 0);
                } else {
                    sym(&mut items, CTX_TRI, 0, 0);
                    let z = zigzag(d);
                    let b = bucket(z);
                    sym(&mut items, CTX_TRI_FAR, b, 0);
                    if b > 1 {
                        items.push(Item::Raw {
                            v: z,
                            bits: b - 1,
                            stream: 0,
                        });
                    }
                }
                last_tri = i64::from(id);
            }
        } else {
            front.push(g as u32);
        }
    }
    // Local leaves: the children outside this cluster, delta coded.
    let mut last_child = e as i64;
    for &f in &front {
        let fk = t.children(f as usize).unwrap_or_default();
        for (side, child) in fk.into_iter().enumerate() {
            if got[f as usize - s] & (1 << side) == 0 {
                let d = i64::from(child) - last_child;
                sym(&mut items, CTX_CHILD, zigzag(d) as u32, 0);
                last_child = i64::from(child);
            }
        }
    }
    // Choose each context's Exp-Golomb parameter, then write.
    let mut cost = [[0u64; MAX_K as usize + 1]; NCTX];
    for it in &items {
        if let Item::Sym { ctx, rank, .. } = *it {
            for (k, c) in cost[ctx].iter_mut().enumerate() {
                *c += golomb_len(rank, k as u32);
            }
        }
    }
    let ks: [u32; NCTX] = std::array::from_fn(|ctx| {
        (0..=MAX_K)
            .min_by_key(|&k| cost[ctx][k as usize])
            .unwrap_or(0)
    });
    // Streams decoded side by side (see `STREAMS`).
    let mut w: [BitWriter; STREAMS] = Default::default();
    w[0].put(u64::from(from_oldest), 1);
    for &k in &ks {
        w[0].put(u64::from(k), 2);
    }
    w[0].put_golomb(pclusters.len() as u32, 0);
    for &pc in &pclusters {
        w[0].put_golomb(c - pc - 1, 0);
    }
    for it in &items {
        match *it {
            Item::Sym {
                ctx,
                rank,
                raw,
                stream,
            } => {
                w[stream].put_golomb(rank, ks[ctx]);
                if let Some(v) = raw {
                    w[stream].put(u64::from(v), raw_bits(ctx, h));
                }
            }
            Item::Raw { v, bits, stream } => w[stream].put(v, bits),
        }
    }
    let w = w.map(BitWriter::finish);
    let table = 4 * (STREAMS - 1);
    let mut out = Vec::with_capacity(table + w.iter().map(Vec::len).sum::<usize>());
    for stream in &w[..STREAMS - 1] {
        out.extend_from_slice(&(stream.len() as u32).to_le_bytes());
    }
    let tree_bits = (table + w[0].len()) as u64 * 8;
    let bv_bits = w[1..].iter().map(|x| x.len() as u64 * 8).sum();
    for stream in &w {
        out.extend_from_slice(stream);
    }
    Ok((out, tree_bits, bv_bits))
}
