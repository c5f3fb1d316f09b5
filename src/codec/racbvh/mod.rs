//! RACBVH: random-accessible compressed BVHs (Kim et al., TVCG 2010, §4–5).
//!
//! The tree's nodes, in layout order, are cut into clusters of `2^k`
//! consecutive nodes ([`RacOptions::cluster_nodes`], 4096 by default, fewer
//! when fitted to a small cache budget: see below), each
//! compressed on its own with every coder context reset, so any cluster can
//! be decompressed in any order. A meta table holds each cluster's start
//! offset and node count. At runtime a cluster decompresses into 32-byte
//! in-core nodes ([`CoreNode`]) held in a sharded LRU cache under a byte
//! budget, beside a cache of single decoded nodes when the budget cannot
//! hold the whole tree (see "Node cache" below); [`RacBvh`] implements
//! [`NodeCursor`](crate::cursor::NodeCursor)
//! (node handle [`RacNode`]: the global node index with the node's child or
//! triangle words) and the paper's atomic access API (§5.1): `root_index`,
//! [`bv`](RacBvh::bv), [`is_leaf`](RacBvh::is_leaf), [`left`](RacBvh::left),
//! [`right`](RacBvh::right), [`triangle_index`](RacBvh::triangle_index).
//!
//! Two modes: pre-loaded ([`RacBvh::encode`], [`RacBvh::from_bytes`]: the
//! compressed bytes in memory) and out-of-core ([`RacBvh::open`]: the
//! container file memory-mapped, clusters read on demand).
//!
//! A model larger than memory is also *built* out of core
//! ([`encode_streamed`], module [`stream`]): read in spatial chunks
//! ([`ChunkedMesh`](crate::build::chunked::ChunkedMesh)), each chunk's
//! tree built and boxed alone, then the clusters cut and coded from the
//! tree over the chunks with each chunk's tree under its leaf, a few
//! chunks in memory at a time. The file is an ordinary RACBVH file.
//!
//! ```no_run
//! use cbvh::codec::Codec;
//! use cbvh::codec::racbvh::{RacBvh, RacOptions};
//! # fn demo(bvh: &cbvh::CanonicalBvh, mesh: &cbvh::Mesh) -> Result<(), cbvh::codec::racbvh::RacError> {
//! let rac = RacBvh::encode(bvh, mesh, &RacOptions::default())?;
//! let stats = rac.stats(); // bits per node, ratio vs plain, seconds
//! rac.save(std::path::Path::new("model.rac"))?;
//! let disk = RacBvh::open(std::path::Path::new("model.rac"), 64 << 20)?;
//! disk.verify()?;
//! # Ok(()) }
//! ```
//!
//! # What a cluster codes, per node in layout order (§4.3, Algorithm 1)
//!
//! - one *structure* symbol: `(front position + 1) << 2 | side << 1 | leaf`,
//!   where the front is the list of this cluster's inner nodes not yet
//!   connected to both children, the position counts from the most recently
//!   added node (0 = newest) or from the oldest, whichever codes the cluster
//!   shorter (one header bit: depth-first orders favour the first,
//!   breadth-first ones the second), and position+1 = 0 marks a *local root* (its
//!   parent is in an earlier cluster). The side bit says left or right child
//!   (for a parent's second child it is implied, and sent as 0);
//!   the leaf bit says whether the node is a leaf (the paper's Algorithm 1
//!   leaves this implicit; it has to be coded somewhere);
//! - for a local root: the parent's cluster as an index into this cluster's
//!   list of parent clusters (stored in the cluster header as deltas), then
//!   the parent's local index in `k` raw bits (the pair index of §4.1);
//! - the box: six residuals of the node's quantized box against the
//!   prediction from its parent's quantized box (§4.2): the parent split at
//!   the middle of its longest axis. Outer faces are coded as inward
//!   distances, the split face as a zig-zagged offset from the middle. Each
//!   residual is sent as its bit length (a dictionary symbol) and its bits
//!   below the leading one (raw): coding the values themselves through the
//!   dictionary escapes too often once boxes span tens of quanta;
//! - for a leaf: its triangle count (only if leaves may hold several) and its
//!   triangle ids, each as `zigzag(delta) + 1` from the previous id (for a
//!   leaf whose sibling is a one-triangle leaf earlier in the cluster, from
//!   the sibling's id: the better reference when the layout is not
//!   depth-first) when `|delta| < threshold` (10), else `0` (§4.3.2). The paper then stores
//!   the id raw; here the far delta is sent as its bit length (a dictionary
//!   symbol of its own context) and its remaining bits raw, which is never
//!   longer than the raw id by more than the length symbol and is much
//!   shorter when the mesh's order is only loosely coherent with the tree's.
//!
//! A cluster's bits are in eight streams, decoded side by side so that the
//! processor overlaps their dependency chains (a code's length depends on
//! the code before it in its stream): the tree (structure, pair indices,
//! triangle ids, local-leaf children), the boxes' zero masks, and one per
//! residual component (min x, y, z, max x, y, z). The cluster starts with
//! the first seven streams' byte lengths (7 × u32, 0.05 bits per node at
//! 4 K nodes a cluster). Eight streams decode about 7 % faster than three.
//!
//! After the nodes, the cluster's *local leaves* (the nodes still in the
//! front: inner nodes with a child in a later cluster) get their missing
//! children's global indices, delta coded from the previous one. The paper
//! codes them when the node is met; coding them at the end lets the decoder
//! know which nodes they are (those left in the front) without a flag.
//!
//! # Choices where the paper leaves them open
//!
//! - **Quantization** (one [`Grid`]):
//!   `2^bits − 1` steps over the root box per axis (the step grown by ulps
//!   until the last grid point reaches the root's max); `min` is the largest
//!   grid point ≤ the true min, `max` the smallest ≥ the true max, both
//!   computed and checked in `f32` exactly as the decoder evaluates them, so
//!   a decoded box always contains its subtree. The boxes are recomputed
//!   from the *stored* mesh first, so they also contain the quantized
//!   triangles the cursor reports.
//! - **Dictionary coder** ([`dict`](crate::codec::common::dict)): the
//!   paper's variant for residual and delta contexts (empty dictionary,
//!   symbols added when met, no combination entries) is used for every
//!   context, including the structure context the paper initialises with all
//!   symbols and codes with full LZW: with one symbol per node and symbols
//!   of many contexts interleaved in a stream, LZW's strings would need
//!   per-context streams and look-ahead for little gain. Ranks are
//!   Exp-Golomb coded with a per-context parameter chosen by the encoder;
//!   entries move one place to the front when used (transpose), so ranks
//!   follow frequencies.
//! - **Box symbols and contexts**: per node, first a 6-bit mask of which
//!   residuals are zero, XORed with the mask predicted from the sibling's
//!   residuals when the sibling is earlier in the same cluster (a face one
//!   sibling leaves is a face the other touches); then each non-zero
//!   residual. Contexts are by (leaf, side, sibling known) for masks and
//!   (leaf, side, min-or-max half, sibling known) for values: 24 in all.
//!   They cannot depend on the parent's split axis, which an incomplete
//!   node's decoder does not know.
//! - **Completion** (§5.2): an incomplete node keeps its residuals in its box
//!   words with [`INCOMPLETE`] set in word 0, and the cluster keeps, per
//!   node, the ordinal of its local root; completing a node loads the local
//!   root's parent (recursively completing it), then completes the local
//!   root's whole subtree inside the cluster, under the cluster's lock.
//! - **Cluster size from the budget**: a front end that sets the cache
//!   budget through [`AnyOptions::with_cache_budget`](crate::codec::AnyOptions::with_cache_budget)
//!   (the drop tests' `-10pct` shapes do) gets [`RacOptions::cluster_nodes`]
//!   halved (down to 256, the paper's smallest) until the budget holds
//!   [`RESIDENT_CLUSTERS`] (256) decoded clusters
//!   ([`RacOptions::cluster_nodes_for_budget`]); the encoder itself takes
//!   the size it is given (`cbvh build --cluster-nodes`). A collision step touches
//!   few nodes of each cluster it enters (depth-first layout, robot in
//!   plant: 837 nodes of the robot's 32 k, in all 8 of its 4096-node
//!   clusters or 50 of its 256-node ones), so a budget of a few large
//!   clusters re-decoded them many times a step (issue 32: with a tenth of
//!   the tree cached, the plant's 9 resident clusters of 4096 nodes took 157
//!   decodes a step, the robot's budget was smaller than one cluster and
//!   nothing was cached). At 256 nodes a cluster a tenth of the plant holds
//!   its 72 clusters a step, and compression loses 11 % (8.0:1 to 7.1:1 on
//!   a 200 k statue). The size depends on the budget only, not on the
//!   tree: the default budget (64 MiB) keeps 4096-node clusters. A file
//!   keeps the size it was encoded with; re-opening it with a smaller
//!   budget does not re-cluster it (encode for the budget you will use).
//!   Clusters alone could not hold the robot's working set at a tenth of
//!   its tree (16x its full cache; even an optimal replacement stayed ~7x):
//!   the node cache below does. Small clusters still pay beside it: each
//!   node-cache miss decodes a cluster, and 256 nodes decode 16 times
//!   faster than 4096.
//! - **Cache**: `lru::LruCache` shards behind mutexes, each with a share of
//!   the byte budget (a shard per 64 clusters of budget, at most 16:
//!   [`shard_count`](crate::codec::common::page_cache::shard_count)); each
//!   thread also pins up to 16 clusters it used, direct-mapped by cluster
//!   index, and
//!   reads them without locks (the paper updates the LRU list only when the
//!   cluster changes). Against four pins searched in order, this cut
//!   shared-cache look-ups by 28 % on random rays in a depth-first layout
//!   and made rays 15 % faster on one thread and 17 % on two. Eviction takes the least recently used cluster that
//!   nobody holds, so a pinned cluster is never evicted, and a thread drops
//!   its pins before it decodes a cluster. Memory bound: the cache holds at
//!   most the budget, and one thread alone adds at most the one cluster it
//!   is decoding. With many threads, a cluster that finds its shard full of
//!   held clusters is used uncached by the thread that decoded it, so each
//!   thread adds at most its pins. Pins outlive the `RacBvh` until the
//!   thread decodes another cluster.
//!   A cluster in core takes 34 bytes per node (the 32-byte node and its
//!   local root's ordinal) plus its multi-triangle leaves' ids.
//! - **Node cache** (`nodecache.rs`; not in the paper, issue 32): when the
//!   budget cannot hold every cluster decoded (less than 34 bytes a node and
//!   128 a cluster), the cluster cache gets [`CLUSTER_CACHE_PERCENT`] (10 %)
//!   of it and the rest is a table of single complete nodes by global index,
//!   allocated once, counted in [`CacheStats::cached_bytes`] and `live_bytes`
//!   ([`CacheStats::node_bytes`], [`CacheStats::node_misses`]), so the total
//!   stays the given budget. A step touches few nodes of many clusters (the
//!   robot in robot-in-plant: ~840 nodes a step in ~50 clusters of 256), so
//!   at a tenth of the tree the clusters churned (36 k decodes in 215 steps,
//!   16x the full cache) while the nodes fit: with the node cache the robot
//!   decodes ~500 clusters in 215 steps and the step takes what it takes with the full
//!   cache (1.0x). Every read of a node (the cursor's children, the access
//!   API, a completion's local root's parent, a leaf's triangle ids) asks the
//!   table first; every miss is filled from the node's cluster, with the
//!   leaf's triangle ids when the leaf holds several (up to 16; a larger
//!   leaf's ids come from its cluster). Entries never go stale: a node's
//!   complete words are the same whichever decode of its cluster they come
//!   from. The table is set-associative, 8 ways a set, sets chosen by
//!   Fibonacci hashing of the node index, not-recently-used replacement (a
//!   reference bit a way, set on a hit if clear, all cleared when an insert
//!   finds them all set: the paper's second-chance idea, per set). 4 ways
//!   missed 3.1 times as often with half the budget for nodes (1.3 times with
//!   85 %) and made the robot 2.6x its full cache there (1.36x with 8).
//!   Threads share the table without locks: each set has a sequence word (odd
//!   while written), readers copy an entry and check the word did not change
//!   (a set being written reads as a miss), a writer that finds the set being
//!   written skips its insert; every word is an atomic, so there is no
//!   `unsafe`. A way takes 36 bytes (8 words and the key), plus 4 a triangle
//!   id when leaves hold several, plus 8 a set. The share: the robot ran at
//!   1.36x its full cache with half the budget for nodes, 1.0x with 70 %, and
//!   0.8–1.0x from 80 to 95 %; with four triangles a leaf (a smaller tree, so
//!   a smaller budget, and wider entries) the robot stays 4.9x at 90 % and
//!   gets worse as the cluster cache takes more (8x at 20 %, 15x at 50 %).
//!   Lucy on the turbine (the default scene) is 1.0–1.1x at the shares tried
//!   (50 to 90 %), and at the papers' scale (`lucy-on-turbine
//!   --statue-tris 28000000 --turbine-tris 1800000 --steps 100`) 0.73x
//!   (1.18x without the node cache): a 164 MiB table in the statue's
//!   182 MiB budget, 50 cluster decodes in 100 steps. With a budget that
//!   holds the tree there is no table and the cursor's path is the cluster
//!   cache's, as before.
//! - **Mesh** ([`mesh`]): vertices quantized over the mesh's box (16 bits
//!   by default) or lossless `f32`; coordinates and vertex indices in
//!   frame-of-reference blocks of 128 values, so any triangle is O(1) away
//!   without a decoded-mesh cache. Not RACM (see [`mesh`] for why). The
//!   cursor keeps the last 1024 triangles each thread decoded (direct-mapped
//!   by id, keyed by tree): a two-tree traversal meets each leaf once per
//!   overlapping leaf of the other tree, and this took the drop test's
//!   narrow phase from 1.65 to 1.14 ms.
//!
//! Errors and validation, in two tiers: every cluster carries an xxh3
//! checksum in the meta table, checked whenever the cluster is decoded; the
//! header, the meta table and the mesh sections carry one too.
//! [`RacBvh::from_bytes`] and [`RacBvh::open`] check the container in
//! O(header + meta table) (sections in order, without overlap, sized for
//! the counts). [`RacBvh::verify`] proves everything a query relies on:
//! every cluster decodes and completes, every node but the root has
//! exactly one parent and children come after their parents (no repeats,
//! no cycles), child boxes lie inside their parent's, each triangle is in
//! exactly one leaf whose box contains it, the mesh's checksum matches and
//! its vertex indices are in range. A caller who skips `verify` is still
//! safe from damaged mesh bytes: the first triangle a query reads checks
//! the mesh sections once ([`RacBvh::check_mesh`]). What only `verify`
//! proves is the tree's global shape (a checksummed file whose tree is a
//! DAG can make queries slow); the CLI, the sims and
//! [`crate::codec::AnyCodec::open`] verify by default. The cursor path and the
//! `bv`/`left`/… accessors panic with a message naming the cluster if they
//! meet corrupted data; the `try_` accessors return the error instead.
//! Nothing in the decoder recurses to a depth the file decides (completion
//! walks the chain of local roots' parents with a loop). Saves are atomic.

