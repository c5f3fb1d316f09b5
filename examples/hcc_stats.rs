//! i-HCCMesh figures against plain and RACBVH, side by side in one run:
//! bytes per triangle by part, vertices duplicated across low-level trees,
//! closest-hit camera rays per second on one thread and the cost of
//! `triangle(id)`; for `f32` and quantized vertices (`--vertex-bits`), one
//! triangle a leaf and the multi-triangle-leaf curve (bytes per triangle
//! and rays per second against triangles per leaf), each quantized row
//! also in tree order (`-T`: no id maps stored, ids in storage order).
//!
//! ```text
//! cargo run --release --features app --example hcc_stats -- [--gen statue|turbine|... --tris N | --mesh FILE]
//!     [--leaves 2,4,8,16] [--vertex-bits 16] [--width 512] [--rounds 5] [--json]
//! ```
//!
//! Rays: a pinhole camera's primary rays (`--width`², in 8×8 tiles). Every
//! structure is timed once per round, structures alternating within a
//! round, and the best round is reported (the machine is shared). The
//! `maps` column is what the input's numbering costs (parts `ids` and
//! `vertex-ids`): `w/o maps` is the structure without it.

use std::time::Instant;

use cbvh::build::{BuildOptions, Layout, build};
use cbvh::codec::ByteSize;
use cbvh::codec::hcc::{HccBvh, HccOptions};
use cbvh::codec::plain::PlainBvh;
use cbvh::codec::racbvh::{RacBvh, RacOptions};
use cbvh::cursor::NodeCursor;
use cbvh::geom::Ray;
use cbvh::query::RayCursor;
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
    /// Bits per coordinate of the quantized rows.
    #[arg(long, default_value_t = 16)]
    vertex_bits: u32,
    /// Camera image width (a multiple of 8).
    #[arg(long, default_value_t = 512)]
    width: usize,
    /// Time only the rows whose name is one of these (plain always runs,
    /// as the reference), comma-separated; all rows when unset.
    #[arg(long, value_delimiter = ',')]
    only: Vec<String>,
    /// Random ids for the `triangle(id)` timing (0: skip it).
    #[arg(long, default_value_t = 20_000)]
    tri_ids: usize,
    /// Timing rounds.
    #[arg(long, default_value_t = 5)]
    rounds: usize,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

