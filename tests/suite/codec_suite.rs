//! The shared codec test suite: every test written once, generic over
//! [`Codec`], and run on every codec by one line at the end of this file:
//!
//! ```text
//! codec_suite!(name, CodecType, lossless: [options, ...], lossy: [options, ...]
//!     [, renumbered: [options, ...]]);
//! ```
//!
//! `lossless` options must decode the very mesh that was encoded (the
//! suite asserts it); `lossy` ones (quantized vertices) are checked against
//! their own decoded mesh; `renumbered` ones (ids in the codec's own order,
//! hcc's tree order) must decode the encoded triangles exactly, in any
//! order, and are then checked against their own decoded mesh. Every query is compared with brute force over the
//! decoded mesh, every box a cursor reports must contain every triangle
//! below it, and damaged files must give errors, never panics. Tests of one
//! codec's own API (RACBVH's cache, random access, options) stay in that
//! codec's test file.

use crate::common;

use std::path::PathBuf;

use cbvh::build::{CanonicalBvh, Layout};
use cbvh::codec::common::MassProps;
use cbvh::codec::{AnyCodec, ByteSize, Codec, CodecFileError, OpenOptions};
use cbvh::contact::EdgeFlags;
use cbvh::geom::{Aabb, Pose, Ray};
use cbvh::query::{self, RayCursor, RayHit};
use cbvh::scene::{Kind, generate};
use cbvh::{Mesh, NodeCursor, TraversalStats};
use common::*;
use glam::Vec3A;

/// A codec's option sets under test.
pub struct Variants<C: Codec> {
    /// Options that must decode the encoded mesh exactly.
    pub lossless: Vec<C::Options>,
    /// Options that may move vertices (checked against the decoded mesh).
    pub lossy: Vec<C::Options>,
    /// Options that renumber the triangles (their exact corners, any ids).
    pub renumbered: Vec<C::Options>,
}

/// What an option set promises of the decoded mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fidelity {
    /// The encoded mesh itself.
    Lossless,
    /// The same triangles in the same order, corners moved a little.
    Lossy,
    /// The same triangles, corner for corner, in another order.
    Renumbered,
}

impl<C: Codec> Variants<C> {
    /// Every option set, with what it promises.
    fn all(&self) -> impl Iterator<Item = (&C::Options, Fidelity)> {
        let lossless = self.lossless.iter().map(|o| (o, Fidelity::Lossless));
        let lossy = self.lossy.iter().map(|o| (o, Fidelity::Lossy));
        let renumbered = self.renumbered.iter().map(|o| (o, Fidelity::Renumbered));
        lossless.chain(lossy).chain(renumbered)
    }
}

/// A mesh's triangles as corner positions (bit patterns), sorted: equal
/// for two meshes holding the same triangles in any order.
fn triangle_multiset(m: &Mesh) -> Vec<[[u32; 3]; 3]> {
    let mut v: Vec<[[u32; 3]; 3]> = (0..m.triangles.len())
        .map(|t| m.triangle_vertices(t).map(|p| p.map(f32::to_bits)))
        .collect();
    v.sort_unstable();
    v
}

fn encode<C: Codec>(bvh: &CanonicalBvh, mesh: &Mesh, o: &C::Options) -> C {
    C::encode(bvh, mesh, o).unwrap_or_else(|e| panic!("{}: encode {o:?}: {e}", C::KIND))
}

fn temp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("cbvh-suite-{}-{name}", std::process::id()))
}

fn hits<C: RayCursor>(c: &C, mesh: &Mesh) -> Vec<Option<RayHit>> {
    let mut stats = TraversalStats::default();
    test_rays(mesh, 5, 100)
        .iter()
        .map(|r| query::closest_hit(c, r, f32::INFINITY, &mut stats))
        .collect()
}

