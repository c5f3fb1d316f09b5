//! i-HCCMesh (one triangle a leaf, and multi-triangle leaves) against the
//! canonical tree and brute force, with the shared suite in `common`.

use crate::common;

use cbvh::Mesh;
use cbvh::build::{CanonicalBvh, Layout};
use cbvh::codec::hcc::template::{TEMPLATE_COUNT, TEMPLATES};
use cbvh::codec::hcc::{HccBvh, HccError, HccOptions, MAX_LEAF_TRIANGLES};
use cbvh::codec::plain::PlainBvh;
use cbvh::codec::{Codec, OpenOptions};
use cbvh::cursor::NodeCursor;
use cbvh::geom::triangle_from_arrays;
use common::*;
use glam::Vec3A;
use proptest::prelude::*;

fn hcc(mesh: &Mesh, leaf: usize) -> (CanonicalBvh, HccBvh) {
    let t = tree(mesh, Layout::DepthFirst, leaf);
    let h = HccBvh::encode(&t, mesh).expect("encode");
    (t, h)
}

/// The decoded tree has the canonical tree's shape, each decoded box
/// contains the canonical box (and equals it when no extent was coded
/// loose), and each leaf holds the canonical leaf's triangles in order.
fn check_round_trip(bvh: &CanonicalBvh, h: &HccBvh, mesh: &Mesh) {
    let exact = h.stats().loose_extents == 0;
    let (root, root_box) = h.root();
    let mut stack = vec![(0u32, root, root_box)];
    while let Some((c, n, b)) = stack.pop() {
        let cn = &bvh.nodes[c as usize];
        let tight = cn.aabb();
        assert!(
            b.contains(&tight),
            "node {c}: {b:?} does not contain {tight:?}"
        );
        if exact {
            assert_eq!(b, tight, "node {c}: decoded box is not the tight box");
        }
        assert_eq!(h.is_leaf(&n), cn.is_leaf(), "node {c}: leaf-ness differs");
        if cn.is_leaf() {
            let mut got = Vec::new();
            h.for_each_triangle(&n, |id, t| {
                assert_eq!(*t, h.triangle(id), "triangle({id}) differs from the leaf's");
                got.push((id, *t));
            });
            let want: Vec<_> = bvh.leaf_triangles[cn.leaf_range()]
                .iter()
                .map(|&id| {
                    (
                        id,
                        triangle_from_arrays(mesh.triangle_vertices(id as usize)),
                    )
                })
                .collect();
            assert_eq!(got, want, "node {c}: leaf triangles (input ids) differ");
        } else {
            let mut kids = Vec::new();
            h.for_each_child(&n, |k, kb| kids.push((k, kb)));
            assert_eq!(kids.len(), 2);
            stack.push((cn.a, kids[0].0, kids[0].1));
            stack.push((cn.b, kids[1].0, kids[1].1));
        }
    }
}

/// The decoded mesh is the input mesh, and every triangle id finds its
/// triangle.
fn check_mesh(h: &HccBvh, mesh: &Mesh) {
    assert_eq!(h.decoded_mesh(), *mesh, "the decoded mesh is not the input");
    assert_eq!(h.triangle_count(), mesh.triangles.len());
    for id in 0..mesh.triangles.len() {
        assert_eq!(
            h.triangle(id as u32),
            triangle_from_arrays(mesh.triangle_vertices(id))
        );
        assert_eq!(h.triangle_vertex_indices(id as u32), mesh.triangles[id]);
    }
}

/// Round trip and the shared suite's structure check (every box contains
/// every triangle below it), without queries.
fn check_boxes(mesh: &Mesh, leaf: usize) -> HccBvh {
    let (t, h) = hcc(mesh, leaf);
    check_round_trip(&t, &h, mesh);
    check_mesh(&h, mesh);
    check_structure(&h, &h.decoded_mesh());
    h
}

/// Everything: round trip, shared-suite structure and queries on the
/// decoded mesh.
fn check_all(mesh: &Mesh, leaf: usize, seed: u64) -> HccBvh {
    let (t, h) = hcc(mesh, leaf);
    check_round_trip(&t, &h, mesh);
    check_mesh(&h, mesh);
    let d = h.decoded_mesh();
    check_structure(&h, &d);
    check_queries(&h, &d, seed);
    h
}

