//! The out-of-core o-HCCMesh builder: a model split into chunks on disk
//! ([`ChunkedMesh`]) in, an o-HCCMesh file out, with peak memory set by
//! the chunk size, not by the model (HCCMesh §5's construction of St.
//! Matthew).
//!
//! # How
//!
//! The file is the one [`encode`](super::encode) writes for a model whose
//! canonical tree is the tree over the chunks with each chunk's own tree
//! under its leaf; nothing in the format changes, and the reader cannot
//! tell. Two passes over the chunks, one at a time:
//!
//! 1. **Build.** Each chunk's canonical tree ([`build`]) and its
//!    i-HCCMesh, quantized on the grid of the *whole* model's bounds
//!    (known from its vertices, which the [`ChunkedMesh`] holds), so that
//!    every chunk's trees are on one grid. The chunk's symbols are counted
//!    for the dictionaries, its edge flags computed alone (its open edges
//!    kept for pairing), its mass summed ([`MassAccumulator`]), and its
//!    i-HCCMesh written to a temporary file (about 6.4 bytes a triangle;
//!    the tree and the boxes are dropped).
//! 2. **Code.** The dictionaries from the summed counts (one for the
//!    whole file, as the format has it); each chunk's i-HCCMesh read back
//!    and its trees coded into the streams, which go to a temporary file
//!    hashed as they are written.
//!
//! Then the high-level tree: the tree over the chunks, its boxes the
//! unions of the chunks' root boxes, with each chunk's high-level tree
//! under its leaf, numbered depth-first as the i-HCCMesh encoder numbers
//! nodes; the edge flags with the open edges paired across chunks
//! ([`EdgeFlags::resolve_open`](crate::contact::EdgeFlags::resolve_open));
//! the header; and the file is written under a temporary name beside the
//! output and renamed over it at the end ([`AtomicFile`]).
//!
//! What stays in memory besides one chunk's build: the model's vertices
//! (12 bytes each), the edge flags (a byte a triangle), a bit a vertex,
//! the chunks' high-level trees (a few bytes a triangle over 600), the
//! dictionaries' counts and the chunks' open edges.
//!
//! # Scope
//! Tree order and no vertex ids (the paper's form, the default): the id
//! maps would have to be merged across chunks and are refused. The file
//! is the same whatever the number of threads (the builder's tree is, the
//! chunks are, every sum is in chunk order).

use std::io::{Read, Write};
use std::path::{Path, PathBuf};

use xxhash_rust::xxh3::{Xxh3, xxh3_64};

use super::super::HccBvh;
use super::super::node::{HIGH_LEAF, HighNode, MAX_TREES};
use super::super::vertices::Quantized;
use super::OocError;
use super::OocOptions;
use super::encode::{
    OocSizes, StreamCoder, SymbolCounts, high_boxes, high_shape, stream_offset, tree_columns,
};
use super::file::{self, Header, SECTIONS};
use crate::build::chunked::{ChunkNode, ChunkScratch, ChunkedMesh};
use crate::build::{BuildOptions, build};
use crate::codec::StreamedReport;
use crate::codec::common::edges::{self, ChunkedFlags};
use crate::codec::common::{MassAccumulator, mass::vertex_mean};
use crate::files::{AtomicFile, IoError};

pub use crate::build::chunked::Progress;

/// What one chunk left after pass 1.
struct Chunk {
    high: Vec<HighNode>,
    /// Per tree: triangles, stored vertices.
    trees: Vec<(u32, u32)>,
    node_words: u64,
    interconnections: u64,
    file: PathBuf,
}

/// What [`encode_streamed`] made.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct StreamedBuild {
    /// The file's bytes by part.
    pub sizes: OocSizes,
    /// Chunks built.
    pub chunks: usize,
    /// The largest chunk's triangles.
    pub largest_chunk: u64,
    /// Low-level trees.
    pub trees: usize,
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
            counts: vec![("trees", self.trees as u64)],
            parts: self.sizes.parts(),
        }
    }
}