mod access;
mod cache;
mod complete;
mod context;
mod contract;
mod cursor;
mod decode;
mod encode;
mod error;
pub mod file;
pub mod mesh;
pub mod node;
mod nodecache;
pub mod stream;
mod tricache;
mod verify;

pub use cache::CacheStats;
pub use cursor::RacNode;
pub use error::RacError;
pub use node::{CoreNode, INCOMPLETE};
pub use stream::{StreamedBuild, encode_streamed};

use crate::codec::common::Store;
use crate::codec::common::quant::{Grid, QBox};
use crate::codec::settings::{CodecOptions, Setting, Settings, SettingsError, Values};
use crate::contact::EdgeFlags;
use context::*;

/// Everything global a cluster's decoder needs.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Header {
    cluster_bits: u32,
    bits: u32,
    node_count: u32,
    triangle_count: u32,
    max_leaf: u32,
    tri_threshold: u32,
    grid: Grid,
    empty: bool,
    tree_bits: u64,
    bv_bits: u64,
    compression_seconds: f64,
}

impl Header {
    /// The root's quantized box: the whole grid (0 on flat axes).
    fn root_qbox(grid: &Grid) -> QBox {
        let mut q = QBox::default();
        for a in 0..3 {
            q.max[a] = if grid.step[a] > 0.0 { grid.max_q } else { 0 };
        }
        q
    }
}

