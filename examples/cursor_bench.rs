//! Every query over [`NodeCursor`] (rays through [`RayCursor`]) on one
//! thread, for every codec of the registry, same tree and same queries:
//! camera rays one at a time (closest hit), shadow rays (any hit), 8×8
//! packets, closest points, box overlaps and two-tree pair enumeration
//! (statue against a turned copy of itself).
//! Prints one JSON object per (codec, query) with nanoseconds per query
//! (the minimum and median of the timed passes) and a checksum of the
//! answers, so that two builds of the crate can be compared run against run
//! (the same answers, and how fast).
//!
//! ```text
//! cargo run --release --features sims --example cursor_bench -- [tris] [passes] [folder]
//! ```
//!
//! `CURSOR_BENCH_ONLY=plain:overlap,bvtt` runs only the matching figures
//! (for `perf stat` on one query).

use std::hint::black_box;
use std::ops::ControlFlow;
use std::time::Instant;

use cbvh::TraversalStats;
use cbvh::build::{BuildOptions, build};
use cbvh::codec::{AnyCodec, AnyOptions, CodecKind, OpenOptions};
use cbvh::cursor::NodeCursor;
use cbvh::geom::{Aabb, Pose, Ray};
use cbvh::query::{self, RayCursor};
use cbvh::scene::{Kind, generate};
use cbvh::with_codec;
use glam::{Quat, Vec3, Vec3A};

#[path = "support/rays.rs"]
mod ray_sets;

/// The queries, built once from the mesh's bounds.
struct Queries {
    camera: Vec<Ray>,
    shadow: Vec<(Ray, f32)>,
    points: Vec<Vec3A>,
    boxes: Vec<Aabb>,
    pose: Pose,
    prediction: f32,
}

/// A small xorshift generator in `[0, 1)`.
fn uniform(seed: u64) -> impl FnMut() -> f32 {
    let mut s = seed;
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 40) as f32 / (1u64 << 24) as f32
    }
}

fn queries<C: RayCursor>(c: &C, lo: Vec3A, hi: Vec3A) -> Queries {
    let (eye, dirs) = ray_sets::camera_tiles(lo, hi, 256);
    let camera: Vec<Ray> = dirs.iter().map(|&d| Ray::new(eye, d)).collect();
    // Shadow rays from the camera rays' hit points towards a light.
    let light = hi + (hi - lo) * Vec3A::new(0.5, 1.0, 0.8);
    let mut s = TraversalStats::default();
    let shadow = camera
        .iter()
        .filter_map(|r| {
            let h = query::closest_hit(c, r, f32::INFINITY, &mut s)?;
            let p = r.at(h.t * 0.9999);
            let d = light - p;
            Some((Ray::new(p, d), 1.0))
        })
        .collect();
    let size = (hi - lo).length();
    let mut f = uniform(0x9e37_79b9_7f4a_7c15);
    let points = (0..20_000)
        .map(|_| lo + (hi - lo) * Vec3A::new(f(), f(), f()))
        .collect();
    let boxes = (0..20_000)
        .map(|_| {
            let c = lo + (hi - lo) * Vec3A::new(f(), f(), f());
            let e = Vec3A::splat(size * 0.01 * f());
            Aabb::new(c - e, c + e)
        })
        .collect();
    let pose = Pose::from_rotation_translation(
        Quat::from_euler(glam::EulerRot::XYZ, 0.2, 0.9, -0.3),
        Vec3::from((hi - lo) * Vec3A::new(0.05, 0.1, 0.0)),
    );
    Queries {
        camera,
        shadow,
        points,
        boxes,
        pose,
        prediction: size * 0.001,
    }
}

/// Times `f` over `passes` passes; prints one JSON line. Skipped unless
/// `codec:query` contains the `CURSOR_BENCH_ONLY` filter (when set).
fn time(codec: &str, name: &str, n: usize, passes: usize, mut f: impl FnMut() -> u64) {
    if let Ok(only) = std::env::var("CURSOR_BENCH_ONLY")
        && !only
            .split(',')
            .any(|o| format!("{codec}:{name}").contains(o))
    {
        return;
    }
    let sum = f();
    let mut ns = Vec::new();
    for _ in 0..passes {
        let t = Instant::now();
        black_box(f());
        ns.push(t.elapsed().as_secs_f64() * 1e9 / n as f64);
    }
    ns.sort_by(f64::total_cmp);
    println!(
        "{{\"codec\":\"{codec}\",\"query\":\"{name}\",\"n\":{n},\"ns_min\":{:.2},\"ns_median\":{:.2},\"checksum\":{sum}}}",
        ns[0],
        ns[ns.len() / 2]
    );
}

