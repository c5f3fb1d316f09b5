//! The out-of-core RACBVH builder: a model split into chunks on disk
//! ([`ChunkedMesh`]) in, a RACBVH file out, with peak memory set by the
//! chunk size, not by the model.
//!
//! # How
//!
//! The file is the one [`RacBvh::encode`] writes for a model whose
//! canonical tree is the tree over the chunks ([`ChunkedMesh::top`]) with
//! each chunk's own tree under its leaf; nothing in the format changes,
//! and the reader cannot tell. The whole tree's layout: the tree over the
//! chunks in depth-first order (a node, its left subtree, its right
//! subtree), each chunk's tree a block of consecutive nodes in its own
//! layout where its leaf of the chunk tree is; so chunks follow each other
//! in their order, parents come before children, and the clusters are cut
//! from that sequence as from an in-memory tree. Triangles are numbered
//! chunk by chunk (each chunk's in file order); vertices keep the file's
//! numbering. Two passes over the chunks, one at a time:
//!
//! 1. **Build.** Each chunk's canonical tree ([`build`]), its boxes
//!    recomputed from its triangles *as stored* (vertices quantized over
//!    the whole model's box, which its vertices, held in memory, give),
//!    its edge flags computed alone (its open edges kept for pairing), its
//!    mass summed ([`MassAccumulator`]), its triangles' vertex indices
//!    appended to the mesh's index array (written as it grows:
//!    [`ForWriter`]), and its tree and boxes written to a temporary file
//!    (about 68 bytes a triangle).
//! 2. **Code.** The box grid over the union of the chunks' root boxes (the
//!    in-memory encoder's grid: the same box), the chunk tree's boxes
//!    quantized from the top (each box clamped into its parent's, as the
//!    in-memory encoder clamps), then the clusters in order: the chunks a
//!    cluster spans are read back (each once) and quantized, and every
//!    cluster they complete is coded by the in-memory encoder's code
//!    (`encode::code_cluster`, the clusters of a batch in parallel) and appended
//!    to a temporary file, hashed as it goes.
//!
//! Then the vertex arrays, the edge flags with the open edges paired across
//! chunks ([`EdgeFlags::resolve_open`]), the meta table and the header;
//! the file is written under a temporary name beside the output and
//! renamed over it at the end ([`AtomicFile`]).
//!
//! What stays in memory besides one chunk's build: the model's vertices
//! (12 bytes each), the edge flags (a byte a triangle), the packed index
//! array's block heads (3/8 byte a triangle), the meta table (20 bytes a
//! cluster), the tree over the chunks and the chunks' open edges. While
//! coding: the chunks the current clusters span (about 76 bytes a
//! triangle of them) and a batch of coded clusters.
//!
//! Measured (a 50 M-triangle generated statue, 2 threads, release,
//! default budget: 16 chunks of at most 6.2 M triangles): out of core
//! 241 s wall (build and code 170 s, verify 66 s), peak RSS 1.68 GiB
//! (35 bytes a triangle), file 12.97 bytes a triangle; in memory
//! (`--memory-mib 22000`) 228 s, 14.5 GiB (310 bytes a triangle), 13.09
//! bytes a triangle (chunk-order triangle ids code a little shorter).
//!
//! # What differs from the in-memory file
//!
//! The tree (the top is cut at the chunks), the triangle numbering, the
//! mass properties' last bits (summed in another order), and the
//! compression time, stored as 0 so that the same input, options and
//! chunks give the same bytes whatever the threads (every other step is
//! deterministic and in chunk order). A model without triangles is
//! encoded in memory (it has nothing to chunk).

use std::collections::VecDeque;
use std::fs::File;
use std::io::{BufWriter, Read, Write};
use std::path::{Path, PathBuf};

use glam::Vec3A;
use rayon::prelude::*;
use xxhash_rust::xxh3::{Xxh3, xxh3_64};

