//! The out-of-core mode (§3.1, §5): an o-HCCMesh file, usually
//! memory-mapped, whose low-level trees are decoded on demand into
//! one-tree i-HCCMeshes kept in a [`PageCache`] under a byte budget.
//!
//! What stays in memory besides the cache is what the paper keeps
//! uncompressed: the high-level tree with its boxes (decoded from the
//! file's `high-level boxes` section at open), each tree's first triangle
//! and first stored vertex, the contexts' decoders, the id maps when
//! the file has them, and the edge flags (a byte a triangle; contacts
//! read them for any triangle they touch, so they are decoded whole at
//! open, not per tree).
//!
//! A high-level leaf's child handle is an *unopened* root (its box is the
//! stored high-level box): the tree is decoded when a traversal enters the
//! box (asks whether it is a leaf, for its children or its triangles), not
//! when it meets it, so a ray that misses a tree's box never decodes it.
//!
//! A node handle is an [`HccNode`] whose tree field names the low-level
//! tree of the whole model; the page's own i-HCCMesh numbers that tree 0,
//! so a handle is re-labelled on the way in and out. A page's triangles are
//! numbered from 0; the tree's first rank is added (and the id map applied)
//! before a triangle id leaves this module.
//!
//! A tree whose bytes do not decode panics in the query that reaches it,
//! naming the tree: [`Paged::verify`] decodes every tree once and proves
//! the file (run it, or open with `OpenOptions::verify`, for files you did
//! not write).

use std::cell::RefCell;
use std::ops::Range;
use std::thread::LocalKey;

use super::super::ids::{IdMap, VertexIds};
use super::super::node::HighNode;
use super::super::pair::outer;
use super::super::{HccBvh, HccNode};
use super::OocError;
use super::decode::{Coder, high_tree, id_maps, stored_boxes, tree_stream, tree_table};
use super::file::{self, SEC_BOXES, SEC_DICTS, SEC_EDGES, SEC_HIGH, SEC_TREES, SECTIONS};
use crate::codec::ByteSize;
use crate::codec::common::page_cache::{
    self, CacheStats, LiveToken, Page, PageCache, Pins, no_pins,
};
use crate::codec::common::{FormatError, MassProps, Store, edges};
use crate::contact::EdgeFlags;
use crate::geom::{Aabb, Triangle};
use crate::mesh::Mesh;
use xxhash_rust::xxh3::xxh3_64;

/// One decoded low-level tree.
pub(super) struct TreePage {
    hcc: HccBvh,
    live: LiveToken,
}

impl Page for TreePage {
    fn bytes(&self) -> usize {
        self.live.bytes()
    }

    fn pins() -> &'static LocalKey<RefCell<Pins<Self>>> {
        thread_local!(static PINNED: RefCell<Pins<TreePage>> = const { RefCell::new(no_pins()) });
        &PINNED
    }
}

/// An o-HCCMesh traversed out of core.
pub(super) struct Paged {
    file: Store,
    sections: [Range<usize>; SECTIONS],
    coder: Coder,
    high: Vec<HighNode>,
    /// Per tree, its first triangle rank and first stored vertex; one more
    /// entry holds the totals.
    firsts: Vec<[u32; 2]>,
    /// Per tree, where its stream starts in the streams section; one more
    /// entry holds the section's length.
    starts: Vec<u32>,
    ids: Option<IdMap>,
    vertex_ids: Option<VertexIds>,
    /// Active edges by triangle id, read whole at open.
    edges: EdgeFlags,
    cache: PageCache<TreePage>,
    owner: u64,
}

impl std::fmt::Debug for Paged {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Paged")
            .field("file", &self.file)
            .field("trees", &(self.firsts.len() - 1))
            .field("cache", &self.cache.stats())
            .finish_non_exhaustive()
    }
}

