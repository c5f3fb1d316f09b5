//! A model larger than memory, split into spatial chunks on disk: the
//! first half of the out-of-core builder, which knows no codec.
//!
//! [`ChunkedMesh`] reads a mesh file's triangles as they are parsed
//! ([`crate::mesh::stream`]), never holding them all, and leaves them on
//! disk grouped by chunk, each chunk small enough to build in memory with
//! the ordinary builder. A codec's out-of-core encoder (o-HCCMesh's
//! [`encode_streamed`](crate::codec::hcc::ooc::encode_streamed),
//! RACBVH's [`encode_streamed`](crate::codec::racbvh::encode_streamed))
//! then builds each chunk's trees in turn ([`ChunkedMesh::chunk`] gives
//! it as a small [`Mesh`]) and joins them under the tree of the chunks
//! ([`ChunkedMesh::top`]).
//!
//! # How
//!
//! 1. **Read.** The triangles go to a temporary file (12 bytes each) as
//!    the reader hands them out; every `s`-th one is kept as a sample,
//!    `s` doubling whenever the sample reaches 2²⁰ triangles. The vertices
//!    stay in memory (12 bytes each: about 6 bytes a triangle for a closed
//!    mesh, whose vertices number half its triangles).
//! 2. **Partition.** Median splits of the sample's centroids, on the
//!    longest axis of each node's centroid bounds, until a node's share of
//!    the triangles is at most the chunk size: a k-d tree whose leaves are
//!    the chunks, numbered depth-first, left first. A triangle belongs to
//!    the leaf its centroid falls in (a centroid equal to a split goes
//!    right). Near the root this is the split a top-down SAH build makes
//!    on a large node anyway (the SAH and the median agree to a few
//!    percent on a finely tessellated surface); the quality measurement
//!    is in the note.
//! 3. **Group.** Two passes over the temporary file: one counts each
//!    chunk's triangles, the other writes each triangle to its chunk's
//!    range of a second file through a buffer per chunk. Chunks left empty
//!    (a sample is not the whole) are pruned from the tree.
//!
//! Everything is deterministic: the same file and chunk size give the same
//! chunks, each holding its triangles in file order, whatever the threads.
//! A chunk is built from [`ChunkedMesh::chunk`] with its own vertex
//! numbering (by first use) and the map back to the file's.
//!
//! The temporary files live in a directory the caller names
//! ([`ChunkOptions::temp_dir`]), created here and removed with the
//! [`ChunkedMesh`] (or on any error); a process killed half way leaves it
//! behind, which is why the command-line builder puts it beside its
//! output under a name that says what it is, and reports one it finds.

use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use crate::files::IoError;
use crate::mesh::{Mesh, MeshError};

/// Triangles in the partition's sample, at most.
const SAMPLE: usize = 1 << 20;

/// Bytes of a stored triangle.
const TRI_BYTES: usize = 12;

/// Bytes of chunk buffers while grouping, at most (each at least 4 KiB).
const GROUP_BUFFERS: usize = 64 << 20;

/// How a [`ChunkedMesh`] splits its model.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ChunkOptions {
    /// The most triangles a chunk should hold (the partition aims at this
    /// from a sample, so a chunk may exceed it by a few percent; a chunk
    /// whose centroids all coincide cannot be split at all).
    pub chunk_triangles: u64,
    /// A directory for the temporary files, created and removed when
    /// done; it must not exist yet (so that nothing of the caller's is
    /// ever removed), and its parent must (it is never created: a missing
    /// directory is an error, not a tree of new ones).
    pub temp_dir: PathBuf,
}

/// What stops a [`ChunkedMesh`].
#[derive(Debug, thiserror::Error)]
pub enum ChunkError {
    /// The input mesh file.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// A temporary file.
    #[error(transparent)]
    Io(#[from] IoError),
    /// The temporary directory exists already.
    #[error(
        "{0}: the temporary directory exists already (left by a build that was killed? remove it)"
    )]
    TempExists(PathBuf),
    /// More triangles than 32-bit ids can number.
    #[error("{0} triangles: more than the 2^32 − 1 that 32-bit triangle ids can number")]
    TooManyTriangles(u64),
    /// A face names a vertex that does not exist.
    #[error("triangle {triangle} names vertex {vertex}, and the mesh has {vertices} vertices")]
    BadIndex {
        /// The triangle (file order).
        triangle: u64,
        /// The vertex it names.
        vertex: u32,
        /// Vertices in the mesh.
        vertices: usize,
    },
}