/// The decoded mesh: lossless options give the encoded mesh itself, lossy
/// ones the same triangles with every corner within 2 % of the mesh's
/// largest extent of the original, renumbered ones the same triangles with
/// the same corners in another order.
fn check_decoded<C: Codec>(c: &C, mesh: &Mesh, fidelity: Fidelity) -> Mesh {
    let dm = c.decoded_mesh();
    match fidelity {
        Fidelity::Lossless => {
            assert_eq!(dm, *mesh, "{}: lossless options changed the mesh", C::KIND);
            return dm;
        }
        Fidelity::Renumbered => {
            assert_eq!(
                triangle_multiset(&dm),
                triangle_multiset(mesh),
                "{}: renumbering options changed the triangles",
                C::KIND
            );
            return dm;
        }
        Fidelity::Lossy => {}
    }
    assert_eq!(dm.triangles.len(), mesh.triangles.len());
    let (lo, hi) = mesh.bounds().unwrap_or(([0.0; 3], [0.0; 3]));
    let extent = (Vec3A::from(hi) - Vec3A::from(lo)).max_element();
    let scale = Vec3A::from(lo)
        .abs()
        .max(Vec3A::from(hi).abs())
        .max_element();
    let tol = 0.02 * extent + 4.0 * f32::EPSILON * scale;
    for t in 0..mesh.triangles.len() {
        let (a, b) = (mesh.triangle_vertices(t), dm.triangle_vertices(t));
        for k in 0..3 {
            let d = (Vec3A::from(a[k]) - Vec3A::from(b[k])).abs().max_element();
            assert!(
                d <= tol,
                "triangle {t} corner {k}: {:?} decoded as {:?}",
                a[k],
                b[k]
            );
        }
    }
    dm
}

/// What the contract promises besides traversal: vertex indices into the
/// decoded mesh, the cursor's triangles from the decoded mesh, sizes by
/// part adding up, and the mass of the original mesh.
fn check_contract<C: Codec>(c: &C, mesh: &Mesh, dm: &Mesh) {
    assert_eq!(c.triangle_count(), mesh.triangles.len());
    for id in 0..dm.triangles.len() as u32 {
        let v = c.triangle_vertices(id);
        assert_eq!(v, dm.triangles[id as usize], "triangle_vertices({id})");
        assert!(v.iter().all(|&i| (i as usize) < dm.vertices.len()));
        let corners = NodeCursor::triangle(c, id).map(|p| p.to_array());
        assert_eq!(corners, dm.triangle_vertices(id as usize), "triangle({id})");
    }
    let parts = c.bytes_by_part();
    assert!(!parts.is_empty(), "{}: no parts", C::KIND);
    let mut names: Vec<&str> = parts.iter().map(|p| p.0).collect();
    assert!(names.iter().all(|n| !n.is_empty()));
    names.sort_unstable();
    names.dedup();
    assert_eq!(names.len(), parts.len(), "part names repeat: {parts:?}");
    assert_eq!(parts.iter().map(|p| p.1).sum::<usize>(), c.bytes_total());
    assert!(c.bytes_total() > 0);
    // Stored at encoding time from the original mesh; for lossless options
    // that is the decoded mesh's too.
    assert_eq!(c.mass(), MassProps::of_mesh(mesh), "{}: mass", C::KIND);
    if dm == mesh {
        assert_eq!(c.mass(), MassProps::of_mesh(dm));
    }
}

/// Structure (conservative boxes, every triangle once, triangles as
/// decoded), every single-tree query against brute force, and the contract.
fn check_all<C: Codec>(c: &C, mesh: &Mesh, fidelity: Fidelity, seed: u64) -> Mesh {
    let dm = check_decoded(c, mesh, fidelity);
    check_structure(c, &dm);
    check_queries(c, &dm, seed);
    check_best_first(c, &dm, seed);
    check_contract(c, mesh, &dm);
    dm
}

/// A random soup in the given layout and leaf size, with every option set.
pub fn soup_case<C: Codec>(v: &Variants<C>, seed: u64, n: usize, layout: usize, leaf: usize) {
    let mesh = soup(seed, n, 10.0);
    let bvh = tree(&mesh, Layout::ALL[layout % Layout::ALL.len()], leaf);
    for (o, fidelity) in v.all() {
        check_all(&encode::<C>(&bvh, &mesh, o), &mesh, fidelity, seed);
    }
}

/// A small generated mesh (closed statue, multi-part turbine, robot).
pub fn generated_case<C: Codec>(v: &Variants<C>, seed: u64, kind: usize) {
    let kind = [Kind::Statue, Kind::Turbine, Kind::Robot][kind % 3];
    let mesh = generate(kind, 1000, seed, &mut |_, _| {}).unwrap();
    let bvh = tree(&mesh, Layout::ALL[seed as usize % Layout::ALL.len()], 1);
    for (o, fidelity) in v.all() {
        check_all(&encode::<C>(&bvh, &mesh, o), &mesh, fidelity, seed);
    }
}

