//! The CLBVH codec: checked against brute force with the shared suite in
//! `common`, against the plain codec answer for answer, and for the
//! conservative-box invariant on random, generated, flat, collinear and
//! far-from-origin meshes.

use crate::common;

use std::collections::BTreeSet;
use std::ops::ControlFlow;

use cbvh::build::Layout;
use cbvh::codec::clbvh::{ClBvh, ClError, ClNode, ClOptions, LeafKind, NodeKind};
use cbvh::codec::plain::PlainBvh;
use cbvh::codec::{ByteSize, Codec};
use cbvh::cursor::NodeCursor;
use cbvh::geom::{Aabb, Pose};
use cbvh::{Mesh, TraversalStats, query};
use common::*;
use glam::Vec3A;
use proptest::prelude::*;

/// Every variant: fast and compact with and without multi-leaf nodes, at
/// leaf sizes 1, 4 and 10.
fn variants() -> Vec<ClOptions> {
    let mut v = Vec::new();
    for leaves in [LeafKind::Fast, LeafKind::Compact] {
        for leaf_size in [1, 4, 10] {
            for multi_leaf in [true, false] {
                v.push(ClOptions {
                    leaf_size,
                    leaves,
                    multi_leaf,
                });
            }
        }
    }
    v
}

fn statue(tris: usize, seed: u64) -> Mesh {
    cbvh::scene::generate(cbvh::scene::Kind::Statue, tris, seed, &mut |_, _| {}).unwrap()
}

/// Every query gives the same bits as on the plain tree: closest hits
/// (distance, triangle, barycentrics), any hits, packets, overlap sets,
/// closest points.
fn check_parity_with_plain(cl: &ClBvh, plain: &PlainBvh, mesh: &Mesh, seed: u64) {
    let mut s = TraversalStats::default();
    for ray in test_rays(mesh, seed, 96) {
        for t_max in [f32::INFINITY, 0.7] {
            assert_eq!(
                query::closest_hit(cl, &ray, t_max, &mut s),
                query::closest_hit(plain, &ray, t_max, &mut s),
                "closest hit differs for {ray:?}"
            );
            assert_eq!(
                query::any_hit(cl, &ray, t_max, &mut s),
                query::any_hit(plain, &ray, t_max, &mut s)
            );
        }
    }
    let rays = test_rays(mesh, seed ^ 1, 64);
    let (mut a, mut b) = (vec![None; 64], vec![None; 64]);
    query::closest_hits(cl, &rays, f32::INFINITY, &mut a, &mut s);
    query::closest_hits(plain, &rays, f32::INFINITY, &mut b, &mut s);
    assert_eq!(a, b, "packet hits differ");
    // CLBVH casts packets ray by ray; the generic packet walk over its
    // batches must agree too.
    let limits = [f32::INFINITY; 64];
    query::packet::closest_hits_generic(cl, &rays, &limits, &mut a, &mut s);
    assert_eq!(a, b, "generic packet hits differ");
    let mut rng = Rng(seed);
    let (lo, hi) = mesh.bounds().unwrap_or(([0.0; 3], [1.0; 3]));
    let (lo, hi) = (Vec3A::from(lo), Vec3A::from(hi));
    for _ in 0..24 {
        let p = lo + (hi - lo) * rng.vec(-0.2, 1.2);
        let q = p + (hi - lo) * rng.vec(0.0, 0.3);
        let qb = Aabb::new(p.min(q), p.max(q));
        let set = |c: &dyn Fn(&mut BTreeSet<u32>)| {
            let mut out = BTreeSet::new();
            c(&mut out);
            out
        };
        let mut s1 = TraversalStats::default();
        let got = set(&|o| {
            query::overlap(cl, &qb, &mut s1.clone(), |id, _| {
                o.insert(id);
                ControlFlow::Continue(())
            });
        });
        let want = set(&|o| {
            query::overlap(plain, &qb, &mut s1.clone(), |id, _| {
                o.insert(id);
                ControlFlow::Continue(())
            });
        });
        assert_eq!(got, want);
        let cp = query::closest_point(cl, p, f32::INFINITY, &mut s1);
        let pp = query::closest_point(plain, p, f32::INFINITY, &mut s1);
        assert_eq!(cp.map(|h| h.distance), pp.map(|h| h.distance));
    }
}

