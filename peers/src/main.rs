//! `peers`: cbvh's ray queries against other BVHs on the same rays.
//!
//! ```text
//! cargo run --release --manifest-path peers/Cargo.toml -- --tris 100000,1000000 --threads 1,2
//! cargo run --release --manifest-path peers/Cargo.toml --features embree -- --tris 100000
//! ```
//!
//! For each triangle count it generates the statue scene, builds cbvh
//! (`PlainBvh`), parry's `TriMesh`, obvhs's CWBVH and (feature `embree`)
//! an Embree scene, casts the same rays through each, checks that they
//! agree on which rays hit, and times the casts.

use std::time::{Duration, Instant};

use glam::Vec3A;
use rayon::prelude::*;

use cbvh::codec::ByteSize;

mod whitted;

#[path = "../../examples/support/rays.rs"]
mod ray_sets;
use cbvh::codec::plain::PlainBvh;

const RUNS: usize = 5;
/// Relative tolerance when comparing hit distances between structures.
const T_REL_TOL: f32 = 1e-3;

struct Args {
    tris: Vec<usize>,
    threads: Vec<usize>,
    width: usize,
    random: usize,
    json: bool,
    whitted: bool,
}

fn parse_list(s: &str, what: &str) -> Vec<usize> {
    s.split(',')
        .map(|x| {
            x.trim()
                .replace('_', "")
                .parse::<usize>()
                .unwrap_or_else(|_| die(&format!("bad {what} value {x:?}")))
        })
        .collect()
}

fn die(msg: &str) -> ! {
    eprintln!("peers: {msg}");
    eprintln!(
        "usage: peers [--tris N[,N..]] [--threads T[,T..]] [--width PX] [--random RAYS] [--whitted] [--json]"
    );
    std::process::exit(2)
}

fn parse_args() -> Args {
    let mut a = Args {
        tris: vec![100_000],
        threads: vec![1],
        width: 512,
        random: 0,
        json: false,
        whitted: false,
    };
    let mut it = std::env::args().skip(1);
    while let Some(arg) = it.next() {
        let mut val = |name: &str| {
            it.next()
                .unwrap_or_else(|| die(&format!("{name} needs a value")))
        };
        match arg.as_str() {
            "--tris" => a.tris = parse_list(&val("--tris"), "--tris"),
            "--threads" => a.threads = parse_list(&val("--threads"), "--threads"),
            "--width" => a.width = parse_list(&val("--width"), "--width")[0],
            "--random" => a.random = parse_list(&val("--random"), "--random")[0],
            "--json" => a.json = true,
            "--whitted" => a.whitted = true,
            "-h" | "--help" => die("help"),
            other => die(&format!("unknown argument {other:?}")),
        }
    }
    if a.threads.contains(&0) || a.width == 0 || !a.width.is_multiple_of(8) {
        die("--threads must be positive and --width a positive multiple of 8");
    }
    a
}

/// A set of rays, cast in chunks (image rows) so that multi-threaded runs
/// hand whole rows to rayon.
struct RaySet {
    name: &'static str,
    origins: Vec<Vec3A>,
    dirs: Vec<Vec3A>,
    chunk: usize,
}

fn camera_rays(lo: Vec3A, hi: Vec3A, width: usize) -> RaySet {
    // cbvh's benchmark camera (`examples/support/rays.rs`): in front of the
    // statue, 8×8 tiles, so that a packet peer casts a tile per packet; a
    // chunk is a row of tiles.
    let (eye, dirs) = ray_sets::camera_tiles(lo, hi, width);
    RaySet {
        name: "camera",
        origins: vec![eye; dirs.len()],
        dirs,
        chunk: width * 8,
    }
}

/// Incoherent rays: from random points on a sphere around the statue
/// (radius 1.5 × its largest extent) towards random points in its box.
fn random_rays(lo: Vec3A, hi: Vec3A, n: usize, chunk: usize) -> RaySet {
    let mut s: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut rnd = move || {
        // splitmix64
        s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = s;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 40) as f32 / (1u64 << 24) as f32
    };
    let centre = (lo + hi) * 0.5;
    let r = 1.5 * (hi - lo).max_element();
    let mut origins = Vec::with_capacity(n);
    let mut dirs = Vec::with_capacity(n);
    while origins.len() < n {
        let p = Vec3A::new(rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0);
        let l = p.length();
        if !(0.1..=1.0).contains(&l) {
            continue;
        }
        let o = centre + p / l * r;
        let target = lo + (hi - lo) * Vec3A::new(rnd(), rnd(), rnd());
        origins.push(o);
        dirs.push((target - o).normalize());
    }
    RaySet {
        name: "random",
        origins,
        dirs,
        chunk,
    }
}