/// One meta-table entry.
#[derive(Clone, Copy, Debug, PartialEq)]
struct ClusterMeta {
    offset: u64,
    nodes: u32,
    /// xxh3-64 of the cluster's bytes, checked on every decode.
    hash: u64,
}

/// A compressed BVH with its mesh and its decompressed-cluster cache.
pub struct RacBvh {
    header: Header,
    /// The clusters' bytes, concatenated.
    data: Store,
    meta: Vec<ClusterMeta>,
    mesh: mesh::PackedMesh,
    /// Checksum of the mesh sections, as stored (checked by `verify`).
    mesh_hash: u64,
    /// Mass properties at density 1, computed from the original mesh.
    mass: crate::codec::common::MassProps,
    /// Whether the mesh sections' checksum and vertex indices were checked
    /// and found good: done once, on the first triangle any query reads (or
    /// by `verify`), so a caller who skips `verify` still never gets
    /// triangles from damaged mesh bytes.
    mesh_ok: std::sync::OnceLock<Result<(), RacError>>,
    /// Active edges by triangle id: computed when encoded (set after
    /// [`assemble`](Self::assemble)), read from the file when opened.
    edges: EdgeFlags,
    cache: cache::ClusterCache,
    /// The decoded-node cache, when the budget cannot hold every cluster.
    nodes: Option<nodecache::NodeCache>,
    /// The budget the caller gave (the cluster cache has what the node
    /// cache leaves of it).
    budget: usize,
    /// Identifies this tree in the threads' pins.
    id: u64,
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

/// Figures of a compressed tree.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct RacStats {
    /// Nodes in the tree.
    pub nodes: u64,
    /// Clusters.
    pub cluster_count: u64,
    /// Bits per node spent on the tree structure (parents, sides, leaf
    /// flags, local-root pair indices, local-leaf children, triangle ids,
    /// cluster headers).
    pub bits_per_node_tree: f64,
    /// Bits per node spent on the boxes.
    pub bits_per_node_bv: f64,
    /// 32 bytes × nodes over the compressed tree (clusters + meta table).
    pub compression_ratio_vs_plain: f64,
    /// Stored mesh bytes per triangle.
    pub mesh_bytes_per_triangle: f64,
    /// Wall time of [`RacBvh::encode`] (0 for a tree read from bytes).
    pub compression_seconds: f64,
}