/// Every decoded child box contains every triangle below it (all ancestor
/// boxes, not just the parent's), every triangle appears once with the
/// mesh's corners and vertex indices, and the decoded mesh is the mesh.
fn check_codec(cl: &ClBvh, mesh: &Mesh) {
    check_structure(cl, mesh);
    for id in 0..mesh.triangles.len() {
        assert_eq!(cl.vertex_indices(id as u32), mesh.triangles[id]);
    }
    assert_eq!(cl.decoded_mesh(), *mesh);
    // Word arrays, but for the edge flags (a byte a triangle).
    let parts = cl.bytes_by_part();
    assert!(
        parts.iter().all(|p| p.1 % 4 == 0 || p.0 == "edge-flags"),
        "{parts:?}"
    );
}

/// Flat (all in one plane), collinear (all on one line) and far from the
/// origin (a small soup shifted by `offset`): the meshes where 8-bit
/// quantization rounds worst.
fn awkward(seed: u64, n: usize, offset: f32) -> Vec<Mesh> {
    let base = soup(seed, n, 1.0);
    let flat = Mesh::new(
        base.vertices.iter().map(|v| [v[0], v[1], 0.25]).collect(),
        base.triangles.clone(),
    );
    let line = Mesh::new(
        base.vertices
            .iter()
            .map(|v| [v[0], v[0] * 0.5, -v[0]])
            .collect(),
        base.triangles.clone(),
    );
    let far = Mesh::new(
        base.vertices
            .iter()
            .map(|v| [v[0] + offset, v[1] - offset, v[2] * 1e-3 + offset])
            .collect(),
        base.triangles.clone(),
    );
    vec![flat, line, far]
}

/// Closest hits, any hits and closest points against brute force (the
/// shared `check_queries` without its packet hit count, which flat and
/// collinear meshes cannot meet).
fn check_rays_and_points(cl: &ClBvh, mesh: &Mesh, seed: u64) {
    let mut s = TraversalStats::default();
    for ray in test_rays(mesh, seed, 64) {
        let got = query::closest_hit(cl, &ray, f32::INFINITY, &mut s);
        let want = brute_closest(mesh, &ray, f32::INFINITY);
        assert_eq!(
            got.is_some(),
            want.is_some(),
            "{ray:?}: {got:?} vs {want:?}"
        );
        if let (Some(g), Some((t, _))) = (got, want) {
            assert_eq!(g.t, t, "{ray:?}");
        }
        assert_eq!(
            query::any_hit(cl, &ray, f32::INFINITY, &mut s),
            want.is_some()
        );
    }
    let mut rng = Rng(seed);
    let (lo, hi) = mesh.bounds().unwrap();
    let (lo, hi) = (Vec3A::from(lo), Vec3A::from(hi));
    for _ in 0..16 {
        check_closest_point(cl, mesh, lo + (hi - lo) * rng.vec(-0.2, 1.2), &mut s);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(16))]

    #[test]
    fn soups_match_brute_force_and_plain(seed in any::<u64>(), n in 1usize..200, leaf in 1usize..3) {
        let mesh = soup(seed, n, 10.0);
        let layout = Layout::ALL[(seed % 3) as usize];
        let bvh = tree(&mesh, layout, leaf);
        let plain = PlainBvh::new(&bvh, &mesh);
        for opts in variants().into_iter().filter(|o| o.leaf_size >= leaf) {
            let cl = ClBvh::encode(&bvh, &mesh, &opts).unwrap();
            check_codec(&cl, &mesh);
            check_queries(&cl, &mesh, seed);
            check_parity_with_plain(&cl, &plain, &mesh, seed);
        }
    }

    #[test]
    fn boxes_are_conservative_on_flat_collinear_and_far_meshes(
        seed in any::<u64>(),
        n in 1usize..300,
        offset in prop_oneof![Just(1e4f32), Just(-5e4f32), Just(3e6f32), Just(-7e7f32), 1.0f32..1e8],
    ) {
        for (k, mesh) in awkward(seed, n, offset).into_iter().enumerate() {
            // Queries against brute force where f32 ray arithmetic is
            // meaningful: as in `far_from_origin.rs`, not beyond 1e5, where
            // the slab test and the watertight triangle test (plain's boxes
            // too) disagree on grazing axis-parallel rays.
            let queries = k < 2 || offset.abs() < 1e5;
            let bvh = tree(&mesh, Layout::DepthFirst, 1);
            for opts in [ClOptions::default(), ClOptions::compact(), ClOptions { leaf_size: 1, ..Default::default() }] {
                let cl = ClBvh::encode(&bvh, &mesh, &opts).unwrap();
                check_codec(&cl, &mesh);
                if queries {
                    check_rays_and_points(&cl, &mesh, seed);
                }
            }
        }
    }

    #[test]
    fn bvtt_matches_brute_force(seed in any::<u64>(), na in 1usize..80, nb in 1usize..80) {
        let ma = soup(seed, na, 2.0);
        let mb = soup(seed.wrapping_add(1), nb, 2.0);
        let a = ClBvh::encode(&tree(&ma, Layout::DepthFirst, 1), &ma, &ClOptions::default()).unwrap();
        let b = ClBvh::encode(&tree(&mb, Layout::CacheEfficient, 2), &mb, &ClOptions::compact()).unwrap();
        check_bvtt(&a, &ma, &b, &mb, seed);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4))]

    /// Generated meshes (closed statues, multi-part turbines, robots).
    #[test]
    fn generated_meshes_match_brute_force_and_plain(seed in 0u64..1000, kind in 0usize..3) {
        let kind = [cbvh::scene::Kind::Statue, cbvh::scene::Kind::Turbine, cbvh::scene::Kind::Robot][kind];
        let mesh = cbvh::scene::generate(kind, 1500, seed, &mut |_, _| {}).unwrap();
        let bvh = tree(&mesh, Layout::DepthFirst, 1);
        let plain = PlainBvh::new(&bvh, &mesh);
        let other = statue(1000, seed + 1);
        let ob = ClBvh::encode(&tree(&other, Layout::VanEmdeBoas, 1), &other, &ClOptions::compact()).unwrap();
        for opts in [ClOptions::default(), ClOptions::compact()] {
            let cl = ClBvh::encode(&bvh, &mesh, &opts).unwrap();
            check_codec(&cl, &mesh);
            check_queries(&cl, &mesh, seed);
            check_parity_with_plain(&cl, &plain, &mesh, seed);
            check_bvtt(&cl, &mesh, &ob, &other, seed);
        }
    }
}