/// Builds the o-HCCMesh of `input` chunk by chunk (see the module docs)
/// with the builder's `build_options` and the codec's `options`, and
/// writes it to `out` (atomically: on error nothing is left under that
/// name). Temporary files go to `input`'s temporary directory.
/// `progress` hears the phases `building` (triangles), `coding`
/// (triangles) and `writing` (bytes).
///
/// # Errors
/// [`OocError::OutOfCore`] for options the out-of-core build cannot keep
/// (id maps) or a chunk the builder refuses, the i-HCCMesh encoder's and
/// the coder's errors (a limit of the format), and I/O errors.
pub fn encode_streamed(
    input: &ChunkedMesh,
    build_options: &BuildOptions,
    options: &OocOptions,
    out: &Path,
    progress: Progress<'_>,
) -> Result<StreamedBuild, OocError> {
    if options.triangle_ids || options.vertex_ids {
        return Err(OocError::OutOfCore(
            "the out-of-core build writes the paper's form, tree order without id maps: \
             turn off hcc-ooc.triangle-ids and hcc-ooc.vertex-ids"
                .into(),
        ));
    }
    let hcc_options = options.hcc();
    let mut out_file = AtomicFile::create(out).map_err(io(out))?;
    let vertices = &input.vertices;
    let (lo, hi) = bounds(vertices);
    let mut grid = Quantized::grid(options.vertex_bits, lo, hi);
    grid.error = quantization_error(&grid, vertices);
    let total = input.triangle_count();
    let temp = input.temp_dir();

    // Pass 1: build, count, flag, sum.
    let mut counts = SymbolCounts::new();
    let mut mass = MassAccumulator::new(vertex_mean(vertices));
    let mut flags = ChunkedFlags::with_capacity(total as usize);
    let mut used = vec![0u64; vertices.len().div_ceil(64)];
    let mut chunks: Vec<Chunk> = Vec::with_capacity(input.chunk_count());
    let mut scratch = ChunkScratch::default();
    let mut multi = false;
    let mut done = 0u64;
    for c in 0..input.chunk_count() {
        let (mesh, global) = input
            .chunk(c, &mut scratch)
            .map_err(|e| OocError::OutOfCore(e.to_string()))?;
        for &g in &global {
            used[g as usize / 64] |= 1 << (g % 64);
        }
        drop(global);
        for t in &mesh.triangles {
            let p = t.map(|v| mesh.vertices[v as usize]);
            mass.add(p[0], p[1], p[2]);
        }
        let n = mesh.triangles.len() as u64;
        let bvh = build(&mesh, build_options, &|d, t| {
            // The builder reports its leaves, then its layout.
            let at = done + (u128::from(n) * u128::from(d.min(t)) / u128::from(t.max(1))) as u64;
            progress("building", at, total);
        })
        .map_err(|e| OocError::OutOfCore(format!("chunk {c}: {e}")))?;
        let mut hcc = HccBvh::encode_part(&bvh, &mesh, &hcc_options, Some((lo, hi)))?;
        drop((bvh, mesh));
        multi |= hcc.multi;
        let q = hcc.vertices.quantized().ok_or(OocError::NotQuantized)?;
        counts.add(&hcc, q)?;
        let (f, o) = edges::of_cursor_open(&hcc);
        flags.push(&f, o);
        // The chunk's file needs its flags (pass 2 reads them back and
        // drops them).
        hcc.edges = f;
        let trees = (0..hcc.headers.len())
            .map(|k| {
                let h = hcc.headers[k];
                let next = hcc.headers.get(k + 1);
                let tris = next.map_or(hcc.triangle_count, |n| n.first_triangle) - h.first_triangle;
                let verts = next.map_or(hcc.stats.tree_vertices as u32, |n| n.vertex_start)
                    - h.vertex_start;
                (tris, verts)
            })
            .collect();
        let file = temp.join(format!("chunk-{c}.hcc"));
        std::fs::write(&file, hcc.to_bytes()).map_err(io(&file))?;
        chunks.push(Chunk {
            high: hcc.high.clone(),
            trees,
            node_words: hcc.nodes.len() as u64,
            interconnections: hcc.ics.len() as u64,
            file,
        });
        done += n;
        progress("building", done, total);
    }

    // Pass 2: the streams, through the whole file's dictionaries.
    let (dicts, dict_bytes) = counts.dictionaries();
    drop(counts);
    let mut coder = StreamCoder::new(&dicts);
    let streams_path = temp.join("streams.bin");
    let mut streams = std::io::BufWriter::with_capacity(
        1 << 20,
        std::fs::File::create(&streams_path).map_err(io(&streams_path))?,
    );
    let mut hasher = Xxh3::new();
    let mut starts: Vec<u32> = Vec::new();
    let (mut at, mut buf, mut coded) = (0u64, Vec::new(), 0u64);
    for chunk in &chunks {
        let bytes = std::fs::read(&chunk.file).map_err(io(&chunk.file))?;
        let hcc = HccBvh::from_bytes(&bytes)?;
        drop(bytes);
        std::fs::remove_file(&chunk.file).ok();
        let q = hcc.vertices.quantized().ok_or(OocError::NotQuantized)?;
        for k in 0..hcc.headers.len() {
            starts.push(stream_offset(at, starts.len())?);
            buf.clear();
            coder.tree(&hcc, q, k, &mut buf)?;
            streams.write_all(&buf).map_err(io(&streams_path))?;
            hasher.update(&buf);
            at += buf.len() as u64;
        }
        coded += u64::from(hcc.triangle_count);
        progress("coding", coded, total);
    }
    let trees: usize = starts.len();
    starts.push(stream_offset(at, trees)?);
    streams.flush().map_err(io(&streams_path))?;
    drop(streams);
    if trees > MAX_TREES {
        return Err(OocError::OutOfCore(format!(
            "{trees} low-level trees: more than the {MAX_TREES} the format numbers"
        )));
    }

    // The high-level tree over the chunks'.
    let tree_base: Vec<u32> = chunks
        .iter()
        .scan(0u32, |n, c| {
            let b = *n;
            *n += c.trees.len() as u32;
            Some(b)
        })
        .collect();
    let high = join_high(input.top(), &chunks, &tree_base);
    let high_bytes = high_shape(&high, trees)?;
    let boxes = high_boxes(&high, &grid)?;
    let starts_bytes = tree_columns(&[&starts]);
    let (mut first_tri, mut first_vert) = (vec![0u32], vec![0u32]);
    for &(t, v) in chunks.iter().flat_map(|c| &c.trees) {
        let (lt, lv) = (
            *first_tri.last().unwrap_or(&0),
            *first_vert.last().unwrap_or(&0),
        );
        first_tri.push(lt + t);
        first_vert.push(
            lv.checked_add(v)
                .ok_or_else(|| OocError::OutOfCore("more than 2^32 stored vertices".into()))?,
        );
    }
    let firsts = tree_columns(&[&first_tri, &first_vert]);
    let (edge_flags, paired_edges) = flags.joined().ok_or(OocError::Corrupt {
        tree: u32::MAX,
        what: "edge flags out of range",
    })?;
    let flag_bytes = edges::encode(&edge_flags);
    drop(edge_flags);
    let node_words: u64 = chunks.iter().map(|c| c.node_words).sum();
    let interconnections: u64 = chunks.iter().map(|c| c.interconnections).sum();
    let count = |n: u64, what: &str| {
        u32::try_from(n).map_err(|_| OocError::OutOfCore(format!("{n} {what}: more than 2^32")))
    };
    let header = Header {
        multi,
        vertex_ids: false,
        tree_order: true,
        high_nodes: count(high.len() as u64, "high-level nodes")?,
        trees: trees as u32,
        node_words: count(node_words, "node words")?,
        interconnections: count(interconnections, "inter-connections")?,
        stored_vertices: *first_vert.last().unwrap_or(&0),
        triangles: count(total, "triangles")?,
        mesh_vertices: count(vertices.len() as u64, "vertices")?,
        used_vertices: used.iter().map(|w| w.count_ones()).sum(),
        bits: grid.bits,
        grid: [grid.origin, grid.step, grid.error],
        mass: mass.finish(),
    };
    let streams_len = at;
    let sections: [(&[u8], Option<u64>); SECTIONS] = [
        (&dict_bytes, None),
        (&high_bytes, None),
        (&starts_bytes, None),
        (&[], Some(hasher.digest())),
        (&[], None),
        (&[], None),
        (&boxes, None),
        (&firsts, None),
        (&flag_bytes, None),
    ];
    let table: [(u64, u64); SECTIONS] = std::array::from_fn(|k| match sections[k] {
        (_, Some(h)) => (streams_len, h),
        (b, None) => (b.len() as u64, xxh3_64(b)),
    });
    let head = file::header(&header, &table);
    let written = head.len() as u64 + table.iter().map(|t| t.0).sum::<u64>();
    let put = |b: &[u8], w: &mut AtomicFile| w.write_all(b).map_err(io(out));
    put(&head, &mut out_file)?;
    let mut so_far = head.len() as u64;
    for (b, streamed) in &sections {
        if streamed.is_some() {
            let mut f = std::fs::File::open(&streams_path).map_err(io(&streams_path))?;
            let mut block = vec![0u8; 1 << 20];
            loop {
                let got = f.read(&mut block).map_err(io(&streams_path))?;
                if got == 0 {
                    break;
                }
                put(&block[..got], &mut out_file)?;
                so_far += got as u64;
                progress("writing", so_far, written);
            }
        } else {
            put(b, &mut out_file)?;
            so_far += b.len() as u64;
        }
    }
    out_file.commit().map_err(io(out))?;
    std::fs::remove_file(&streams_path).ok();
    progress("writing", written, written);
    let sizes = OocSizes::from_sections(&table.map(|t| t.0), &coder.part_bits);
    Ok(StreamedBuild {
        sizes,
        chunks: chunks.len(),
        largest_chunk: (0..input.chunk_count())
            .map(|c| input.chunk_len(c))
            .max()
            .unwrap_or(0),
        trees,
        paired_edges,
    })
}

