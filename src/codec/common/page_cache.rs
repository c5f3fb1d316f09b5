//! [`PageCache`]: decoded pieces of a compressed tree (RACBVH's clusters,
//! o-HCCMesh's low-level trees), kept in `lru::LruCache` shards behind
//! mutexes, each with a share of a byte budget, and per thread a few
//! pinned pages ([`PINS`]) read without the shards' locks.
//!
//! A page type says how big it is and names its own thread-local pin table
//! ([`Page::pins`]), so the pins stay typed (no downcast on the hot path)
//! while the cache's code is written once.

use std::cell::RefCell;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::LocalKey;

use lru::LruCache;

/// A decoded piece a [`PageCache`] holds.
pub trait Page: Send + Sync + Sized + 'static {
    /// In-core bytes of the page.
    fn bytes(&self) -> usize;

    /// This page type's thread-local pin table; implement it as
    /// `thread_local!` inside the function, returning the key:
    ///
    /// ```text
    /// fn pins() -> &'static LocalKey<RefCell<Pins<Self>>> {
    ///     thread_local!(static P: RefCell<Pins<MyPage>> = const { RefCell::new(no_pins()) });
    ///     &P
    /// }
    /// ```
    fn pins() -> &'static LocalKey<RefCell<Pins<Self>>>;
}

/// Counters of live decoded pages, shared by a cache and its pages.
#[derive(Default, Debug)]
pub struct Live {
    bytes: AtomicUsize,
    peak: AtomicUsize,
}

impl Live {
    /// Records a new page of `n` bytes; the token takes it off when the
    /// page (which holds the token) is dropped.
    pub fn token(self: &Arc<Self>, n: usize) -> LiveToken {
        let now = self.bytes.fetch_add(n, Ordering::Relaxed) + n;
        self.peak.fetch_max(now, Ordering::Relaxed);
        LiveToken {
            live: self.clone(),
            bytes: n,
        }
    }
}

/// A page's share of [`Live`]: its bytes, counted while it lives.
#[derive(Debug)]
pub struct LiveToken {
    live: Arc<Live>,
    bytes: usize,
}

impl LiveToken {
    /// The bytes counted.
    pub fn bytes(&self) -> usize {
        self.bytes
    }
}

impl Drop for LiveToken {
    fn drop(&mut self) {
        self.live.bytes.fetch_sub(self.bytes, Ordering::Relaxed);
    }
}

/// The cache's counters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct CacheStats {
    /// The byte budget.
    pub budget_bytes: usize,
    /// Bytes of the pages the cache holds now.
    pub cached_bytes: usize,
    /// Bytes of every decoded page alive now (cached, pinned by a thread,
    /// or in use).
    pub live_bytes: usize,
    /// The most `live_bytes` ever reached.
    pub peak_live_bytes: usize,
    /// Pages decoded.
    pub decodes: u64,
    /// Cache look-ups that found their page.
    pub hits: u64,
    /// Number of shards.
    pub shards: usize,
    /// Bytes of a cache of single decoded nodes kept beside the pages
    /// (RACBVH's node cache; 0 if none), included in `cached_bytes`,
    /// `live_bytes` and the budget.
    pub node_bytes: usize,
    /// Look-ups the node cache missed.
    pub node_misses: u64,
}

impl CacheStats {
    /// One line for reports: the budget, the decodes, the share of shared
    /// look-ups that hit (look-ups a thread's pins answer are not counted)
    /// and the peak of decoded bytes.
    pub fn summary(&self) -> String {
        let mib = |b: usize| b as f64 / (1 << 20) as f64;
        let budget = if self.budget_bytes == usize::MAX {
            "unlimited".to_string()
        } else {
            format!("{:.1} MiB", mib(self.budget_bytes))
        };
        let looks = self.hits + self.decodes;
        let nodes = if self.node_bytes > 0 {
            format!(
                " ({:.1} KiB of it a node cache, {} misses)",
                self.node_bytes as f64 / 1024.0,
                self.node_misses
            )
        } else {
            String::new()
        };
        format!(
            "{budget} budget{nodes}, {} decodes, {:.1} % of shared look-ups hit, peak {:.1} MiB decoded",
            self.decodes,
            100.0 * self.hits as f64 / looks.max(1) as f64,
            mib(self.peak_live_bytes)
        )
    }
}

/// Pages a shard can hold at least, when the budget allows one shard that
/// many.
pub const PAGES_PER_SHARD: usize = 64;

/// The most shards a cache has.
pub const MAX_SHARDS: usize = 16;

/// How many shards a cache of `budget` bytes for pages of at most
/// `max_page` bytes gets: up to [`MAX_SHARDS`], each able to hold at least
/// [`PAGES_PER_SHARD`] pages. Pages go to shards by number, each shard
/// evicts by its own LRU order, so a shard must hold a working set's share
/// with room to spare: with 16 pages a shard, the few pages of a step that
/// hash to one shard evict each other while other shards sit idle (and the
/// threads' pins, up to 16 pages each, could fill it).
pub fn shard_count(budget: usize, max_page: usize) -> usize {
    (budget / PAGES_PER_SHARD.saturating_mul(max_page.max(1))).clamp(1, MAX_SHARDS)
}