#[test]
fn edge_cases() {
    for mesh in edge_case_meshes() {
        for layout in Layout::ALL {
            let bvh = tree(&mesh, layout, 1);
            let plain = PlainBvh::new(&bvh, &mesh);
            for opts in variants() {
                let cl = ClBvh::encode(&bvh, &mesh, &opts).unwrap();
                check_codec(&cl, &mesh);
                check_queries(&cl, &mesh, 5);
                check_parity_with_plain(&cl, &plain, &mesh, 5);
                check_bvtt(&cl, &mesh, &cl, &mesh, 9);
            }
        }
    }
}

#[test]
fn empty_mesh_answers_nothing() {
    let mesh = Mesh::default();
    let bvh = tree(&mesh, Layout::DepthFirst, 1);
    for opts in variants() {
        let cl = ClBvh::encode(&bvh, &mesh, &opts).unwrap();
        assert_eq!(cl.triangle_count(), 0);
        let ray = cbvh::geom::Ray::new(Vec3A::ZERO, Vec3A::X);
        let mut stats = TraversalStats::default();
        assert!(query::closest_hit(&cl, &ray, f32::INFINITY, &mut stats).is_none());
        assert!(query::bvtt_pairs(&cl, &cl, &Pose::IDENTITY, 1.0, &mut stats).is_empty());
    }
}