use super::encode::{TreeSource, check_tree, clamp_into, code_cluster, node_boxes};
use super::file::{self, FRAME, SECTIONS};
use super::mesh::VertexCoder;
use super::{ClusterMeta, Header, RacBvh, RacError, RacOptions};
use crate::build::chunked::{ChunkNode, ChunkScratch, ChunkedMesh};
use crate::build::{BuildOptions, CanonicalBvh, LEAF_FLAG, build};
use crate::codec::StreamedReport;
use crate::codec::common::edges::{self, ChunkedFlags};
use crate::codec::common::packed::{ForPieces, ForWriter};
use crate::codec::common::quant::{Grid, QBox};
use crate::codec::common::{MassAccumulator, mass::vertex_mean};
use crate::contact::EdgeFlags;
use crate::files::{AtomicFile, IoError};
use crate::geom::Aabb;

pub use crate::build::chunked::Progress;

/// What [`encode_streamed`] made.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct StreamedBuild {
    /// The file's bytes.
    pub bytes: u64,
    /// Bytes of the clusters' tree structure (as the in-memory
    /// [`ByteSize`](crate::codec::ByteSize) parts count them).
    pub tree_bytes: u64,
    /// Bytes of the clusters' boxes.
    pub box_bytes: u64,
    /// Bytes of the meta table.
    pub meta_bytes: u64,
    /// Bytes of the stored mesh.
    pub mesh_bytes: u64,
    /// Bytes of the edge flags.
    pub edge_bytes: u64,
    /// Nodes in the tree.
    pub nodes: u64,
    /// Clusters.
    pub clusters: u64,
    /// Chunks built.
    pub chunks: usize,
    /// The largest chunk's triangles.
    pub largest_chunk: u64,
    /// Edges shared by two chunks, paired after the chunks were built.
    pub paired_edges: u64,
}

impl StreamedBuild {
    /// The codec-neutral report (the contract's
    /// [`encode_streamed`](crate::codec::Codec::encode_streamed)).
    pub fn report(&self) -> StreamedReport {
        StreamedReport {
            chunks: self.chunks,
            largest_chunk: self.largest_chunk,
            paired_edges: self.paired_edges,
            counts: vec![("nodes", self.nodes), ("clusters", self.clusters)],
            parts: self.parts(),
        }
    }

    /// The file's bytes by part, named as the in-memory tree names them.
    pub fn parts(&self) -> Vec<(&'static str, f64)> {
        vec![
            ("bvh_tree", self.tree_bytes as f64),
            ("bvh_bv", self.box_bytes as f64),
            ("meta", self.meta_bytes as f64),
            ("mesh", self.mesh_bytes as f64),
            ("edge-flags", self.edge_bytes as f64),
        ]
    }
}

/// What pass 1 keeps of a chunk.
struct Chunk {
    nodes: u32,
    first_triangle: u32,
    root: Aabb,
    file: PathBuf,
}