/// A node of the tree over the chunks (see the module docs): node 0 is
/// the root, children come after their parent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ChunkNode {
    /// Split on `axis` at `at`: centroids below go to `children[0]`.
    Inner {
        /// 0, 1 or 2.
        axis: u8,
        /// The split coordinate (of a centroid's three-corner sum).
        at: f32,
        /// The two children.
        children: [u32; 2],
    },
    /// Chunk `chunk` (chunks are numbered depth-first, left first).
    Leaf {
        /// The chunk.
        chunk: u32,
    },
}

/// Removes the temporary directory when dropped.
#[derive(Debug)]
struct TempDir(PathBuf);

impl Drop for TempDir {
    fn drop(&mut self) {
        std::fs::remove_dir_all(&self.0).ok();
    }
}

/// Per-chunk scratch for [`ChunkedMesh::chunk`]: the file's vertex →
/// the chunk's, reused from chunk to chunk (4 bytes a vertex).
#[derive(Debug, Default)]
pub struct ChunkScratch {
    local_of: Vec<u32>,
}

/// A model split into chunks on disk (see the module docs).
#[derive(Debug)]
pub struct ChunkedMesh {
    /// Every vertex of the model.
    pub vertices: Vec<[f32; 3]>,
    triangles: u64,
    nodes: Vec<ChunkNode>,
    /// Per chunk, its first triangle in the chunk file and its count.
    chunks: Vec<(u64, u64)>,
    file: PathBuf,
    _dir: TempDir,
}

/// What the progress callback hears: a phase name, work done, work in
/// all (0 when not known).
pub type Progress<'a> = &'a (dyn Fn(&str, u64, u64) + Sync);

impl ChunkedMesh {
    /// Reads the mesh file at `path` into chunks (see the module docs),
    /// calling `progress` as it goes (phases `reading`, `grouping`).
    ///
    /// # Errors
    /// The file's [`MeshError`] (with the line or byte it is at), a
    /// temporary file's I/O error, more than 2³² − 1 triangles, and a
    /// `temp_dir` that exists already.
    pub fn from_path(
        path: &Path,
        opts: &ChunkOptions,
        progress: Progress<'_>,
    ) -> Result<Self, ChunkError> {
        Self::read(opts, progress, |take| {
            Ok(crate::mesh::stream(path, take)?.vertices)
        })
    }

    /// Splits a mesh in memory into chunks as [`from_path`](Self::from_path)
    /// splits a file: the same chunks as from a file holding `mesh`. For
    /// tests, and for generated models.
    ///
    /// # Errors
    /// As [`from_path`](Self::from_path), but for the file's.
    pub fn from_mesh(
        mesh: &Mesh,
        opts: &ChunkOptions,
        progress: Progress<'_>,
    ) -> Result<Self, ChunkError> {
        Self::read(opts, progress, |take| {
            for batch in mesh.triangles.chunks(1 << 16) {
                take(batch)?;
            }
            Ok(mesh.vertices.clone())
        })
    }

