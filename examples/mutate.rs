//! The long run of the mutation harness: every codec's file of a generated
//! statue, in each layout variant, attacked with truncations, raw bit
//! flips, bit flips with checksums recomputed, forged header words and
//! section tables, and structurally corrupt trees written by the codec's
//! own encoder; prints the table of outcomes (Markdown).
//!
//! `cargo run --release --features sims --example mutate -- [TRIANGLES] [CASES] [SEED]`
//! (defaults 20000, 2000, 1). Exits with an error if any case panicked,
//! was accepted inconsistent with its own triangles, left a forged header
//! word unnoticed, or a must-catch attack gave another file.

#[path = "support/mutate.rs"]
mod mutate;

use mutate::print_table;

fn main() -> Result<(), String> {
    let arg = |k: usize, d: u64| {
        std::env::args().nth(k).map_or(Ok(d), |s| {
            s.parse().map_err(|e| format!("argument {k}: {e}"))
        })
    };
    let (tris, cases, seed) = (arg(1, 20_000)?, arg(2, 2000)?, arg(3, 1)?);
    // Panics are counted, not printed (unless MUTATE_PANICS is set).
    if std::env::var_os("MUTATE_PANICS").is_none() {
        std::panic::set_hook(Box::new(|_| {}));
    }
    let mesh = cbvh::scene::generate(cbvh::scene::Kind::Statue, tris as usize, 7, &mut |_, _| {})
        .map_err(|e| e.to_string())?;
    println!(
        "statue of {} triangles, {cases} cases per random attack, seed {seed}",
        mesh.triangles.len()
    );
    let mut rows = Vec::new();
    for v in mutate::variants() {
        let (subject, bvh, options) = mutate::variant(&mesh, v);
        rows.extend(subject.run(cases as usize, seed));
        let n = (cases as usize / 10).max(10);
        rows.push(subject.corrupt_trees(&bvh, &mesh, &options, n, seed));
    }
    print_table(&rows);
    if rows.iter().all(|r| r.ok()) {
        Ok(())
    } else {
        Err("some case failed: see the rows with a first bad case".into())
    }
}