/// A fan: one centre vertex and `n` rim vertices, so the centre's
/// neighbourhood has `n + 1` vertices.
fn fan(n: usize, offset: f32) -> Mesh {
    let mut v = vec![[offset, offset, offset]];
    for k in 0..n {
        let a = k as f32 / n as f32 * std::f32::consts::TAU;
        v.push([
            offset + a.cos(),
            offset + a.sin(),
            offset + 0.01 * (k % 3) as f32,
        ]);
    }
    let t = (0..n as u32)
        .map(|k| [0, 1 + k, 1 + (k + 1) % n as u32])
        .collect();
    Mesh::new(v, t)
}

/// A grid of `n × n` quads in the plane z = 0 (or, `collinear`, all on the
/// x axis).
fn grid(n: usize, collinear: bool) -> Mesh {
    let mut v = Vec::new();
    for y in 0..=n {
        for x in 0..=n {
            if collinear {
                v.push([(x + y * (n + 1)) as f32 * 0.1, 0.0, 0.0]);
            } else {
                v.push([x as f32, y as f32, 0.0]);
            }
        }
    }
    let mut t = Vec::new();
    let w = (n + 1) as u32;
    for y in 0..n as u32 {
        for x in 0..n as u32 {
            let a = y * w + x;
            t.push([a, a + 1, a + w]);
            t.push([a + 1, a + w + 1, a + w]);
        }
    }
    Mesh::new(v, t)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(20))]

    #[test]
    fn soups_match_brute_force(seed in any::<u64>(), n in 1usize..200, leaf in 1usize..6) {
        check_all(&soup(seed, n, 10.0), leaf, seed);
    }

    /// Far from the origin: queries against brute force at 1e4; at 3e6,
    /// where f32 spacing is 0.25 and plain's answers differ from brute force
    /// too (`tests/far_from_origin.rs`), boxes and triangles only.
    #[test]
    fn far_from_origin_soups_are_conservative(seed in any::<u64>(), n in 1usize..80, leaf in 1usize..4) {
        for (offset, queries) in [(1.0e4f32, true), (3.0e6, false)] {
            let mut mesh = soup(seed, n, 0.5);
            for p in &mut mesh.vertices {
                for c in p.iter_mut() {
                    *c += offset;
                }
            }
            if queries {
                check_all(&mesh, leaf, seed);
            } else {
                check_boxes(&mesh, leaf);
            }
        }
    }

    #[test]
    fn bvtt_matches_brute_force(seed in any::<u64>(), na in 1usize..60, nb in 1usize..60) {
        let ma = soup(seed, na, 2.0);
        let mb = soup(seed.wrapping_add(1), nb, 2.0);
        let (_, a) = hcc(&ma, 1);
        let (_, b) = hcc(&mb, 3);
        check_bvtt(&a, &a.decoded_mesh(), &b, &b.decoded_mesh(), seed);
        let p = PlainBvh::new(&tree(&mb, Layout::DepthFirst, 1), &mb);
        check_bvtt(&a, &a.decoded_mesh(), &p, &mb, seed);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4))]

    /// Generated meshes of several thousand triangles: many low-level trees,
    /// vertices shared across them.
    #[test]
    fn generated_meshes_match_brute_force(seed in 0u64..1000, kind in 0usize..3, leaf in prop::sample::select(vec![1usize, 4, 8])) {
        let kind = [cbvh::scene::Kind::Statue, cbvh::scene::Kind::Turbine, cbvh::scene::Kind::Robot][kind];
        let mesh = cbvh::scene::generate(kind, 3000, seed, &mut |_, _| {}).unwrap();
        let h = check_all(&mesh, leaf, seed);
        prop_assert!(h.tree_count() > 1, "{} low-level trees", h.tree_count());
        prop_assert!(h.stats().tree_vertices > h.stats().mesh_vertices, "no vertex is shared across trees");
    }
}

#[test]
fn edge_cases() {
    let mut meshes = edge_case_meshes();
    meshes.push(grid(12, false));
    for mesh in meshes {
        for leaf in [1, 4] {
            let h = check_all(&mesh, leaf, 3);
            check_bvtt(&h, &h.decoded_mesh(), &h, &h.decoded_mesh(), 4);
        }
    }
    // Collinear: every triangle degenerate, where plain's ray answers
    // differ from brute force too; boxes and triangles only.
    for leaf in [1, 4] {
        check_boxes(&grid(6, true), leaf);
    }
}