    /// The triangles `source` hands to its argument, batch by batch, to
    /// the temporary file and the sample; `source` returns the vertices.
    /// Then the partition.
    fn read(
        opts: &ChunkOptions,
        progress: Progress<'_>,
        source: impl FnOnce(crate::mesh::TriangleBatches<'_>) -> Result<Vec<[f32; 3]>, ChunkError>,
    ) -> Result<Self, ChunkError> {
        let dir = make_dir(&opts.temp_dir)?;
        let faces = dir.0.join("faces.bin");
        let mut w = Writer::create(&faces)?;
        let mut sample = Sample::default();
        let vertices = source(&mut |batch| {
            sample.add(batch);
            w.triangles(batch)
                .map_err(|source| MeshError::from(IoError::new(&faces, source)))?;
            progress("reading", sample.seen, 0);
            Ok(())
        })?;
        w.finish()?;
        Self::partition(dir, faces, vertices, sample, opts, progress)
    }

    fn partition(
        dir: TempDir,
        faces: PathBuf,
        vertices: Vec<[f32; 3]>,
        sample: Sample,
        opts: &ChunkOptions,
        progress: Progress<'_>,
    ) -> Result<Self, ChunkError> {
        let total = sample.seen;
        if total > u64::from(u32::MAX) {
            return Err(ChunkError::TooManyTriangles(total));
        }
        let nv = vertices.len();
        let centroid = |t: &[u32; 3]| -> Option<[f32; 3]> {
            let mut c = [0f32; 3];
            for &v in t {
                let p = vertices.get(v as usize)?;
                for k in 0..3 {
                    c[k] += p[k];
                }
            }
            Some(c)
        };
        let mut cents = Vec::with_capacity(sample.tris.len());
        for (i, t) in sample.tris.iter().enumerate() {
            let c = centroid(t).ok_or_else(|| ChunkError::BadIndex {
                triangle: i as u64 * sample.stride,
                vertex: t.iter().copied().max().unwrap_or(0),
                vertices: nv,
            })?;
            cents.push(c);
        }
        drop(sample);
        let kd = split(&mut cents, total, opts.chunk_triangles.max(1));
        let leaves = kd
            .iter()
            .filter(|n| matches!(n, ChunkNode::Leaf { .. }))
            .count();
        // Pass 1: each leaf's triangles.
        let mut counts = vec![0u64; leaves];
        let mut seen = 0u64;
        read_triangles(&faces, &mut |batch| {
            for t in batch {
                let c = centroid(t).ok_or_else(|| ChunkError::BadIndex {
                    triangle: seen,
                    vertex: t.iter().copied().max().unwrap_or(0),
                    vertices: nv,
                })?;
                counts[leaf_of(&kd, c) as usize] += 1;
                seen += 1;
            }
            progress("grouping", seen, 2 * total);
            Ok(())
        })?;
        // Empty leaves pruned; the rest renumbered depth-first.
        let (nodes, chunk_of) = prune(&kd, &counts);
        let mut chunks = Vec::new();
        let mut at = 0u64;
        for (leaf, &n) in counts.iter().enumerate() {
            if chunk_of[leaf] != u32::MAX {
                debug_assert_eq!(chunk_of[leaf] as usize, chunks.len());
                chunks.push((at, n));
                at += n;
            }
        }
        // Pass 2: each triangle to its chunk's range.
        let file = dir.0.join("chunks.bin");
        let io = IoError::at;
        let mut out = File::create(&file).map_err(io(&file))?;
        out.set_len(total * TRI_BYTES as u64).map_err(io(&file))?;
        let cap = (GROUP_BUFFERS / chunks.len().max(1)).max(4096) / TRI_BYTES * TRI_BYTES;
        let mut bufs: Vec<Vec<u8>> = vec![Vec::new(); chunks.len()];
        let mut next: Vec<u64> = chunks.iter().map(|c| c.0).collect();
        let flush = |out: &mut File, buf: &mut Vec<u8>, next: &mut u64| {
            out.seek(SeekFrom::Start(*next * TRI_BYTES as u64))?;
            out.write_all(buf)?;
            *next += (buf.len() / TRI_BYTES) as u64;
            buf.clear();
            Ok::<(), std::io::Error>(())
        };
        let mut done = 0u64;
        read_triangles(&faces, &mut |batch| {
            for t in batch {
                // Pass 1 checked every index.
                let c = centroid(t).unwrap_or_default();
                let k = chunk_of[leaf_of(&kd, c) as usize] as usize;
                let buf = &mut bufs[k];
                for v in t {
                    buf.extend_from_slice(&v.to_le_bytes());
                }
                if buf.len() >= cap {
                    flush(&mut out, buf, &mut next[k]).map_err(io(&file))?;
                }
            }
            done += batch.len() as u64;
            progress("grouping", total + done, 2 * total);
            Ok(())
        })?;
        for (k, buf) in bufs.iter_mut().enumerate() {
            flush(&mut out, buf, &mut next[k]).map_err(io(&file))?;
        }
        out.sync_all().ok();
        drop(out);
        std::fs::remove_file(&faces).ok();
        Ok(Self {
            vertices,
            triangles: total,
            nodes,
            chunks,
            file,
            _dir: dir,
        })
    }

    /// The temporary directory (removed with `self`), where an encoder
    /// may put its own temporary files.
    pub fn temp_dir(&self) -> &Path {
        &self._dir.0
    }

    /// Triangles in the model.
    pub fn triangle_count(&self) -> u64 {
        self.triangles
    }

    /// Chunks (none for a model without triangles).
    pub fn chunk_count(&self) -> usize {
        self.chunks.len()
    }

    /// Triangles of chunk `c`.
    pub fn chunk_len(&self, c: usize) -> u64 {
        self.chunks[c].1
    }

    /// The tree over the chunks: node 0 the root, each chunk one leaf,
    /// chunks numbered in the depth-first order of the leaves. Empty for
    /// a model without triangles.
    pub fn top(&self) -> &[ChunkNode] {
        &self.nodes
    }

    /// Chunk `c` as a mesh of its own (vertices numbered by first use)
    /// and each of its vertices' index in the model.
    ///
    /// # Errors
    /// The chunk file's I/O error.
    pub fn chunk(
        &self,
        c: usize,
        scratch: &mut ChunkScratch,
    ) -> Result<(Mesh, Vec<u32>), ChunkError> {
        let (first, n) = self.chunks[c];
        let io = |source| ChunkError::Io(IoError::new(&self.file, source));
        let mut f = File::open(&self.file).map_err(io)?;
        f.seek(SeekFrom::Start(first * TRI_BYTES as u64))
            .map_err(io)?;
        let mut bytes = vec![0u8; n as usize * TRI_BYTES];
        f.read_exact(&mut bytes).map_err(io)?;
        if scratch.local_of.len() != self.vertices.len() {
            scratch.local_of = vec![u32::MAX; self.vertices.len()];
        }
        let mut global = Vec::new();
        let mut vertices = Vec::new();
        let triangles: Vec<[u32; 3]> = bytes
            .chunks_exact(TRI_BYTES)
            .map(|b| {
                std::array::from_fn(|k| {
                    let g =
                        u32::from_le_bytes([b[4 * k], b[4 * k + 1], b[4 * k + 2], b[4 * k + 3]]);
                    let slot = &mut scratch.local_of[g as usize];
                    if *slot == u32::MAX {
                        *slot = global.len() as u32;
                        global.push(g);
                        vertices.push(self.vertices[g as usize]);
                    }
                    *slot
                })
            })
            .collect();
        for &g in &global {
            scratch.local_of[g as usize] = u32::MAX;
        }
        Ok((Mesh::new(vertices, triangles), global))
    }
}

fn make_dir(dir: &Path) -> Result<TempDir, ChunkError> {
    if dir.exists() {
        return Err(ChunkError::TempExists(dir.to_path_buf()));
    }
    // Not create_dir_all: a build must not make the directories of a
    // mistyped output path and report success.
    std::fs::create_dir(dir).map_err(|source| ChunkError::Io(IoError::new(dir, source)))?;
    Ok(TempDir(dir.to_path_buf()))
}

/// Every `stride`-th triangle read.
#[derive(Debug)]
struct Sample {
    tris: Vec<[u32; 3]>,
    stride: u64,
    seen: u64,
}

impl Default for Sample {
    fn default() -> Self {
        Self {
            tris: Vec::new(),
            stride: 1,
            seen: 0,
        }
    }
}

impl Sample {
    fn add(&mut self, batch: &[[u32; 3]]) {
        for t in batch {
            if self.seen.is_multiple_of(self.stride) {
                if self.tris.len() == SAMPLE {
                    // Keep every other one: those at multiples of the
                    // doubled stride.
                    let mut k = 0;
                    self.tris.retain(|_| {
                        k += 1;
                        k % 2 == 1
                    });
                    self.stride *= 2;
                }
                if self.seen.is_multiple_of(self.stride) {
                    self.tris.push(*t);
                }
            }
            self.seen += 1;
        }
    }
}

/// Buffered writes of triangles, 12 little-endian bytes each.
struct Writer {
    out: BufWriter<File>,
    path: PathBuf,
}

impl Writer {
    fn create(path: &Path) -> Result<Self, ChunkError> {
        let f = File::create(path).map_err(|source| ChunkError::Io(IoError::new(path, source)))?;
        Ok(Self {
            out: BufWriter::with_capacity(1 << 20, f),
            path: path.to_path_buf(),
        })
    }