/// Casts every ray of `rays` with `cast` (returning the hit distance) on
/// the current rayon pool, one chunk per task; returns the number of hits.
fn cast_all(rays: &RaySet, p: &Peer) -> usize {
    rays.origins
        .par_chunks(rays.chunk)
        .zip(rays.dirs.par_chunks(rays.chunk))
        .map(|(os, ds)| {
            let mut out = vec![None; os.len()];
            cast_slice(p, os, ds, &mut out);
            out.iter().filter(|h| h.is_some()).count()
        })
        .sum()
}

/// Single-threaded, per-ray results, for the agreement check.
fn cast_each(rays: &RaySet, p: &Peer) -> Vec<Option<f32>> {
    let mut out = vec![None; rays.origins.len()];
    cast_slice(p, &rays.origins, &rays.dirs, &mut out);
    out
}

struct Row {
    tris: usize,
    rays: &'static str,
    structure: &'static str,
    threads: usize,
    mrays: f64,
    runs_ms: Vec<f64>,
    hits: usize,
    bytes: usize,
    build_s: f64,
}

struct Agreement {
    tris: usize,
    rays: &'static str,
    structure: &'static str,
    hits: usize,
    hit_miss_mismatches: usize,
    t_mismatches: usize,
    /// Of the distance mismatches, how many have this structure's hit
    /// nearer than cbvh's.
    t_nearer: usize,
}

/// Rays on which the structures disagreed, settled by brute force.
struct Brute {
    tris: usize,
    rays: &'static str,
    disputed: usize,
    /// Disputed rays on which brute force with cbvh's triangle test and
    /// brute force with obvhs's disagree.
    tests_disagree: usize,
    /// `(structure, rays it got wrong)`.
    wrong: Vec<(&'static str, usize)>,
}

fn same_hit(a: Option<f32>, b: Option<f32>) -> bool {
    match (a, b) {
        (Some(a), Some(b)) => (a - b).abs() <= T_REL_TOL * a.abs().max(1e-6),
        (None, None) => true,
        _ => false,
    }
}

/// The closest hit over every triangle of `mesh`.
fn brute_force(mesh: &cbvh::Mesh, o: Vec3A, d: Vec3A) -> Option<f32> {
    let ray = cbvh::geom::Ray::new(o, d);
    let mut best = f32::INFINITY;
    for t in 0..mesh.triangle_count() {
        let tri = cbvh::geom::triangle_from_arrays(mesh.triangle_vertices(t));
        if let Some(h) = cbvh::geom::ray_triangle(&ray, &tri, best) {
            best = best.min(h.t);
        }
    }
    best.is_finite().then_some(best)
}

/// The closest hit over every triangle of `mesh` with obvhs's
/// (independent) Möller–Trumbore variant.
fn brute_force_obvhs(mesh: &cbvh::Mesh, o: Vec3A, d: Vec3A) -> Option<f32> {
    let ray = obvhs::ray::Ray::new_inf(o, d);
    let mut best = f32::INFINITY;
    for t in 0..mesh.triangle_count() {
        let [a, b, c] = mesh.triangle_vertices(t);
        let tri = obvhs::triangle::Triangle {
            v0: Vec3A::from(a),
            v1: Vec3A::from(b),
            v2: Vec3A::from(c),
        };
        best = best.min(tri.intersect(&ray));
    }
    best.is_finite().then_some(best)
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// One structure: its name, size, build time and ray-cast function.
struct Peer<'a> {
    name: &'static str,
    bytes: usize,
    build: Duration,
    cast: Box<dyn Fn(Vec3A, Vec3A) -> Option<f32> + Sync + 'a>,
    /// Casts up to 64 rays as one packet, if the structure has a packet
    /// path (`cast` is then used for nothing).
    packet: Option<PacketFn<'a>>,
}

/// A packet caster: origins, directions, one result slot per ray.
type PacketFn<'a> = Box<dyn Fn(&[Vec3A], &[Vec3A], &mut [Option<f32>]) + Sync + 'a>;

/// Rays per packet: an 8×8 tile of the camera.
const PACKET: usize = 64;

/// Casts `os`/`ds` through `p`, in packets of [`PACKET`] if it has them.
fn cast_slice(p: &Peer, os: &[Vec3A], ds: &[Vec3A], out: &mut [Option<f32>]) {
    match &p.packet {
        Some(f) => {
            for ((o, d), r) in os
                .chunks(PACKET)
                .zip(ds.chunks(PACKET))
                .zip(out.chunks_mut(PACKET))
            {
                f(o, d, r);
            }
        }
        None => {
            for ((o, d), r) in os.iter().zip(ds).zip(out.iter_mut()) {
                *r = (p.cast)(*o, *d);
            }
        }
    }
}

/// A cbvh codec as a peer: single rays through `closest_hit`.
fn cursor_peer<'a, C: cbvh::codec::Codec>(
    name: &'static str,
    target: &'a cbvh::render::CursorTarget<C>,
    build: Duration,
) -> Peer<'a> {
    let c = target.cursor();
    Peer {
        name,
        bytes: c.bytes_total(),
        build,
        cast: Box::new(move |o, d| {
            cbvh::query::closest_hit(
                c,
                &cbvh::geom::Ray::new(o, d),
                f32::INFINITY,
                &mut cbvh::TraversalStats::default(),
            )
            .map(|h| h.t)
        }),
        packet: None,
    }
}

