//! A short run of the mutation harness (`examples/support/mutate.rs`) over
//! every codec's file: every truncated, flipped, forged or structurally
//! corrupt file ends in an error from the reader, in `verify` catching it,
//! or in the original's answers (or, with checksums recomputed, in a
//! consistent different file); never a panic or a hang. The long run is
//! `cargo run --release --example mutate`.
//!
//! A test binary of its own, outside `tests/suite`: it installs a global
//! allocator that records the largest allocation in the process, which the
//! suite's other tests, running beside it, would inflate.

#[path = "../examples/support/mutate.rs"]
mod mutate;

use cbvh::build::{BuildOptions, build};
use cbvh::codec::plain::PlainBvh;
use cbvh::codec::racbvh::{RacBvh, RacOptions};
use mutate::{Subject, print_table};

/// Counts the largest single allocation, so that a forged count that makes
/// a reader or `verify` allocate far more than the file is caught.
struct Largest;

static LARGEST: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

// SAFETY: forwards every call to the system allocator unchanged; only
// records the requested size.
unsafe impl std::alloc::GlobalAlloc for Largest {
    unsafe fn alloc(&self, l: std::alloc::Layout) -> *mut u8 {
        LARGEST.fetch_max(l.size(), std::sync::atomic::Ordering::Relaxed);
        // SAFETY: the caller's contract is passed on unchanged.
        unsafe { std::alloc::System.alloc(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: std::alloc::Layout) {
        // SAFETY: `p` came from `System.alloc` with layout `l`.
        unsafe { std::alloc::System.dealloc(p, l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: std::alloc::Layout, size: usize) -> *mut u8 {
        LARGEST.fetch_max(size, std::sync::atomic::Ordering::Relaxed);
        // SAFETY: as for `realloc` on the system allocator.
        unsafe { std::alloc::System.realloc(p, l, size) }
    }
}

#[global_allocator]
static ALLOC: Largest = Largest;

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
    let biggest_file = plain.len().max(rac.len());
    let mut rows = Vec::new();
    for (codec, bytes) in [("plain", plain), ("racbvh", rac)] {
        let subject = Subject::new(codec, bytes);
        rows.extend(subject.run(60, 42));
        if codec == "racbvh" {
            rows.push(subject.racbvh_corrupt_trees(&bvh, &mesh, &rac_opts, 24, 42));
        }
    }
    print_table(&rows);
    // No case allocated more than the largest file (plus the decoded mesh
    // and a cluster's working set, both bounded by the original).
    let largest = LARGEST.load(std::sync::atomic::Ordering::Relaxed);
    assert!(
        largest <= 2 * biggest_file,
        "an allocation of {largest} bytes for files of at most {biggest_file}"
    );
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