/// Two trees, each with every option set, against brute force: BVTT pairs,
/// its early exit, the parallel traversal and two-tree branch and bound.
pub fn two_tree_case<C: Codec>(v: &Variants<C>, seed: u64, na: usize, nb: usize) {
    let ma = soup(seed, na, 2.0);
    let mb = soup(seed.wrapping_add(1), nb, 2.0);
    let ta = tree(&ma, Layout::DepthFirst, 1);
    let tb = tree(&mb, Layout::CacheEfficient, 2);
    let all: Vec<_> = v.all().collect();
    for (k, (o, _)) in all.iter().enumerate() {
        let a = encode::<C>(&ta, &ma, o);
        // B with the next option set, so that mixed settings meet too.
        let b = encode::<C>(&tb, &mb, all[(k + 1) % all.len()].0);
        let (da, db) = (a.decoded_mesh(), b.decoded_mesh());
        check_bvtt(&a, &da, &b, &db, seed);
        check_bvtt_par_and_min(&a, &da, &b, &db, seed);
    }
}

/// Encode, save, open through the registry and through the codec's own
/// reader (with a small cache, for codecs that have one), and read the
/// bytes back: the same decoded mesh, answers, sizes and mass every way.
pub fn round_trip<C: Codec>(v: &Variants<C>) {
    let mesh = generate(Kind::Statue, 1500, 2, &mut |_, _| {}).unwrap();
    let bvh = tree(&mesh, Layout::CacheEfficient, 1);
    for (k, (o, fidelity)) in v.all().enumerate() {
        let c = encode::<C>(&bvh, &mesh, o);
        let dm = check_decoded(&c, &mesh, fidelity);
        c.verify().unwrap();
        let want = hits(&c, &dm);
        let bytes = c.to_bytes();
        assert!(bytes.starts_with(&C::MAGIC));
        let path = temp(&format!("{}-{k}.bin", C::KIND));
        c.save(&path).unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), bytes, "save writes to_bytes");

        let any = AnyCodec::open(&path, &OpenOptions::default()).unwrap();
        assert_eq!(any.kind(), C::KIND);
        assert_eq!(any.decoded_mesh(), dm);
        assert_eq!(cbvh::with_codec!(&any, |a| hits(a, &dm)), want);
        // The parts in memory depend on the cache budget (hcc-ooc decodes
        // whole or runs out of core by it): the same as the same bytes
        // read with the same options.
        let parts = |o: &OpenOptions| C::from_bytes(&bytes, o).unwrap().bytes_by_part();
        assert_eq!(any.bytes_by_part(), parts(&OpenOptions::default()));
        assert_eq!(any.mass(), c.mass());
        assert_eq!(any.to_bytes(), bytes);

        let small = OpenOptions {
            verify: false,
            cache_budget_bytes: 16 << 10,
        };
        let own = C::open(&path, &small).unwrap();
        own.verify().unwrap();
        assert_eq!(own.decoded_mesh(), dm);
        assert_eq!(hits(&own, &dm), want);
        check_structure(&own, &dm);
        assert_eq!(own.bytes_by_part(), parts(&small));
        assert_eq!(own.mass(), c.mass());
        drop((any, own));
        std::fs::remove_file(&path).unwrap();

        let back = C::from_bytes(&bytes, &small).unwrap();
        back.verify().unwrap();
        assert_eq!(back.to_bytes(), bytes, "reading and writing is stable");
        assert_eq!(hits(&back, &dm), want);

        assert!(C::open(&path, &small).is_err(), "opening a missing file");
        let e = AnyCodec::open(&path, &OpenOptions::default()).unwrap_err();
        assert!(matches!(e, CodecFileError::Io(_)), "{e}");
    }
}