    fn triangles(&mut self, batch: &[[u32; 3]]) -> std::io::Result<()> {
        for t in batch {
            for v in t {
                self.out.write_all(&v.to_le_bytes())?;
            }
        }
        Ok(())
    }

    fn finish(mut self) -> Result<(), ChunkError> {
        self.out
            .flush()
            .map_err(|source| ChunkError::Io(IoError::new(&self.path, source)))
    }
}

/// What [`read_triangles`] calls with each batch.
type Batches<'a> = &'a mut dyn FnMut(&[[u32; 3]]) -> Result<(), ChunkError>;

/// Calls `f` with the triangles of `path`, in batches.
fn read_triangles(path: &Path, f: Batches<'_>) -> Result<(), ChunkError> {
    let io = |source| ChunkError::Io(IoError::new(path, source));
    let mut r = BufReader::with_capacity(1 << 20, File::open(path).map_err(io)?);
    let mut bytes = vec![0u8; TRI_BYTES << 16];
    let mut batch = Vec::with_capacity(1 << 16);
    loop {
        let mut got = 0;
        while got < bytes.len() {
            let n = r.read(&mut bytes[got..]).map_err(io)?;
            if n == 0 {
                break;
            }
            got += n;
        }
        batch.clear();
        batch.extend(
            bytes[..got - got % TRI_BYTES]
                .chunks_exact(TRI_BYTES)
                .map(|b| {
                    std::array::from_fn(|k| {
                        u32::from_le_bytes([b[4 * k], b[4 * k + 1], b[4 * k + 2], b[4 * k + 3]])
                    })
                }),
        );
        if !batch.is_empty() {
            f(&batch)?;
        }
        if got < bytes.len() {
            return Ok(());
        }
    }
}

/// The k-d tree over the sample's centroids (see the module docs), for
/// `total` triangles in chunks of at most `chunk`.
fn split(cents: &mut [[f32; 3]], total: u64, chunk: u64) -> Vec<ChunkNode> {
    let n = cents.len().max(1) as u64;
    let mut nodes = vec![ChunkNode::Leaf { chunk: 0 }];
    // (node, sample range)
    let mut stack = vec![(0usize, 0usize, cents.len())];
    let mut leaves = Vec::new();
    while let Some((node, lo, hi)) = stack.pop() {
        let share = (total as u128 * (hi - lo) as u128).div_ceil(u128::from(n)) as u64;
        let s = &mut cents[lo..hi];
        let axis = longest_axis(s);
        if share <= chunk || s.len() < 2 || axis.is_none() {
            leaves.push(node);
            continue;
        }
        let axis = axis.unwrap_or(0);
        s.sort_unstable_by(|a, b| a[axis].total_cmp(&b[axis]));
        // The median; centroids equal to it go right. When more than half
        // equal the least value, the split moves up to the next value (the
        // axis has one: its extent is not 0), so neither side is empty.
        let mut at = s[s.len() / 2][axis];
        let mut left = s.partition_point(|c| c[axis] < at);
        if left == 0 {
            left = s.partition_point(|c| c[axis] <= at);
            at = s[left][axis];
        }
        let first = nodes.len() as u32;
        nodes.push(ChunkNode::Leaf { chunk: 0 });
        nodes.push(ChunkNode::Leaf { chunk: 0 });
        nodes[node] = ChunkNode::Inner {
            axis: axis as u8,
            at,
            children: [first, first + 1],
        };
        // Right first, so the left is split (and numbered) first.
        stack.push((first as usize + 1, lo + left, hi));
        stack.push((first as usize, lo, lo + left));
    }
    // Leaves numbered depth-first, left first.
    let mut order = Vec::new();
    let mut stack = vec![0u32];
    while let Some(i) = stack.pop() {
        match nodes[i as usize] {
            ChunkNode::Inner { children, .. } => {
                stack.push(children[1]);
                stack.push(children[0]);
            }
            ChunkNode::Leaf { .. } => order.push(i),
        }
    }
    debug_assert_eq!(order.len(), leaves.len());
    for (k, &i) in order.iter().enumerate() {
        nodes[i as usize] = ChunkNode::Leaf { chunk: k as u32 };
    }
    nodes
}

/// The axis on which `s` spreads most, or `None` if its points coincide.
fn longest_axis(s: &[[f32; 3]]) -> Option<usize> {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for c in s {
        for k in 0..3 {
            lo[k] = lo[k].min(c[k]);
            hi[k] = hi[k].max(c[k]);
        }
    }
    let ext: [f32; 3] = std::array::from_fn(|k| hi[k] - lo[k]);
    let axis = (0..3).max_by(|&a, &b| ext[a].total_cmp(&ext[b]))?;
    (ext[axis] > 0.0).then_some(axis)
}

/// The leaf of `kd` that centroid `c` falls in.
fn leaf_of(kd: &[ChunkNode], c: [f32; 3]) -> u32 {
    let mut i = 0usize;
    loop {
        match kd[i] {
            ChunkNode::Inner { axis, at, children } => {
                i = children[usize::from(c[axis as usize] >= at)] as usize;
            }
            ChunkNode::Leaf { chunk } => return chunk,
        }
    }
}

/// `kd` without its empty leaves (`counts` by leaf), each inner node left
/// with one child replaced by it; the chunks renumbered depth-first
/// (`chunk_of[leaf]`, `u32::MAX` for a pruned one).
fn prune(kd: &[ChunkNode], counts: &[u64]) -> (Vec<ChunkNode>, Vec<u32>) {
    // Triangles under each node, children after parents: bottom-up by
    // walking the nodes backwards.
    let mut under = vec![0u64; kd.len()];
    for i in (0..kd.len()).rev() {
        under[i] = match kd[i] {
            ChunkNode::Inner { children, .. } => {
                under[children[0] as usize] + under[children[1] as usize]
            }
            ChunkNode::Leaf { chunk } => counts[chunk as usize],
        };
    }
    let mut chunk_of = vec![u32::MAX; counts.len()];
    let mut out: Vec<ChunkNode> = Vec::new();
    if under.first().is_none_or(|&n| n == 0) {
        return (out, chunk_of);
    }
    let mut chunks = 0u32;
    // (old node, new slot)
    out.push(ChunkNode::Leaf { chunk: 0 });
    let mut stack = vec![(0usize, 0usize)];
    while let Some((mut i, slot)) = stack.pop() {
        // Skip inner nodes with an empty side.
        while let ChunkNode::Inner { children, .. } = kd[i] {
            let [l, r] = children.map(|c| c as usize);
            if under[l] == 0 {
                i = r;
            } else if under[r] == 0 {
                i = l;
            } else {
                break;
            }
        }
        match kd[i] {
            ChunkNode::Inner { axis, at, children } => {
                let first = out.len() as u32;
                out.push(ChunkNode::Leaf { chunk: 0 });
                out.push(ChunkNode::Leaf { chunk: 0 });
                out[slot] = ChunkNode::Inner {
                    axis,
                    at,
                    children: [first, first + 1],
                };
                stack.push((children[1] as usize, first as usize + 1));
                stack.push((children[0] as usize, first as usize));
            }
            ChunkNode::Leaf { chunk } => {
                chunk_of[chunk as usize] = chunks;
                out[slot] = ChunkNode::Leaf { chunk: chunks };
                chunks += 1;
            }
        }
    }
    (out, chunk_of)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str) -> PathBuf {
        std::env::temp_dir().join(format!("cbvh-chunked-{name}-{}", std::process::id()))
    }

