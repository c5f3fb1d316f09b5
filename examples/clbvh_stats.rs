//! CLBVH figures (the paper's Table 1 columns) on one mesh: bytes per
//! triangle by part (nodes, leaf data, mesh) for the uncompressed 8-wide
//! tree, CLBVH fast and CLBVH compact; node memory against the 8-wide tree;
//! traversal steps and triangle tests per camera ray; encode time; and
//! single-thread camera rays/s against the plain codec, all in one run
//! (timed casts alternate between the structures).
//!
//! ```text
//! cargo run --release --features app --example clbvh_stats -- [--gen statue] [--tris 1000000]
//!     [--mesh FILE.off] [--leaf-size 4] [--compact-leaf-size 6] [--width 512]
//!     [--repeat 5] [--json]
//! ```

use std::time::Instant;

use cbvh::build::{BuildOptions, build};
use cbvh::codec::ByteSize;
use cbvh::codec::clbvh::{COMPACT_LEAF_SIZE, ClBvh, ClOptions, LeafKind};
use cbvh::codec::plain::PlainBvh;
use cbvh::geom::Ray;
use cbvh::query::RayCursor;
use cbvh::scene::{Kind, generate};
use cbvh::{TraversalStats, query};
use clap::Parser;
use glam::Vec3A;

#[path = "support/rays.rs"]
mod ray_sets;

/// Command-line options.
#[derive(Parser)]
struct Args {
    /// Generated model: statue, turbine, plant, robot or isosurface
    /// (ignored with `--mesh`).
    #[arg(long = "gen", default_value_t = Kind::Statue)]
    gen_kind: Kind,
    /// Generated model's size in triangles (ignored with `--mesh`).
    #[arg(long, default_value_t = 1_000_000)]
    tris: usize,
    /// A mesh file instead of the generated statue.
    #[arg(long)]
    mesh: Option<std::path::PathBuf>,
    /// CLBVH leaf size `M` (threshold `8 · M`) of the 8-wide and fast trees.
    #[arg(long, default_value_t = ClOptions::default().leaf_size)]
    leaf_size: usize,
    /// `M` of the compact tree.
    #[arg(long, default_value_t = COMPACT_LEAF_SIZE)]
    compact_leaf_size: usize,
    /// Camera image width and height (`width²` primary rays).
    #[arg(long, default_value_t = 512)]
    width: usize,
    /// Timed casts per structure (the median is reported).
    #[arg(long, default_value_t = 5)]
    repeat: usize,
    /// One JSON object per structure instead of a table.
    #[arg(long)]
    json: bool,
}

fn cast<C: RayCursor>(c: &C, rays: &[Ray]) -> (f64, TraversalStats, u64) {
    let mut stats = TraversalStats::default();
    let t = Instant::now();
    let mut sum = 0u64;
    for r in rays {
        if let Some(h) = query::closest_hit(c, r, f32::INFINITY, &mut stats) {
            sum = sum.wrapping_add(u64::from(h.triangle) ^ u64::from(h.t.to_bits()));
        }
    }
    (t.elapsed().as_secs_f64(), stats, sum)
}