#[test]
fn empty_mesh_answers_nothing() {
    let mesh = Mesh::default();
    let (_, h) = hcc(&mesh, 1);
    let (root, b) = h.root();
    assert!(b.is_empty() && h.is_leaf(&root));
    let mut n = 0;
    h.for_each_triangle(&root, |_, _| n += 1);
    assert_eq!((n, h.triangle_count(), h.tree_count()), (0, 0, 0));
}

#[test]
fn a_neighbourhood_of_more_than_512_vertices_is_split() {
    let mesh = fan(700, 0.0);
    let h = check_all(&mesh, 1, 1);
    assert!(
        h.tree_count() >= 2,
        "{} trees for a 701-vertex fan",
        h.tree_count()
    );
    // The centre is in every tree.
    assert!(h.stats().tree_vertices >= h.stats().mesh_vertices + h.tree_count() - 1);
    let far = fan(700, 1.0e5);
    check_all(&far, 4, 2);
}

#[test]
fn many_triangles_over_few_vertices_split_by_node_count() {
    // 9000 copies of one triangle: 3 vertices but more nodes than a
    // low-level tree addresses.
    let one = &edge_case_meshes()[0];
    let mesh = Mesh::new(one.vertices.clone(), vec![[0, 1, 2]; 9000]);
    let (t, h) = hcc(&mesh, 1);
    assert!(h.tree_count() >= 3, "{} trees", h.tree_count());
    check_round_trip(&t, &h, &mesh);
    check_structure(&h, &h.decoded_mesh());
}

#[test]
fn every_template_occurs_and_round_trips() {
    // Random soups give SAH trees of every local shape.
    let mesh = soup(42, 6000, 20.0);
    let (t, h) = hcc(&mesh, 1);
    let missing: Vec<usize> = (0..TEMPLATE_COUNT)
        .filter(|&k| h.stats().templates[k] == 0)
        .collect();
    assert!(
        missing.is_empty(),
        "templates {missing:?} never occur: {:?}",
        h.stats().templates
    );
    check_round_trip(&t, &h, &mesh);
    // Every template the cursor reports is one of the table's, and every
    // one is reached by a traversal.
    let mut seen = [false; TEMPLATE_COUNT];
    let (root, _) = h.root();
    let mut stack = vec![root];
    while let Some(n) = stack.pop() {
        if let Some(k) = n.template() {
            seen[k as usize] = true;
        }
        if !h.is_leaf(&n) {
            h.for_each_child(&n, |c, _| stack.push(c));
        }
    }
    assert!(seen.iter().all(|&s| s), "templates reached: {seen:?}");
    assert_eq!(TEMPLATES.len(), TEMPLATE_COUNT);
}

#[test]
fn both_children_inherit_the_same_extent() {
    // Two triangles spanning the same x range [0, 1], y and z apart: both
    // children have the parent's min x and max x; the structure of four
    // such strips makes inner/inner pairs that share extents.
    let mut v = Vec::new();
    let mut t = Vec::new();
    for k in 0..8u32 {
        let y = k as f32;
        v.extend([[0.0, y, 0.0], [1.0, y, 0.0], [0.5, y + 0.5, 0.0]]);
        t.push([3 * k, 3 * k + 1, 3 * k + 2]);
    }
    let mesh = Mesh::new(v, t);
    let (c, h) = hcc(&mesh, 1);
    assert_eq!(h.stats().loose_extents, 0);
    assert!(h.stats().inner_pairs > 0);
    check_round_trip(&c, &h, &mesh);
    // Every decoded inner box spans x from 0 to 1 exactly.
    let (root, _) = h.root();
    let mut stack = vec![root];
    while let Some(n) = stack.pop() {
        if !h.is_leaf(&n) {
            h.for_each_child(&n, |k, b| {
                assert_eq!((b.min.x, b.max.x), (0.0, 1.0));
                stack.push(k);
            });
        }
    }
}