/// The i-HCCMesh bytes the file decodes to, estimated from the header's
/// counts (exact but for the per-tree records): what decides whether a
/// file is pre-loaded or paged.
pub(super) fn decoded_estimate(h: &file::Header) -> usize {
    let words = h.node_words as usize;
    h.high_nodes as usize * 32
        + h.trees as usize * 40
        + words * 4
        + words.div_ceil(64) * 12
        + h.interconnections as usize * 4
        + (h.stored_vertices as usize * 3 * h.bits as usize).div_ceil(8)
        // The edge flags, a byte a triangle.
        + h.triangles as usize
}

impl Paged {
    /// Opens the file `file` (checked in O(header) but for the high-level
    /// tree and the id maps, which are read whole) with a cache of
    /// `budget` bytes.
    pub(super) fn new(file: Store, budget: usize) -> Result<Self, OocError> {
        let b: &[u8] = &file;
        let (h, sec) = file::parse_with(b, false)?;
        let coder = Coder::new(&h, sec[SEC_DICTS])?;
        let (mut high, leaf_of_tree) = high_tree(&h, sec[SEC_HIGH])?;
        let boxes = stored_boxes(&coder, &high, sec[SEC_BOXES])?;
        let (starts, firsts) = tree_table(&h, &sec)?;
        for (n, bx) in high.iter_mut().zip(&boxes) {
            n.min = [bx[0], bx[1], bx[2]];
            n.max = [bx[3], bx[4], bx[5]];
        }
        let bad = |what| OocError::Corrupt {
            tree: u32::MAX,
            what,
        };
        if boxes.iter().flatten().any(|x| !x.is_finite()) {
            return Err(bad("a stored high-level box is not finite"));
        }
        // Trees are numbered as the high-level leaves are met depth-first.
        debug_assert_eq!(leaf_of_tree.len() + 1, firsts.len());
        let (ids, vertex_ids) = id_maps(&h, &sec)?;
        let edges = edges::decode(sec[SEC_EDGES], u64::from(h.triangles))?;
        let range = |s: &[u8]| {
            let at = s.as_ptr() as usize - b.as_ptr() as usize;
            at..at + s.len()
        };
        let sections = std::array::from_fn(|k| range(sec[k]));
        let max_page = 4 * decoded_estimate(&h) / (h.trees as usize).max(1) + 4096;
        Ok(Self {
            sections,
            coder,
            high,
            firsts,
            starts,
            ids,
            vertex_ids,
            edges,
            cache: PageCache::new(budget, max_page),
            owner: page_cache::next_owner(),
            file,
        })
    }

    fn section(&self, k: usize) -> &[u8] {
        &self.file[self.sections[k].clone()]
    }

    /// Decodes tree `k` (no cache).
    fn decode(&self, k: u32) -> Result<TreePage, OocError> {
        let bytes = tree_stream(&self.starts, self.section(SEC_TREES), k)?;
        let (hcc, _) = self.coder.tree(k, bytes)?;
        let n = hcc.bytes_total() + size_of::<TreePage>();
        Ok(TreePage {
            hcc,
            live: self.cache.live().token(n),
        })
    }

    /// Runs `f` on tree `k`'s page: pinned, cached, or decoded now.
    ///
    /// # Panics
    /// If the tree's bytes do not decode (see the module docs).
    #[inline]
    fn with_page<R>(&self, k: u32, f: impl FnOnce(&TreePage) -> R) -> R {
        let mut f = Some(f);
        let pinned = page_cache::with_pinned(self.owner, k, |p: &TreePage| f.take().map(|f| f(p)));
        match (pinned, f) {
            (Some(r), _) => r,
            (None, Some(f)) => self.with_page_slow(k, f),
            // The closure runs only when the page is pinned, and then
            // returns `Some`.
            (None, None) => unreachable!("a pinned page's closure returned nothing"),
        }
    }