/// Builds the RACBVH of `input` chunk by chunk (see the module docs) with
/// the builder's `build_options` and the codec's `options`, and writes it
/// to `out` (atomically: on error nothing is left under that name).
/// Temporary files go to `input`'s temporary directory. `progress` hears
/// the phases `building` (triangles), `coding` (nodes) and `writing`
/// (bytes).
///
/// # Errors
/// [`RacError::OutOfCore`] for a chunk that could not be read or built or
/// a model beyond the format's counts, the encoder's errors for options
/// and meshes it refuses, and I/O errors.
pub fn encode_streamed(
    input: &ChunkedMesh,
    build_options: &BuildOptions,
    options: &RacOptions,
    out: &Path,
    progress: Progress<'_>,
) -> Result<StreamedBuild, RacError> {
    options.validate()?;
    let mut out_file = AtomicFile::create(out).map_err(io(out))?;
    let vertices = &input.vertices;
    let coder = VertexCoder::of(vertices, options.vertex_bits)?;
    let vertex_count = u32::try_from(vertices.len())
        .map_err(|_| RacError::OutOfCore("more than 2^32 vertices".into()))?;
    let total = input.triangle_count();
    if total == 0 {
        return without_triangles(input, build_options, options, out_file);
    }
    let triangle_count = u32::try_from(total)
        .map_err(|_| RacError::OutOfCore(format!("{total} triangles: more than 2^32 - 1")))?;
    let temp = input.temp_dir();

    // Pass 1: build, box, flag, sum; the index array as it grows.
    let tri_path = temp.join("rac-triangles.bin");
    let mut tri_w = ForWriter::new(create(&tri_path)?);
    let mut mass = MassAccumulator::new(vertex_mean(vertices));
    let mut flags = ChunkedFlags::with_capacity(total as usize);
    let mut chunks: Vec<Chunk> = Vec::with_capacity(input.chunk_count());
    let mut scratch = ChunkScratch::default();
    let mut done = 0u64;
    for c in 0..input.chunk_count() {
        let (mesh, global) = input
            .chunk(c, &mut scratch)
            .map_err(|e| RacError::OutOfCore(e.to_string()))?;
        for t in &mesh.triangles {
            let p = t.map(|v| mesh.vertices[v as usize]);
            mass.add(p[0], p[1], p[2]);
            for &v in t {
                tri_w.push(global[v as usize]).map_err(io(&tri_path))?;
            }
        }
        drop(global);
        let n = mesh.triangles.len() as u64;
        let bvh = build(&mesh, build_options, &|d, t| {
            // The builder reports its leaves, then its layout.
            let at = done + (u128::from(n) * u128::from(d.min(t)) / u128::from(t.max(1))) as u64;
            progress("building", at, total);
        })
        .map_err(|e| RacError::OutOfCore(format!("chunk {c}: {e}")))?;
        check_tree(&bvh, mesh.triangles.len())?;
        // The triangles as the reader will decode them.
        let stored: Vec<Vec3A> = mesh.vertices.iter().map(|&v| coder.stored(v)).collect();
        let tri = |t: u32| mesh.triangles[t as usize].map(|v| stored[v as usize]);
        let (f, o) = EdgeFlags::from_visit_open(n as usize, |visit| {
            for t in 0..n as u32 {
                visit(t, &tri(t));
            }
        });
        let base = flags.push(&f, o);
        drop(f);
        let boxes = node_boxes(&bvh, &tri);
        let file = temp.join(format!("rac-chunk-{c}.bin"));
        std::fs::write(&file, chunk_bytes(&bvh, &boxes)).map_err(io(&file))?;
        chunks.push(Chunk {
            nodes: bvh.nodes.len() as u32,
            first_triangle: base as u32,
            root: boxes[0],
            file,
        });
        done += n;
        progress("building", done, total);
    }
    let tri_pieces = tri_w.finish().map_err(io(&tri_path))?;
    let triangles = Packed::of(tri_pieces, tri_path)?;

    // The tree over the chunks: boxes, global numbering, quantized boxes.
    let top = input.top();
    let mut tbox = vec![Aabb::EMPTY; top.len()];
    for i in (0..top.len()).rev() {
        tbox[i] = match top[i] {
            ChunkNode::Leaf { chunk } => chunks[chunk as usize].root,
            ChunkNode::Inner { children, .. } => {
                tbox[children[0] as usize].union(&tbox[children[1] as usize])
            }
        };
    }
    let root_box = tbox[0];
    if !(root_box.min.is_finite() && root_box.max.is_finite() && root_box.extent().is_finite()) {
        return Err(RacError::InvalidMesh(
            "the mesh's bounding box is not finite in f32".into(),
        ));
    }
    let grid = Grid::new(&root_box, options.bits);
    let layout = Layout::new(top, &chunks, &tbox, &grid)?;
    let node_count = layout.nodes;
    let header = Header {
        cluster_bits: options.cluster_nodes.trailing_zeros(),
        bits: options.bits,
        node_count,
        triangle_count,
        max_leaf: build_options.max_leaf_triangles.max(1) as u32,
        tri_threshold: options.tri_delta_threshold,
        grid,
        empty: false,
        tree_bits: 0,
        bv_bits: 0,
        compression_seconds: 0.0,
    };

    // Pass 2: the clusters, in order, batch by batch.
    let csize = options.cluster_nodes as usize;
    let n_nodes = node_count as usize;
    let clusters = n_nodes.div_ceil(csize);
    let clusters_path = temp.join("rac-clusters.bin");
    let mut clusters_w = create(&clusters_path)?;
    let mut clusters_hash = Xxh3::new();
    let mut meta: Vec<ClusterMeta> = Vec::with_capacity(clusters);
    let (mut offset, mut tree_bits, mut bv_bits) = (0u64, 0u64, 0u64);
    let mut window = Window {
        top: &layout.top,
        segs: VecDeque::new(),
    };
    let (mut next_item, mut loaded_end, mut next_cluster) = (0usize, 0usize, 0usize);
    while next_cluster < clusters {
        match layout.order.get(next_item) {
            Some(&Item::Top) => loaded_end += 1,
            Some(&Item::Chunk(c)) => {
                let seg = load(&chunks[c as usize], &layout, c as usize, &grid)?;
                std::fs::remove_file(&chunks[c as usize].file).ok();
                loaded_end += seg.parent.len();
                window.segs.push_back(seg);
            }
            None => {
                return Err(RacError::OutOfCore(
                    "the layout ended before the clusters (a bug)".into(),
                ));
            }
        }
        next_item += 1;
        let ready = if loaded_end == n_nodes {
            clusters
        } else {
            loaded_end / csize
        };
        if ready <= next_cluster {
            continue;
        }
        let coded: Vec<(Vec<u8>, u64, u64)> = (next_cluster..ready)
            .into_par_iter()
            .map(|c| {
                let s = c * csize;
                code_cluster(&window, &header, c as u32, s, (s + csize).min(n_nodes))
            })
            .collect::<Result<_, RacError>>()?;
        for (k, (bytes, tb, bb)) in coded.into_iter().enumerate() {
            let s = (next_cluster + k) * csize;
            meta.push(ClusterMeta {
                offset,
                nodes: ((s + csize).min(n_nodes) - s) as u32,
                hash: xxh3_64(&bytes),
            });
            clusters_w.write_all(&bytes).map_err(io(&clusters_path))?;
            clusters_hash.update(&bytes);
            offset += bytes.len() as u64;
            tree_bits += tb;
            bv_bits += bb;
        }
        next_cluster = ready;
        progress(
            "coding",
            (next_cluster * csize).min(n_nodes) as u64,
            n_nodes as u64,
        );
        let first_needed = next_cluster * csize;
        while window
            .segs
            .front()
            .is_some_and(|f| f.start as usize + f.parent.len() <= first_needed)
        {
            window.segs.pop_front();
        }
    }
    drop(window);
    clusters_w.flush().map_err(io(&clusters_path))?;
    drop(clusters_w);
    let clusters_len = offset;

    // The vertex arrays.
    let mut axes = Vec::with_capacity(3);
    for a in 0..3 {
        let path = temp.join(format!("rac-vertices-{a}.bin"));
        let mut w = ForWriter::new(create(&path)?);
        for v in vertices {
            w.push(coder.quantize(*v)[a]).map_err(io(&path))?;
        }
        axes.push(Packed::of(w.finish().map_err(io(&path))?, path)?);
    }

    // The edge flags, paired across chunks.
    let (edge_flags, paired_edges) = flags
        .joined()
        .ok_or(RacError::Corrupt("edge flags out of range (a bug)"))?;
    let flag_bytes = edges::encode(&edge_flags);
    drop(edge_flags);

    // The header, then every section.
    let mut meta_bytes = Vec::with_capacity(meta.len() * file::META_ENTRY);
    for e in &meta {
        file::meta_entry(e, &mut meta_bytes);
    }
    let header = Header {
        tree_bits,
        bv_bits,
        ..header
    };
    let mut head = file::fields(
        &header,
        &coder.params(vertex_count, triangle_count),
        &mass.finish(),
    );
    let vertices_len: u64 = axes.iter().map(Packed::len).sum();
    let table: [(u64, u64); SECTIONS] = [
        (meta_bytes.len() as u64, xxh3_64(&meta_bytes)),
        (clusters_len, clusters_hash.digest()),
        (vertices_len, hash_packed(&axes)?),
        (
            triangles.len(),
            hash_packed(std::slice::from_ref(&triangles))?,
        ),
        (flag_bytes.len() as u64, xxh3_64(&flag_bytes)),
    ];
    FRAME.write_table(&mut head, &table);
    let written = head.len() as u64 + table.iter().map(|t| t.0).sum::<u64>();
    let mut so_far = 0u64;
    let mut put = |b: &[u8], w: &mut AtomicFile| {
        w.write_all(b).map_err(io(out))?;
        so_far += b.len() as u64;
        progress("writing", so_far, written);
        Ok::<(), RacError>(())
    };
    put(&head, &mut out_file)?;
    put(&meta_bytes, &mut out_file)?;
    copy_file(&clusters_path, &mut |b| put(b, &mut out_file))?;
    std::fs::remove_file(&clusters_path).ok();
    for p in axes.iter().chain([&triangles]) {
        put(&p.prefix, &mut out_file)?;
        put(&p.heads, &mut out_file)?;
        copy_file(&p.path, &mut |b| put(b, &mut out_file))?;
        std::fs::remove_file(&p.path).ok();
    }
    put(&flag_bytes, &mut out_file)?;
    out_file.commit().map_err(io(out))?;
    let bv = bv_bits / 8;
    Ok(StreamedBuild {
        bytes: written,
        tree_bytes: clusters_len - bv.min(clusters_len),
        box_bytes: bv.min(clusters_len),
        meta_bytes: meta_bytes.len() as u64,
        mesh_bytes: vertices_len + triangles.len() + 48,
        edge_bytes: flag_bytes.len() as u64,
        nodes: u64::from(node_count),
        clusters: clusters as u64,
        chunks: chunks.len(),
        largest_chunk: (0..input.chunk_count())
            .map(|c| input.chunk_len(c))
            .max()
            .unwrap_or(0),
        paired_edges,
    })
}

