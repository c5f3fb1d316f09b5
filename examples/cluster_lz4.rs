//! The paper's general-purpose-compressor comparison (Kim et al. 2010 put
//! gzip beside RACBVH): the plain 32-byte nodes cut into clusters of 4096
//! consecutive nodes (RACBVH's default cluster), each cluster compressed on
//! its own with LZ4 (`lz4_flex` block format, so any cluster decompresses
//! alone), side by side with RACBVH's own figures for the same tree in the
//! same run.
//!
//! ```text
//! cargo run --release --features sims --example cluster_lz4 -- [tris] [--gen statue|turbine|...]
//! cargo run --release --features sims --example cluster_lz4 -- 1000000
//! cargo run --release --features sims --example cluster_lz4 -- 1000000 --gen turbine
//! ```
//!
//! Both trees are the canonical BVH of the default build. Bits per node
//! count the compressed clusters plus a per-cluster table (RACBVH: its meta
//! table; LZ4: an 8-byte offset per cluster). Decompression is one core,
//! every cluster in turn with no cache, the best of 3 sweeps (the machine
//! may be shared); the LZ4 figure includes checking each cluster's length.

use std::hint::black_box;
use std::time::Instant;

use cbvh::build::{BuildOptions, build};
use cbvh::codec::plain::PlainBvh;
use cbvh::codec::racbvh::{RacBvh, RacOptions};
use cbvh::scene::{Kind, generate};

/// Nodes per LZ4 cluster (RACBVH's default `cluster_nodes`).
const CLUSTER_NODES: usize = 4096;

/// Plain bytes per node.
const NODE_BYTES: usize = 32;

/// Best-of-`n` throughput (items per second) of `f`, which returns the
/// number of items it processed.
fn best_of(n: usize, mut f: impl FnMut() -> usize) -> f64 {
    (0..n)
        .map(|_| {
            let t = Instant::now();
            let items = f();
            items as f64 / t.elapsed().as_secs_f64()
        })
        .fold(0.0, f64::max)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut kind = Kind::Statue;
    let mut tris = 1_000_000usize;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        if a == "--gen" {
            kind = it
                .next()
                .expect("--gen needs a kind")
                .parse()
                .expect("kind");
        } else if let Some(k) = a.strip_prefix("--gen=") {
            kind = k.parse().expect("kind");
        } else {
            tris = a.parse().expect("triangle count");
        }
    }

    let mesh = generate(kind, tris, 0, &mut |_, _| {}).expect("generate");
    let bvh = build(&mesh, &BuildOptions::default(), &|_, _| {}).expect("build");
    let plain = PlainBvh::new(&bvh, &mesh);
    let nodes = plain.nodes();
    let n = nodes.len();
    let bytes: &[u8] = bytemuck::cast_slice(nodes);

    // LZ4, one block per cluster.
    let t = Instant::now();
    let clusters: Vec<Vec<u8>> = bytes
        .chunks(CLUSTER_NODES * NODE_BYTES)
        .map(lz4_flex::block::compress)
        .collect();
    let lz4_compress_s = t.elapsed().as_secs_f64();
    let lz4_bytes: usize = clusters.iter().map(Vec::len).sum::<usize>() + 8 * clusters.len();
    let mut out = vec![0u8; CLUSTER_NODES * NODE_BYTES];
    // Check the round trip once, then time.
    for (k, c) in clusters.iter().enumerate() {
        let len = lz4_flex::block::decompress_into(c, &mut out).expect("lz4 decode");
        let at = k * CLUSTER_NODES * NODE_BYTES;
        assert_eq!(&out[..len], &bytes[at..at + len], "lz4 round trip");
    }
    let lz4_nodes_per_s = best_of(3, || {
        let mut decoded = 0;
        for c in &clusters {
            let len = lz4_flex::block::decompress_into(c, &mut out).expect("lz4 decode");
            decoded += len / NODE_BYTES;
            black_box(&out);
        }
        decoded
    });

    // RACBVH, default options, same tree.
    let rac = RacBvh::encode(&bvh, &mesh, &RacOptions::default()).expect("encode");
    let st = rac.stats();
    let rac_nodes_per_s = best_of(3, || {
        (0..rac.cluster_count() as u32)
            .map(|c| rac.decode_cluster_uncached(c).expect("decode"))
            .sum()
    });

    let plain_bytes = n * NODE_BYTES;
    let lz4_bpn = lz4_bytes as f64 * 8.0 / n as f64;
    let rac_bpn = st.bits_per_node_tree + st.bits_per_node_bv;
    let rac_total_bpn = NODE_BYTES as f64 * 8.0 / st.compression_ratio_vs_plain;
    println!(
        "{}: {} triangles, {} nodes, {} clusters of {} nodes",
        kind.name(),
        mesh.triangles.len(),
        n,
        clusters.len(),
        CLUSTER_NODES
    );
    println!(
        "{:<28} {:>12} {:>10} {:>22}",
        "codec", "bits/node", "ratio", "decompress (1 core)"
    );
    println!(
        "{:<28} {:>12.2} {:>9.2}:1 {:>14} M nodes/s",
        "plain (32 B/node)", 256.0, 1.0, "-"
    );
    println!(
        "{:<28} {:>12.2} {:>9.2}:1 {:>14.1} M nodes/s",
        "lz4 block / 4096-node clust.",
        lz4_bpn,
        plain_bytes as f64 / lz4_bytes as f64,
        lz4_nodes_per_s / 1e6
    );
    println!(
        "{:<28} {:>12.2} {:>9.2}:1 {:>14.1} M nodes/s",
        "racbvh (default options)",
        rac_total_bpn,
        st.compression_ratio_vs_plain,
        rac_nodes_per_s / 1e6
    );
    println!(
        "racbvh bits/node: tree {:.2} + BV {:.2} = {:.2} (coded bits; {:.2} with cluster padding and meta)",
        st.bits_per_node_tree, st.bits_per_node_bv, rac_bpn, rac_total_bpn
    );
    println!(
        "compression: lz4 {:.2} s, racbvh {:.2} s",
        lz4_compress_s, st.compression_seconds
    );
}