/// Compression settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RacOptions {
    /// Nodes per cluster: a power of two in 256..=16384 (4096 by default).
    /// A front end that sets the cache budget through
    /// [`AnyOptions::with_cache_budget`](crate::codec::AnyOptions::with_cache_budget)
    /// gets the size that budget suits
    /// ([`cluster_nodes_for_budget`](Self::cluster_nodes_for_budget));
    /// the encoder itself takes this value as it is.
    pub cluster_nodes: u32,
    /// Bits per quantized box coordinate, 8..=24 (16 by default).
    pub bits: u32,
    /// Bits per vertex coordinate, 8..=24, or `None` to keep `f32` vertices
    /// (16 by default).
    pub vertex_bits: Option<u32>,
    /// Byte budget of the decompressed-cluster cache (64 MiB by default).
    pub cache_budget_bytes: usize,
    /// Triangle-index deltas with `|delta| < threshold` are dictionary
    /// coded, others stored raw (§4.3.2; 10 by default, 1..=4096).
    pub tri_delta_threshold: u32,
}

impl Default for RacOptions {
    fn default() -> Self {
        Self {
            cluster_nodes: 4096,
            bits: 16,
            vertex_bits: Some(16),
            cache_budget_bytes: 64 << 20,
            tri_delta_threshold: 10,
        }
    }
}