/// The edge flags: computed when encoding from the codec's own triangles
/// (its ids, its vertex precision) and equal to a fresh computation by id
/// ([`EdgeFlags::compute`] over [`NodeCursor::triangle`], not the
/// traversal the encoder used); read back unchanged from the bytes and
/// from the file, with any cache budget. A closed mesh, a multi-part one
/// and an open soup, every option set.
pub fn edge_flags_round_trip<C: Codec>(v: &Variants<C>) {
    let meshes = [
        generate(Kind::Statue, 1500, 6, &mut |_, _| {}).unwrap(),
        generate(Kind::Turbine, 1500, 6, &mut |_, _| {}).unwrap(),
        soup(6, 400, 3.0),
    ];
    for (m, mesh) in meshes.iter().enumerate() {
        let bvh = tree(mesh, Layout::CacheEfficient, 1 + m % 2);
        for (k, (o, _)) in v.all().enumerate() {
            let c = encode::<C>(&bvh, mesh, o);
            let e = c.edge_flags();
            let n = c.triangle_count();
            let fresh = EdgeFlags::compute(n, |id| NodeCursor::triangle(&c, id));
            assert_eq!(e.len(), n, "{}: mesh {m}", C::KIND);
            assert_eq!(
                e.as_slice(),
                fresh.as_slice(),
                "{}: mesh {m}, {o:?}",
                C::KIND
            );
            // The counters and the volume too, bit for bit.
            assert_eq!(e, &fresh, "{}: mesh {m}, {o:?}", C::KIND);
            let bytes = c.to_bytes();
            for budget in [usize::MAX, 1] {
                let o = OpenOptions {
                    verify: true,
                    cache_budget_bytes: budget,
                };
                let back = C::from_bytes(&bytes, &o).unwrap();
                assert_eq!(
                    back.edge_flags(),
                    e,
                    "{}: from bytes, budget {budget}",
                    C::KIND
                );
            }
            let path = temp(&format!("{}-edges-{m}-{k}.bin", C::KIND));
            c.save(&path).unwrap();
            let any = AnyCodec::open(&path, &OpenOptions::default()).unwrap();
            assert_eq!(any.edge_flags(), e, "{}: through the registry", C::KIND);
            std::fs::remove_file(&path).unwrap();
        }
    }
}

/// Meshes at the edges of what a builder and a codec take, and one large
/// enough for many clusters or blocks.
fn edge_meshes() -> Vec<(&'static str, Mesh)> {
    let mut out = common::edge_meshes();
    out.push(("3000-triangle soup", soup(5, 3000, 20.0)));
    out
}

/// Every edge mesh, in two leaf sizes, with every option set.
pub fn edge_cases<C: Codec>(v: &Variants<C>) {
    for (name, mesh) in edge_meshes() {
        for (layout, leaf) in [(Layout::VanEmdeBoas, 1), (Layout::DepthFirst, 4)] {
            let bvh = tree(&mesh, layout, leaf);
            for (o, fidelity) in v.all() {
                let c = C::encode(&bvh, &mesh, o)
                    .unwrap_or_else(|e| panic!("{}: {name}: encode {o:?}: {e}", C::KIND));
                c.verify()
                    .unwrap_or_else(|e| panic!("{}: {name}: verify: {e}", C::KIND));
                let dm = check_all(&c, &mesh, fidelity, 5);
                if mesh.triangles.len() <= 200 {
                    check_bvtt(&c, &dm, &c, &dm, 9);
                }
                let back = C::from_bytes(&c.to_bytes(), &OpenOptions::default()).unwrap();
                back.verify().unwrap();
                assert_eq!(back.decoded_mesh(), dm, "{name}");
                assert_eq!(back.edge_flags(), c.edge_flags(), "{name}");
                assert_eq!(c.edge_flags().len(), mesh.triangles.len(), "{name}");
                assert_eq!(hits(&back, &dm), hits(&c, &dm), "{name}");
            }
        }
    }
}

/// The empty mesh: either a tree that answers nothing and survives a
/// round trip, or an error that says something.
pub fn empty_mesh<C: Codec>(v: &Variants<C>) {
    let mesh = Mesh::default();
    let bvh = tree(&mesh, Layout::VanEmdeBoas, 1);
    for (o, _) in v.all() {
        let c = match C::encode(&bvh, &mesh, o) {
            Ok(c) => c,
            Err(e) => {
                assert!(!e.to_string().is_empty(), "{}: a silent error", C::KIND);
                continue;
            }
        };
        c.verify().unwrap();
        assert_eq!(c.triangle_count(), 0);
        assert!(c.root().1.is_empty(), "an empty tree's root box is empty");
        assert_eq!(c.decoded_mesh().triangles.len(), 0);
        assert_eq!(c.mass(), MassProps::ZERO);
        let mut stats = TraversalStats::default();
        let ray = Ray::new(Vec3A::ZERO, Vec3A::X);
        assert!(query::closest_hit(&c, &ray, f32::INFINITY, &mut stats).is_none());
        assert!(!query::any_hit(&c, &ray, f32::INFINITY, &mut stats));
        assert!(query::closest_point(&c, Vec3A::ONE, f32::INFINITY, &mut stats).is_none());
        let everything = Aabb::new(Vec3A::splat(-1e30), Vec3A::splat(1e30));
        query::overlap(&c, &everything, &mut stats, |id, _| {
            panic!("the empty tree reported triangle {id}")
        });
        assert!(query::bvtt_pairs(&c, &c, &Pose::IDENTITY, 1.0, &mut stats).is_empty());
        let back = C::from_bytes(&c.to_bytes(), &OpenOptions::default()).unwrap();
        back.verify().unwrap();
        assert_eq!(back.triangle_count(), 0);
        assert_eq!(back.to_bytes(), c.to_bytes());
        assert!(back.edge_flags().is_empty() && c.edge_flags().is_empty());
    }
}