    #[test]
    fn chunks_hold_every_triangle_once_in_file_order() {
        let mesh =
            crate::scene::generate(crate::scene::Kind::Statue, 20_000, 2, &mut |_, _| {}).unwrap();
        for chunk in [1u64, 700, 5000, 1 << 40] {
            let opts = ChunkOptions {
                chunk_triangles: chunk,
                temp_dir: temp(&format!("order-{chunk}")),
            };
            let c = ChunkedMesh::from_mesh(&mesh, &opts, &|_, _, _| {}).unwrap();
            assert_eq!(c.triangle_count(), mesh.triangles.len() as u64);
            let mut seen = Vec::new();
            let mut scratch = ChunkScratch::default();
            for k in 0..c.chunk_count() {
                let (m, global) = c.chunk(k, &mut scratch).unwrap();
                assert!(!m.triangles.is_empty());
                for t in &m.triangles {
                    seen.push(t.map(|v| global[v as usize]));
                    for &v in t {
                        assert_eq!(
                            m.vertices[v as usize],
                            mesh.vertices[global[v as usize] as usize]
                        );
                    }
                }
            }
            let mut want = mesh.triangles.clone();
            want.sort_unstable();
            let mut got = seen.clone();
            got.sort_unstable();
            assert_eq!(got, want, "chunk size {chunk}");
            // Chunk sizes near the request (a few percent over at most;
            // a one-triangle request gives one-triangle-ish chunks).
            if chunk < (1 << 40) {
                let largest = (0..c.chunk_count()).map(|k| c.chunk_len(k)).max().unwrap();
                assert!(largest <= chunk.max(2) * 11 / 10 + 2, "{largest} > {chunk}");
                assert!(c.chunk_count() as u64 >= mesh.triangles.len() as u64 / chunk.max(1) / 2);
            } else {
                assert_eq!(c.chunk_count(), 1);
                assert_eq!(seen, mesh.triangles);
            }
            // The tree: every chunk once, depth-first.
            let mut order = Vec::new();
            let mut stack = vec![0u32];
            while let Some(i) = stack.pop() {
                match c.top()[i as usize] {
                    ChunkNode::Inner { children, .. } => {
                        stack.push(children[1]);
                        stack.push(children[0]);
                    }
                    ChunkNode::Leaf { chunk } => order.push(chunk),
                }
            }
            assert_eq!(order, (0..c.chunk_count() as u32).collect::<Vec<_>>());
            drop(c);
            assert!(
                !opts.temp_dir.exists(),
                "the temporary directory is removed"
            );
        }
    }