/// A model without triangles, encoded in memory (the compression time
/// zeroed, as the streamed file's).
fn without_triangles(
    input: &ChunkedMesh,
    build_options: &BuildOptions,
    options: &RacOptions,
    mut out_file: AtomicFile,
) -> Result<StreamedBuild, RacError> {
    let mesh = crate::mesh::Mesh::new(input.vertices.clone(), Vec::new());
    let bvh =
        build(&mesh, build_options, &|_, _| {}).map_err(|e| RacError::OutOfCore(e.to_string()))?;
    let mut rac = RacBvh::encode(&bvh, &mesh, options)?;
    rac.header.compression_seconds = 0.0;
    let bytes = rac.to_bytes();
    let path = out_file.path().to_path_buf();
    out_file
        .write_all(&bytes)
        .and_then(|()| out_file.commit())
        .map_err(io(&path))?;
    let parts = crate::codec::ByteSize::bytes_by_part(&rac);
    let part = |k: usize| parts.get(k).map_or(0, |p| p.1 as u64);
    Ok(StreamedBuild {
        bytes: bytes.len() as u64,
        tree_bytes: part(0),
        box_bytes: part(1),
        meta_bytes: part(2),
        mesh_bytes: part(3),
        edge_bytes: part(4),
        nodes: rac.node_count() as u64,
        clusters: rac.cluster_count() as u64,
        chunks: 0,
        largest_chunk: 0,
        paired_edges: 0,
    })
}

