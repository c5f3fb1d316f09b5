//! The decompressed-cluster cache (§5.3): the shared
//! [`PageCache`](crate::codec::common::page_cache::PageCache) of
//! [`Cluster`]s, with this codec's pin table.

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