    #[test]
    fn coincident_centroids_stay_one_chunk_and_a_used_temp_dir_is_refused() {
        // Every triangle the same: nothing to split on.
        let mesh = Mesh::new(
            vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![[0, 1, 2]; 50],
        );
        let opts = ChunkOptions {
            chunk_triangles: 4,
            temp_dir: temp("same"),
        };
        let c = ChunkedMesh::from_mesh(&mesh, &opts, &|_, _, _| {}).unwrap();
        assert_eq!(c.chunk_count(), 1);
        assert!(matches!(
            ChunkedMesh::from_mesh(&mesh, &opts, &|_, _, _| {}),
            Err(ChunkError::TempExists(_))
        ));
        drop(c);
        // A bad index is an error naming it.
        let bad = Mesh::new(vec![[0.0; 3]; 3], vec![[0, 1, 2], [0, 1, 7]]);
        let opts = ChunkOptions {
            chunk_triangles: 1,
            temp_dir: temp("bad"),
        };
        let e = ChunkedMesh::from_mesh(&bad, &opts, &|_, _, _| {}).unwrap_err();
        assert!(e.to_string().contains("vertex 7"), "{e}");
        assert!(!opts.temp_dir.exists());
        // A temporary directory whose parent is missing is an error, and
        // the parent is not made.
        let parent = temp("no-parent");
        let opts = ChunkOptions {
            chunk_triangles: 4,
            temp_dir: parent.join("t"),
        };
        assert!(matches!(
            ChunkedMesh::from_mesh(&mesh, &opts, &|_, _, _| {}),
            Err(ChunkError::Io(_))
        ));
        assert!(!parent.exists());
    }
}