/// Bytes of a stored chunk node: `a`, `b`, the box.
const NODE_BYTES: usize = 32;

/// A chunk's tree and boxes for pass 2: the node count, each node's `a`,
/// `b` and box (six `f32`), the leaf triangles (local ids).
fn chunk_bytes(bvh: &CanonicalBvh, boxes: &[Aabb]) -> Vec<u8> {
    let mut b = Vec::with_capacity(8 + bvh.nodes.len() * NODE_BYTES + 4 * bvh.leaf_triangles.len());
    b.extend_from_slice(&(bvh.nodes.len() as u32).to_le_bytes());
    b.extend_from_slice(&(bvh.leaf_triangles.len() as u32).to_le_bytes());
    for (n, x) in bvh.nodes.iter().zip(boxes) {
        b.extend_from_slice(&n.a.to_le_bytes());
        b.extend_from_slice(&n.b.to_le_bytes());
        for v in x.min.to_array().into_iter().chain(x.max.to_array()) {
            b.extend_from_slice(&v.to_le_bytes());
        }
    }
    for &t in &bvh.leaf_triangles {
        b.extend_from_slice(&t.to_le_bytes());
    }
    b
}

/// Where the nodes go: the tree over the chunks in depth-first order,
/// each chunk a block where its leaf is.
struct Layout {
    /// The sequence of the whole tree's nodes: a top node, or a chunk's
    /// block.
    order: Vec<Item>,
    /// The top's inner nodes by global index (increasing).
    top: Vec<TopNode>,
    /// Each chunk's first node, and its root's parent (`u32::MAX` for
    /// the root) and that parent's quantized box.
    chunk: Vec<(u32, u32, QBox)>,
    /// Nodes in all.
    nodes: u32,
}

