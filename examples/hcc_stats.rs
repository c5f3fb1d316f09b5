//! i-HCCMesh figures against plain and RACBVH, side by side in one run:
//! bytes per triangle by part, vertices duplicated across low-level trees,
//! and closest-hit camera rays per second on one thread; then the
//! multi-triangle-leaf curve (bytes per triangle and rays per second
//! against triangles per leaf).
//!
//! ```text
//! cargo run --release --example hcc_stats -- [--gen statue|turbine|... --tris N | --mesh FILE]
//!     [--leaves 2,4,8,16] [--width 512] [--rounds 5] [--json]
//! ```
//!
//! Rays: a pinhole camera's primary rays (`--width`², in 8×8 tiles). Every
//! structure is timed once per round, structures alternating within a
//! round, and the best round is reported (the machine is shared).

use std::time::Instant;

use cbvh::build::{BuildOptions, Layout, build};
use cbvh::codec::ByteSize;
use cbvh::codec::hcc::HccBvh;
use cbvh::codec::plain::PlainBvh;
use cbvh::codec::racbvh::{RacBvh, RacOptions};
use cbvh::cursor::NodeCursor;
use cbvh::geom::Ray;
use cbvh::scene::{Kind, generate};
use cbvh::{Mesh, TraversalStats, query};
use clap::Parser;
use glam::Vec3A;

#[path = "support/rays.rs"]
mod ray_sets;

/// Command-line options.
#[derive(Parser)]
struct Args {
    /// Generated scene kind (statue, turbine, plant, robot, iso).
    #[arg(long, default_value = "statue")]
    r#gen: String,
    /// Triangles of the generated scene.
    #[arg(long, default_value_t = 1_000_000)]
    tris: usize,
    /// A mesh file instead of a generated scene.
    #[arg(long)]
    mesh: Option<std::path::PathBuf>,
    /// Leaf sizes of the multi-triangle variant, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "2,4,8,16")]
    leaves: Vec<usize>,
    /// Camera image width (a multiple of 8).
    #[arg(long, default_value_t = 512)]
    width: usize,
    /// Timing rounds.
    #[arg(long, default_value_t = 5)]
    rounds: usize,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

/// Closest hits of every ray; the number of hits.
fn trace<C: NodeCursor>(c: &C, rays: &[Ray]) -> usize {
    let mut stats = TraversalStats::default();
    rays.iter()
        .filter(|r| query::closest_hit(c, r, f32::INFINITY, &mut stats).is_some())
        .count()
}

fn per_tri(parts: &[(&'static str, usize)], tris: usize) -> Vec<(&'static str, f64)> {
    parts
        .iter()
        .map(|&(n, b)| (n, b as f64 / tris as f64))
        .collect()
}

fn main() {
    let a = Args::parse();
    let mesh: Mesh = match &a.mesh {
        Some(p) => cbvh::mesh::load(p).expect("load mesh"),
        None => {
            let kind: Kind = a.r#gen.parse().expect("scene kind");
            generate(kind, a.tris, 0, &mut |_, _| {}).expect("generate")
        }
    };
    let n = mesh.triangles.len();
    let tree = |leaf: usize| {
        let opts = BuildOptions {
            max_leaf_triangles: leaf,
            layout: Layout::DepthFirst,
            ..Default::default()
        };
        build(&mesh, &opts, &|_, _| {}).expect("build")
    };
    let bvh = tree(1);
    let plain = PlainBvh::new(&bvh, &mesh);
    let rac = RacBvh::encode(&bvh, &mesh, &RacOptions::default()).expect("racbvh");
    let budget = rac.cluster_count() * rac.cluster_nodes() as usize * 48;
    let rac = RacBvh::from_bytes(&rac.to_bytes(), budget).expect("reopen racbvh");
    let t = Instant::now();
    let hcc = HccBvh::encode(&bvh, &mesh).expect("hcc");
    let encode_s = t.elapsed().as_secs_f64();
    let multi: Vec<(usize, HccBvh)> = a
        .leaves
        .iter()
        .map(|&k| (k, HccBvh::encode(&tree(k), &mesh).expect("hcc-multi")))
        .collect();

    let (lo, hi) = mesh.bounds().expect("non-empty mesh");
    let (eye, dirs) = ray_sets::camera_tiles(Vec3A::from(lo), Vec3A::from(hi), a.width);
    let rays: Vec<Ray> = dirs.iter().map(|&d| Ray::new(eye, d)).collect();

    // Timing: alternate structures within each round, keep the best.
    let names: Vec<String> = ["plain", "racbvh", "hcc"]
        .iter()
        .map(|s| s.to_string())
        .chain(multi.iter().map(|(k, _)| format!("hcc-multi{k}")))
        .collect();
    let mut best = vec![0f64; names.len()];
    let mut hits = vec![0usize; names.len()];
    // Warm the RACBVH cache once.
    trace(&rac, &rays);
    for _ in 0..a.rounds {
        for (i, best) in best.iter_mut().enumerate() {
            let t = Instant::now();
            hits[i] = match i {
                0 => trace(&plain, &rays),
                1 => trace(&rac, &rays),
                2 => trace(&hcc, &rays),
                k => trace(&multi[k - 3].1, &rays),
            };
            *best = best.max(rays.len() as f64 / t.elapsed().as_secs_f64());
        }
    }

    let bytes: Vec<Vec<(&'static str, usize)>> = [
        plain.bytes_by_part(),
        rac.bytes_by_part(),
        hcc.bytes_by_part(),
    ]
    .into_iter()
    .chain(multi.iter().map(|(_, h)| h.bytes_by_part()))
    .collect();
    let totals: Vec<f64> = bytes
        .iter()
        .map(|p| p.iter().map(|x| x.1).sum::<usize>() as f64 / n as f64)
        .collect();
    let st = hcc.stats();
    if a.json {
        let rows: Vec<_> = names
            .iter()
            .enumerate()
            .map(|(i, name)| {
                serde_json::json!({
                    "codec": name, "bytes_per_triangle": totals[i],
                    "parts_per_triangle": per_tri(&bytes[i], n),
                    "rays_per_s": best[i], "vs_plain": best[i] / best[0], "hits": hits[i],
                })
            })
            .collect();
        let v = serde_json::json!({
            "triangles": n, "vertices": mesh.vertices.len(), "threads": 1,
            "rays": rays.len(), "hcc_encode_s": encode_s,
            "hcc_trees": st.trees, "duplicated_vertices": st.duplicated_fraction(),
            "loose_extents": st.loose_extents, "rows": rows,
        });
        println!("{v}");
        return;
    }
    println!(
        "{n} triangles, {} vertices; i-HCCMesh: {} low-level trees, encode {encode_s:.2} s, \
         {:.1} % of vertices duplicated across trees, {} loose extents",
        mesh.vertices.len(),
        st.trees,
        100.0 * st.duplicated_fraction(),
        st.loose_extents
    );
    println!(
        "{} camera rays, 1 thread, best of {} rounds",
        rays.len(),
        a.rounds
    );
    for (i, name) in names.iter().enumerate() {
        let parts: Vec<String> = per_tri(&bytes[i], n)
            .iter()
            .map(|(p, b)| format!("{p} {b:.2}"))
            .collect();
        println!(
            "{name:<13} {:6.2} B/tri  {:7.3} M rays/s ({:.2}x plain, {} hits)  [{}]",
            totals[i],
            best[i] / 1e6,
            best[i] / best[0],
            hits[i],
            parts.join(", ")
        );
    }
}
