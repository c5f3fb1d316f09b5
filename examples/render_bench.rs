//! Ray-tracing throughput of every cbvh codec (plain, RACBVH, ...) and
//! parry's `TriMesh`, side by side in one process: rays per second on generated statues, primary
//! rays only and full Whitted (shadows from 3 lights, 2 mirror bounces),
//! on 1 and 2 threads.
//!
//! ```text
//! cargo run --release --features app --example render_bench -- [--tris 100000,1000000]
//!     [--threads 1,2] [--width 640 --height 480] [--repeat 3] [--json]
//! ```
//!
//! Each configuration renders the same image `--repeat` times after one
//! warm-up render; the best wall-clock time is reported, and rays per CPU
//! second of the process over all timed renders, which a shared machine
//! distorts less (a thread that waits for a core spends no CPU time).

use std::time::Instant;

use cbvh::build::{BuildOptions, build};
use cbvh::codec::{AnyCodec, AnyOptions, CodecKind};
use cbvh::render::{
    RayTarget, RenderOptions, RenderStats, Scene, VertexNormals, any_target, render,
};
use cbvh::scene::{Kind, generate};
use clap::Parser;

/// Command-line options.
#[derive(Parser)]
struct Args {
    /// Statue sizes in triangles, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "100000,1000000")]
    tris: Vec<usize>,
    /// Thread counts, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "1,2")]
    threads: Vec<usize>,
    /// Image width.
    #[arg(long, default_value_t = 640)]
    width: u32,
    /// Image height.
    #[arg(long, default_value_t = 480)]
    height: u32,
    /// Timed renders per configuration (the best is reported).
    #[arg(long, default_value_t = 3)]
    repeat: usize,
    /// Print one JSON object per configuration instead of a table.
    #[arg(long)]
    json: bool,
}

/// CPU time of this process so far (all threads, user + system), from
/// `/proc/self/stat` (Linux; 10 ms ticks). `None` elsewhere.
fn cpu_seconds() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the parenthesised command name; utime and stime are
    // fields 14 and 15 of the whole line.
    let rest = &s[s.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

/// The best of `repeat` timed renders after a warm-up, and rays per CPU
/// second over all timed renders (robust on a shared machine).
fn best_of(
    scene: &Scene,
    opts: &RenderOptions,
    threads: usize,
    repeat: usize,
) -> (RenderStats, Option<f64>) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool");
    pool.install(|| {
        let mut best = render(scene, opts, &|_, _| {}).expect("render").1;
        best.seconds = f64::INFINITY;
        let cpu0 = cpu_seconds();
        let mut rays = 0;
        for _ in 0..repeat.max(1) {
            let s = render(scene, opts, &|_, _| {}).expect("render").1;
            rays += s.rays.total();
            if s.seconds < best.seconds {
                best = s;
            }
        }
        let cpu = cpu_seconds()
            .zip(cpu0)
            .map(|(b, a)| b - a)
            .filter(|&c| c > 0.0);
        (best, cpu.map(|c| rays as f64 / c))
    })
}

fn main() {
    let a = Args::parse();
    if !a.json {
        println!(
            "{:>10} {:>6} {:>8} {:>7} {:>10} {:>8} {:>9} {:>11} {:>8} {:>8} {:>7}",
            "triangles",
            "codec",
            "mode",
            "threads",
            "rays",
            "seconds",
            "Mrays/s",
            "Mrays/cpu-s",
            "steps/r",
            "prims/r",
            "B/tri"
        );
    }
    for &tris in &a.tris {
        let mesh = generate(Kind::Statue, tris, 0, &mut |_, _| {}).expect("generate");
        let t0 = Instant::now();
        let bvh = build(&mesh, &BuildOptions::default(), &|_, _| {}).expect("build");
        let tree_build = t0.elapsed().as_secs_f64();
        // Codecs with a cache get one that holds the whole tree (the
        // warm-up render fills it).
        let options = AnyOptions::default().with_cache_budget(usize::MAX);
        let mut owned: Vec<(Box<dyn RayTarget>, f64)> = CodecKind::ALL
            .iter()
            .map(|&k| {
                let t0 = Instant::now();
                let codec = AnyCodec::encode(k, &bvh, &mesh, &options).expect("encode");
                (any_target(codec), tree_build + t0.elapsed().as_secs_f64())
            })
            .collect();
        drop(bvh);
        let t0 = Instant::now();
        let parry = cbvh::parry::parry_trimesh(&mesh).expect("parry TriMesh");
        owned.push((Box::new(parry), t0.elapsed().as_secs_f64()));
        let normals = VertexNormals::from_mesh(&mesh);
        let n = mesh.triangle_count();
        drop(mesh);
        let targets: Vec<(&dyn RayTarget, f64)> =
            owned.iter().map(|(t, s)| (t.as_ref(), *s)).collect();
        let base = RenderOptions {
            width: a.width,
            height: a.height,
            ..Default::default()
        };
        for (mode, opts) in [
            ("primary", base.clone().primary_only()),
            ("whitted", base.clone()),
        ] {
            for &threads in &a.threads {
                for &(target, build_seconds) in &targets {
                    let scene = Scene::single(target, Some(&normals));
                    let (s, per_cpu) = best_of(&scene, &opts, threads, a.repeat);
                    let rays = s.rays.total();
                    let per = |x: u64| target.counts_traversal().then(|| x as f64 / rays as f64);
                    let steps = per(s.rays.traversal.nodes_visited);
                    let prims = per(s.rays.traversal.primitive_tests);
                    if a.json {
                        let v = serde_json::json!({
                            "triangles": n,
                            "codec": target.name(),
                            "mode": mode,
                            "threads": s.threads,
                            "width": a.width,
                            "height": a.height,
                            "rays": rays,
                            "seconds": s.seconds,
                            "rays_per_second": s.rays_per_second(),
                            "rays_per_cpu_second": per_cpu,
                            "traversal_steps_per_ray": steps,
                            "primitive_tests_per_ray": prims,
                            "bytes_per_triangle": target.bytes_per_triangle(),
                            "build_seconds": build_seconds,
                        });
                        println!("{v}");
                    } else {
                        let f = |x: Option<f64>| x.map_or("-".to_string(), |x| format!("{x:.2}"));
                        println!(
                            "{n:>10} {:>6} {mode:>8} {:>7} {rays:>10} {:>8.3} {:>9.2} {:>11} {:>8} {:>8} {:>7.1}",
                            target.name(),
                            s.threads,
                            s.seconds,
                            s.rays_per_second() / 1e6,
                            f(per_cpu.map(|r| r / 1e6)),
                            f(steps),
                            f(prims),
                            target.bytes_per_triangle()
                        );
                    }
                }
            }
        }
    }
}