#[test]
fn a_child_that_is_a_single_triangle() {
    // A big triangle whose box holds a small cluster: the root's children
    // are the big triangle (a leaf) and the cluster (inner), which differs
    // from the parent in all six extents and keeps three of them.
    let mut v = vec![
        [-10.0, -10.0, -10.0],
        [10.0, 10.0, -10.0],
        [10.0, -10.0, 10.0],
    ];
    let mut t = vec![[0, 1, 2]];
    for k in 0..6u32 {
        let o = k as f32 * 0.1;
        let b = v.len() as u32;
        v.extend([[o, 0.0, 0.0], [o + 0.05, 0.1, 0.0], [o, 0.0, 0.1]]);
        t.push([b, b + 1, b + 2]);
    }
    let mesh = Mesh::new(v, t);
    let (c, h) = hcc(&mesh, 1);
    assert!(h.stats().mixed_pairs > 0);
    assert!(h.stats().loose_extents >= 3, "{:?}", h.stats());
    check_round_trip(&c, &h, &mesh);
    check_structure(&h, &h.decoded_mesh());
    check_queries(&h, &h.decoded_mesh(), 8);
}

#[test]
fn leaves_too_large_are_errors() {
    let mesh = soup(3, 200, 1.0);
    let t = tree(&mesh, Layout::DepthFirst, MAX_LEAF_TRIANGLES + 1);
    assert!(matches!(
        HccBvh::encode(&t, &mesh),
        Err(HccError::LeafSize { .. })
    ));
    let other = soup(4, 10, 1.0);
    assert!(matches!(
        HccBvh::encode(&tree(&mesh, Layout::DepthFirst, 1), &other),
        Err(HccError::MeshMismatch { .. })
    ));
}

#[test]
fn every_layout_encodes_the_same_answers() {
    let mesh = soup(9, 700, 5.0);
    for layout in Layout::ALL {
        let t = tree(&mesh, layout, 1);
        let h = HccBvh::encode(&t, &mesh).unwrap();
        check_round_trip(&t, &h, &mesh);
    }
}

#[test]
fn files_round_trip_and_reject_damage() {
    let mesh = cbvh::scene::generate(cbvh::scene::Kind::Turbine, 3000, 5, &mut |_, _| {}).unwrap();
    for leaf in [1, 4] {
        let (_, h) = hcc(&mesh, leaf);
        h.verify().expect("a fresh encode verifies");
        let bytes = h.to_bytes();
        let back = HccBvh::from_bytes(&bytes).expect("read back");
        back.verify().expect("read back verifies");
        assert_eq!(back.to_bytes(), bytes);
        assert_eq!(back.decoded_mesh(), h.decoded_mesh());
        check_structure(&back, &h.decoded_mesh());
        let dir = std::env::temp_dir().join(format!("cbvh-hcc-{}-{leaf}.hcc", std::process::id()));
        Codec::save(&h, &dir).unwrap();
        let opened = <HccBvh as Codec>::open(&dir, &OpenOptions::default()).unwrap();
        assert_eq!(opened.to_bytes(), bytes);
        std::fs::remove_file(&dir).unwrap();
        for cut in [0, 7, 100, 247, 248, bytes.len() / 2, bytes.len() - 1] {
            assert!(
                HccBvh::from_bytes(&bytes[..cut]).is_err(),
                "cut at {cut} accepted"
            );
        }
        let mut rng = Rng(leaf as u64);
        for _ in 0..300 {
            let mut b = bytes.clone();
            let i = rng.below(b.len());
            b[i] ^= 1 << rng.below(8);
            assert!(
                HccBvh::from_bytes(&b).is_err(),
                "a bit flip at byte {i} accepted"
            );
        }
    }
}

/// A header that claims more low-level trees than a node handle numbers
/// (its checksum rewritten) is refused by name.
#[test]
fn more_trees_than_handles_number_is_refused() {
    use cbvh::codec::hcc::node::MAX_TREES;
    use xxhash_rust::xxh3::xxh3_64;
    let mesh = cbvh::scene::generate(cbvh::scene::Kind::Turbine, 1000, 5, &mut |_, _| {}).unwrap();
    let (_, h) = hcc(&mesh, 1);
    let mut bytes = h.to_bytes();
    // The header's counts start at byte 16: high-level nodes, then trees;
    // the header (408 bytes) ends with its checksum.
    bytes[20..24].copy_from_slice(&(MAX_TREES as u32 + 1).to_le_bytes());
    let sum = xxh3_64(&bytes[..400]);
    bytes[400..408].copy_from_slice(&sum.to_le_bytes());
    let e = HccBvh::from_bytes(&bytes).expect_err("a file with too many trees was accepted");
    assert!(e.to_string().contains("low-level trees"), "{e}");
}

