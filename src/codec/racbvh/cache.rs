//! The decompressed-cluster cache (§5.3): `lru::LruCache` shards behind
//! mutexes, each with a share of the byte budget, and per thread a few
//! pinned clusters ([`PINS`]) read without the shards' locks.

use std::cell::RefCell;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use lru::LruCache;

use super::decode::Cluster;

/// Counters of live decoded clusters, shared by a cache and its clusters.
#[derive(Default, Debug)]
pub struct Live {
    bytes: AtomicUsize,
    peak: AtomicUsize,
}

impl Live {
    /// Records a new cluster of `n` bytes.
    pub fn add(&self, n: usize) {
        let now = self.bytes.fetch_add(n, Ordering::Relaxed) + n;
        self.peak.fetch_max(now, Ordering::Relaxed);
    }

    /// Records a dropped cluster of `n` bytes.
    pub fn sub(&self, n: usize) {
        self.bytes.fetch_sub(n, Ordering::Relaxed);
    }
}

/// The cache's counters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct CacheStats {
    /// The byte budget.
    pub budget_bytes: usize,
    /// Bytes of the clusters the cache holds now.
    pub cached_bytes: usize,
    /// Bytes of every decoded cluster alive now (cached, pinned by a
    /// thread, or in use).
    pub live_bytes: usize,
    /// The most `live_bytes` ever reached.
    pub peak_live_bytes: usize,
    /// Clusters decompressed.
    pub decodes: u64,
    /// Cache look-ups that found their cluster.
    pub hits: u64,
    /// Number of shards.
    pub shards: usize,
}

struct Shard {
    lru: LruCache<u32, Arc<Cluster>>,
    bytes: usize,
    /// Look-ups that found their cluster (counted under the shard's lock:
    /// a shared atomic counter would be a contention point of its own).
    hits: u64,
}

/// The sharded cache.
pub struct ClusterCache {
    shards: Vec<Mutex<Shard>>,
    shard_budget: usize,
    budget: usize,
    pub(super) live: Arc<Live>,
    decodes: AtomicU64,
}

impl ClusterCache {
    /// A cache of `budget` bytes for clusters of at most `max_cluster` bytes:
    /// up to 16 shards, each able to hold at least 16 clusters (so that the
    /// threads' pins rarely fill a shard).
    pub fn new(budget: usize, max_cluster: usize) -> Self {
        let shards = (budget / (16 * max_cluster.max(1))).clamp(1, 16);
        Self {
            shards: (0..shards)
                .map(|_| {
                    Mutex::new(Shard {
                        lru: LruCache::unbounded(),
                        bytes: 0,
                        hits: 0,
                    })
                })
                .collect(),
            shard_budget: budget / shards,
            budget,
            live: Arc::new(Live::default()),
            decodes: AtomicU64::new(0),
        }
    }

    fn shard(&self, c: u32) -> std::sync::MutexGuard<'_, Shard> {
        let m = &self.shards[c as usize % self.shards.len()];
        m.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The cached cluster `c`, if any (marked most recently used).
    pub fn get(&self, c: u32) -> Option<Arc<Cluster>> {
        let mut s = self.shard(c);
        let hit = s.lru.get(&c).cloned();
        s.hits += u64::from(hit.is_some());
        hit
    }