/// Closest hits of every ray; the number of hits.
fn trace<C: RayCursor>(c: &C, rays: &[Ray]) -> usize {
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

/// One structure under test.
#[allow(clippy::large_enum_variant)] // a handful of rows, built once
enum Row {
    Plain(PlainBvh),
    Rac(RacBvh),
    Hcc(HccBvh),
}

impl Row {
    fn trace(&self, rays: &[Ray]) -> usize {
        match self {
            Row::Plain(c) => trace(c, rays),
            Row::Rac(c) => trace(c, rays),
            Row::Hcc(c) => trace(c, rays),
        }
    }

    fn parts(&self) -> Vec<(&'static str, usize)> {
        match self {
            Row::Plain(c) => c.bytes_by_part(),
            Row::Rac(c) => c.bytes_by_part(),
            Row::Hcc(c) => c.bytes_by_part(),
        }
    }

    /// Nanoseconds per `triangle(id)` over `ids`.
    fn triangle_ns(&self, ids: &[u32]) -> f64 {
        fn run<C: NodeCursor>(c: &C, ids: &[u32]) -> f64 {
            let t = Instant::now();
            let mut acc = Vec3A::ZERO;
            for &id in ids {
                acc += c.triangle(id)[0];
            }
            std::hint::black_box(acc);
            t.elapsed().as_secs_f64() * 1e9 / ids.len() as f64
        }
        match self {
            Row::Plain(c) => run(c, ids),
            Row::Rac(c) => run(c, ids),
            Row::Hcc(c) => run(c, ids),
        }
    }
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
    let f32_opts = HccOptions::default();
    let q_opts = HccOptions {
        vertex_bits: Some(a.vertex_bits),
        ..Default::default()
    };
    let t = Instant::now();
    let hcc = HccBvh::encode(&bvh, &mesh).expect("hcc");
    let encode_s = t.elapsed().as_secs_f64();
    let st = *hcc.stats();
    let q = a.vertex_bits;
    let mut names = vec!["plain".to_string(), "racbvh".into(), "hcc".into()];
    let mut rows = vec![Row::Plain(plain), Row::Rac(rac), Row::Hcc(hcc)];
    let tree_opts = HccOptions::tree_order(Some(a.vertex_bits));
    for (name, o) in [
        (format!("hcc-q{q}"), q_opts),
        (format!("hcc-q{q}-T"), tree_opts),
    ] {
        names.push(name);
        rows.push(Row::Hcc(
            HccBvh::encode_with(&bvh, &mesh, &o).expect("hcc quantized"),
        ));
    }
    drop(bvh);
    for &k in &a.leaves {
        let t = tree(k);
        for (name, o) in [
            (format!("hcc-L{k}"), f32_opts),
            (format!("hcc-q{q}-L{k}"), q_opts),
            (format!("hcc-q{q}-L{k}-T"), tree_opts),
        ] {
            names.push(name);
            rows.push(Row::Hcc(
                HccBvh::encode_with(&t, &mesh, &o).expect("hcc multi"),
            ));
        }
    }

    let (lo, hi) = mesh.bounds().expect("non-empty mesh");
    let (eye, dirs) = ray_sets::camera_tiles(Vec3A::from(lo), Vec3A::from(hi), a.width);
    let rays: Vec<Ray> = dirs.iter().map(|&d| Ray::new(eye, d)).collect();
    let mut s = 0x2545_F491_4F6C_DD1Du64;
    let ids: Vec<u32> = (0..a.tri_ids)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s % n as u64) as u32
        })
        .collect();

    // Timing: alternate structures within each round, keep the best.
    let mut best = vec![0f64; rows.len()];
    let mut tri_ns = vec![f64::INFINITY; rows.len()];
    let mut hits = vec![0usize; rows.len()];
    let timed = |i: usize| i == 0 || a.only.is_empty() || a.only.contains(&names[i]);
    // Warm the RACBVH cache once.
    if timed(1) {
        rows[1].trace(&rays);
    }
    for _ in 0..a.rounds {
        for (i, r) in rows.iter().enumerate().filter(|p| timed(p.0)) {
            let t = Instant::now();
            hits[i] = r.trace(&rays);
            best[i] = best[i].max(rays.len() as f64 / t.elapsed().as_secs_f64());
            if !ids.is_empty() {
                tri_ns[i] = tri_ns[i].min(r.triangle_ns(&ids));
            }
        }
    }

    let bytes: Vec<Vec<(&'static str, usize)>> = rows.iter().map(Row::parts).collect();
    let totals: Vec<f64> = bytes
        .iter()
        .map(|p| p.iter().map(|x| x.1).sum::<usize>() as f64 / n as f64)
        .collect();
    let maps: Vec<f64> = bytes
        .iter()
        .map(|p| {
            p.iter()
                .filter(|x| x.0 == "ids" || x.0 == "vertex-ids")
                .map(|x| x.1)
                .sum::<usize>() as f64
                / n as f64
        })
        .collect();
    if a.json {
        let rows: Vec<_> = names
            .iter()
            .enumerate()
            .map(|(i, name)| {
                serde_json::json!({
                    "codec": name, "bytes_per_triangle": totals[i],
                    "maps_per_triangle": maps[i],
                    "parts_per_triangle": per_tri(&bytes[i], n),
                    "rays_per_s": best[i], "vs_plain": best[i] / best[0], "hits": hits[i],
                    "triangle_ns": tri_ns[i],
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
        "{} camera rays, 1 thread, best of {} rounds; triangle(id): {} random ids",
        rays.len(),
        a.rounds,
        ids.len()
    );
    println!(
        "{:<13} {:>6} {:>6} {:>8}  {:>13} {:>5} {:>9} {:>8}",
        "", "B/tri", "maps", "w/o maps", "M rays/s", "plain", "hits", "tri(id)"
    );
    for (i, name) in names.iter().enumerate() {
        let parts: Vec<String> = per_tri(&bytes[i], n)
            .iter()
            .map(|(p, b)| format!("{p} {b:.2}"))
            .collect();
        println!(
            "{name:<13} {:6.2} {:6.2} {:8.2}  {:13.3} {:4.2}x {:9} {:6.0}ns  [{}]",
            totals[i],
            maps[i],
            totals[i] - maps[i],
            best[i] / 1e6,
            best[i] / best[0],
            hits[i],
            tri_ns[i],
            parts.join(", ")
        );
    }
}