#[derive(Clone, Copy)]
enum Item {
    Top,
    Chunk(u32),
}

/// An inner node of the tree over the chunks, placed.
struct TopNode {
    g: u32,
    parent: u32,
    children: [u32; 2],
    q: QBox,
}

impl Layout {
    fn new(
        top: &[ChunkNode],
        chunks: &[Chunk],
        tbox: &[Aabb],
        grid: &Grid,
    ) -> Result<Self, RacError> {
        // Global index of each top node (a leaf: its chunk's root).
        let mut g_of = vec![0u32; top.len()];
        let mut parent_of = vec![u32::MAX; top.len()];
        let mut order = Vec::with_capacity(top.len());
        let mut next = 0u64;
        let mut stack = vec![0u32];
        while let Some(i) = stack.pop() {
            g_of[i as usize] = next as u32;
            match top[i as usize] {
                ChunkNode::Inner { children, .. } => {
                    order.push(Item::Top);
                    next += 1;
                    for &c in &children {
                        parent_of[c as usize] = i;
                    }
                    stack.push(children[1]);
                    stack.push(children[0]);
                }
                ChunkNode::Leaf { chunk } => {
                    order.push(Item::Chunk(chunk));
                    next += u64::from(chunks[chunk as usize].nodes);
                }
            }
            if next >= 1 << 31 {
                return Err(RacError::OutOfCore(format!(
                    "more than 2^31 - 1 nodes (the format's limit): {next} so far"
                )));
            }
        }
        // Quantized boxes from the top down (parents first in `top`).
        let root_q = Header::root_qbox(grid);
        let mut q = vec![QBox::default(); top.len()];
        let mut tops = Vec::new();
        let mut chunk = vec![(0u32, u32::MAX, root_q); chunks.len()];
        for i in 0..top.len() {
            let p = parent_of[i];
            let pq = (p != u32::MAX).then(|| q[p as usize]);
            let pg = pq.map_or(u32::MAX, |_| g_of[p as usize]);
            match top[i] {
                ChunkNode::Inner { children, .. } => {
                    q[i] = match pq {
                        None => root_q,
                        Some(pq) => {
                            let mut x = grid.quantize(&tbox[i]);
                            clamp_into(&mut x, &pq);
                            x
                        }
                    };
                    tops.push(TopNode {
                        g: g_of[i],
                        parent: pg,
                        children: children.map(|c| g_of[c as usize]),
                        q: q[i],
                    });
                }
                ChunkNode::Leaf { chunk: c } => {
                    chunk[c as usize] = (g_of[i], pg, pq.unwrap_or(root_q));
                }
            }
        }
        tops.sort_unstable_by_key(|t| t.g);
        Ok(Self {
            order,
            top: tops,
            chunk,
            nodes: next as u32,
        })
    }
}