/// The shape of the tree: leaves of at most `M` triangles outside
/// multi-leaf nodes, multi-leaf nodes of at most `8 · M`, at most 8
/// children a node, and on a statue most triangles in multi-leaf nodes
/// (the paper's §4.3 observation).
#[test]
fn threshold_and_node_types() {
    let mesh = statue(20_000, 3);
    let bvh = tree(&mesh, Layout::DepthFirst, 1);
    for leaf_size in [1, 2, 4, 8] {
        let opts = ClOptions {
            leaf_size,
            ..Default::default()
        };
        let cl = ClBvh::encode(&bvh, &mesh, &opts).unwrap();
        let (root, _) = cl.root();
        let mut stack = vec![root];
        let (mut in_multi, mut isolated) = (0usize, 0usize);
        let count = |n: &ClNode| {
            let mut k = 0;
            cl.for_each_triangle(n, |_, _| k += 1);
            k
        };
        while let Some(n) = stack.pop() {
            match cl.kind(&n) {
                NodeKind::Leaf => {
                    let k = count(&n);
                    assert!(k <= leaf_size, "isolated leaf of {k} > {leaf_size}");
                    isolated += k;
                }
                NodeKind::Lane => unreachable!("lanes are counted with their node"),
                kind => {
                    let mut kids = Vec::new();
                    cl.for_each_child(&n, |c, _| kids.push(c));
                    assert!((1..=8).contains(&kids.len()));
                    if kind == NodeKind::MultiLeaf {
                        assert!(kids.iter().all(|c| cl.kind(c) == NodeKind::Lane));
                        let k: usize = kids.iter().map(count).sum();
                        assert!(k <= 8 * leaf_size, "multi-leaf node of {k}");
                        in_multi += k;
                    } else {
                        stack.extend(kids);
                    }
                }
            }
        }
        assert_eq!(in_multi + isolated, mesh.triangles.len());
        assert!(
            in_multi * 10 >= mesh.triangles.len() * 8,
            "M={leaf_size}: only {in_multi} of {} triangles in multi-leaf nodes",
            mesh.triangles.len()
        );
        assert!(cl.multi_leaf_count() > 0);
    }
    // Without multi-leaf nodes: none, and more node bytes.
    let flat = ClBvh::encode(
        &bvh,
        &mesh,
        &ClOptions {
            multi_leaf: false,
            ..Default::default()
        },
    )
    .unwrap();
    let with = ClBvh::encode(&bvh, &mesh, &ClOptions::default()).unwrap();
    assert_eq!(flat.multi_leaf_count(), 0);
    let nodes = |c: &ClBvh| {
        c.bytes_by_part()
            .iter()
            .filter(|p| p.0.contains("nodes"))
            .map(|p| p.1)
            .sum::<usize>()
    };
    assert!(
        nodes(&with) * 10 < nodes(&flat) * 7,
        "{} vs {}",
        nodes(&with),
        nodes(&flat)
    );
    let compact = ClBvh::encode(&bvh, &mesh, &ClOptions::compact()).unwrap();
    assert!(compact.bytes_total() * 2 < with.bytes_total());
}

#[test]
fn bad_options_are_errors() {
    let mesh = soup(1, 30, 1.0);
    let bvh = tree(&mesh, Layout::DepthFirst, 1);
    for leaf_size in [0, 11] {
        let e = ClBvh::encode(
            &bvh,
            &mesh,
            &ClOptions {
                leaf_size,
                ..Default::default()
            },
        )
        .unwrap_err();
        assert!(matches!(e, ClError::LeafSize { got, .. } if got == leaf_size));
    }
    let big = tree(&mesh, Layout::DepthFirst, 5);
    let e = ClBvh::encode(&big, &mesh, &ClOptions::default()).unwrap_err();
    assert!(e.to_string().contains("max_leaf_triangles"), "{e}");
    let other = soup(2, 31, 1.0);
    assert!(matches!(
        ClBvh::encode(&bvh, &other, &ClOptions::default()),
        Err(ClError::MeshMismatch { tree: 30, mesh: 31 })
    ));
}