struct Shard<T> {
    lru: LruCache<u32, Arc<T>>,
    bytes: usize,
    /// Look-ups that found their page (counted under the shard's lock: a
    /// shared atomic counter would be a contention point of its own).
    hits: u64,
}

/// The sharded cache of pages numbered by `u32`.
pub struct PageCache<T> {
    shards: Vec<Mutex<Shard<T>>>,
    shard_budget: usize,
    budget: usize,
    live: Arc<Live>,
    decodes: AtomicU64,
}

impl<T: Page> PageCache<T> {
    /// A cache of `budget` bytes for pages of at most `max_page` bytes:
    /// [`shard_count`] shards, each with an equal share of the budget.
    pub fn new(budget: usize, max_page: usize) -> Self {
        let shards = shard_count(budget, max_page);
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

    /// The live-bytes counters new pages take a [`LiveToken`] from.
    pub fn live(&self) -> &Arc<Live> {
        &self.live
    }

    fn shard(&self, c: u32) -> std::sync::MutexGuard<'_, Shard<T>> {
        let m = &self.shards[c as usize % self.shards.len()];
        m.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The cached page `c`, if any (marked most recently used).
    pub fn get(&self, c: u32) -> Option<Arc<T>> {
        let mut s = self.shard(c);
        let hit = s.lru.get(&c).cloned();
        s.hits += u64::from(hit.is_some());
        hit
    }

    /// Puts a freshly decoded page in the cache, evicting the least
    /// recently used pages of its shard that nobody holds to stay within
    /// the budget, and returns the page to use (another thread's copy if it
    /// got there first). A page that does not fit (larger than the shard's
    /// budget, or every cached page held) is returned but not cached.
    pub fn insert(&self, c: u32, page: Arc<T>) -> Arc<T> {
        self.decodes.fetch_add(1, Ordering::Relaxed);
        let mut s = self.shard(c);
        if let Some(other) = s.lru.get(&c) {
            return other.clone();
        }
        let n = page.bytes();
        if n > self.shard_budget {
            return page;
        }
        let mut evicted = Vec::new();
        while s.bytes + n > self.shard_budget {
            // The least recently used page nobody holds (no thread's pin, no
            // traversal in progress): with the shard locked, no new holder
            // can appear.
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
                // Everything is held: use the new page without caching it.
                None => return page,
            }
        }
        s.bytes += n;
        s.lru.put(c, page.clone());
        drop(s);
        drop(evicted);
        page
    }

    /// Page `c` from the cache, or decoded by `decode` and put in it. The
    /// thread's pins are dropped before decoding (a pinned page is never
    /// evicted; with no pins of its own a thread adds at most the page it
    /// decodes to what the cache holds).
    pub fn get_or_decode<E>(
        &self,
        c: u32,
        decode: impl FnOnce() -> Result<T, E>,
    ) -> Result<Arc<T>, E> {
        if let Some(p) = self.get(c) {
            return Ok(p);
        }
        unpin::<T>();
        Ok(self.insert(c, Arc::new(decode()?)))
    }

    /// Drops every cached page.
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
            node_bytes: 0,
            node_misses: 0,
        }
    }
}

/// How many pages a thread keeps pinned per page type, direct-mapped by
/// page number: enough for a traversal's back-and-forth between a parent
/// page and its child pages to stay off the shared cache. Every look-up
/// that misses the pins takes a shard's lock and moves reference counts
/// that all threads share.
pub const PINS: usize = 16;

/// A thread's pinned pages of one type: (owner id, page number, page), in
/// slot `page number % PINS`.
pub type Pins<T> = [Option<(u64, u32, Arc<T>)>; PINS];

/// An empty pin table (for [`Page::pins`]'s `thread_local!`).
pub const fn no_pins<T>() -> Pins<T> {
    [const { None }; PINS]
}

/// A fresh owner id for [`with_pinned`] and [`pin`]: one per cache, so
/// that two trees' pages never meet in a thread's pins.
pub fn next_owner() -> u64 {
    static NEXT: AtomicU64 = AtomicU64::new(1);
    NEXT.fetch_add(1, Ordering::Relaxed)
}

/// Runs `f` on page `c` of `owner` if this thread has it pinned.
#[inline]
pub fn with_pinned<T: Page, R>(owner: u64, c: u32, f: impl FnOnce(&T) -> Option<R>) -> Option<R> {
    T::pins().with(|p| {
        let p = p.try_borrow().ok()?;
        match &p[c as usize % PINS] {
            Some((o, k, page)) if *o == owner && *k == c => f(page),
            _ => None,
        }
    })
}