fn main() {
    let args = parse_args();
    let mut rows: Vec<Row> = Vec::new();
    let mut agreements: Vec<Agreement> = Vec::new();
    let mut brute: Vec<Brute> = Vec::new();
    let pools: Vec<(usize, rayon::ThreadPool)> = args
        .threads
        .iter()
        .map(|&t| {
            (
                t,
                rayon::ThreadPoolBuilder::new()
                    .num_threads(t)
                    .build()
                    .expect("rayon pool"),
            )
        })
        .collect();

    for &n in &args.tris {
        let whitted_opts = cbvh::render::RenderOptions {
            width: 640,
            height: 480,
            ..Default::default()
        };
        eprintln!("[{n} tris] generating statue");
        let mesh = cbvh::scene::generate(cbvh::scene::Kind::Statue, n, 0, &mut |_, _| {})
            .unwrap_or_else(|e| die(&format!("generate: {e}")));
        let ntri = mesh.triangle_count();
        let (lo, hi) = mesh.bounds().expect("non-empty mesh");
        let (lo, hi) = (Vec3A::from(lo), Vec3A::from(hi));
        eprintln!("[{n} tris] {ntri} triangles, bounds {lo:?}..{hi:?}");

        // cbvh, plain codec.
        let t0 = Instant::now();
        let bvh = cbvh::build::build(&mesh, &cbvh::build::BuildOptions::default(), &|_, _| {})
            .unwrap_or_else(|e| die(&format!("cbvh build: {e}")));
        let plain_target =
            cbvh::render::CursorTarget::new(PlainBvh::new(&bvh, &mesh)).with_name("cbvh plain");
        let build = t0.elapsed();
        drop(bvh);
        let plain_ref = plain_target.cursor();
        let plain = plain_ref;
        let p_cbvh = Peer {
            name: "cbvh plain",
            bytes: plain.bytes_total(),
            build,
            cast: Box::new(move |o, d| {
                cbvh::query::closest_hit(
                    plain_ref,
                    &cbvh::geom::Ray::new(o, d),
                    f32::INFINITY,
                    &mut cbvh::TraversalStats::default(),
                )
                .map(|h| h.t)
            }),
            packet: None,
        };

        // cbvh plain again, casting 8×8 tiles as packets.
        let p_packets = Peer {
            name: "cbvh plain packets",
            bytes: plain.bytes_total(),
            build: p_cbvh.build,
            cast: Box::new(|_, _| unreachable!("a packet peer")),
            packet: Some(Box::new(move |os, ds, out| {
                let rays: Vec<cbvh::geom::Ray> = os
                    .iter()
                    .zip(ds)
                    .map(|(o, d)| cbvh::geom::Ray::new(*o, *d))
                    .collect();
                let mut hits = [None; PACKET];
                cbvh::query::closest_hits(
                    plain_ref,
                    &rays,
                    f32::INFINITY,
                    &mut hits[..rays.len()],
                    &mut cbvh::TraversalStats::default(),
                );
                for (o, h) in out.iter_mut().zip(&hits) {
                    *o = h.map(|h| h.t);
                }
            })),
        };

        // cbvh, RACBVH codec, with a cache that holds every cluster (warmed
        // by the agreement pass below, before anything is timed).
        let t0 = Instant::now();
        let bvh = cbvh::build::build(&mesh, &cbvh::build::BuildOptions::default(), &|_, _| {})
            .unwrap_or_else(|e| die(&format!("cbvh build: {e}")));
        let rac = cbvh::codec::racbvh::RacBvh::encode(
            &bvh,
            &mesh,
            &cbvh::codec::racbvh::RacOptions {
                cache_budget_bytes: usize::MAX,
                ..Default::default()
            },
        )
        .unwrap_or_else(|e| die(&format!("racbvh: {e}")));
        let build = t0.elapsed();
        drop(bvh);
        let rac_target = cbvh::render::CursorTarget::new(rac).with_name("cbvh racbvh");
        let p_rac = cursor_peer("cbvh racbvh", &rac_target, build);

        // parry TriMesh.
        let t0 = Instant::now();
        let trimesh = cbvh::parry::parry_trimesh(&mesh)
            .unwrap_or_else(|e| die(&format!("parry TriMesh: {e:?}")));
        let build = t0.elapsed();
        let tm_ref = &trimesh;
        let p_parry = Peer {
            name: "parry TriMesh",
            bytes: cbvh::parry::trimesh_bytes_by_part(&trimesh)
                .iter()
                .map(|p| p.1)
                .sum(),
            build,
            cast: Box::new(move |o, d| {
                use parry3d::math::Vector;
                use parry3d::query::RayCast;
                let ray = parry3d::query::Ray::new(
                    Vector::new(o.x, o.y, o.z),
                    Vector::new(d.x, d.y, d.z),
                );
                tm_ref.cast_local_ray(&ray, f32::MAX, true)
            }),
            packet: None,
        };

        // obvhs CWBVH (PLOC + reinsertion, medium preset), with the
        // triangles reordered into BVH order as its examples do.
        let tris: Vec<obvhs::triangle::Triangle> = (0..ntri)
            .map(|t| {
                let [a, b, c] = mesh.triangle_vertices(t);
                obvhs::triangle::Triangle {
                    v0: Vec3A::from(a),
                    v1: Vec3A::from(b),
                    v2: Vec3A::from(c),
                }
            })
            .collect();
        let t0 = Instant::now();
        let cw = obvhs::cwbvh::builder::build_cwbvh_from_tris(
            &tris,
            obvhs::BvhBuildParams::medium_build(),
            &mut Duration::default(),
        );
        let cw_tris: Vec<obvhs::triangle::Triangle> = cw
            .primitive_indices
            .iter()
            .map(|&i| tris[i as usize])
            .collect();
        let build = t0.elapsed();
        drop(tris);
        let cw_bytes = size_of_val(cw.nodes.as_slice())
            + size_of_val(cw.primitive_indices.as_slice())
            + size_of_val(cw_tris.as_slice());
        let (cw_ref, cwt_ref) = (&cw, &cw_tris);
        let p_obvhs = Peer {
            name: "obvhs CWBVH",
            bytes: cw_bytes,
            build,
            cast: Box::new(move |o, d| {
                let ray = obvhs::ray::Ray::new_inf(o, d);
                let mut hit = obvhs::ray::RayHit::none();
                cw_ref
                    .ray_traverse(ray, &mut hit, |r, id| cwt_ref[id].intersect(r))
                    .then_some(hit.t)
            }),
            packet: None,
        };

        // cbvh CLBVH, fast and compact leaves (issue 12), from the same
        // canonical tree (built again: its build time counts for each).
        let t0 = Instant::now();
        let bvh = cbvh::build::build(&mesh, &cbvh::build::BuildOptions::default(), &|_, _| {})
            .unwrap_or_else(|e| die(&format!("cbvh build: {e}")));
        let canonical = t0.elapsed();
        let t0 = Instant::now();
        let clb = cbvh::codec::clbvh::ClBvh::encode(&bvh, &mesh, &Default::default())
            .unwrap_or_else(|e| die(&format!("clbvh: {e}")));
        let clb_build = canonical + t0.elapsed();
        let t0 = Instant::now();
        let clc = cbvh::codec::clbvh::ClBvhCompact::encode(&bvh, &mesh, &Default::default())
            .unwrap_or_else(|e| die(&format!("clbvh-compact: {e}")));
        let clc_build = canonical + t0.elapsed();
        drop(bvh);
        // cbvh i-HCCMesh (issue 11), lossless vertices, for the bytes.
        let t0 = Instant::now();
        let bvh = cbvh::build::build(&mesh, &cbvh::build::BuildOptions::default(), &|_, _| {})
            .unwrap_or_else(|e| die(&format!("cbvh build: {e}")));
        let hcc = cbvh::codec::hcc::HccBvh::encode(&bvh, &mesh)
            .unwrap_or_else(|e| die(&format!("hcc: {e}")));
        let hcc_build = t0.elapsed();
        drop(bvh);
        let hcc_target = cbvh::render::CursorTarget::new(hcc).with_name("cbvh hcc");
        let clb_target = cbvh::render::CursorTarget::new(clb).with_name("cbvh clbvh");
        let clc_target = cbvh::render::CursorTarget::new(clc).with_name("cbvh clbvh-compact");
        // The peers borrow the targets above, so the list is made after them.
        #[cfg(feature = "embree")]
        let embree = embree_peer::Embree::new(&mesh);
        #[allow(unused_mut)]
        let mut peers: Vec<Peer> = vec![p_cbvh, p_packets, p_rac, p_parry, p_obvhs];
        #[cfg(feature = "embree")]
        peers.push(embree.peer());
        peers.push(cursor_peer("cbvh clbvh", &clb_target, clb_build));
        peers.push(cursor_peer("cbvh clbvh-compact", &clc_target, clc_build));
        peers.push(cursor_peer("cbvh hcc", &hcc_target, hcc_build));

        let mut ray_sets = vec![camera_rays(lo, hi, args.width)];
        if args.random > 0 {
            ray_sets.push(random_rays(lo, hi, args.random, args.width));
        }

        for rays in &ray_sets {
            // Agreement: every structure against cbvh, ray by ray.
            let results: Vec<Vec<Option<f32>>> = peers.iter().map(|p| cast_each(rays, p)).collect();
            let reference = &results[0];
            for (p, mine) in peers.iter().zip(&results) {
                let mut hm = 0;
                let mut tm = 0;
                let mut nearer = 0;
                for (i, (a, b)) in reference.iter().zip(mine.iter()).enumerate() {
                    match (a, b) {
                        (Some(a), Some(b)) => {
                            if (a - b).abs() > T_REL_TOL * a.abs().max(1e-6) {
                                tm += 1;
                                if b < a {
                                    nearer += 1;
                                }
                                if tm <= 3 {
                                    eprintln!(
                                        "  {} ray {i}: cbvh t={a} {} t={b} (origin {:?}, dir {:?})",
                                        rays.name, p.name, rays.origins[i], rays.dirs[i]
                                    );
                                }
                            }
                        }
                        (None, None) => {}
                        _ => hm += 1,
                    }
                }
                let hits = mine.iter().filter(|h| h.is_some()).count();
                eprintln!(
                    "[{n} tris] {} rays, {}: {hits} hits of {}, {hm} hit/miss mismatches vs cbvh, {tm} distance mismatches ({nearer} nearer than cbvh)",
                    rays.name,
                    p.name,
                    mine.len()
                );
                agreements.push(Agreement {
                    tris: ntri,
                    rays: rays.name,
                    structure: p.name,
                    hits,
                    hit_miss_mismatches: hm,
                    t_mismatches: tm,
                    t_nearer: nearer,
                });
            }

            // Rays on which the structures disagree: settle them by brute
            // force over every triangle (cbvh's two-sided Möller–Trumbore).
            let disputed: Vec<usize> = (0..rays.origins.len())
                .filter(|&i| results.iter().any(|r| !same_hit(r[i], reference[i])))
                .collect();
            if !disputed.is_empty() {
                let truth: Vec<Option<f32>> = disputed
                    .par_iter()
                    .map(|&i| brute_force(&mesh, rays.origins[i], rays.dirs[i]))
                    .collect();
                let truth_obvhs: Vec<Option<f32>> = disputed
                    .par_iter()
                    .map(|&i| brute_force_obvhs(&mesh, rays.origins[i], rays.dirs[i]))
                    .collect();
                let tests_disagree = truth
                    .iter()
                    .zip(&truth_obvhs)
                    .filter(|(a, b)| !same_hit(**a, **b))
                    .count();
                eprintln!(
                    "[{n} tris] {} rays: brute force with cbvh's and obvhs's triangle tests disagree on {tests_disagree} of {} disputed rays",
                    rays.name,
                    disputed.len()
                );
                let wrong: Vec<usize> = results
                    .iter()
                    .map(|r| {
                        disputed
                            .iter()
                            .zip(&truth)
                            .filter(|(i, t)| !same_hit(r[**i], **t))
                            .count()
                    })
                    .collect();
                for (p, w) in peers.iter().zip(&wrong) {
                    eprintln!(
                        "[{n} tris] {} rays, {}: wrong on {w} of {} disputed rays (brute force)",
                        rays.name,
                        p.name,
                        disputed.len()
                    );
                }
                brute.push(Brute {
                    tris: ntri,
                    rays: rays.name,
                    disputed: disputed.len(),
                    tests_disagree,
                    wrong: peers.iter().map(|p| p.name).zip(wrong).collect(),
                });
            }

            for (threads, pool) in &pools {
                // Round-robin: run k of every structure before run k + 1 of
                // any, so that a burst of load from other processes on a
                // shared machine spreads over all of them instead of
                // landing on one structure's runs.
                let mut all_times = vec![Vec::with_capacity(RUNS); peers.len()];
                let mut all_hits = vec![0; peers.len()];
                pool.install(|| {
                    for _ in 0..RUNS {
                        for (k, p) in peers.iter().enumerate() {
                            let t0 = Instant::now();
                            all_hits[k] = cast_all(rays, p);
                            all_times[k].push(t0.elapsed().as_secs_f64());
                        }
                    }
                });
                for ((p, mut times), hits) in peers.iter().zip(all_times).zip(all_hits) {
                    let runs_ms: Vec<f64> = times.iter().map(|t| t * 1e3).collect();
                    let med = median(&mut times);
                    let mrays = rays.origins.len() as f64 / med / 1e6;
                    eprintln!(
                        "[{n} tris] {} rays, {}, {threads} thread(s): {mrays:.2} M rays/s",
                        rays.name, p.name
                    );
                    rows.push(Row {
                        tris: ntri,
                        rays: rays.name,
                        structure: p.name,
                        threads: *threads,
                        mrays,
                        runs_ms,
                        hits,
                        bytes: p.bytes,
                        build_s: p.build.as_secs_f64(),
                    });
                }
            }
        }

        // Full Whitted renders, every structure behind cbvh's renderer.
        if args.whitted {
            let ob = whitted::Foreign {
                queries: whitted::Obvhs {
                    cw: &cw,
                    tris: &cw_tris,
                },
                mesh: &mesh,
                bytes: cw_bytes,
                name: "obvhs CWBVH",
            };
            #[allow(unused_mut)]
            let mut targets: Vec<(
                &dyn cbvh::render::RayTarget,
                &'static str,
                Duration,
            )> = vec![
                (&plain_target, "cbvh plain", peers[0].build),
                (&rac_target, "cbvh racbvh", peers[2].build),
                (&trimesh, "parry TriMesh", peers[3].build),
                (&ob, "obvhs CWBVH", peers[4].build),
            ];
            #[cfg(feature = "embree")]
            let et = embree.target(&mesh);
            #[cfg(feature = "embree")]
            targets.push((&et, "embree", peers[5].build));
            let last = peers.len() - 3;
            targets.push((&clb_target, "cbvh clbvh", peers[last].build));
            targets.push((&clc_target, "cbvh clbvh-compact", peers[last + 1].build));
            targets.push((&hcc_target, "cbvh hcc", peers[last + 2].build));
            for (threads, pool) in &pools {
                // One warm-up render each, then round-robin as above.
                let mut all_runs = vec![Vec::with_capacity(RUNS); targets.len()];
                let mut all_rays = vec![0; targets.len()];
                for round in 0..=RUNS {
                    for (k, &(t, _, _)) in targets.iter().enumerate() {
                        let (rays, secs) = whitted::timed_render(t, &whitted_opts, pool);
                        if round == 0 {
                            all_rays[k] = rays;
                        } else {
                            all_runs[k].push(secs);
                        }
                    }
                }
                for ((&(t, name, build), mut runs), rays) in
                    targets.iter().zip(all_runs).zip(all_rays)
                {
                    let runs_ms: Vec<f64> = runs.iter().map(|s| s * 1e3).collect();
                    let secs = median(&mut runs);
                    let mrays = rays as f64 / secs / 1e6;
                    eprintln!(
                        "[{n} tris] whitted 640x480, {name}, {threads} thread(s): {mrays:.2} M rays/s ({rays} rays)"
                    );
                    rows.push(Row {
                        tris: ntri,
                        rays: "whitted",
                        structure: name,
                        threads: *threads,
                        mrays,
                        runs_ms,
                        hits: 0,
                        bytes: t.bytes_total(),
                        build_s: build.as_secs_f64(),
                    });
                }
            }
        }
    }

    if args.json {
        let json = serde_json::json!({
            "width": args.width,
            "random_rays": args.random,
            "runs": RUNS,
            "results": rows.iter().map(|r| serde_json::json!({
                "tris": r.tris,
                "rays": r.rays,
                "structure": r.structure,
                "threads": r.threads,
                "mrays_per_s": r.mrays,
                "runs_ms": r.runs_ms,
                "hits": r.hits,
                "bytes": r.bytes,
                "bytes_per_tri": r.bytes as f64 / r.tris as f64,
                "build_s": r.build_s,
            })).collect::<Vec<_>>(),
            "agreement": agreements.iter().map(|a| serde_json::json!({
                "tris": a.tris,
                "rays": a.rays,
                "structure": a.structure,
                "hits": a.hits,
                "hit_miss_mismatches_vs_cbvh": a.hit_miss_mismatches,
                "distance_mismatches_vs_cbvh": a.t_mismatches,
                "distance_mismatches_nearer_than_cbvh": a.t_nearer,
            })).collect::<Vec<_>>(),
            "brute_force": brute.iter().map(|b| serde_json::json!({
                "tris": b.tris,
                "rays": b.rays,
                "disputed_rays": b.disputed,
                "brute_force_cbvh_vs_obvhs_triangle_test_disagree": b.tests_disagree,
                "wrong": b.wrong.iter().map(|(s, w)| serde_json::json!({"structure": s, "rays": w})).collect::<Vec<_>>(),
            })).collect::<Vec<_>>(),
        });
        println!("{}", serde_json::to_string_pretty(&json).unwrap());
        return;
    }

    println!(
        "{:>9} {:>7} {:<18} {:>7} {:>10} {:>9} {:>8} {:>8}",
        "tris", "rays", "structure", "threads", "M rays/s", "B/tri", "build s", "hits"
    );
    for r in &rows {
        println!(
            "{:>9} {:>7} {:<18} {:>7} {:>10.2} {:>9.1} {:>8.2} {:>8}",
            r.tris,
            r.rays,
            r.structure,
            r.threads,
            r.mrays,
            r.bytes as f64 / r.tris as f64,
            r.build_s,
            r.hits
        );
    }
    println!();
    println!("agreement with cbvh (per ray; distances within {T_REL_TOL} relative):");
    for a in &agreements {
        println!(
            "{:>9} {:>7} {:<18} hits {:>8}  hit/miss mismatches {:>5}  distance mismatches {:>5} ({} nearer than cbvh)",
            a.tris, a.rays, a.structure, a.hits, a.hit_miss_mismatches, a.t_mismatches, a.t_nearer
        );
    }
    for b in &brute {
        let w: Vec<String> = b.wrong.iter().map(|(s, w)| format!("{s} {w}")).collect();
        println!(
            "{:>9} {:>7} {} disputed rays ({} where brute force with cbvh's vs obvhs's triangle test disagree), wrong vs brute force with cbvh's test: {}",
            b.tris,
            b.rays,
            b.disputed,
            b.tests_disagree,
            w.join(", ")
        );
    }
}

