//! Camera rays one at a time against 8×8 packets, on one thread, same
//! tree, same rays, side by side (the peers crate compares with parry,
//! obvhs and Embree).
//!
//! ```text
//! cargo run --release --features sims --example packet_bench -- [tris] [width] [codec, default plain]
//! ```

use std::time::Instant;

use cbvh::TraversalStats;
use cbvh::build::{BuildOptions, build};
use cbvh::codec::{AnyCodec, AnyOptions, CodecKind};
use cbvh::geom::Ray;
use cbvh::query::{self, RayCursor, RayHit};
use cbvh::scene::{Kind, generate};
use glam::Vec3A;

#[path = "support/rays.rs"]
mod ray_sets;

fn bench<C: RayCursor>(c: &C, rays: &[Ray]) {
    let single = |out: &mut Vec<Option<RayHit>>| {
        out.clear();
        let mut s = TraversalStats::default();
        out.extend(
            rays.iter()
                .map(|r| query::closest_hit(c, r, f32::INFINITY, &mut s)),
        );
        s
    };
    let packets = |out: &mut Vec<Option<RayHit>>| {
        out.clear();
        out.resize(rays.len(), None);
        let mut s = TraversalStats::default();
        for (r, o) in rays.chunks(64).zip(out.chunks_mut(64)) {
            query::closest_hits(c, r, f32::INFINITY, o, &mut s);
        }
        s
    };
    let (mut a, mut b) = (Vec::new(), Vec::new());
    single(&mut a);
    packets(&mut b);
    let differ = a.iter().zip(&b).filter(|(x, y)| x != y).count();
    assert_eq!(
        differ, 0,
        "packets and single rays disagree on {differ} rays"
    );
    let hits = a.iter().filter(|h| h.is_some()).count();
    for (name, f) in [
        (
            "single",
            &single as &dyn Fn(&mut Vec<Option<RayHit>>) -> TraversalStats,
        ),
        ("packets", &packets),
    ] {
        let mut runs = Vec::new();
        let mut stats = TraversalStats::default();
        for _ in 0..7 {
            let t = Instant::now();
            stats = f(&mut a);
            runs.push(rays.len() as f64 / t.elapsed().as_secs_f64() / 1e6);
        }
        runs.sort_by(f64::total_cmp);
        println!(
            "{name:>8}: {:.2} M rays/s (median of 7), {hits} hits of {}, {:.1} nodes and {:.1} triangle tests per ray",
            runs[3],
            rays.len(),
            stats.nodes_visited as f64 / rays.len() as f64,
            stats.primitive_tests as f64 / rays.len() as f64
        );
    }
}

fn main() {
    let mut args = std::env::args().skip(1);
    let tris: usize = args
        .next()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1_000_000);
    let width: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(512);
    let codec: CodecKind = match args.next() {
        Some(name) => name.parse().unwrap_or_else(|e| panic!("{e}")),
        None => CodecKind::Plain,
    };
    let mesh = generate(Kind::Statue, tris, 0, &mut |_, _| {}).expect("generate");
    let (lo, hi) = mesh.bounds().expect("non-empty");
    let (eye, dirs) = ray_sets::camera_tiles(Vec3A::from(lo), Vec3A::from(hi), width);
    let rays: Vec<Ray> = dirs.iter().map(|&d| Ray::new(eye, d)).collect();
    let bvh = build(&mesh, &BuildOptions::default(), &|_, _| {}).expect("build");
    println!(
        "statue, {} triangles, {width}×{width} camera, 1 thread, {codec}",
        mesh.triangle_count()
    );
    // A codec with a cache gets one that holds the whole tree.
    let options = AnyOptions::default().with_cache_budget(usize::MAX);
    let codec = AnyCodec::encode(codec, &bvh, &mesh, &options).expect("encode");
    cbvh::with_codec!(&codec, |c| bench(c, &rays));
}