/// Truncations and bit flips of a saved file: an error from reading or
/// verifying, never a panic and never a file that passes as sound.
pub fn corruption<C: Codec>(v: &Variants<C>) {
    let mesh = generate(Kind::Statue, 1000, 4, &mut |_, _| {}).unwrap();
    let bvh = tree(&mesh, Layout::CacheEfficient, 2);
    let opts = OpenOptions {
        verify: false,
        cache_budget_bytes: 1 << 16,
    };
    let mut rng = Rng(0xC0DEC ^ C::MAGIC[0] as u64);
    for (k, (o, _)) in v.all().enumerate() {
        let c = encode::<C>(&bvh, &mesh, o);
        let bytes = c.to_bytes();
        let n = bytes.len();
        // Every length in the first 512 bytes (headers), then strided.
        let lens = (0..n.min(512))
            .chain((512..n).step_by(n / 150 + 1))
            .chain([n - 1]);
        for len in lens {
            assert!(
                C::from_bytes(&bytes[..len], &opts).is_err(),
                "{}: truncated to {len} of {n} bytes",
                C::KIND
            );
        }
        // Single-bit flips: half in the first 512 bytes, half anywhere.
        for f in 0..300 {
            let mut bad = bytes.clone();
            let at = if f % 2 == 0 {
                rng.below(n.min(512))
            } else {
                rng.below(n)
            };
            bad[at] ^= 1 << rng.below(8);
            if let Ok(t) = C::from_bytes(&bad, &opts) {
                assert!(
                    t.verify().is_err(),
                    "{}: a flip at byte {at} of {n} went unnoticed",
                    C::KIND
                );
            }
        }
        // Through files and the registry (verify on by default).
        let path = temp(&format!("{}-bad-{k}.bin", C::KIND));
        for _ in 0..8 {
            let mut bad = bytes.clone();
            let at = 8 + rng.below(n - 8);
            bad[at] ^= 1 << rng.below(8);
            std::fs::write(&path, &bad).unwrap();
            let e = AnyCodec::open(&path, &OpenOptions::default());
            assert!(
                matches!(
                    e,
                    Err(CodecFileError::Open { .. } | CodecFileError::Verify { .. })
                ),
                "{}: a flip at byte {at} opened as {e:?}",
                C::KIND
            );
        }
        std::fs::write(&path, &bytes[..n / 2]).unwrap();
        assert!(AnyCodec::open(&path, &OpenOptions::default()).is_err());
        std::fs::remove_file(&path).unwrap();
    }
}

/// Generates the module `$name` running the whole suite on `$codec` with
/// the given option sets.
macro_rules! codec_suite {
    ($name:ident, $codec:ty, lossless: [$($ll:expr),* $(,)?], lossy: [$($ly:expr),* $(,)?]) => {
        codec_suite!($name, $codec, lossless: [$($ll),*], lossy: [$($ly),*], renumbered: []);
    };
    ($name:ident, $codec:ty, lossless: [$($ll:expr),* $(,)?], lossy: [$($ly:expr),* $(,)?],
        renumbered: [$($rn:expr),* $(,)?]) => {
        mod $name {
            use super::*;
            use proptest::prelude::*;

            fn variants() -> Variants<$codec> {
                Variants {
                    lossless: vec![$($ll),*],
                    lossy: vec![$($ly),*],
                    renumbered: vec![$($rn),*],
                }
            }

            #[test]
            fn round_trip_through_files_and_bytes() {
                round_trip(&variants());
            }

            #[test]
            fn edge_flags_are_stored_and_read_back() {
                edge_flags_round_trip(&variants());
            }

            #[test]
            fn edge_case_meshes_match_brute_force() {
                edge_cases(&variants());
            }

            #[test]
            fn empty_mesh_answers_nothing_or_is_an_error() {
                empty_mesh(&variants());
            }

            #[test]
            fn damaged_files_are_errors_never_panics() {
                corruption(&variants());
            }

            proptest! {
                #![proptest_config(ProptestConfig::with_cases(24))]

                #[test]
                fn random_soups_match_brute_force(
                    seed in any::<u64>(), n in 1usize..120, layout in 0usize..3, leaf in 1usize..4
                ) {
                    soup_case(&variants(), seed, n, layout, leaf);
                }

                #[test]
                fn two_trees_match_brute_force(seed in any::<u64>(), na in 1usize..50, nb in 1usize..50) {
                    two_tree_case(&variants(), seed, na, nb);
                }
            }

            proptest! {
                #![proptest_config(ProptestConfig::with_cases(6))]

                #[test]
                fn generated_meshes_match_brute_force(seed in 0u64..1000, kind in 0usize..3) {
                    generated_case(&variants(), seed, kind);
                }
            }
        }
    };
}

