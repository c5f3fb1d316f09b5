//! [`RacBvh`]: the compressed tree with its mesh and its cache, and the
//! figures about it.

use super::{CacheStats, RacError, RacStats, cache, decode, file, mesh, nodecache};
use crate::codec::common::Store;
use crate::codec::common::quant::{Grid, QBox};
use crate::contact::EdgeFlags;

/// Everything global a cluster's decoder needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Header {
    pub(super) cluster_bits: u32,
    pub(super) bits: u32,
    pub(super) node_count: u32,
    pub(super) triangle_count: u32,
    pub(super) max_leaf: u32,
    pub(super) tri_threshold: u32,
    pub(super) grid: Grid,
    pub(super) empty: bool,
    pub(super) tree_bits: u64,
    pub(super) bv_bits: u64,
    pub(super) compression_seconds: f64,
}

impl Header {
    /// The root's quantized box: the whole grid (0 on flat axes).
    pub(super) fn root_qbox(grid: &Grid) -> QBox {
        let mut q = QBox::default();
        for a in 0..3 {
            q.max[a] = if grid.step[a] > 0.0 { grid.max_q } else { 0 };
        }
        q
    }
}

/// One meta-table entry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct ClusterMeta {
    pub(super) offset: u64,
    pub(super) nodes: u32,
    /// xxh3-64 of the cluster's bytes, checked on every decode.
    pub(super) hash: u64,
}

/// A compressed BVH with its mesh and its decompressed-cluster cache.
pub struct RacBvh {
    pub(super) header: Header,
    /// The clusters' bytes, concatenated.
    pub(super) data: Store,
    pub(super) meta: Vec<ClusterMeta>,
    pub(super) mesh: mesh::PackedMesh,
    /// Checksum of the mesh sections, as stored (checked by `verify`).
    pub(super) mesh_hash: u64,
    /// Mass properties at density 1, computed from the original mesh.
    pub(super) mass: crate::codec::common::MassProps,
    /// Whether the mesh sections' checksum and vertex indices were checked
    /// and found good: done once, on the first triangle any query reads (or
    /// by `verify`), so a caller who skips `verify` still never gets
    /// triangles from damaged mesh bytes.
    pub(super) mesh_ok: std::sync::OnceLock<Result<(), RacError>>,
    /// Active edges by triangle id: computed when encoded (set after
    /// [`assemble`](Self::assemble)), read from the file when opened.
    pub(super) edges: EdgeFlags,
    pub(super) cache: cache::ClusterCache,
    /// The decoded-node cache, when the budget cannot hold every cluster.
    pub(super) nodes: Option<nodecache::NodeCache>,
    /// The budget the caller gave (the cluster cache has what the node
    /// cache leaves of it).
    pub(super) budget: usize,
    /// Identifies this tree in the threads' pins.
    pub(super) id: u64,
}

impl std::fmt::Debug for RacBvh {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RacBvh")
            .field("nodes", &self.header.node_count)
            .field("clusters", &self.meta.len())
            .field("triangles", &self.header.triangle_count)
            .finish_non_exhaustive()
    }
}

impl RacBvh {
    pub(super) fn assemble(
        header: Header,
        data: Store,
        meta: Vec<ClusterMeta>,
        mesh: mesh::PackedMesh,
        mesh_hash: u64,
        mass: crate::codec::common::MassProps,
        budget: usize,
    ) -> Self {
        let max_cluster = (1usize << header.cluster_bits) * decode::CLUSTER_BYTES_PER_NODE;
        let ids = nodecache::NodeCache::ids_for(header.max_leaf);
        let sets = node_cache_sets(budget, header.node_count, meta.len(), ids);
        let node_bytes = sets * nodecache::NodeCache::set_bytes(ids);
        let cache = cache::ClusterCache::new(budget - node_bytes, max_cluster);
        let nodes = (sets > 0)
            .then(|| nodecache::NodeCache::new(sets, ids, cache.live().token(node_bytes)));
        Self {
            header,
            data,
            meta,
            mesh_hash,
            mesh,
            mass,
            mesh_ok: std::sync::OnceLock::new(),
            edges: EdgeFlags::default(),
            cache,
            nodes,
            budget,
            id: crate::codec::common::page_cache::next_owner(),
        }
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.header.node_count as usize
    }

    /// Number of clusters.
    pub fn cluster_count(&self) -> usize {
        self.meta.len()
    }

    /// Nodes per cluster.
    pub fn cluster_nodes(&self) -> u32 {
        1 << self.header.cluster_bits
    }

    /// The mesh as stored (with quantized vertices decoded): the triangles
    /// the cursor reports.
    ///
    /// # Panics
    /// If the mesh sections are damaged (see [`check_mesh`](Self::check_mesh)).
    pub fn decoded_mesh(&self) -> crate::mesh::Mesh {
        self.expect_mesh();
        self.mesh.decoded()
    }

    /// Checks the mesh sections once (their checksum, then every vertex
    /// index) and remembers the answer: O(mesh) the first time, O(1) after.
    /// Queries call it before their first triangle.
    pub fn check_mesh(&self) -> Result<(), RacError> {
        self.mesh_ok
            .get_or_init(|| {
                if self.mesh_hash != file::mesh_hash(&self.mesh) {
                    return Err(RacError::Corrupt(
                        "the mesh sections' checksum does not match",
                    ));
                }
                self.mesh.check()
            })
            .clone()
    }