/// A chunk's nodes placed, for the clusters it is in.
struct Seg {
    /// Global index of the first node.
    start: u32,
    parent: Vec<u32>,
    /// Global children, or a leaf's first id in `ids` and
    /// [`LEAF_FLAG`] | count.
    node: Vec<[u32; 2]>,
    q: Vec<QBox>,
    /// Global triangle ids.
    ids: Vec<u32>,
}

/// Reads chunk `c`'s file back and places it (see [`Layout`]).
fn load(chunk: &Chunk, layout: &Layout, c: usize, grid: &Grid) -> Result<Seg, RacError> {
    let b = std::fs::read(&chunk.file).map_err(io(&chunk.file))?;
    let damaged = || RacError::OutOfCore(format!("{}: damaged", chunk.file.display()));
    let word = |at: usize| -> Result<u32, RacError> {
        b.get(at..at + 4)
            .map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]))
            .ok_or_else(damaged)
    };
    let (n, ids_len) = (word(0)? as usize, word(4)? as usize);
    if n != chunk.nodes as usize || b.len() != 8 + n * NODE_BYTES + 4 * ids_len {
        return Err(damaged());
    }
    let (start, root_parent, root_pq) = layout.chunk[c];
    let mut node = Vec::with_capacity(n);
    let mut boxes = Vec::with_capacity(n);
    let mut parent = vec![root_parent; n];
    for j in 0..n {
        let at = 8 + j * NODE_BYTES;
        let (a, bb) = (word(at)?, word(at + 4)?);
        let f: [f32; 6] = std::array::from_fn(|k| {
            let w = &b[at + 8 + 4 * k..at + 12 + 4 * k];
            f32::from_le_bytes([w[0], w[1], w[2], w[3]])
        });
        boxes.push(Aabb::from_arrays([f[0], f[1], f[2]], [f[3], f[4], f[5]]));
        if bb & LEAF_FLAG != 0 {
            node.push([a, bb]);
        } else {
            for k in [a, bb] {
                *parent.get_mut(k as usize).ok_or_else(damaged)? = start + j as u32;
            }
            node.push([start + a, start + bb]);
        }
    }
    let ids_at = 8 + n * NODE_BYTES;
    let ids = (0..ids_len)
        .map(|k| word(ids_at + 4 * k).map(|t| chunk.first_triangle + t))
        .collect::<Result<Vec<u32>, _>>()?;
    let mut q: Vec<QBox> = boxes.par_iter().map(|x| grid.quantize(x)).collect();
    // Parents come before children (checked in pass 1).
    clamp_into(&mut q[0], &root_pq);
    if root_parent == u32::MAX {
        q[0] = root_pq;
    }
    for j in 1..n {
        let pq = q[(parent[j] - start) as usize];
        clamp_into(&mut q[j], &pq);
    }
    Ok(Seg {
        start,
        parent,
        node,
        q,
        ids,
    })
}

