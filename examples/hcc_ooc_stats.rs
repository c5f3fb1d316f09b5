//! o-HCCMesh figures: bytes per triangle on disk by part, against the
//! i-HCCMesh it codes (same options), and the o → i decode rate on one
//! thread (the paper's Table 1 columns and its 2.3 M triangles/s).
//!
//! ```text
//! cargo run --release --features app --example hcc_ooc_stats -- [--gen statue --tris 1000000 --seed 1 | --mesh FILE]
//!     [--vertex-bits 16] [--ids] [--leaf-size 1] [--rounds 5] [--json]
//! ```
//!
//! The i-HCCMesh is built in tree order (no id maps: the paper's form)
//! unless `--ids` keeps the input's triangle and vertex ids (stored
//! uncoded in both forms). The decode is timed once per round and the best
//! round reported, in wall-clock time and in the thread's CPU time (Linux;
//! on a shared machine the latter is the decoder's own cost); each decode
//! is checked to equal the directly built i-HCCMesh byte for byte.

use std::time::Instant;

use cbvh::Mesh;
use cbvh::build::{BuildOptions, Layout, build};
use cbvh::codec::ByteSize;
use cbvh::codec::hcc::HccBvh;
use cbvh::codec::hcc::ooc::OocOptions;
use cbvh::codec::plain::PlainBvh;
use cbvh::scene::{Kind, generate};
use clap::Parser;

/// Command-line options.
#[derive(Parser)]
struct Args {
    /// Generated scene kind (statue, turbine, plant, robot, iso).
    #[arg(long, default_value = "statue")]
    r#gen: String,
    /// Triangles of the generated scene.
    #[arg(long, default_value_t = 1_000_000)]
    tris: usize,
    /// Seed of the generated scene.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// A mesh file instead of a generated scene.
    #[arg(long)]
    mesh: Option<std::path::PathBuf>,
    /// Bits per grid coordinate.
    #[arg(long, default_value_t = 16)]
    vertex_bits: u32,
    /// Keep the input's triangle and vertex ids.
    #[arg(long)]
    ids: bool,
    /// The most triangles a leaf of the canonical tree holds (above 1:
    /// the i-HCCMesh's multi-triangle leaves).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u16).range(1..))]
    leaf_size: u16,
    /// Timing rounds.
    #[arg(long, default_value_t = 5)]
    rounds: usize,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

/// This thread's CPU time in nanoseconds (Linux: the first field of
/// `/proc/thread-self/schedstat`), to time the decode apart from what the
/// machine's other work takes; `None` elsewhere.
fn thread_cpu_ns() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    s.split_whitespace().next()?.parse().ok()
}