    #[cold]
    fn with_page_slow<R>(&self, k: u32, f: impl FnOnce(&TreePage) -> R) -> R {
        let page = self
            .cache
            .get_or_decode(k, || self.decode(k))
            .unwrap_or_else(|e| panic!("hcc-ooc: {e} (run verify() to check the file)"));
        let r = f(&page);
        page_cache::pin(self.owner, k, page);
        r
    }

    /// The root and its box.
    pub(super) fn root(&self) -> (HccNode, Aabb) {
        if self.high.is_empty() {
            return (HccNode::empty(), Aabb::EMPTY);
        }
        let n = self.high_child(0);
        (n, n.bounds())
    }

    #[inline]
    fn high_child(&self, i: u32) -> HccNode {
        let h = &self.high[i as usize];
        let bounds = Aabb::from_arrays(h.min, h.max);
        if h.is_leaf() {
            HccNode::unopened(h.a, bounds)
        } else {
            HccNode::high(i, bounds)
        }
    }

    /// `node`, its tree's root word read if it is an unopened root.
    #[inline]
    pub(super) fn open(&self, node: &HccNode) -> HccNode {
        if node.is_unopened() {
            let (t, bounds) = (node.tree(), node.bounds());
            self.with_page(t, |p| p.hcc.low_root(0, bounds).in_tree(t))
        } else {
            *node
        }
    }

    /// The two children of the inner node `node`.
    #[inline]
    pub(super) fn children_of(&self, node: &HccNode) -> [(HccNode, Aabb); 2] {
        if node.is_high() {
            let h = &self.high[node.pos() as usize];
            return [h.a, h.b].map(|c| {
                let n = self.high_child(c);
                (n, n.bounds())
            });
        }
        let node = self.open(node);
        let t = node.tree();
        let local = node.in_tree(0);
        self.with_page(t, |p| {
            p.hcc.children_of(&local).map(|(n, b)| (n.in_tree(t), b))
        })
    }

    /// The triangle id of storage rank `rank`.
    #[inline]
    pub(super) fn id_of(&self, rank: u32) -> u32 {
        match &self.ids {
            Some(m) => m.id(rank),
            None => rank,
        }
    }

    /// Calls `f` with each triangle of the leaf `node`.
    #[inline]
    pub(super) fn for_each_triangle(&self, node: &HccNode, f: &mut impl FnMut(u32, &Triangle)) {
        self.for_each_ranked_triangle(node, &mut |rank, tri| f(self.id_of(rank), tri));
    }

    /// Calls `f` with the storage rank and corners of each triangle of the
    /// leaf `node`.
    #[inline]
    pub(super) fn for_each_ranked_triangle(
        &self,
        node: &HccNode,
        f: &mut impl FnMut(u32, &Triangle),
    ) {
        if node.is_empty() {
            return;
        }
        let node = self.open(node);
        let t = node.tree();
        let first = self.firsts[t as usize][0];
        let local = node.in_tree(0);
        self.with_page(t, |p| {
            use crate::cursor::NodeCursor;
            p.hcc
                .for_each_triangle_keyed(&local, |rank, tri| f(first + rank, tri))
        })
    }

    /// The tree holding rank `rank`, and its first rank.
    fn tree_of_rank(&self, rank: u32) -> (u32, u32) {
        let t = self
            .firsts
            .partition_point(|f| f[0] <= rank)
            .saturating_sub(1);
        let t = t.min(self.firsts.len().saturating_sub(2));
        (t as u32, self.firsts[t][0])
    }

    /// The storage rank of triangle `id` (0 when out of range).
    fn rank_of(&self, id: u32) -> u32 {
        let n = self.triangle_count() as u32;
        match &self.ids {
            Some(m) => m.rank(id).unwrap_or(0),
            None if id < n => id,
            None => 0,
        }
    }

    /// Triangle `id`.
    pub(super) fn triangle(&self, id: u32) -> Triangle {
        use crate::cursor::NodeCursor;
        let rank = self.rank_of(id);
        let (t, first) = self.tree_of_rank(rank);
        self.with_page(t, |p| p.hcc.triangle(rank - first))
    }

