//! A short run of the mutation harness (`examples/support/mutate.rs`) over
//! every codec's file: every truncated, flipped, forged or structurally
//! corrupt file ends in an error from the reader, in `verify` catching it,
//! or in the original's answers (or, with checksums recomputed, in a
//! consistent different file); never a panic or a hang. The long run is
//! `cargo run --release --example mutate`.

#[path = "../examples/support/mutate.rs"]
mod mutate;

use cbvh::build::{BuildOptions, build};
use cbvh::codec::plain::PlainBvh;
use cbvh::codec::racbvh::{RacBvh, RacOptions};
use mutate::{Subject, print_table};

#[test]
fn every_codec_survives_the_mutation_harness() {
    let mesh = cbvh::scene::generate(cbvh::scene::Kind::Statue, 1500, 7, &mut |_, _| {}).unwrap();
    let bvh = build(&mesh, &BuildOptions::default(), &|_, _| {}).unwrap();
    let plain = PlainBvh::new(&bvh, &mesh).to_bytes();
    let rac_opts = RacOptions {
        cluster_nodes: 256,
        ..Default::default()
    };
    let rac = RacBvh::encode(&bvh, &mesh, &rac_opts).unwrap().to_bytes();
    let mut rows = Vec::new();
    for (codec, bytes) in [("plain", plain), ("racbvh", rac)] {
        let subject = Subject::new(codec, bytes);
        rows.extend(subject.run(60, 42));
        if codec == "racbvh" {
            rows.push(subject.racbvh_corrupt_trees(&bvh, &mesh, &rac_opts, 24, 42));
        }
    }
    print_table(&rows);
    for r in &rows {
        assert!(r.ok(), "{r:?}");
        assert_eq!(
            r.cases,
            r.open_error + r.verify_error + r.same + r.consistent,
            "{r:?}"
        );
        // Each attack is caught at least once (an attack that changes
        // nothing would test nothing).
        assert!(r.open_error + r.verify_error > 0, "{r:?}");
    }
}
