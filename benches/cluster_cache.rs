//! The shared decompressed-cluster cache under parallel random access:
//! `lru::LruCache` shards behind mutexes (the codec's own
//! `codec::common::page_cache::PageCache`, which RACBVH and o-HCCMesh use)
//! against `quick_cache::sync::Cache`, both under a byte budget,
//! driven by the same trace of cluster look-ups from real ray traversals.
//!
//! The trace: closest-hit rays (random rays from a sphere around the model
//! towards random points of its box, as `examples/racbvh_stats.rs` shoots
//! them) traverse the plain BVH of a generated statue (`CBVH_BENCH_TRIS`,
//! default 1 000 000 triangles, default build); every node whose box the
//! traversal reads (the root, and both children of each node it opens) maps
//! to its RACBVH cluster, `node >> log2(cluster_nodes)` (RACBVH keeps the
//! layout order). The rays are dealt round-robin to the threads, and each
//! thread's sequence goes through a model of the codec's per-thread pins
//! (16 clusters, direct-mapped by cluster index, are read without the
//! shared cache), so
//! what is replayed is what reaches the shared cache (the codec also drops
//! a thread's pins when it decodes; the model does not). `CBVH_CACHE_RAYS`
//! sets the ray count (default 20 000).
//!
//! On a miss the thread really decompresses the cluster
//! (`RacBvh::decode_cluster_uncached`, about 0.3 ms) and caches a value of
//! the decoded cluster's in-core size (34 bytes per node, `Arc<Vec<u8>>`).
//! Budgets, as in `examples/racbvh_stats.rs`: `all` is 48 bytes per node of
//! every cluster (every cluster fits, in either cache's shards), `quarter`
//! a quarter of that, replaying only the first `CBVH_CACHE_QUARTER_RAYS`
//! rays (default 1 500: there the decodes dominate the time). Both caches
//! are warmed with two replays before timing (the quarter budget runs in
//! steady state). Threads: 1, 2, and 8 (oversubscribed on small machines).
//! Throughput is cluster look-ups per second.
//!
//! ```text
//! cargo bench --features sims --bench cluster_cache             # about 2 min with setup
//! cargo bench --features sims --bench cluster_cache -- --quick  # a faster, rougher pass
//! cargo bench --features sims --bench cluster_cache -- all/     # only the all-fit budget
//! ```
//! Misses, decodes and hit rates of both caches are printed before the
//! timings (quick_cache's eviction is not LRU, so its hit rate differs).

use std::hint::black_box;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use cbvh::build::{BuildOptions, build};
use cbvh::codec::plain::PlainBvh;
use cbvh::codec::racbvh::{RacBvh, RacOptions};
use cbvh::cursor::NodeCursor;
use cbvh::geom::{Aabb, Triangle};
use cbvh::query::RayCursor;
use cbvh::scene::{Kind, generate};
use cbvh::{TraversalStats, query};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3A;

/// The rays of `examples/racbvh_stats.rs`.
#[path = "../examples/support/rays.rs"]
mod ray_sets;
use cbvh::codec::common::page_cache::{Page, PageCache, Pins, no_pins};
use std::cell::RefCell;
use std::thread::LocalKey;

/// In-core bytes per node of a decoded cluster (the codec's
/// `CLUSTER_BYTES_PER_NODE`: the 32-byte node and its local root's ordinal).
const CLUSTER_BYTES_PER_NODE: usize = 34;

/// Per-thread pins of the codec (`cache::PINS`), direct-mapped by cluster
/// index.
const PINS: usize = 16;

/// A cached cluster value.
type Value = Arc<Blob>;

fn env_usize(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

/// A plain-BVH cursor that logs the cluster of every node whose box it
/// hands out.
struct Recorder<'a> {
    plain: &'a PlainBvh,
    shift: u32,
    log: Mutex<Vec<u32>>,
}

impl Recorder<'_> {
    fn note(&self, node: u32) {
        self.log.lock().unwrap().push(node >> self.shift);
    }
}