    /// Triangle `id`'s corners as indices into the decoded mesh's vertices.
    pub(super) fn triangle_vertices(&self, id: u32) -> [u32; 3] {
        let rank = self.rank_of(id);
        let (t, first) = self.tree_of_rank(rank);
        let base = self.firsts[t as usize][1];
        let local = self.with_page(t, |p| p.hcc.triangle_vertex_indices(rank - first));
        local.map(|l| self.vertex_index(base + l))
    }

    fn vertex_index(&self, s: u32) -> u32 {
        match &self.vertex_ids {
            Some(v) => v.get(s),
            None => s,
        }
    }

    /// Triangles.
    pub(super) fn triangle_count(&self) -> usize {
        self.coder.h.triangles as usize
    }

    /// Mass properties at density 1.
    pub(super) fn mass(&self) -> MassProps {
        self.coder.h.mass
    }

    /// Active edges by triangle id.
    pub(super) fn edge_flags(&self) -> &EdgeFlags {
        &self.edges
    }

    /// The mesh as stored, decoded tree by tree (the same mesh the
    /// pre-loaded mode's [`HccBvh::decoded_mesh`] gives).
    pub(super) fn decoded_mesh(&self) -> Mesh {
        let h = &self.coder.h;
        let mut triangles = vec![[0u32; 3]; h.triangles as usize];
        let mut vertices = match &self.vertex_ids {
            Some(_) => vec![[0f32; 3]; h.mesh_vertices as usize],
            None => Vec::with_capacity(h.stored_vertices as usize),
        };
        for t in 0..self.firsts.len() - 1 {
            let [first, base] = self.firsts[t];
            // Outside the cache: a whole-mesh pass would only churn it.
            let m = self
                .decode(t as u32)
                .unwrap_or_else(|e| panic!("hcc-ooc: {e} (run verify() to check the file)"))
                .hcc
                .decoded_mesh();
            for (r, tri) in m.triangles.iter().enumerate() {
                if let Some(slot) = triangles.get_mut(self.id_of(first + r as u32) as usize) {
                    *slot = tri.map(|l| self.vertex_index(base + l));
                }
            }
            for (l, &p) in m.vertices.iter().enumerate() {
                match &self.vertex_ids {
                    Some(v) => {
                        if let Some(slot) = vertices.get_mut(v.get(base + l as u32) as usize) {
                            *slot = p;
                        }
                    }
                    None => vertices.push(p),
                }
            }
        }
        if let Some(v) = &self.vertex_ids {
            for &(i, p) in &v.unused {
                if let Some(slot) = vertices.get_mut(i as usize) {
                    *slot = p;
                }
            }
        }
        Mesh::new(vertices, triangles)
    }