/// How many clusters the cache budget should hold at least:
/// [`RacOptions::cluster_nodes_for_budget`] shrinks clusters (down to 256
/// nodes) until it does. A drop test's step
/// touches 6 to 72 distinct clusters of each tree (robot in plant, Lucy on
/// turbine, 256- to 4096-node clusters) and LRU needs head room above the
/// working set; a cache of a handful of 4096-node clusters re-decoded
/// clusters (0.2 ms each) dozens of times a step.
pub const RESIDENT_CLUSTERS: usize = 256;

/// The smallest cluster the format allows.
pub const MIN_CLUSTER_NODES: u32 = 256;

impl RacOptions {
    /// The cluster size that suits the cache budget:
    /// [`cluster_nodes`](Self::cluster_nodes), halved while the cache budget holds fewer than [`RESIDENT_CLUSTERS`]
    /// decoded clusters of that size (34 bytes a node), down to 256 nodes.
    /// Compression loses little (a 200 k-triangle statue: 8.0:1 at 4096
    /// nodes, 7.8:1 at 1024, 7.1:1 at 256) and a small cache then holds
    /// the tree's working set instead of a few clusters mostly not touched.
    pub fn cluster_nodes_for_budget(&self) -> u32 {
        let mut c = self.cluster_nodes;
        while c > MIN_CLUSTER_NODES
            && self.cache_budget_bytes / (c as usize * decode::CLUSTER_BYTES_PER_NODE)
                < RESIDENT_CLUSTERS
        {
            c /= 2;
        }
        c
    }