/// RACBVH options with small clusters (so that small meshes span several).
fn rac(bits: u32, vertex_bits: Option<u32>) -> cbvh::codec::racbvh::RacOptions {
    cbvh::codec::racbvh::RacOptions {
        cluster_nodes: 256,
        bits,
        vertex_bits,
        ..Default::default()
    }
}

/// hcc options: `f32` or quantized vertices, with or without the input's
/// vertex ids (without them the decoded mesh repeats shared vertices, so
/// it is checked as a lossy one), input triangle ids kept.
fn hcc(vertex_bits: Option<u32>, vertex_ids: bool) -> cbvh::codec::hcc::HccOptions {
    cbvh::codec::hcc::HccOptions {
        vertex_bits,
        vertex_ids,
        triangle_ids: true,
    }
}

/// hcc in tree order: triangles numbered as stored (no triangle id map),
/// with or without the input's vertex ids; `f32` vertices.
fn hcc_tree_order(vertex_ids: bool) -> cbvh::codec::hcc::HccOptions {
    cbvh::codec::hcc::HccOptions {
        vertex_ids,
        ..cbvh::codec::hcc::HccOptions::tree_order(None)
    }
}

/// o-HCCMesh options: `bits` per grid coordinate, the input's triangle ids
/// kept (so that the decoded mesh is checked triangle by triangle), with
/// or without its vertex ids, and a cache budget: `usize::MAX` decodes
/// the whole model, 1 byte runs it out of core with no tree ever cached.
fn ooc(vertex_bits: u32, vertex_ids: bool, budget: usize) -> cbvh::codec::hcc::ooc::OocOptions {
    cbvh::codec::hcc::ooc::OocOptions {
        vertex_bits,
        vertex_ids,
        triangle_ids: true,
        cache_budget_bytes: budget,
    }
}

// One line per codec.
codec_suite!(plain, cbvh::codec::plain::PlainBvh, lossless: [()], lossy: []);
/// RACBVH options with a 2 KiB cache: smaller than any tree of more than
/// a few dozen triangles, so that queries go through the node cache, with
/// clusters evicted all the time.
fn rac_tiny_cache() -> cbvh::codec::racbvh::RacOptions {
    cbvh::codec::racbvh::RacOptions {
        cache_budget_bytes: 2048,
        ..rac(16, None)
    }
}

codec_suite!(racbvh, cbvh::codec::racbvh::RacBvh, lossless: [rac(16, None), rac_tiny_cache()], lossy: [rac(8, Some(8)), rac(16, Some(16))]);
codec_suite!(clbvh, cbvh::codec::clbvh::ClBvh, lossless: [Default::default()], lossy: []);
codec_suite!(clbvh_compact, cbvh::codec::clbvh::ClBvhCompact, lossless: [Default::default()], lossy: []);
codec_suite!(hcc, cbvh::codec::hcc::HccBvh, lossless: [hcc(None, true)], lossy: [hcc(None, false), hcc(Some(16), true), hcc(Some(8), false)]);
codec_suite!(hcc_tree_order, cbvh::codec::hcc::HccBvh, lossless: [], lossy: [], renumbered: [hcc_tree_order(false), hcc_tree_order(true)]);
codec_suite!(hcc_ooc, cbvh::codec::hcc::ooc::HccOocBvh, lossless: [], lossy: [ooc(16, false, usize::MAX), ooc(8, true, usize::MAX), ooc(16, true, 1)]);