    /// Proves the file: the streams' checksum, every tree decoded and
    /// verified as an i-HCCMesh, its root box equal to its high-level
    /// leaf's stored box, its triangle and vertex counts matching the
    /// stored firsts, and every stored inner box the combination of its
    /// children's. Decodes tree by tree, outside the cache.
    pub(super) fn verify(&self) -> Result<(), OocError> {
        let streams = self.section(SEC_TREES);
        let entry = file::FRAME.entry(&self.file, SEC_TREES);
        if xxh3_64(streams) != entry.2 {
            return Err(FormatError::Checksum {
                section: file::NAMES[SEC_TREES],
            }
            .into());
        }
        let mut leaf_box = vec![None; self.firsts.len() - 1];
        for (i, n) in self.high.iter().enumerate() {
            if n.is_leaf() {
                leaf_box[n.a as usize] = Some(i);
            }
        }
        let mut boxes = vec![[0f32; 6]; self.high.len()];
        let (mut words, mut ics) = (0u64, 0u64);
        for (t, leaf) in leaf_box.iter().enumerate() {
            let k = t as u32;
            let bad = |what| OocError::Corrupt { tree: k, what };
            let bytes = tree_stream(&self.starts, streams, k)?;
            let (hcc, root) = self.coder.tree(k, bytes)?;
            hcc.verify()?;
            words += hcc.nodes.len() as u64;
            ics += hcc.ics.len() as u64;
            let [first, base] = self.firsts[t];
            let [next, next_base] = self.firsts[t + 1];
            if hcc.triangle_count != next - first
                || hcc.stats.tree_vertices as u32 != next_base - base
            {
                return Err(bad(
                    "the tree's triangles or vertices disagree with the stored firsts",
                ));
            }
            let i = leaf.ok_or(bad("no high-level leaf names the tree"))?;
            boxes[i] = root;
        }
        let h = &self.coder.h;
        if words != u64::from(h.node_words) || ics != u64::from(h.interconnections) {
            return Err(OocError::Corrupt {
                tree: u32::MAX,
                what: "the trees hold another number of node words or inter-connections than the header says",
            });
        }
        for i in (0..self.high.len()).rev() {
            let n = self.high[i];
            if !n.is_leaf() {
                let (l, r) = (boxes[n.a as usize], boxes[n.b as usize]);
                boxes[i] = std::array::from_fn(|e| if outer(e, r[e], l[e]) { r[e] } else { l[e] });
            }
            let stored = n.min.into_iter().chain(n.max);
            if stored
                .zip(boxes[i])
                .any(|(x, y)| x.to_bits() != y.to_bits())
            {
                return Err(OocError::Corrupt {
                    tree: u32::MAX,
                    what: "a stored high-level box disagrees with the box its trees rebuild",
                });
            }
        }
        if let Some(ids) = &self.ids {
            ids.verify().map_err(|what| OocError::Corrupt {
                tree: u32::MAX,
                what,
            })?;
        }
        Ok(())
    }

    /// The cache's counters.
    pub(super) fn cache_stats(&self) -> CacheStats {
        self.cache.stats()
    }

    /// The file's bytes.
    pub(super) fn file(&self) -> &Store {
        &self.file
    }

    /// The i-HCCMesh bytes the whole file decodes to (estimated from the
    /// header).
    pub(super) fn decoded_estimate(&self) -> usize {
        decoded_estimate(&self.coder.h)
    }

    /// The header's fields for `cbvh info`.
    pub(super) fn header_fields(&self) -> Vec<(&'static str, String)> {
        let h = &self.coder.h;
        let [x, y, z] = h.grid[2];
        vec![
            ("low-level trees", h.trees.to_string()),
            ("multi-triangle leaves", h.multi.to_string()),
            (
                "vertices",
                format!(
                    "{}-bit grid over the mesh, error at most ({x:e}, {y:e}, {z:e})",
                    h.bits
                ),
            ),
            ("stored vertices", h.stored_vertices.to_string()),
            (
                "input mesh",
                format!(
                    "{} vertices, {} of them used",
                    h.mesh_vertices, h.used_vertices
                ),
            ),
            ("vertex ids", h.vertex_ids.to_string()),
            (
                "triangle ids",
                if h.tree_order {
                    "tree order"
                } else {
                    "input's"
                }
                .to_string(),
            ),
        ]
    }

    /// In-memory parts besides the cache.
    pub(super) fn parts(&self) -> Vec<(&'static str, usize)> {
        vec![
            ("high-level", self.high.len() * size_of::<HighNode>()),
            ("tree-firsts", self.firsts.len() * 8 + self.starts.len() * 4),
            ("ids", self.ids.as_ref().map_or(0, IdMap::bytes)),
            (
                "vertex-ids",
                self.vertex_ids.as_ref().map_or(0, VertexIds::bytes),
            ),
            ("edge-flags", self.edges.bytes()),
            ("o-hccmesh-file", self.file.len()),
        ]
    }
}