    /// [`check_mesh`](Self::check_mesh), panicking with its error.
    #[inline]
    pub(super) fn expect_mesh(&self) {
        if let Err(e) = self.check_mesh() {
            panic!("racbvh: {e} (the file is damaged; verify() reports this as an error)");
        }
    }

    /// Mass properties at density 1 (computed from the original mesh when
    /// encoded, stored in the file).
    pub fn mass(&self) -> crate::codec::common::MassProps {
        self.mass
    }

    /// Active edges by triangle id (stored in the file).
    pub fn edge_flags(&self) -> &EdgeFlags {
        &self.edges
    }

    /// The vertex indices of stored triangle `t` (for smooth shading).
    ///
    /// # Panics
    /// If `t` is not a triangle of the tree.
    pub fn triangle_indices(&self, t: u32) -> [u32; 3] {
        assert!(
            (t as usize) < self.header.triangle_count as usize,
            "racbvh: no triangle {t}"
        );
        self.expect_mesh();
        self.mesh.indices(t)
    }

    /// The header's fields, for reports (`cbvh info`).
    pub fn header_fields(&self) -> Vec<(&'static str, String)> {
        let h = &self.header;
        let m = &self.mesh;
        vec![
            ("version", file::VERSION.to_string()),
            ("nodes", h.node_count.to_string()),
            (
                "clusters",
                format!("{} of {} nodes", self.meta.len(), 1u32 << h.cluster_bits),
            ),
            ("box bits", h.bits.to_string()),
            (
                "vertex bits",
                if m.lossless {
                    "32 (lossless f32)".to_string()
                } else {
                    m.vertex_bits.to_string()
                },
            ),
            ("vertices", m.vertex_count.to_string()),
            ("max leaf tris", h.max_leaf.to_string()),
            ("triangle-delta threshold", h.tri_threshold.to_string()),
            (
                "coded bits",
                format!("{} of structure, {} of boxes", h.tree_bits, h.bv_bits),
            ),
            ("compression time", format!("{} s", h.compression_seconds)),
        ]
    }

    /// Compression figures.
    pub fn stats(&self) -> RacStats {
        let n = f64::from(self.header.node_count.max(1));
        let tree = (self.data.len() + self.meta.len() * file::META_ENTRY) as f64;
        RacStats {
            nodes: u64::from(self.header.node_count),
            cluster_count: self.meta.len() as u64,
            bits_per_node_tree: self.header.tree_bits as f64 / n,
            bits_per_node_bv: self.header.bv_bits as f64 / n,
            compression_ratio_vs_plain: 32.0 * n / tree.max(1.0),
            mesh_bytes_per_triangle: self.mesh.bytes() as f64
                / f64::from(self.header.triangle_count.max(1)),
            compression_seconds: self.header.compression_seconds,
        }
    }

    /// The cache's counters.
    pub fn cache_stats(&self) -> CacheStats {
        let mut s = self.cache.stats();
        s.budget_bytes = self.budget;
        if let Some(n) = &self.nodes {
            s.cached_bytes += n.bytes();
            s.node_bytes = n.bytes();
            s.node_misses = n.misses();
        }
        s
    }

    /// How many nodes the node cache holds (0 when the budget holds every
    /// cluster and there is none).
    pub fn node_cache_capacity(&self) -> usize {
        self.nodes.as_ref().map_or(0, |n| n.capacity())
    }

    /// Empties the cache (pinned clusters stay alive until their threads
    /// move on).
    pub fn clear_cache(&self) {
        self.cache.clear();
        if let Some(n) = &self.nodes {
            n.clear();
        }
    }
}

/// The share of the cache budget the cluster cache keeps, in percent, when
/// the budget cannot hold every cluster; the node cache takes the rest
/// (see the module docs of [`racbvh`](super), "Node cache", for the
/// measurements that chose it).
pub const CLUSTER_CACHE_PERCENT: usize = 10;

/// How many sets (of entries with `ids` triangle ids) the node cache gets
/// under `budget`, for a tree of `nodes` nodes in `clusters` clusters:
/// none if the budget holds every cluster decoded (at least 34 bytes a
/// node and 128 a cluster); else the budget but the cluster cache's
/// [`CLUSTER_CACHE_PERCENT`], and no more sets than give every node a way.
pub(super) fn node_cache_sets(budget: usize, nodes: u32, clusters: usize, ids: usize) -> usize {
    let whole = (nodes as usize)
        .saturating_mul(decode::CLUSTER_BYTES_PER_NODE)
        .saturating_add(clusters.saturating_mul(128));
    if budget >= whole {
        return 0;
    }
    let clusters_share =
        budget / 100 * CLUSTER_CACHE_PERCENT + budget % 100 * CLUSTER_CACHE_PERCENT / 100;
    ((budget - clusters_share) / nodecache::NodeCache::set_bytes(ids))
        .min((nodes as usize).div_ceil(nodecache::WAYS))
}

impl crate::codec::ByteSize for RacBvh {
    fn bytes_by_part(&self) -> Vec<(&'static str, usize)> {
        let bv = (self.header.bv_bits / 8) as usize;
        vec![
            ("bvh_tree", self.data.len() - bv.min(self.data.len())),
            ("bvh_bv", bv.min(self.data.len())),
            ("meta", self.meta.len() * file::META_ENTRY),
            ("mesh", self.mesh.bytes()),
            ("edge-flags", self.edges.bytes()),
        ]
    }
}