impl NodeCursor for Recorder<'_> {
    type Node = u32;

    fn root(&self) -> (u32, Aabb) {
        self.note(0);
        self.plain.root()
    }

    fn is_leaf(&self, node: &u32) -> bool {
        self.plain.is_leaf(node)
    }

    fn for_each_child(&self, node: &u32, mut f: impl FnMut(u32, Aabb)) {
        self.plain.for_each_child(node, |c, b| {
            self.note(c);
            f(c, b)
        });
    }

    fn for_each_triangle(&self, node: &u32, f: impl FnMut(u32, &Triangle)) {
        self.plain.for_each_triangle(node, f);
    }

    fn triangle(&self, id: u32) -> Triangle {
        self.plain.triangle(id)
    }

    fn triangle_count(&self) -> usize {
        self.plain.triangle_count()
    }
}

/// The generic ray traversals (which log through the methods above).
impl RayCursor for Recorder<'_> {}

/// The look-ups one thread sends to the shared cache: its rays' cluster
/// accesses, minus those its [`PINS`] direct-mapped pins serve.
fn thread_trace(per_ray: &[Vec<u32>], thread: usize, threads: usize) -> Vec<u32> {
    let mut pins = [u32::MAX; PINS];
    let mut out = Vec::new();
    for ray in per_ray.iter().skip(thread).step_by(threads) {
        for &c in ray {
            let slot = &mut pins[c as usize % PINS];
            if *slot == c {
                // A pinned cluster: no look-up.
                continue;
            }
            out.push(c);
            *slot = c;
        }
    }
    out
}

/// The cache under test.
trait ClusterCache: Sync {
    fn get(&self, c: u32) -> Option<Value>;
    fn insert(&self, c: u32, v: Value) -> Value;
}

/// A decoded cluster's stand-in: its in-core bytes.
struct Blob(Vec<u8>);

impl Page for Blob {
    fn bytes(&self) -> usize {
        self.0.len()
    }

    fn pins() -> &'static LocalKey<RefCell<Pins<Self>>> {
        thread_local!(static PINNED: RefCell<Pins<Blob>> = const { RefCell::new(no_pins()) });
        &PINNED
    }
}

/// The codec's own cache (`codec::common::page_cache`, as RACBVH uses
/// it): up to 16 `Mutex<LruCache>` shards (one per 16 clusters of
/// budget), each with an equal share of the budget, evicting its least
/// recently used unheld clusters.
type Sharded = PageCache<Blob>;

impl ClusterCache for Sharded {
    fn get(&self, c: u32) -> Option<Value> {
        PageCache::get(self, c)
    }

    fn insert(&self, c: u32, v: Value) -> Value {
        PageCache::insert(self, c, v)
    }
}

/// Weighs a cluster by its bytes.
#[derive(Clone)]
struct Bytes;

impl quick_cache::Weighter<u32, Value> for Bytes {
    fn weight(&self, _: &u32, v: &Value) -> u64 {
        v.0.len() as u64
    }
}

/// `quick_cache::sync::Cache` weighed in bytes, with its default shard
/// count and hasher; a miss decodes outside the cache, then inserts (the same protocol
/// as the sharded cache).
struct Quick {
    cache: quick_cache::sync::Cache<u32, Value, Bytes>,
    decodes: AtomicU64,
}

impl Quick {
    fn new(budget: usize, clusters: usize) -> Self {
        Self {
            cache: quick_cache::sync::Cache::with_weighter(clusters, budget as u64, Bytes),
            decodes: AtomicU64::new(0),
        }
    }
}

impl ClusterCache for Quick {
    fn get(&self, c: u32) -> Option<Value> {
        self.cache.get(&c)
    }

    fn insert(&self, c: u32, v: Value) -> Value {
        self.decodes.fetch_add(1, Ordering::Relaxed);
        self.cache.insert(c, v.clone());
        v
    }
}

/// Looks up every cluster of `trace`, decoding and inserting misses.
fn replay(cache: &impl ClusterCache, rac: &RacBvh, trace: &[u32]) -> u64 {
    let mut sum = 0u64;
    for &c in trace {
        let v = match cache.get(c) {
            Some(v) => v,
            None => {
                let nodes = rac.decode_cluster_uncached(c).expect("decode");
                let v: Value = Arc::new(Blob(vec![1u8; nodes * CLUSTER_BYTES_PER_NODE]));
                cache.insert(c, v)
            }
        };
        sum += u64::from(v.0[v.0.len() - 1]);
    }
    sum
}

/// Replays each thread's trace on its own thread, all on `cache`.
fn run(cache: &impl ClusterCache, rac: &RacBvh, traces: &[Vec<u32>]) -> u64 {
    std::thread::scope(|s| {
        let hs: Vec<_> = traces
            .iter()
            .map(|t| s.spawn(move || replay(cache, rac, t)))
            .collect();
        hs.into_iter().map(|h| h.join().unwrap()).sum()
    })
}

