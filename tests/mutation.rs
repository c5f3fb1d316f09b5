//! A short run of the mutation harness (`examples/support/mutate.rs`) over
//! every codec's file and its layout variants: every truncated, flipped,
//! forged or structurally corrupt file ends in an error from the reader, in
//! `verify` catching it, or in the original's answers (or, with checksums
//! recomputed, in a consistent different file); never a panic, a hang, an
//! accepted file inconsistent with its own triangles, or an ignored header
//! word. The long run is
//! `cargo run --release --features sims --example mutate`.
//!
//! A test binary of its own, outside `tests/suite`: it installs a global
//! allocator that records the largest allocation in the process, which the
//! suite's other tests, running beside it, would inflate.

#[path = "../examples/support/mutate.rs"]
mod mutate;

use mutate::print_table;

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
    let mesh = cbvh::scene::generate(cbvh::scene::Kind::Statue, 1000, 7, &mut |_, _| {}).unwrap();
    let mut rows = Vec::new();
    let mut originals = Vec::new();
    for v in mutate::variants() {
        let (mut subject, bvh, options) = mutate::variant(&mesh, v);
        subject.probe = Some(|| LARGEST.swap(0, std::sync::atomic::Ordering::Relaxed));
        // What reading the original allocates at most.
        let original = subject.largest_allocation(&subject.bytes);
        let attacks = subject.run(16, 42);
        originals.extend(attacks.iter().map(|_| (original, subject.bytes.len())));
        rows.extend(attacks);
        // The encoder's allocations are not a reader's.
        subject.probe = None;
        let trees = subject.corrupt_trees(&bvh, &mesh, &options, 9, 42);
        originals.push((usize::MAX / 4, subject.bytes.len()));
        rows.push(trees);
    }
    print_table(&rows);
    // Every codec and variant ran.
    for kind in cbvh::codec::CodecKind::ALL {
        assert!(
            rows.iter()
                .any(|r| r.codec.split(' ').next() == Some(kind.name())),
            "{} was not attacked",
            kind.name()
        );
    }
    // No attacked file made the reader, `verify` or the queries allocate
    // more than twice what the original made them allocate at most, or
    // twice the file: a forged count never buys a large allocation.
    for (r, (original, file)) in rows.iter().zip(&originals) {
        if let Some((largest, case)) = &r.largest_alloc {
            assert!(
                *largest <= 2 * original.max(file),
                "{} {}, {case}: an allocation of {largest} bytes, where the original's \
                 largest is {original} and its file {file} bytes",
                r.codec,
                r.attack
            );
        }
    }
    for r in &rows {
        assert!(r.ok(), "{r:?}");
        assert_eq!(
            r.cases,
            r.open_error + r.verify_error + r.same + r.consistent + r.inconsistent + r.panic,
            "{r:?}"
        );
        // Each attack is caught at least once (an attack that changes
        // nothing would test nothing), except the encoder's, which may
        // refuse every corrupt tree itself.
        if r.cases > 0 {
            assert!(r.open_error + r.verify_error > 0, "{r:?}");
        }
    }
}