/// The nodes the clusters being coded can ask for: the chunks they span,
/// and the tree over the chunks.
struct Window<'a> {
    top: &'a [TopNode],
    segs: VecDeque<Seg>,
}

/// Where a node is.
enum At<'a> {
    Seg(&'a Seg, usize),
    Top(&'a TopNode),
}

impl Window<'_> {
    fn at(&self, g: usize) -> At<'_> {
        let k = self.segs.partition_point(|s| s.start as usize <= g);
        if k > 0 {
            let s = &self.segs[k - 1];
            let j = g - s.start as usize;
            if j < s.parent.len() {
                return At::Seg(s, j);
            }
        }
        let t = self.top.partition_point(|t| (t.g as usize) < g);
        match self.top.get(t) {
            Some(t) if t.g as usize == g => At::Top(t),
            _ => panic!("racbvh stream: node {g} asked for outside the window (a bug)"),
        }
    }
}

impl TreeSource for Window<'_> {
    fn parent(&self, g: usize) -> usize {
        match self.at(g) {
            At::Seg(s, j) => s.parent[j] as usize,
            At::Top(t) => t.parent as usize,
        }
    }

    fn children(&self, g: usize) -> Option<[u32; 2]> {
        match self.at(g) {
            At::Seg(s, j) => (s.node[j][1] & LEAF_FLAG == 0).then_some(s.node[j]),
            At::Top(t) => Some(t.children),
        }
    }

    fn leaf_ids(&self, g: usize) -> &[u32] {
        match self.at(g) {
            At::Seg(s, j) => {
                let [a, b] = s.node[j];
                let first = a as usize;
                &s.ids[first..first + (b & !LEAF_FLAG) as usize]
            }
            At::Top(_) => &[],
        }
    }

    fn qbox(&self, g: usize) -> &QBox {
        match self.at(g) {
            At::Seg(s, j) => &s.q[j],
            At::Top(t) => &t.q,
        }
    }
}

/// A packed array on disk: its prefix and heads in memory, its offsets
/// in a file.
struct Packed {
    prefix: [u8; 16],
    heads: Vec<u8>,
    path: PathBuf,
    data_len: u64,
}

impl Packed {
    fn of(p: ForPieces<BufWriter<File>>, path: PathBuf) -> Result<Self, RacError> {
        drop(p.out);
        let data_len = std::fs::metadata(&path).map_err(io(&path))?.len();
        Ok(Self {
            prefix: p.prefix,
            heads: p.heads,
            path,
            data_len,
        })
    }

    fn len(&self) -> u64 {
        16 + self.heads.len() as u64 + self.data_len
    }
}

/// The xxh3-64 of the arrays back to back.
fn hash_packed(arrays: &[Packed]) -> Result<u64, RacError> {
    let mut h = Xxh3::new();
    for p in arrays {
        h.update(&p.prefix);
        h.update(&p.heads);
        copy_file(&p.path, &mut |b| {
            h.update(b);
            Ok(())
        })?;
    }
    Ok(h.digest())
}

/// Calls `f` with the bytes of `path`, a block at a time.
fn copy_file(
    path: &Path,
    f: &mut dyn FnMut(&[u8]) -> Result<(), RacError>,
) -> Result<(), RacError> {
    let mut r = File::open(path).map_err(io(path))?;
    let mut block = vec![0u8; 1 << 20];
    loop {
        let got = r.read(&mut block).map_err(io(path))?;
        if got == 0 {
            return Ok(());
        }
        f(&block[..got])?;
    }
}

/// A buffered temporary file.
fn create(path: &Path) -> Result<BufWriter<File>, RacError> {
    Ok(BufWriter::with_capacity(
        1 << 20,
        File::create(path).map_err(io(path))?,
    ))
}

/// An I/O error on `path` as a [`RacError`].
fn io(path: &Path) -> impl Fn(std::io::Error) -> RacError + '_ {
    move |e| IoError::new(path, e).into()
}