    /// Puts a freshly decoded cluster in the cache, evicting the least
    /// recently used clusters of its shard that nobody holds to stay within
    /// the budget, and returns the cluster to use (another thread's copy if
    /// it got there first). A cluster that does not fit (larger than the
    /// shard's budget, or every cached cluster held) is returned but not
    /// cached.
    pub fn insert(&self, c: u32, cl: Arc<Cluster>) -> Arc<Cluster> {
        self.decodes.fetch_add(1, Ordering::Relaxed);
        let mut s = self.shard(c);
        if let Some(other) = s.lru.get(&c) {
            return other.clone();
        }
        let n = cl.bytes();
        if n > self.shard_budget {
            return cl;
        }
        let mut evicted = Vec::new();
        while s.bytes + n > self.shard_budget {
            // The least recently used cluster nobody holds (no thread's pin,
            // no traversal in progress): with the shard locked, no new
            // holder can appear.
            let victim = s
                .lru
                .iter()
                .rev()
                .find(|(_, v)| Arc::strong_count(v) == 1)
                .map(|(k, _)| *k);
            match victim.and_then(|k| s.lru.pop(&k)) {
                Some(old) => {
                    s.bytes -= old.bytes();
                    evicted.push(old);
                }
                // Everything is held: use the new cluster without caching it.
                None => return cl,
            }
        }
        s.bytes += n;
        s.lru.put(c, cl.clone());
        drop(s);
        drop(evicted);
        cl
    }

    /// Drops every cached cluster.
    pub fn clear(&self) {
        for m in &self.shards {
            let mut s = m.lock().unwrap_or_else(|e| e.into_inner());
            s.lru.clear();
            s.bytes = 0;
        }
    }

    /// The counters.
    pub fn stats(&self) -> CacheStats {
        let (mut cached, mut hits) = (0, 0);
        for m in &self.shards {
            let s = m.lock().unwrap_or_else(|e| e.into_inner());
            cached += s.bytes;
            hits += s.hits;
        }
        CacheStats {
            budget_bytes: self.budget,
            cached_bytes: cached,
            live_bytes: self.live.bytes.load(Ordering::Relaxed),
            peak_live_bytes: self.live.peak.load(Ordering::Relaxed),
            decodes: self.decodes.load(Ordering::Relaxed),
            hits,
            shards: self.shards.len(),
        }
    }
}

/// How many clusters a thread keeps pinned, direct-mapped by cluster
/// index: enough for a traversal's back-and-forth between a parent
/// cluster and its child clusters to stay off the shared cache. Every
/// look-up that misses the pins takes a shard's lock and moves reference
/// counts that all threads share (see the module docs for the figures).
pub const PINS: usize = 16;

/// A thread's pinned clusters: (tree id, cluster index, cluster), in slot
/// `cluster index % PINS`.
type Pins = [Option<(u64, u32, Arc<Cluster>)>; PINS];

thread_local! {
    static PIN: RefCell<Pins> = const { RefCell::new([const { None }; PINS]) };
}

/// Runs `f` on cluster `c` of tree `owner` if this thread has it pinned.
#[inline]
pub fn with_pinned<R>(owner: u64, c: u32, f: impl FnOnce(&Cluster) -> Option<R>) -> Option<R> {
    PIN.with(|p| {
        let p = p.try_borrow().ok()?;
        match &p[c as usize % PINS] {
            Some((o, k, cl)) if *o == owner && *k == c => f(cl),
            _ => None,
        }
    })
}

/// Pins `cl` for this thread (replacing the pin in its slot). Takes the
/// caller's reference rather than a clone: each reference-count change is a
/// write to a cache line every thread shares.
pub fn pin(owner: u64, c: u32, cl: Arc<Cluster>) {
    PIN.with(|p| {
        if let Ok(mut p) = p.try_borrow_mut() {
            let slot = &mut p[c as usize % PINS];
            if matches!(slot, Some((o, k, _)) if *o == owner && *k == c) {
                return;
            }
            let old = slot.replace((owner, c, cl));
            drop(p);
            drop(old);
        }
    });
}

/// Drops this thread's pins (before decoding a cluster: a pinned cluster
/// is never evicted, and with no pins of its own a thread adds at most the
/// cluster it decodes to what the cache holds).
pub fn unpin() {
    PIN.with(|p| {
        let old = p
            .try_borrow_mut()
            .ok()
            .map(|mut p| std::mem::replace(&mut *p, [const { None }; PINS]));
        drop(old);
    });
}
