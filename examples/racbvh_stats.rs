//! RACBVH compression figures (the paper's Table 1 columns) and runtime
//! throughput against the plain codec, measured side by side in one run.
//!
//! ```text
//! cargo run --release --features sims --example racbvh_stats -- [tris] [layout] [bits] [cluster_nodes] [--json]
//! cargo run --release --features sims --example racbvh_stats -- 1000000 cache-efficient 16 4096
//! ```
//! Decompression and ray figures are single-threaded unless marked; the
//! decompression figure is the fastest of repeated sweeps over all clusters.

use std::time::Instant;

use cbvh::build::{BuildOptions, Layout, build};
use cbvh::codec::ByteSize;
use cbvh::codec::plain::PlainBvh;
use cbvh::codec::racbvh::{RacBvh, RacOptions};
use cbvh::geom::Ray;
use cbvh::scene::{Kind, generate};
use cbvh::{TraversalStats, query};
use glam::Vec3A;

#[path = "support/rays.rs"]
mod ray_sets;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).filter(|a| a != "--json").collect();
    let json = std::env::args().any(|a| a == "--json");
    let tris: usize = args
        .first()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1_000_000);
    let layout: Layout = args
        .get(1)
        .map_or(Layout::CacheEfficient, |s| s.parse().expect("layout"));
    let bits: u32 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(16);
    let cluster_nodes: u32 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(4096);

    let t = Instant::now();
    let mesh = generate(Kind::Statue, tris, 0, &mut |_, _| {}).expect("generate");
    let gen_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let bvh = build(
        &mesh,
        &BuildOptions {
            layout,
            ..Default::default()
        },
        &|_, _| {},
    )
    .expect("build");
    let build_s = t.elapsed().as_secs_f64();
    let opts = RacOptions {
        bits,
        cluster_nodes,
        ..Default::default()
    };
    let rac = RacBvh::encode(&bvh, &mesh, &opts).expect("encode");
    let st = rac.stats();
    let plain = PlainBvh::new(&bvh, &mesh);

    // Single-core decompression: every cluster, no cache; the fastest of
    // repeated sweeps (the machine is shared).
    let mut decode_nodes_per_s = 0f64;
    let t = Instant::now();
    while t.elapsed().as_secs_f64() < 2.0 {
        let t1 = Instant::now();
        let mut decoded = 0usize;
        for c in 0..rac.cluster_count() as u32 {
            decoded += rac.decode_cluster_uncached(c).expect("decode");
        }
        decode_nodes_per_s = decode_nodes_per_s.max(decoded as f64 / t1.elapsed().as_secs_f64());
    }
    if std::env::var_os("RACBVH_DECODE_ONLY").is_some() {
        println!(
            "bits/node tree {:.2}, BV {:.2}, ratio {:.2}:1, decompression (1 core) {:.1} M nodes/s",
            st.bits_per_node_tree,
            st.bits_per_node_bv,
            st.compression_ratio_vs_plain,
            decode_nodes_per_s / 1e6
        );
        return;
    }

    // Closest-hit rays, plain vs RACBVH (warm cache, default budget), one thread.
    let (lo, hi) = mesh.bounds().expect("non-empty");
    let rs = ray_sets::random_rays(Vec3A::from(lo), Vec3A::from(hi), 200_000);
    let time_rays = |f: &dyn Fn(&Ray) -> Option<u32>| {
        let t = Instant::now();
        let hits = rs.iter().filter(|r| f(r).is_some()).count();
        (rs.len() as f64 / t.elapsed().as_secs_f64(), hits)
    };
    let hit = |c: &dyn Fn(&Ray, &mut TraversalStats) -> Option<u32>, r: &Ray| {
        c(r, &mut TraversalStats::default())
    };
    let (plain_rps, plain_hits) = time_rays(&|r| {
        hit(
            &|r, s| query::closest_hit(&plain, r, f32::INFINITY, s).map(|h| h.triangle),
            r,
        )
    });
    // RACBVH with a cache that holds every cluster (warmed once), then with
    // one that holds a quarter of them.
    let full_budget = rac.cluster_count() * rac.cluster_nodes() as usize * 48;
    let warm = RacBvh::from_bytes(&rac.to_bytes(), full_budget).expect("reopen");
    for r in rs.iter().take(20_000) {
        query::closest_hit(&warm, r, f32::INFINITY, &mut TraversalStats::default());
    }
    let (rac_rps, rac_hits) = time_rays(&|r| {
        hit(
            &|r, s| query::closest_hit(&warm, r, f32::INFINITY, s).map(|h| h.triangle),
            r,
        )
    });
    // (RACBVH_SKIP_SMALL_CACHE skips the slow thrashing run, for profiling.)
    let small = RacBvh::from_bytes(&rac.to_bytes(), full_budget / 4).expect("reopen");
    let small_rps = if std::env::var_os("RACBVH_SKIP_SMALL_CACHE").is_some() {
        f64::NAN
    } else {
        time_rays(&|r| {
            hit(
                &|r, s| query::closest_hit(&small, r, f32::INFINITY, s).map(|h| h.triangle),
                r,
            )
        })
        .0
    };
    // All threads of the machine on one shared cache (warm), plain alongside.
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let parallel = |f: &(dyn Fn(&Ray) -> bool + Sync)| {
        let t = Instant::now();
        std::thread::scope(|s| {
            for k in 0..threads {
                let rs = &rs;
                s.spawn(move || rs.iter().skip(k).step_by(threads).filter(|r| f(r)).count());
            }
        });
        rs.len() as f64 / t.elapsed().as_secs_f64()
    };
    let plain_mt = parallel(&|r| {
        query::closest_hit(&plain, r, f32::INFINITY, &mut TraversalStats::default()).is_some()
    });
    let rac_mt = parallel(&|r| {
        query::closest_hit(&warm, r, f32::INFINITY, &mut TraversalStats::default()).is_some()
    });
    let cache = warm.cache_stats();
    let small_cache = small.cache_stats();
    let parts = rac.bytes_by_part();
    let plain_bytes = plain.bytes_by_part();

    if json {
        let v = serde_json::json!({
            "tris": mesh.triangles.len(), "nodes": bvh.nodes.len(), "layout": layout.name(),
            "bits": bits, "cluster_nodes": cluster_nodes,
            "stats": st, "parts": parts, "plain_parts": plain_bytes,
            "decode_nodes_per_s": decode_nodes_per_s,
            "plain_rays_per_s": plain_rps, "racbvh_rays_per_s": rac_rps,
            "racbvh_quarter_cache_rays_per_s": small_rps,
            "threads": threads, "plain_rays_per_s_all_threads": plain_mt,
            "racbvh_rays_per_s_all_threads": rac_mt,
            "hits": [plain_hits, rac_hits], "cache": cache, "quarter_cache": small_cache,
        });
        println!("{v}");
        return;
    }
    println!(
        "statue: {} triangles, {} nodes, layout {layout}, {bits}-bit boxes, {cluster_nodes}-node clusters",
        mesh.triangles.len(),
        bvh.nodes.len()
    );
    println!(
        "generate {gen_s:.1} s, build {build_s:.1} s, compress {:.2} s",
        st.compression_seconds
    );
    println!("clusters                  {}", st.cluster_count);
    println!("bits/node tree            {:.2}", st.bits_per_node_tree);
    println!("bits/node BV              {:.2}", st.bits_per_node_bv);
    println!(
        "bits/node total           {:.2}",
        st.bits_per_node_tree + st.bits_per_node_bv
    );
    println!(
        "ratio vs plain nodes      {:.2}:1  (32 B/node over clusters + meta)",
        st.compression_ratio_vs_plain
    );
    println!(
        "mesh bytes/triangle       {:.2}  (plain: {:.2})",
        st.mesh_bytes_per_triangle,
        (plain_bytes[1].1 + plain_bytes[2].1) as f64 / mesh.triangles.len() as f64
    );
    println!("parts                     {parts:?}");
    println!(
        "decompression (1 core)    {:.1} M nodes/s",
        decode_nodes_per_s / 1e6
    );
    println!(
        "closest-hit rays (1 core) plain {:.3} M/s, racbvh {:.3} M/s ({:.2}x), hits {plain_hits} vs {rac_hits}",
        plain_rps / 1e6,
        rac_rps / 1e6,
        rac_rps / plain_rps
    );
    println!(
        "  with a cache of 1/4 of the clusters: {:.3} M/s ({:.2}x)",
        small_rps / 1e6,
        small_rps / plain_rps
    );
    println!(
        "closest-hit rays ({threads} threads, one shared cache) plain {:.3} M/s, racbvh {:.3} M/s ({:.2}x)",
        plain_mt / 1e6,
        rac_mt / 1e6,
        rac_mt / plain_mt
    );
    println!("cache (all)               {cache:?}");
    println!("cache (1/4)               {small_cache:?}");
}
