//! The long run of the mutation harness: every codec's file of a generated
//! statue, attacked with truncations, raw bit flips, bit flips with
//! checksums recomputed, forged headers and structurally corrupt but
//! checksummed trees; prints the table of outcomes (Markdown).
//!
//! `cargo run --release --example mutate -- [TRIANGLES] [CASES] [SEED]`
//! (defaults 20000, 2000, 1). Exits with an error if any case panicked or a
//! must-catch attack gave a different answer.

#[path = "support/mutate.rs"]
mod mutate;

use cbvh::build::{BuildOptions, build};
use cbvh::codec::plain::PlainBvh;
use cbvh::codec::racbvh::{RacBvh, RacOptions};
use mutate::{Subject, print_table};

fn main() -> Result<(), String> {
    let arg = |k: usize, d: u64| {
        std::env::args().nth(k).map_or(Ok(d), |s| {
            s.parse().map_err(|e| format!("argument {k}: {e}"))
        })
    };
    let (tris, cases, seed) = (arg(1, 20_000)?, arg(2, 2000)?, arg(3, 1)?);
    // Panics are counted, not printed.
    std::panic::set_hook(Box::new(|_| {}));
    let mesh = cbvh::scene::generate(cbvh::scene::Kind::Statue, tris as usize, 7, &mut |_, _| {})
        .map_err(|e| e.to_string())?;
    let bvh = build(&mesh, &BuildOptions::default(), &|_, _| {}).map_err(|e| e.to_string())?;
    let plain = PlainBvh::new(&bvh, &mesh).to_bytes();
    let rac_opts = RacOptions {
        cluster_nodes: 256,
        ..Default::default()
    };
    let rac = RacBvh::encode(&bvh, &mesh, &rac_opts)
        .map_err(|e| e.to_string())?
        .to_bytes();
    println!(
        "statue of {} triangles, {cases} cases per random attack, seed {seed}",
        mesh.triangles.len()
    );
    let mut rows = Vec::new();
    for (codec, bytes) in [("plain", plain), ("racbvh", rac)] {
        let subject = Subject::new(codec, bytes);
        rows.extend(subject.run(cases as usize, seed));
        if codec == "racbvh" {
            let n = (cases as usize / 10).max(10);
            rows.push(subject.racbvh_corrupt_trees(&bvh, &mesh, &rac_opts, n, seed));
        }
    }
    print_table(&rows);
    if rows.iter().all(|r| r.ok()) {
        Ok(())
    } else {
        Err("some case panicked or a must-catch attack went unnoticed".into())
    }
}