/// Regression: `verify` read an inner root's template id as vertex
/// indices and rejected trees with fewer vertices than the id (40 copies
/// of one triangle: 3 vertices, root template id above 3).
#[test]
fn an_inner_root_whose_template_id_exceeds_its_vertex_count_verifies() {
    let one = &edge_case_meshes()[0];
    let mesh = Mesh::new(one.vertices.clone(), vec![[0, 1, 2]; 40]);
    for leaf in [1, 4] {
        let (_, h) = hcc(&mesh, leaf);
        h.verify().unwrap();
        check_mesh(&h, &mesh);
    }
}

/// Quantized vertices: every decoded vertex within half a grid step (and
/// `f32` rounding) of the input's, the reported error the largest one
/// found, the input's triangle and vertex numbering kept, boxes still
/// conservative over the decoded triangles, and fewer bytes than `f32`.
#[test]
fn quantized_vertices_stay_within_half_a_step() {
    use cbvh::codec::ByteSize;
    let mesh = cbvh::scene::generate(cbvh::scene::Kind::Turbine, 4000, 3, &mut |_, _| {}).unwrap();
    for (bits, leaf) in [(16, 1), (10, 8), (24, 4)] {
        let t = tree(&mesh, Layout::DepthFirst, leaf);
        let o = HccOptions {
            vertex_bits: Some(bits),
            ..Default::default()
        };
        let h = HccBvh::encode_with(&t, &mesh, &o).unwrap();
        h.verify().unwrap();
        assert_eq!(h.vertex_bits(), Some(bits));
        let d = h.decoded_mesh();
        assert_eq!(d.triangles, mesh.triangles, "the numbering is kept");
        let (step, err) = (h.vertex_step(), h.vertex_error());
        let mut worst = [0f32; 3];
        for (p, q) in mesh.vertices.iter().zip(&d.vertices) {
            for a in 0..3 {
                let e = (p[a] - q[a]).abs();
                worst[a] = worst[a].max(e);
                assert!(
                    e <= 0.5 * step[a] + 4.0 * f32::EPSILON * p[a].abs(),
                    "{bits} bits: {p:?} → {q:?}"
                );
            }
        }
        assert_eq!(worst, err, "the reported error is the largest found");
        check_structure(&h, &d);
        check_queries(&h, &d, 11);
        let lossless = HccBvh::encode(&t, &mesh).unwrap();
        assert!(h.bytes_total() < lossless.bytes_total());
        let back = HccBvh::from_bytes(&h.to_bytes()).unwrap();
        back.verify().unwrap();
        assert_eq!(back.decoded_mesh(), d);
        assert_eq!(back.vertex_error(), err);
    }
    let t = tree(&mesh, Layout::DepthFirst, 1);
    let too_many = HccOptions {
        vertex_bits: Some(25),
        ..Default::default()
    };
    assert!(matches!(
        HccBvh::encode_with(&t, &mesh, &too_many),
        Err(HccError::VertexBits { got: 25, .. })
    ));
}