fn main() {
    let a = Args::parse();
    let (mesh, name) = match &a.mesh {
        Some(p) => (
            cbvh::mesh::load(p).expect("load mesh"),
            p.display().to_string(),
        ),
        None => (
            generate(a.gen_kind, a.tris, 0, &mut |_, _| {}).expect("generate"),
            format!("{} {}", a.gen_kind, a.tris),
        ),
    };
    let n = mesh.triangle_count();
    let t = Instant::now();
    let bvh = build(&mesh, &BuildOptions::default(), &|_, _| {}).expect("build");
    let build_s = t.elapsed().as_secs_f64();
    let plain = PlainBvh::new(&bvh, &mesh);
    let opts = |leaf_size, leaves, multi_leaf| ClOptions {
        leaf_size,
        leaves,
        multi_leaf,
    };
    let configs = [
        ("bvh8", opts(a.leaf_size, LeafKind::Fast, false)),
        ("clbvh", opts(a.leaf_size, LeafKind::Fast, true)),
        (
            "clbvh-compact",
            opts(a.compact_leaf_size, LeafKind::Compact, true),
        ),
    ];
    let mut trees = Vec::new();
    for (label, o) in configs {
        let t = Instant::now();
        let c = ClBvh::encode(&bvh, &mesh, &o).expect("encode");
        trees.push((label, c, t.elapsed().as_secs_f64()));
    }
    drop(bvh);
    let (lo, hi) = mesh.bounds().expect("non-empty mesh");
    let (eye, dirs) = ray_sets::camera_tiles(Vec3A::from(lo), Vec3A::from(hi), a.width);
    let rays: Vec<Ray> = dirs.iter().map(|&d| Ray::new(eye, d)).collect();

    // Timed casts, alternating between the structures; the answers must
    // agree with plain's.
    let mut times: Vec<Vec<f64>> = vec![Vec::new(); trees.len() + 1];
    let mut stats = vec![TraversalStats::default(); trees.len() + 1];
    let (_, s, want) = cast(&plain, &rays);
    stats[0] = s;
    for (k, (label, c, _)) in trees.iter().enumerate() {
        let (_, s, got) = cast(c, &rays);
        assert_eq!(got, want, "{label} answers differently from plain");
        stats[k + 1] = s;
    }
    for _ in 0..a.repeat.max(1) {
        times[0].push(cast(&plain, &rays).0);
        for (k, (_, c, _)) in trees.iter().enumerate() {
            times[k + 1].push(cast(c, &rays).0);
        }
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let nr = rays.len() as f64;
    let bvh8_nodes = node_bytes(&trees[0].1);
    if !a.json {
        println!(
            "{name}: {n} triangles, {} camera rays, 1 thread, canonical build {build_s:.2} s",
            rays.len()
        );
        println!(
            "{:>14} {:>8} {:>8} {:>8} {:>8} {:>9} {:>8} {:>8} {:>9} {:>8}",
            "structure",
            "nodes",
            "leaves",
            "mesh",
            "B/tri",
            "node mem",
            "steps/r",
            "tris/r",
            "Mrays/s",
            "encode s"
        );
    }
    let plain_bytes = plain.bytes_by_part();
    let plain_nodes = plain_bytes[0].1 as f64;
    let rows = std::iter::once((
        "plain",
        plain_nodes,
        0.0,
        (plain.bytes_total() as f64) - plain_nodes,
        0.0,
    ))
    .chain(trees.iter().map(|(l, c, s)| {
        let nodes = node_bytes(c) as f64;
        let parts = c.bytes_by_part();
        let get = |name: &str| parts.iter().find(|p| p.0 == name).map_or(0, |p| p.1) as f64;
        let mesh_b = get("vertices") + get("triangles") + get("triangle slots");
        (*l, nodes, get("leaf data"), mesh_b, *s)
    }));
    for (k, (label, nodes, leaves, mesh_b, enc)) in rows.enumerate() {
        let t = median(&mut times[k]);
        let per = |x: f64| x / n as f64;
        // Plain's binary nodes have no 8-wide counterpart.
        let node_mem = (k != 0).then(|| nodes / bvh8_nodes as f64 - 1.0);
        let st = &stats[k];
        if a.json {
            let v = serde_json::json!({
                "mesh": name, "triangles": n, "structure": label,
                "node_bytes_per_tri": per(nodes), "leaf_bytes_per_tri": per(leaves),
                "mesh_bytes_per_tri": per(mesh_b), "bytes_per_tri": per(nodes + leaves + mesh_b),
                "node_memory_vs_bvh8": node_mem,
                "steps_per_ray": st.nodes_visited as f64 / nr,
                "triangle_tests_per_ray": st.primitive_tests as f64 / nr,
                "rays_per_second": nr / t, "encode_seconds": enc,
                "canonical_build_seconds": build_s,
            });
            println!("{v}");
        } else {
            println!(
                "{label:>14} {:>8.2} {:>8.2} {:>8.2} {:>8.2} {:>9} {:>8.2} {:>8.2} {:>9.3} {:>8.2}",
                per(nodes),
                per(leaves),
                per(mesh_b),
                per(nodes + leaves + mesh_b),
                node_mem.map_or("–".to_string(), |m| format!("{:.1}%", m * 100.0)),
                st.nodes_visited as f64 / nr,
                st.primitive_tests as f64 / nr,
                nr / t / 1e6,
                enc
            );
        }
    }
}

fn node_bytes(c: &ClBvh) -> usize {
    c.bytes_by_part()
        .iter()
        .filter(|p| p.0.ends_with("nodes"))
        .map(|p| p.1)
        .sum()
}
