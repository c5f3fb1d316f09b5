//! The decompressed-cluster cache (§5.3): the shared
//! [`PageCache`](crate::codec::common::page_cache::PageCache) of
//! [`Cluster`]s, with this codec's pin table.
//!
//! When the budget cannot hold every cluster, the cluster cache gets
//! [`CLUSTER_CACHE_PERCENT`](super::CLUSTER_CACHE_PERCENT) of it and the
//! rest goes to the node cache (`nodecache.rs`), which every read of a
//! node asks first: then this cache serves only the node cache's misses,
//! and a cluster decoded for one is kept for its neighbours (a traversal
//! that enters new ground reads a parent's children, then theirs, mostly
//! in the same cluster). [`RacBvh::cache_stats`](super::RacBvh::cache_stats)
//! reports both: the budget the caller gave, and the node table's bytes in
//! `cached_bytes`, `live_bytes` and `node_bytes`.

use std::cell::RefCell;
use std::thread::LocalKey;

use super::decode::Cluster;
pub use crate::codec::common::page_cache::{CacheStats, pin, with_pinned};
use crate::codec::common::page_cache::{Page, PageCache, Pins, no_pins};

/// The cluster cache.
pub type ClusterCache = PageCache<Cluster>;

impl Page for Cluster {
    fn bytes(&self) -> usize {
        self.live.bytes()
    }

    fn pins() -> &'static LocalKey<RefCell<Pins<Self>>> {
        thread_local!(static PINNED: RefCell<Pins<Cluster>> = const { RefCell::new(no_pins()) });
        &PINNED
    }
}