#[test]
fn tree_order_numbers_triangles_as_stored_without_maps() {
    use cbvh::codec::{ByteSize, Codec, OpenOptions};
    let mesh = cbvh::scene::generate(cbvh::scene::Kind::Statue, 3000, 7, &mut |_, _| {}).unwrap();
    let n = mesh.triangles.len();
    for (bits, leaf) in [(None, 1), (Some(16), 8), (Some(12), 1), (None, 4)] {
        let t = tree(&mesh, Layout::CacheEfficient, leaf);
        let kept = HccOptions {
            vertex_bits: bits,
            vertex_ids: false,
            triangle_ids: true,
        };
        let a = HccBvh::encode_with(&t, &mesh, &kept).unwrap();
        let b = HccBvh::encode_with(&t, &mesh, &HccOptions::tree_order(bits)).unwrap();
        b.verify().unwrap();
        assert!(a.has_triangle_ids() && !b.has_triangle_ids());
        // The same tree, box for box; leaf by leaf the same triangles, `a`
        // naming input ids and `b` storage ranks.
        let mut pairs = Vec::new();
        let mut stack = vec![(a.root(), b.root())];
        while let Some(((na, ba), (nb, bb))) = stack.pop() {
            assert_eq!(ba, bb);
            assert_eq!(a.is_leaf(&na), b.is_leaf(&nb));
            if a.is_leaf(&na) {
                let (mut ta, mut tb) = (Vec::new(), Vec::new());
                a.for_each_triangle(&na, |id, t| ta.push((id, *t)));
                b.for_each_triangle(&nb, |id, t| tb.push((id, *t)));
                assert_eq!(ta.len(), tb.len());
                for ((ia, xa), (ib, xb)) in ta.into_iter().zip(tb) {
                    assert_eq!(xa, xb);
                    assert_eq!(b.triangle(ib), xb, "triangle({ib})");
                    pairs.push((ia, ib));
                }
            } else {
                let (mut ca, mut cb) = (Vec::new(), Vec::new());
                a.for_each_child(&na, |c, x| ca.push((c, x)));
                b.for_each_child(&nb, |c, x| cb.push((c, x)));
                assert_eq!(ca.len(), cb.len());
                stack.extend(ca.into_iter().zip(cb));
            }
        }
        // Every rank once, and the decoded meshes agree through the pairs.
        let mut ranks: Vec<u32> = pairs.iter().map(|p| p.1).collect();
        ranks.sort_unstable();
        assert!(ranks.iter().copied().eq(0..n as u32));
        let (da, db) = (a.decoded_mesh(), b.decoded_mesh());
        assert_eq!(db.triangles.len(), n);
        for &(ia, ib) in &pairs {
            let (xa, xb) = (
                da.triangle_vertices(ia as usize),
                db.triangle_vertices(ib as usize),
            );
            assert_eq!(xa, xb, "input {ia}, rank {ib}");
            if bits.is_none() {
                assert_eq!(xb, mesh.triangle_vertices(ia as usize));
            }
        }
        // No map is stored: `b` is `a` less its `ids` part.
        let part =
            |c: &HccBvh, name: &str| c.bytes_by_part().iter().find(|p| p.0 == name).map(|p| p.1);
        assert!(part(&a, "ids").is_some_and(|x| x > 0));
        assert_eq!(part(&b, "ids"), None);
        assert_eq!(part(&b, "vertex-ids"), None);
        assert_eq!(b.bytes_total() + part(&a, "ids").unwrap(), a.bytes_total());
        // The file keeps the numbering.
        let back = <HccBvh as Codec>::from_bytes(&b.to_bytes(), &OpenOptions::default()).unwrap();
        back.verify().unwrap();
        assert!(!back.has_triangle_ids());
        assert_eq!(back.decoded_mesh(), db);
        assert_eq!(back.to_bytes(), b.to_bytes());
    }
}

/// i-HCCMesh's own ray traversal (module `trace`) against the generic
/// traversal over its cursor, on the same tree: the same closest hit, bit
/// for bit, and the same any hit, on random, centroid and camera rays with
/// and without a limit; lossless and quantized vertices, one and four
/// triangles a leaf, on a statue, a soup and flat, collinear and
/// far-from-origin meshes.
#[test]
fn own_traversal_equals_the_generic_one_bit_for_bit() {
    let statue =
        cbvh::scene::generate(cbvh::scene::Kind::Statue, 6000, 3, &mut |_, _| {}).expect("statue");
    let meshes = [
        statue,
        soup(11, 2000, 3.0),
        grid(30, false),
        grid(20, true),
        fan(700, 1e4),
    ];
    for (m, mesh) in meshes.iter().enumerate() {
        let (lo, hi) = mesh.bounds().unwrap();
        let size = (Vec3A::from(hi) - Vec3A::from(lo)).length().max(1e-3);
        let mut rays = test_rays(mesh, m as u64, 600);
        rays.extend(camera_rays(mesh));
        for (leaf, options) in [
            (1, HccOptions::default()),
            (1, HccOptions::tree_order(Some(16))),
            (4, HccOptions::default()),
            (4, HccOptions::tree_order(Some(12))),
        ] {
            let t = tree(mesh, Layout::DepthFirst, leaf);
            let h = HccBvh::encode_with(&t, mesh, &options).expect("encode");
            let t_maxes = [f32::INFINITY, 0.9 * size, 1e-3];
            let what = format!("mesh {m}, leaf {leaf}, {options:?}");
            let hits = check_own_traversal_is_generic(&h, &rays, t_maxes, &what);
            // The collinear grid has no area: only rays along its line
            // and through its points hit it.
            let enough = if m == 3 { 1 } else { rays.len() / 4 };
            assert!(hits >= enough, "mesh {m}: only {hits} hits");
        }
    }
}