/// An I/O error on `path` as an [`OocError`].
fn io(path: &Path) -> impl Fn(std::io::Error) -> OocError + '_ {
    move |e| IoError::new(path, e).into()
}

/// The model's high-level tree: the tree over the chunks, each chunk's
/// high-level tree under its leaf, allocated as the i-HCCMesh encoder
/// allocates (depth-first, a node's two children side by side), trees
/// numbered chunk by chunk.
fn join_high(top: &[ChunkNode], chunks: &[Chunk], tree_base: &[u32]) -> Vec<HighNode> {
    #[derive(Clone, Copy)]
    enum At {
        Top(u32),
        Chunk(u32, u32),
    }
    // The top nodes' boxes, children after parents.
    let mut boxes = vec![([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]); top.len()];
    for i in (0..top.len()).rev() {
        boxes[i] = match top[i] {
            ChunkNode::Leaf { chunk } => {
                let r = &chunks[chunk as usize].high[0];
                (r.min, r.max)
            }
            ChunkNode::Inner { children, .. } => {
                let (a, b) = (boxes[children[0] as usize], boxes[children[1] as usize]);
                (
                    std::array::from_fn(|k| a.0[k].min(b.0[k])),
                    std::array::from_fn(|k| a.1[k].max(b.1[k])),
                )
            }
        };
    }
    let zero = HighNode {
        min: [0.0; 3],
        max: [0.0; 3],
        a: 0,
        b: 0,
    };
    let mut high = Vec::new();
    if top.is_empty() {
        return high;
    }
    high.push(zero);
    let mut stack = vec![(At::Top(0), 0usize)];
    while let Some((at, slot)) = stack.pop() {
        let at = match at {
            At::Top(i) => match top[i as usize] {
                ChunkNode::Leaf { chunk } => At::Chunk(chunk, 0),
                ChunkNode::Inner { children, .. } => {
                    let first = high.len();
                    high.extend([zero, zero]);
                    let (min, max) = boxes[i as usize];
                    high[slot] = HighNode {
                        min,
                        max,
                        a: first as u32,
                        b: first as u32 + 1,
                    };
                    stack.push((At::Top(children[1]), first + 1));
                    stack.push((At::Top(children[0]), first));
                    continue;
                }
            },
            at => at,
        };
        let At::Chunk(c, j) = at else { continue };
        let n = chunks[c as usize].high[j as usize];
        if n.is_leaf() {
            high[slot] = HighNode {
                a: tree_base[c as usize] + n.a,
                b: HIGH_LEAF,
                ..n
            };
        } else {
            let first = high.len();
            high.extend([zero, zero]);
            high[slot] = HighNode {
                a: first as u32,
                b: first as u32 + 1,
                ..n
            };
            stack.push((At::Chunk(c, n.b), first + 1));
            stack.push((At::Chunk(c, n.a), first));
        }
    }
    high
}

/// The bounds of `v` (zeros for none).
fn bounds(v: &[[f32; 3]]) -> ([f32; 3], [f32; 3]) {
    let Some(&first) = v.first() else {
        return ([0.0; 3], [0.0; 3]);
    };
    let (mut lo, mut hi) = (first, first);
    for p in v {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}

/// The largest distance per axis between a vertex and its grid point, as
/// the in-memory encoder measures it.
fn quantization_error(q: &Quantized, v: &[[f32; 3]]) -> [f32; 3] {
    let mut error = [0f32; 3];
    for p in v {
        for a in 0..3 {
            let g = q.nearest(a, p[a]);
            error[a] = error[a].max((q.value(a, g) - p[a]).abs());
        }
    }
    error
}