    /// `cluster_nodes` as a setting (`racbvh.cluster-nodes`): a power of
    /// two from 256 ([`MIN_CLUSTER_NODES`]) to 16384.
    pub const CLUSTER_NODES: Setting =
        Setting::power_of_two("cluster-nodes", MIN_CLUSTER_NODES as u64, 16384);

    /// `bits` as a setting (`racbvh.bits`): 8 to 24.
    pub const BITS: Setting = Setting::whole("bits", 8, 24);

    /// `tri_delta_threshold` as a setting (`racbvh.tri-delta-threshold`):
    /// 1 to 4096.
    pub const TRI_DELTA_THRESHOLD: Setting = Setting::whole("tri-delta-threshold", 1, 4096);

    /// The bits `vertex_bits` may give: 8 to 24.
    pub const VERTEX_BIT_RANGE: Values = Values::whole(8, 24);

    /// Checks every field, against the bounds its setting declares
    /// ([`RacOptions::CLUSTER_NODES`], [`RacOptions::BITS`],
    /// [`RacOptions::TRI_DELTA_THRESHOLD`], [`RacOptions::VERTEX_BIT_RANGE`]).
    pub fn validate(&self) -> Result<(), RacError> {
        let check = |what, value: u32, values: Values| {
            allowed(
                values.allows(u64::from(value)),
                what,
                value,
                values.to_string(),
            )
        };
        check(
            "cluster_nodes",
            self.cluster_nodes,
            Self::CLUSTER_NODES.values,
        )?;
        check("bits", self.bits, Self::BITS.values)?;
        if let Some(b) = self.vertex_bits {
            let expected = format!(
                "{}, or None for lossless f32 vertices",
                Self::VERTEX_BIT_RANGE
            );
            allowed(
                Self::VERTEX_BIT_RANGE.allows(u64::from(b)),
                "vertex_bits",
                b,
                expected,
            )?;
        }
        check(
            "tri_delta_threshold",
            self.tri_delta_threshold,
            Self::TRI_DELTA_THRESHOLD.values,
        )
    }
}