/// Pins `page` for this thread (replacing the pin in its slot). Takes the
/// caller's reference rather than a clone: each reference-count change is a
/// write to a cache line every thread shares.
pub fn pin<T: Page>(owner: u64, c: u32, page: Arc<T>) {
    T::pins().with(|p| {
        if let Ok(mut p) = p.try_borrow_mut() {
            let slot = &mut p[c as usize % PINS];
            if matches!(slot, Some((o, k, _)) if *o == owner && *k == c) {
                return;
            }
            let old = slot.replace((owner, c, page));
            drop(p);
            drop(old);
        }
    });
}

/// Drops this thread's pins of page type `T`.
pub fn unpin<T: Page>() {
    T::pins().with(|p| {
        let old = p
            .try_borrow_mut()
            .ok()
            .map(|mut p| std::mem::replace(&mut *p, no_pins()));
        drop(old);
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    struct P {
        _live: LiveToken,
        n: usize,
    }

    impl Page for P {
        fn bytes(&self) -> usize {
            self.n
        }
        fn pins() -> &'static LocalKey<RefCell<Pins<Self>>> {
            thread_local!(static PINNED: RefCell<Pins<P>> = const { RefCell::new(no_pins()) });
            &PINNED
        }
    }

    fn page(c: &PageCache<P>, n: usize) -> P {
        P {
            _live: c.live().token(n),
            n,
        }
    }

    #[test]
    fn the_budget_evicts_the_least_recently_used_page_nobody_holds() {
        let c = PageCache::<P>::new(300, 100);
        for k in 0..3 {
            c.insert(k, Arc::new(page(&c, 100)));
        }
        assert!(c.get(0).is_some()); // 0 is now the most recent
        let held = c.get(1).unwrap(); // 1 is held
        c.insert(3, Arc::new(page(&c, 100)));
        // 2 was the least recently used page nobody held.
        assert!(c.get(2).is_none());
        assert!(c.get(1).is_some() && c.get(0).is_some() && c.get(3).is_some());
        let s = c.stats();
        assert_eq!(s.cached_bytes, 300);
        assert_eq!(s.live_bytes, 300);
        assert_eq!(s.peak_live_bytes, 400);
        assert_eq!(s.decodes, 4);
        drop(held);
    }

    #[test]
    fn a_page_larger_than_the_budget_is_used_but_not_cached() {
        let c = PageCache::<P>::new(100, 100);
        let p = c.insert(7, Arc::new(page(&c, 150)));
        assert_eq!(p.bytes(), 150);
        assert!(c.get(7).is_none());
        drop(p);
        assert_eq!(c.stats().live_bytes, 0);
    }

    #[test]
    fn each_shard_holds_at_least_64_pages_when_the_budget_allows() {
        // Less than 64 pages' worth: one shard with the whole budget.
        assert_eq!(shard_count(63 * 100, 100), 1);
        assert_eq!(shard_count(0, 100), 1);
        assert_eq!(shard_count(1000, 0), 1000 / 64); // (pages of at least a byte)
        // 64 pages a shard, up to 16 shards.
        assert_eq!(shard_count(64 * 100, 100), 1);
        assert_eq!(shard_count(4 * 64 * 100 + 99, 100), 4);
        assert_eq!(shard_count(usize::MAX, 1 << 20), MAX_SHARDS);
        assert_eq!(shard_count(usize::MAX, usize::MAX), 1);
        for (budget, page) in [(6400, 100), (1 << 20, 8704), (13 << 20, 139_392)] {
            let c = PageCache::<P>::new(budget, page);
            let s = c.stats().shards;
            assert!(
                s == 1 || budget / s >= PAGES_PER_SHARD * page,
                "{budget} {page} {s}"
            );
        }
    }

    #[test]
    fn a_repeated_working_set_that_fits_hits_after_its_first_round() {
        // 40 pages of 100 bytes in a 64-page budget, looked up round after
        // round in the same order: each is decoded once.
        let c = PageCache::<P>::new(6400, 100);
        for _ in 0..10 {
            for k in 0..40 {
                drop(c.get_or_decode::<()>(k, || Ok(page(&c, 100))).unwrap());
            }
        }
        let s = c.stats();
        assert_eq!(s.decodes, 40);
        assert_eq!(s.hits, 9 * 40);
        unpin::<P>();
    }

    #[test]
    fn pins_are_per_owner_and_page() {
        let c = PageCache::<P>::new(1000, 100);
        let p = c.get_or_decode::<()>(5, || Ok(page(&c, 10))).unwrap();
        let (a, b) = (next_owner(), next_owner());
        pin(a, 5, p);
        assert_eq!(with_pinned::<P, _>(a, 5, |p| Some(p.n)), Some(10));
        assert_eq!(with_pinned::<P, _>(b, 5, |p| Some(p.n)), None);
        assert_eq!(with_pinned::<P, _>(a, 21, |p| Some(p.n)), None);
        unpin::<P>();
        assert_eq!(with_pinned::<P, _>(a, 5, |p| Some(p.n)), None);
    }
}