fn mix(h: u64, x: u64) -> u64 {
    (h ^ x).wrapping_mul(0x0100_0000_01b3).rotate_left(17)
}

fn bench<C: RayCursor>(codec: &str, c: &C, q: &Queries, passes: usize) {
    time(codec, "closest_hit", q.camera.len(), passes, || {
        let mut s = TraversalStats::default();
        q.camera.iter().fold(0, |h, r| {
            let hit = query::closest_hit(c, r, f32::INFINITY, &mut s);
            mix(
                h,
                hit.map_or(u64::MAX, |h| {
                    (h.triangle as u64) << 32 | h.t.to_bits() as u64
                }),
            )
        })
    });
    time(codec, "any_hit", q.shadow.len(), passes, || {
        let mut s = TraversalStats::default();
        q.shadow.iter().fold(0, |h, (r, t)| {
            mix(h, query::any_hit(c, r, *t, &mut s) as u64)
        })
    });
    time(codec, "packets", q.camera.len(), passes, || {
        let mut s = TraversalStats::default();
        let mut out = [None; 64];
        let mut h = 0;
        for r in q.camera.chunks(64) {
            query::closest_hits(c, r, f32::INFINITY, &mut out[..r.len()], &mut s);
            for o in &out[..r.len()] {
                h = mix(
                    h,
                    o.map_or(u64::MAX, |h| {
                        (h.triangle as u64) << 32 | h.t.to_bits() as u64
                    }),
                );
            }
        }
        h
    });
    time(codec, "closest_point", q.points.len(), passes, || {
        let mut s = TraversalStats::default();
        q.points.iter().fold(0, |h, p| {
            let hit = query::closest_point(c, *p, f32::INFINITY, &mut s);
            mix(
                h,
                hit.map_or(u64::MAX, |h| {
                    (h.triangle as u64) << 32 | h.distance.to_bits() as u64
                }),
            )
        })
    });
    time(codec, "overlap", q.boxes.len(), passes, || {
        let mut s = TraversalStats::default();
        q.boxes.iter().fold(0, |mut h, b| {
            query::overlap(c, b, &mut s, |id, _| {
                h = mix(h, id as u64);
                ControlFlow::Continue(())
            });
            h
        })
    });
    time(codec, "bvtt", 1, passes.min(5), || {
        let mut s = TraversalStats::default();
        let mut h = 0;
        query::bvtt(c, c, &q.pose, q.prediction, &mut s, |i, _, j, _| {
            h = mix(h, (i as u64) << 32 | j as u64);
            ControlFlow::Continue(())
        });
        h
    });
}

fn main() {
    let mut args = std::env::args().skip(1);
    let tris: usize = args
        .next()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1_000_000);
    let passes: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(7);
    // With a folder, the trees are kept there as files and reopened by
    // later runs (generating and encoding take longer than the queries).
    let dir = args.next().map(std::path::PathBuf::from);
    // Codecs with a cache get one that holds the whole tree.
    let options = AnyOptions::default().with_cache_budget(usize::MAX);
    let open = OpenOptions {
        cache_budget_bytes: usize::MAX,
        ..Default::default()
    };
    let mut built = None;
    let codecs: Vec<AnyCodec> = CodecKind::ALL
        .iter()
        .map(|&k| {
            let file = dir.as_ref().map(|d| d.join(format!("statue-{tris}.{k}")));
            if let Some(f) = file.as_ref().filter(|f| f.exists()) {
                return AnyCodec::open(f, &open).expect("open");
            }
            let (mesh, bvh) = built.get_or_insert_with(|| {
                let mesh = generate(Kind::Statue, tris, 0, &mut |_, _| {}).expect("generate");
                let bvh = build(&mesh, &BuildOptions::default(), &|_, _| {}).expect("build");
                (mesh, bvh)
            });
            let codec = AnyCodec::encode(k, bvh, mesh, &options).expect("encode");
            if let Some(f) = &file {
                codec.save(f).expect("save");
            }
            codec
        })
        .collect();
    drop(built);
    let root = with_codec!(&codecs[0], |c| c.root().1);
    let q = with_codec!(&codecs[0], |c| queries(c, root.min, root.max));
    for codec in &codecs {
        with_codec!(codec, |c| bench(codec.name(), c, &q, passes));
    }
}