impl CodecOptions for RacOptions {
    const SETTINGS: &'static [Setting] =
        &[Self::CLUSTER_NODES, Self::BITS, Self::TRI_DELTA_THRESHOLD];
    const VERTEX_BITS: Option<Values> = Some(RacOptions::VERTEX_BIT_RANGE);

    /// The options from a front end's settings ([`crate::codec::settings`]):
    /// `racbvh.cluster-nodes`, `racbvh.bits`, `racbvh.tri-delta-threshold`,
    /// and the common `vertex_bits` (16 by default, 0 for `f32`). Checked
    /// as [`RacOptions::validate`] checks them.
    fn from_settings(s: &Settings) -> Result<Self, SettingsError> {
        let d = Self::default();
        let o = Self {
            cluster_nodes: s
                .get("racbvh", Self::CLUSTER_NODES.key)?
                .unwrap_or(d.cluster_nodes),
            bits: s.get("racbvh", Self::BITS.key)?.unwrap_or(d.bits),
            tri_delta_threshold: s
                .get("racbvh", Self::TRI_DELTA_THRESHOLD.key)?
                .unwrap_or(d.tri_delta_threshold),
            vertex_bits: s.vertex_bits_or(d.vertex_bits),
            ..d
        };
        o.validate().map_err(|e| SettingsError::Invalid {
            codec: "racbvh".into(),
            reason: e.to_string(),
        })?;
        Ok(o)
    }
}

/// `Ok` when `ok`, else the [`RacError::Option`] that says the option
/// `what` may not be `value` and what to use instead (`expected`).
fn allowed(ok: bool, what: &'static str, value: u32, expected: String) -> Result<(), RacError> {
    if ok {
        Ok(())
    } else {
        Err(RacError::Option {
            what,
            value: u64::from(value),
            expected,
        })
    }
}

impl RacBvh {
    fn assemble(
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

    /// The same tree over the same bytes with an empty cache of `budget`
    /// bytes: a memory-mapped file stays mapped (shared, not copied), and
    /// the mesh check already done is kept.
    pub fn with_cache_budget(&self, budget: usize) -> RacBvh {
        let mut t = Self::assemble(
            self.header,
            self.data.clone(),
            self.meta.clone(),
            self.mesh.clone(),
            self.mesh_hash,
            self.mass,
            budget,
        );
        t.edges = self.edges.clone();
        if let Some(checked) = self.mesh_ok.get() {
            t.mesh_ok.set(checked.clone()).ok();
        }
        t
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
    fn expect_mesh(&self) {
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
/// (see the module docs of [`racbvh`](crate::codec::racbvh), "Node
/// cache", for the measurements that chose it).
pub const CLUSTER_CACHE_PERCENT: usize = 10;

/// How many sets (of entries with `ids` triangle ids) the node cache gets
/// under `budget`, for a tree of `nodes` nodes in `clusters` clusters:
/// none if the budget holds every cluster decoded (at least 34 bytes a
/// node and 128 a cluster); else the budget but the cluster cache's
/// [`CLUSTER_CACHE_PERCENT`], and no more sets than give every node a way.
fn node_cache_sets(budget: usize, nodes: u32, clusters: usize, ids: usize) -> usize {
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