fn bench(c: &mut Criterion) {
    let tris = env_usize("CBVH_BENCH_TRIS", 1_000_000);
    let nrays = env_usize("CBVH_CACHE_RAYS", 20_000);
    let mesh = generate(Kind::Statue, tris, 0, &mut |_, _| {}).expect("generate");
    let bvh = build(&mesh, &BuildOptions::default(), &|_, _| {}).expect("build");
    let rac = RacBvh::encode(&bvh, &mesh, &RacOptions::default()).expect("encode");
    let plain = PlainBvh::new(&bvh, &mesh);
    let cn = rac.cluster_nodes() as usize;
    let clusters = rac.cluster_count();
    let rec = Recorder {
        plain: &plain,
        shift: cn.trailing_zeros(),
        log: Mutex::new(Vec::new()),
    };
    let (lo, hi) = mesh.bounds().expect("non-empty");
    let per_ray: Vec<Vec<u32>> = ray_sets::random_rays(Vec3A::from(lo), Vec3A::from(hi), nrays)
        .iter()
        .map(|r| {
            query::closest_hit(&rec, r, f32::INFINITY, &mut TraversalStats::default());
            std::mem::take(&mut *rec.log.lock().unwrap())
        })
        .collect();
    let raw: usize = per_ray.iter().map(Vec::len).sum();
    let max_cluster = cn * CLUSTER_BYTES_PER_NODE;
    // As `examples/racbvh_stats.rs`: 48 bytes per node of every cluster, so
    // that every cluster fits even in a fuller than average shard.
    let all_bytes = clusters * cn * 48;
    let quarter_rays = env_usize("CBVH_CACHE_QUARTER_RAYS", 1_500).min(per_ray.len());
    eprintln!(
        "statue {tris} triangles, {} nodes, {clusters} clusters of {cn} nodes ({} KiB decoded), \
         {nrays} rays, {raw} node-box reads",
        rac.node_count(),
        max_cluster / 1024
    );

    let mut g = c.benchmark_group("cluster_cache");
    g.sample_size(10);
    let budgets = [
        ("all", all_bytes, &per_ray[..], 500, 2_000),
        (
            "quarter",
            all_bytes / 4,
            &per_ray[..quarter_rays],
            100,
            3_000,
        ),
    ];
    for (budget_name, budget, rays, warm_ms, measure_ms) in budgets {
        g.warm_up_time(Duration::from_millis(warm_ms))
            .measurement_time(Duration::from_millis(measure_ms));
        for threads in [1usize, 2, 8] {
            let traces: Vec<Vec<u32>> = (0..threads)
                .map(|k| thread_trace(rays, k, threads))
                .collect();
            let lookups: usize = traces.iter().map(Vec::len).sum();
            g.throughput(Throughput::Elements(lookups as u64));

            let sharded = Sharded::new(budget, max_cluster);
            run(&sharded, &rac, &traces);
            let warm = sharded.stats();
            run(&sharded, &rac, &traces);
            let done = sharded.stats();
            let (d1, h1) = (done.decodes - warm.decodes, done.hits - warm.hits);
            let quick = Quick::new(budget, clusters);
            run(&quick, &rac, &traces);
            let q0 = quick.decodes.load(Ordering::Relaxed);
            run(&quick, &rac, &traces);
            let q1 = quick.decodes.load(Ordering::Relaxed) - q0;
            eprintln!(
                "budget {budget_name} ({} KiB), {threads} threads: {lookups} look-ups per replay; \
                 warm replay misses: lru-sharded {d1} ({:.3}% , {} shards, {h1} hits), \
                 quick_cache {q1} ({:.3}%)",
                budget / 1024,
                100.0 * d1 as f64 / lookups as f64,
                done.shards,
                100.0 * q1 as f64 / lookups as f64,
            );

            let id = format!("{budget_name}/{threads}t");
            g.bench_function(BenchmarkId::new("lru-sharded", &id), |b| {
                b.iter(|| black_box(run(&sharded, &rac, &traces)))
            });
            g.bench_function(BenchmarkId::new("quick_cache", &id), |b| {
                b.iter(|| black_box(run(&quick, &rac, &traces)))
            });
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