fn main() {
    let a = Args::parse();
    let mesh: Mesh = match &a.mesh {
        Some(p) => cbvh::mesh::load(p).expect("load mesh"),
        None => {
            let kind: Kind = a.r#gen.parse().expect("scene kind");
            generate(kind, a.tris, a.seed, &mut |_, _| {}).expect("generate")
        }
    };
    let n = mesh.triangles.len();
    let opts = BuildOptions {
        max_leaf_triangles: usize::from(a.leaf_size),
        layout: Layout::DepthFirst,
        ..Default::default()
    };
    let bvh = build(&mesh, &opts, &|_, _| {}).expect("build");
    let o = OocOptions {
        vertex_bits: a.vertex_bits,
        vertex_ids: a.ids,
        triangle_ids: a.ids,
        ..Default::default()
    };
    let t = Instant::now();
    let hcc = HccBvh::encode_with(&bvh, &mesh, &o.hcc()).expect("i-HCCMesh");
    let i_secs = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let (bytes, sizes) = hcc.to_ooc().expect("o-HCCMesh");
    let o_secs = t.elapsed().as_secs_f64();
    let direct = hcc.to_bytes();
    let i_parts = hcc.bytes_by_part();
    let duplicated = hcc.stats().duplicated_fraction();
    drop(hcc);
    // The uncompressed reference (Table 1's "Ori."): plain's 32-byte nodes
    // and f32 mesh, over the same tree.
    let plain = PlainBvh::encode(&bvh, &mesh).expect("plain").bytes_total();
    let (mut best, mut best_cpu) = (f64::INFINITY, f64::INFINITY);
    for _ in 0..a.rounds.max(1) {
        let cpu = thread_cpu_ns();
        let t = Instant::now();
        let back = HccBvh::from_ooc(&bytes).expect("decode");
        best = best.min(t.elapsed().as_secs_f64());
        if let (Some(a), Some(b)) = (cpu, thread_cpu_ns()) {
            best_cpu = best_cpu.min((b - a) as f64 * 1e-9);
        }
        assert!(
            back.to_bytes() == direct,
            "o → i differs from the direct i-HCCMesh"
        );
    }
    let per = |b: f64| b / n as f64;
    let rate = n as f64 / best;
    let i_total: usize = i_parts.iter().map(|p| p.1).sum();
    if a.json {
        let o_parts: serde_json::Map<String, serde_json::Value> = sizes
            .parts()
            .into_iter()
            .map(|(k, b)| (k.to_string(), per(b).into()))
            .collect();
        let i_parts: serde_json::Map<String, serde_json::Value> = i_parts
            .iter()
            .map(|&(k, b)| (k.to_string(), per(b as f64).into()))
            .collect();
        let v = serde_json::json!({
            "triangles": n, "vertices": mesh.vertices.len(), "vertex_bits": a.vertex_bits,
            "ids": a.ids, "leaf_size": a.leaf_size, "threads": 1,
            "o_bytes_per_triangle": per(bytes.len() as f64),
            "o_bytes_per_triangle_by_part": o_parts,
            "i_bytes_per_triangle": per(i_total as f64),
            "i_bytes_per_triangle_by_part": i_parts,
            "duplicated_vertices": duplicated,
            "plain_bytes_per_triangle": per(plain as f64),
            "i_ratio_to_plain": plain as f64 / i_total as f64,
            "o_ratio_to_plain": plain as f64 / bytes.len() as f64,
            "decode_seconds": best, "decode_triangles_per_second": rate,
            "decode_cpu_seconds": best_cpu.is_finite().then_some(best_cpu),
            "decode_triangles_per_cpu_second": best_cpu.is_finite().then(|| n as f64 / best_cpu),
            "encode_i_seconds": i_secs, "encode_o_seconds": o_secs,
        });
        println!("{v}");
        return;
    }
    println!(
        "{n} triangles, {} vertices, {}-bit grid, at most {} triangle(s) a leaf, {}",
        mesh.vertices.len(),
        a.vertex_bits,
        a.leaf_size,
        if a.ids {
            "input ids kept"
        } else {
            "tree order"
        }
    );
    println!("o-HCCMesh on disk: {:.3} B/tri", per(bytes.len() as f64));
    for (k, b) in sizes.parts() {
        println!("  {k:<14} {:>8.3} B/tri", per(b));
    }
    println!("i-HCCMesh (same options): {:.3} B/tri", per(i_total as f64));
    for (k, b) in &i_parts {
        println!("  {k:<14} {:>8.3} B/tri", per(*b as f64));
    }
    println!(
        "vertices duplicated across low-level trees: {:.1} %",
        100.0 * duplicated
    );
    println!(
        "plain (32-byte nodes, f32 mesh): {:.3} B/tri; compression {:.1} : 1 (i), {:.1} : 1 (o)",
        per(plain as f64),
        plain as f64 / i_total as f64,
        plain as f64 / bytes.len() as f64
    );
    println!(
        "o → i decode, one thread: {:.1} ms best of {}, {:.2} M tri/s",
        best * 1e3,
        a.rounds.max(1),
        rate / 1e6
    );
    if best_cpu.is_finite() {
        println!(
            "  on this thread's CPU time: {:.1} ms, {:.2} M tri/s",
            best_cpu * 1e3,
            n as f64 / best_cpu / 1e6
        );
    }
    println!("encode: i-HCCMesh {i_secs:.2} s, o-HCCMesh from it {o_secs:.2} s");
}
