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
//! - **Quantization** (one [`Grid`](crate::codec::common::quant::Grid)):
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
mod tree;
mod tricache;
mod verify;

pub use cache::CacheStats;
pub use cursor::RacNode;
pub use encode::{MIN_CLUSTER_NODES, RESIDENT_CLUSTERS, RacOptions, RacStats};
pub use error::RacError;
pub use node::{CoreNode, INCOMPLETE};
pub use stream::{StreamedBuild, encode_streamed};
pub use tree::{CLUSTER_CACHE_PERCENT, RacBvh};

use context::*;
use tree::{ClusterMeta, Header};