#[test]
fn file_round_trip() {
    let mesh = statue(3000, 8);
    let bvh = tree(&mesh, Layout::VanEmdeBoas, 1);
    let dir = std::env::temp_dir().join(format!("cbvh-clbvh-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for opts in variants() {
        let cl = ClBvh::encode(&bvh, &mesh, &opts).unwrap();
        cl.verify().unwrap();
        let bytes = cl.to_bytes();
        let back = ClBvh::from_bytes(&bytes).unwrap();
        back.verify().unwrap();
        assert_eq!(back.to_bytes(), bytes);
        assert_eq!(back.options(), &opts);
        assert_eq!(back.bytes_by_part(), cl.bytes_by_part());
        assert_eq!(back.mass(), cl.mass());
        let path = dir.join("t.clbvh");
        Codec::save(&cl, &path).unwrap();
        // Either leaf kind: the inherent reader (the registry's `open`
        // takes one kind per codec name).
        let opened = ClBvh::from_bytes(&std::fs::read(&path).unwrap()).unwrap();
        opened.verify().unwrap();
        check_codec(&opened, &mesh);
        let mut s = TraversalStats::default();
        for ray in test_rays(&mesh, 2, 50) {
            assert_eq!(
                query::closest_hit(&opened, &ray, f32::INFINITY, &mut s),
                query::closest_hit(&cl, &ray, f32::INFINITY, &mut s)
            );
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Recomputes every section checksum and the header checksum (the layout
/// of `codec::clbvh::file`), so that a test can hand `verify` structurally
/// damaged bytes that pass `from_bytes`.
fn rechecksum(b: &mut [u8]) {
    use xxhash_rust::xxh3::xxh3_64;
    for k in 0..7 {
        let e = 112 + 24 * k;
        let off = u64::from_le_bytes(b[e..e + 8].try_into().unwrap()) as usize;
        let len = u64::from_le_bytes(b[e + 8..e + 16].try_into().unwrap()) as usize;
        let h = xxh3_64(&b[off..off + len]);
        b[e + 16..e + 24].copy_from_slice(&h.to_le_bytes());
    }
    let h = xxh3_64(&b[..280]);
    b[280..288].copy_from_slice(&h.to_le_bytes());
}

#[test]
fn corruption_is_an_error_never_a_wrong_answer() {
    let mesh = soup(4, 300, 3.0);
    let bvh = tree(&mesh, Layout::DepthFirst, 1);
    for opts in [ClOptions::default(), ClOptions::compact()] {
        let bytes = ClBvh::encode(&bvh, &mesh, &opts).unwrap().to_bytes();
        for cut in [0, 7, 100, 287, 288, bytes.len() / 2, bytes.len() - 1] {
            assert!(ClBvh::from_bytes(&bytes[..cut]).is_err(), "cut at {cut}");
        }
        let mut rng = Rng(opts.leaf_size as u64);
        let mut rejected = 0;
        for _ in 0..400 {
            let mut b = bytes.clone();
            let at = rng.below(b.len());
            b[at] ^= 1 << rng.below(8);
            assert!(
                ClBvh::from_bytes(&b).is_err(),
                "bit flip at {at} passed the checksums"
            );
            // The same flip with fresh checksums: `verify` must reject it,
            // or the tree must still answer like brute force.
            if at >= 288 {
                rechecksum(&mut b);
                match ClBvh::from_bytes(&b).map(|t| t.verify().map(|_| t)) {
                    Err(_) | Ok(Err(_)) => rejected += 1,
                    Ok(Ok(t)) => {
                        let dm = t.decoded_mesh();
                        check_structure(&t, &dm);
                        check_queries(&t, &dm, 3);
                    }
                }
            }
        }
        assert!(rejected > 100, "only {rejected} damaged trees rejected");
    }
}

/// Rays at vertices and along edges, where the watertight test's edge
/// functions come out exactly zero and it decides in double precision.
fn vertex_rays(mesh: &Mesh, seed: u64, n: usize) -> Vec<cbvh::geom::Ray> {
    let mut rng = Rng(seed);
    let (lo, hi) = mesh.bounds().unwrap();
    let (lo, hi) = (Vec3A::from(lo), Vec3A::from(hi));
    let size = (hi - lo).length().max(1e-3);
    (0..n)
        .map(|k| {
            let t = tri(mesh, rng.below(mesh.triangles.len()) as u32);
            let target = match k % 3 {
                0 => t[0],
                1 => (t[0] + t[1]) * 0.5,
                _ => t[2],
            };
            let origin = (lo + hi) * 0.5 + rng.vec(-1.0, 1.0).normalize_or(Vec3A::Y) * size;
            cbvh::geom::Ray::new(origin, (target - origin).normalize_or(Vec3A::Z))
        })
        .collect()
}

/// CLBVH's own traversal (eight boxes and four triangles an AVX2
/// instruction, where the processor has AVX2) against the generic
/// traversal over its cursor, on the same tree: the same closest hit, bit
/// for bit, and the same any hit, on camera-like, random, vertex and edge
/// rays with and without a limit, for fast and compact leaves.
#[test]
fn own_traversal_equals_the_generic_one_bit_for_bit() {
    let mut meshes = vec![statue(6000, 3), statue(1000, 9)];
    meshes.extend(awkward(5, 300, 1e4));
    meshes.push(soup(11, 2000, 3.0));
    for (m, mesh) in meshes.iter().enumerate() {
        let bvh = tree(mesh, Layout::DepthFirst, 1);
        let (lo, hi) = mesh.bounds().unwrap();
        let (lo, hi) = (Vec3A::from(lo), Vec3A::from(hi));
        let mut rays = test_rays(mesh, m as u64, 400);
        rays.extend(vertex_rays(mesh, m as u64, 300));
        rays.extend(camera_rays(mesh));
        for opts in [
            ClOptions::default(),
            ClOptions::compact(),
            ClOptions {
                leaf_size: 10,
                ..Default::default()
            },
            ClOptions {
                multi_leaf: false,
                ..Default::default()
            },
        ] {
            let cl = ClBvh::encode(&bvh, mesh, &opts).unwrap();
            let t_maxes = [f32::INFINITY, 0.9 * (hi - lo).length(), 1e-3];
            let what = format!("mesh {m}, {opts:?}");
            let hits = check_own_traversal_is_generic(&cl, &rays, t_maxes, &what);
            assert!(hits > rays.len() / 4, "mesh {m}: only {hits} hits");
        }
    }
}
