//! Times and sanity-checks the scene generators.
//!
//! ```text
//! cargo run --release --features sims --example gen_bench -- bench statue 10000000
//! cargo run --release --features sims --example gen_bench -- dump        # OFF files in /tmp
//! cargo run --release --features sims --example gen_bench -- counts [seeds [iso_max iso_step]]
//! cargo run --release --features sims --example gen_bench -- sweep isosurface 3 500000 2000000
//! cargo run --release --features sims --example gen_bench -- check statue 10000000
//! ```
//! `bench` prints throughput and peak memory (VmHWM) against the mesh's own
//! size; set `RAYON_NUM_THREADS=1` for single-core figures.

use std::io::Write;
use std::time::Instant;

use cbvh::mesh::{Mesh, boundary_edges, degenerate_triangles};
use cbvh::scene::{Kind, default_tris, generate, planned_triangles};

fn peak_rss_mb() -> f64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

/// User + system CPU seconds of this process so far.
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let fields: Vec<&str> = stat
        .rsplit(')')
        .next()
        .unwrap_or("")
        .split_whitespace()
        .collect();
    let ticks = |i: usize| {
        fields
            .get(i)
            .and_then(|s| s.parse::<f64>().ok())
            .unwrap_or(f64::NAN)
    };
    (ticks(11) + ticks(12)) / 100.0
}

fn signed_volume(m: &Mesh) -> f64 {
    m.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.vertices[i as usize].map(|x| x as f64));
            let cross = [
                b[1] * c[2] - b[2] * c[1],
                b[2] * c[0] - b[0] * c[2],
                b[0] * c[1] - b[1] * c[0],
            ];
            (a[0] * cross[0] + a[1] * cross[1] + a[2] * cross[2]) / 6.0
        })
        .sum()
}

fn write_off(m: &Mesh, path: &str) -> std::io::Result<()> {
    let mut w = cbvh::files::AtomicFile::create(std::path::Path::new(path))?;
    writeln!(w, "OFF\n{} {} 0", m.vertices.len(), m.triangles.len())?;
    for v in &m.vertices {
        writeln!(w, "{} {} {}", v[0], v[1], v[2])?;
    }
    for t in &m.triangles {
        writeln!(w, "3 {} {} {}", t[0], t[1], t[2])?;
    }
    w.commit()
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("bench") => {
            let kind: Kind = args
                .get(1)
                .map_or("statue", String::as_str)
                .parse()
                .expect("kind");
            let tris: usize = args
                .get(2)
                .map_or(Ok(10_000_000), |s| s.parse())
                .expect("tris");
            let threads = rayon::current_num_threads();
            let c0 = cpu_seconds();
            let t0 = Instant::now();
            let mut calls = 0u64;
            let mesh = generate(kind, tris, 1, &mut |_, _| calls += 1).expect("generate");
            let secs = t0.elapsed().as_secs_f64();
            let cpu = cpu_seconds() - c0;
            let n = mesh.triangles.len();
            let bytes = (mesh.vertices.len() * 12 + n * 12) as f64 / (1 << 20) as f64;
            println!(
                "{kind} {tris}: {n} triangles ({:+.2} %), {} vertices, {threads} threads, {secs:.2} s, \
                 {:.2} M tris/s ({cpu:.2} s CPU: {:.2} M tris per CPU-second), peak RSS {:.0} MiB, mesh {bytes:.0} MiB ({:.2}x), {calls} progress calls",
                (n as f64 / tris as f64 - 1.0) * 100.0,
                mesh.vertices.len(),
                n as f64 / secs / 1e6,
                n as f64 / cpu / 1e6,
                peak_rss_mb(),
                peak_rss_mb() / bytes,
            );
        }
        Some("dump") => {
            for kind in Kind::ALL {
                let tris = args
                    .get(1)
                    .map_or(default_tris(kind), |s| s.parse().expect("tris"));
                let mesh = generate(kind, tris, 0, &mut |_, _| {}).expect("generate");
                let (lo, hi) = mesh.bounds().expect("vertices");
                let path = format!("/tmp/gen_{kind}.off");
                write_off(&mesh, &path).expect("write");
                println!(
                    "{kind:>10}: {} tris, {} verts, bounds {lo:.3?}..{hi:.3?}, boundary edges {}, degenerate {}, volume {:.4} -> {path}",
                    mesh.triangles.len(),
                    mesh.vertices.len(),
                    boundary_edges(&mesh),
                    degenerate_triangles(&mesh),
                    signed_volume(&mesh),
                );
            }
        }
        Some("counts") => {
            // Worst planned-count error over a sweep of requests and seeds.
            let seeds: u64 = args.get(1).map_or(1, |s| s.parse().expect("seeds"));
            let iso_limit: f64 = args.get(2).map_or(400e3, |s| s.parse().expect("iso limit"));
            let iso_step: f64 = args.get(3).map_or(1.05, |s| s.parse().expect("iso step"));
            for kind in Kind::ALL {
                let mut worst = (0.0f64, 0usize, 0u64);
                for seed in 0..seeds {
                    let mut t = 1000.0f64;
                    let (limit, step) = if kind == Kind::Isosurface {
                        (iso_limit, iso_step)
                    } else {
                        (200e6, 1.003)
                    };
                    while t <= limit {
                        let tris = t as usize;
                        let got = planned_triangles(kind, tris, seed).expect("plan");
                        let err = (got as f64 / tris as f64 - 1.0).abs();
                        if err > worst.0 {
                            worst = (err, tris, seed);
                        }
                        t *= step;
                    }
                }
                println!(
                    "{kind:>10}: worst planned count error {:.3} % at {} (seed {})",
                    worst.0 * 100.0,
                    worst.1,
                    worst.2
                );
            }
        }
        Some("check") => {
            // Closedness and degeneracy of one large mesh.
            let kind: Kind = args
                .get(1)
                .map_or("statue", String::as_str)
                .parse()
                .expect("kind");
            let tris: usize = args
                .get(2)
                .map_or(Ok(2_000_000), |s| s.parse())
                .expect("tris");
            let mesh = generate(kind, tris, 0, &mut |_, _| {}).expect("generate");
            println!(
                "{kind} {tris}: {} tris, boundary edges {}, degenerate {}, volume {:.4}",
                mesh.triangles.len(),
                boundary_edges(&mesh),
                degenerate_triangles(&mesh),
                signed_volume(&mesh)
            );
        }
        Some("sweep") => {
            // Actual counts produced for a kind over requests and seeds.
            let kind: Kind = args
                .get(1)
                .map_or("isosurface", String::as_str)
                .parse()
                .expect("kind");
            let seeds: u64 = args.get(2).map_or(3, |s| s.parse().expect("seeds"));
            for tris in args
                .iter()
                .skip(3)
                .map(|s| s.parse::<usize>().expect("tris"))
            {
                for seed in 0..seeds {
                    let t0 = Instant::now();
                    let m = generate(kind, tris, seed, &mut |_, _| {}).expect("generate");
                    let n = m.triangles.len();
                    println!(
                        "{kind} {tris} seed {seed}: {n} ({:+.2} %) in {:.2} s",
                        (n as f64 / tris as f64 - 1.0) * 100.0,
                        t0.elapsed().as_secs_f64()
                    );
                }
            }
        }
        _ => eprintln!(
            "usage: gen_bench bench <kind> <tris> | dump [tris] | check <kind> <tris> | counts [seeds [iso_max iso_step]] | sweep <kind> <seeds> <tris>..."
        ),
    }
}