#[cfg(feature = "embree")]
mod embree_peer {
    /// Embree's queries for cbvh's renderer: `rtcIntersect1` for closest
    /// hits, `rtcOccluded1` for shadow rays.
    pub struct EmbreeQueries<'a>(&'a Scene<'static>);

    impl crate::whitted::Queries for EmbreeQueries<'_> {
        fn closest(&self, ray: &cbvh::geom::Ray, t_max: f32) -> Option<(f32, u32)> {
            let mut ctx = IntersectContext::coherent();
            let mut rh = RayHit::from(Ray::segment(
                ray.origin.to_array(),
                ray.dir.to_array(),
                0.0,
                t_max,
            ));
            self.0.intersect(&mut ctx, &mut rh);
            rh.hit.is_valid().then_some((rh.ray.tfar, rh.hit.primID))
        }

        fn any(&self, ray: &cbvh::geom::Ray, t_max: f32) -> bool {
            let mut ctx = IntersectContext::incoherent();
            let mut r = Ray::segment(ray.origin.to_array(), ray.dir.to_array(), 0.0, t_max);
            self.0.occluded(&mut ctx, &mut r)
        }
    }

    use std::sync::Arc;
    use std::sync::atomic::{AtomicIsize, Ordering};
    use std::time::{Duration, Instant};

    use embree3::{
        BufferUsage, Device, Format, GeometryKind, IntersectContext, Ray, RayHit, Scene,
    };
    use glam::Vec3A;

    use super::Peer;

    /// An Embree scene with one triangle geometry, and its memory as
    /// Embree's memory monitor reports it (net bytes allocated by the
    /// device after the commit: geometry buffers plus the BVH).
    pub struct Embree {
        scene: Scene<'static>,
        bytes: usize,
        build: Duration,
    }

    impl Embree {
        pub fn new(mesh: &cbvh::Mesh) -> Self {
            let device = Device::new().expect("embree device");
            let net = Arc::new(AtomicIsize::new(0));
            let counter = net.clone();
            device.set_memory_monitor_function(move |bytes, _post| {
                counter.fetch_add(bytes, Ordering::Relaxed);
                true
            });
            let t0 = Instant::now();
            let mut scene = device.create_scene().expect("embree scene");
            let mut g = device
                .create_geometry(GeometryKind::TRIANGLE)
                .expect("embree geometry");
            g.set_new_buffer::<[f32; 3]>(
                BufferUsage::VERTEX,
                0,
                Format::FLOAT3,
                3 * 4,
                mesh.vertices.len(),
            )
            .expect("vertex buffer")
            .copy_from_slice(&mesh.vertices);
            g.set_new_buffer::<[u32; 3]>(
                BufferUsage::INDEX,
                0,
                Format::UINT3,
                3 * 4,
                mesh.triangles.len(),
            )
            .expect("index buffer")
            .copy_from_slice(&mesh.triangles);
            let g = g.commit();
            scene.attach_geometry(&g);
            scene.commit();
            let build = t0.elapsed();
            let bytes = net.load(Ordering::Relaxed).max(0) as usize;
            Self {
                scene,
                bytes,
                build,
            }
        }

        /// The scene behind cbvh's renderer interface (face normals).
        pub fn target<'a>(
            &'a self,
            mesh: &'a cbvh::Mesh,
        ) -> crate::whitted::Foreign<'a, EmbreeQueries<'a>> {
            crate::whitted::Foreign {
                queries: EmbreeQueries(&self.scene),
                mesh,
                bytes: self.bytes,
                name: "embree",
            }
        }

        pub fn peer(&self) -> Peer<'_> {
            let scene = &self.scene;
            Peer {
                name: "embree",
                bytes: self.bytes,
                build: self.build,
                cast: Box::new(move |o: Vec3A, d: Vec3A| {
                    let mut ctx = IntersectContext::coherent();
                    let mut rh =
                        RayHit::from(Ray::segment(o.to_array(), d.to_array(), 0.0, f32::INFINITY));
                    scene.intersect(&mut ctx, &mut rh);
                    rh.hit.is_valid().then_some(rh.ray.tfar)
                }),
                packet: None,
            }
        }
    }
}
