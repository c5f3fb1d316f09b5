//! What only RACBVH has: agreement with the canonical tree node by node,
//! the random-access API, its options, the cluster cache and its threads.
//! What every codec must do (brute-force parity, conservative boxes, edge
//! cases, files, corruption) is in the shared suite, `codec_suite.rs`.

use crate::common;

use cbvh::build::{CanonicalBvh, Layout};
use cbvh::codec::common::FormatError;
use cbvh::codec::racbvh::{RacBvh, RacError, RacOptions};
use cbvh::codec::{AnyOptions, ByteSize};
use cbvh::cursor::NodeCursor;
use cbvh::scene::{Kind, generate};
use cbvh::{Mesh, TraversalStats, query};
use common::*;

fn opts(cluster_nodes: u32, vertex_bits: Option<u32>) -> RacOptions {
    RacOptions {
        cluster_nodes,
        vertex_bits,
        ..Default::default()
    }
}

fn statue(tris: usize) -> Mesh {
    generate(Kind::Statue, tris, 1, &mut |_, _| {}).expect("generate")
}

/// Every node of `rac` agrees with `bvh`: structure, triangle ids, and a
/// box that contains the canonical box and is within one quantum of it.
fn check_against_canonical(rac: &RacBvh, bvh: &CanonicalBvh, order: &[u32]) {
    let root = bvh.root_aabb();
    let quantum = root.extent() / ((1u32 << RacOptions::default().bits) - 1) as f32;
    let slack = quantum * 1.001
        + glam::Vec3A::splat(root.min.abs().max(root.max.abs()).max_element() * 4.0 * f32::EPSILON);
    for &i in order {
        let n = &bvh.nodes[i as usize];
        assert_eq!(rac.is_leaf(i), n.is_leaf(), "node {i}");
        if n.is_leaf() {
            assert_eq!(
                rac.leaf_triangles(i),
                bvh.leaf_triangles[n.leaf_range()].to_vec(),
                "node {i}"
            );
        } else {
            assert_eq!([rac.left(i), rac.right(i)], n.children(), "node {i}");
        }
        let b = rac.bv(i);
        let c = n.aabb();
        assert!(b.contains(&c), "node {i}: {b:?} does not contain {c:?}");
        assert!(
            (c.min - b.min).cmple(slack).all() && (b.max - c.max).cmple(slack).all(),
            "node {i}: {b:?} is more than a quantum from {c:?}"
        );
    }
}

#[test]
fn round_trip_matches_the_canonical_tree_in_every_layout() {
    let mesh = statue(2000);
    for layout in Layout::ALL {
        let bvh = tree(&mesh, layout, 1);
        let rac = RacBvh::encode(&bvh, &mesh, &opts(256, None)).unwrap();
        assert!(rac.cluster_count() > 8, "{} clusters", rac.cluster_count());
        let order: Vec<u32> = (0..bvh.nodes.len() as u32).collect();
        check_against_canonical(&rac, &bvh, &order);
        rac.verify().unwrap();
        let s = rac.stats();
        assert!(s.bits_per_node_tree > 0.0 && s.bits_per_node_bv > 0.0);
        assert!(s.compression_ratio_vs_plain > 2.0, "{s:?}");
        let parts = rac.bytes_by_part();
        assert_eq!(
            parts.iter().map(|p| p.0).collect::<Vec<_>>(),
            ["bvh_tree", "bvh_bv", "meta", "mesh", "edge-flags"]
        );
    }
}

#[test]
fn any_access_order_gives_the_same_nodes_with_completion_across_clusters() {
    let mesh = statue(3000);
    let bvh = tree(&mesh, Layout::CacheEfficient, 1);
    let crossing = (1..bvh.nodes.len())
        .filter(|&i| bvh.parents[i] as usize >> 8 != i >> 8)
        .count();
    assert!(crossing > 20, "only {crossing} local roots");
    // Reverse order: every first touch of a cluster meets incomplete nodes
    // whose parents are in clusters not loaded yet.
    let mut order: Vec<u32> = (0..bvh.nodes.len() as u32).rev().collect();
    let rac = RacBvh::encode(&bvh, &mesh, &opts(256, Some(16))).unwrap();
    let lossless = RacBvh::encode(&bvh, &mesh, &opts(256, None)).unwrap();
    check_against_canonical(&lossless, &bvh, &order);
    let want: Vec<_> = order.iter().map(|&i| (rac.bv(i), rac.is_leaf(i))).collect();
    // A pseudo-random order on a cold tree with a cache of two clusters.
    let mut rng = Rng(9);
    for k in (1..order.len()).rev() {
        order.swap(k, rng.below(k + 1));
    }
    let bytes = rac.to_bytes();
    let cold = RacBvh::from_bytes(&bytes, 2 * 256 * 40).unwrap();
    let rev: Vec<u32> = (0..bvh.nodes.len() as u32).rev().collect();
    for &i in &order {
        let pos = rev.iter().position(|&x| x == i).unwrap();
        assert_eq!((cold.bv(i), cold.is_leaf(i)), want[pos], "node {i}");
    }
    // The deepest cluster first, on a cold tree: completion loads parents.
    let cold = RacBvh::from_bytes(&bytes, 64 << 20).unwrap();
    let last = bvh.nodes.len() as u32 - 1;
    assert_eq!(cold.bv(last), rac.bv(last));
    assert!(cold.cache_stats().decodes > 1, "{:?}", cold.cache_stats());
}

#[test]
fn the_empty_tree_has_no_triangle_by_random_access() {
    let empty = Mesh::default();
    let rac = RacBvh::encode(
        &tree(&empty, Layout::VanEmdeBoas, 1),
        &empty,
        &RacOptions::default(),
    )
    .unwrap();
    let back = RacBvh::from_bytes(&rac.to_bytes(), 1 << 20).unwrap();
    assert_eq!(back.node_count(), 1);
    assert!(back.is_leaf(0));
    assert_eq!(back.triangle_index(0), None);
    assert!(back.leaf_triangles(0).is_empty());
}

#[test]
fn bad_options_are_errors() {
    let mesh = soup(1, 10, 1.0);
    let bvh = tree(&mesh, Layout::DepthFirst, 1);
    for o in [
        RacOptions {
            cluster_nodes: 1000,
            ..Default::default()
        },
        RacOptions {
            cluster_nodes: 128,
            ..Default::default()
        },
        RacOptions {
            cluster_nodes: 32768,
            ..Default::default()
        },
        RacOptions {
            bits: 7,
            ..Default::default()
        },
        RacOptions {
            bits: 25,
            ..Default::default()
        },
        RacOptions {
            vertex_bits: Some(30),
            ..Default::default()
        },
        RacOptions {
            tri_delta_threshold: 0,
            ..Default::default()
        },
    ] {
        let e = RacBvh::encode(&bvh, &mesh, &o).unwrap_err();
        assert!(matches!(e, RacError::Option { .. }), "{e}");
    }
    for c in [256, 512, 16384] {
        RacBvh::encode(
            &bvh,
            &mesh,
            &RacOptions {
                cluster_nodes: c,
                ..Default::default()
            },
        )
        .unwrap();
    }
}

#[test]
fn the_cache_stays_within_its_budget() {
    let mesh = statue(3000);
    let bvh = tree(&mesh, Layout::CacheEfficient, 1);
    let full = RacBvh::encode(&bvh, &mesh, &opts(256, Some(16))).unwrap();
    let cluster_bound = 256 * (32 + 2 + 12) + 128;
    let budget = 3 * cluster_bound;
    let rac = RacBvh::from_bytes(&full.to_bytes(), budget).unwrap();
    let dm = rac.decoded_mesh();
    let mut stats = TraversalStats::default();
    for ray in test_rays(&dm, 4, 100) {
        let got = query::closest_hit(&rac, &ray, f32::INFINITY, &mut stats);
        assert_eq!(
            got,
            query::closest_hit(&full, &ray, f32::INFINITY, &mut stats)
        );
        let s = rac.cache_stats();
        assert!(s.cached_bytes <= budget, "{s:?}");
        assert!(s.live_bytes <= budget + cluster_bound, "{s:?}");
    }
    let s = rac.cache_stats();
    assert!(s.peak_live_bytes <= budget + cluster_bound, "{s:?}");
    assert!(
        s.decodes > rac.cluster_count() as u64,
        "the small cache must have evicted: {s:?}"
    );
    rac.clear_cache();
    // The node cache's table stays allocated (and counted), emptied.
    let s = rac.cache_stats();
    assert!(s.node_bytes > 0, "{s:?}");
    assert_eq!(s.cached_bytes, s.node_bytes);
}

#[test]
fn the_cluster_size_is_chosen_from_the_cache_budget() {
    use cbvh::codec::racbvh::{MIN_CLUSTER_NODES, RESIDENT_CLUSTERS};
    let per = |c: usize| RESIDENT_CLUSTERS * c * 34;
    let with = |cluster_nodes, cache_budget_bytes| RacOptions {
        cluster_nodes,
        cache_budget_bytes,
        ..Default::default()
    };
    assert_eq!(with(4096, usize::MAX).cluster_nodes_for_budget(), 4096);
    assert_eq!(with(4096, 64 << 20).cluster_nodes_for_budget(), 4096);
    assert_eq!(with(4096, per(4096)).cluster_nodes_for_budget(), 4096);
    assert_eq!(with(4096, per(4096) - 1).cluster_nodes_for_budget(), 2048);
    assert_eq!(with(16384, per(1024)).cluster_nodes_for_budget(), 1024);
    assert_eq!(with(1024, per(4096)).cluster_nodes_for_budget(), 1024);
    assert_eq!(with(4096, 0).cluster_nodes_for_budget(), MIN_CLUSTER_NODES);
}

/// Issue 32: a cache of a tenth of the tree, encoded for that budget, holds
/// many small clusters instead of less than one large one, answers every
/// query as the full cache does, and a repeated working set that fits is
/// decoded once.
#[test]
fn a_tenth_cache_encoded_for_its_budget_agrees_with_the_full_cache() {
    let mesh = statue(20_000);
    let bvh = tree(&mesh, Layout::DepthFirst, 1);
    let full = RacBvh::encode(&bvh, &mesh, &RacOptions::default()).unwrap();
    assert_eq!(full.cluster_nodes(), 4096);
    for i in 0..full.node_count() as u32 {
        full.bv(i);
    }
    let tenth = full.cache_stats().cached_bytes / 10;
    assert!(
        tenth < 4096 * 34,
        "a tenth holds less than one default cluster"
    );
    // The encoder takes the cluster size it is given, whatever the budget.
    let asked = RacOptions {
        cache_budget_bytes: tenth,
        ..Default::default()
    };
    assert_eq!(
        RacBvh::encode(&bvh, &mesh, &asked).unwrap().cluster_nodes(),
        4096
    );
    // Fitted to the budget (as `AnyOptions::with_cache_budget` does).
    let o = AnyOptions::default().with_cache_budget(tenth).racbvh;
    assert_eq!(o.cache_budget_bytes, tenth);
    let small = RacBvh::encode(&bvh, &mesh, &o).unwrap();
    assert_eq!(small.cluster_nodes(), 256);
    assert_eq!(small.cache_stats().budget_bytes, tenth);
    // Node by node, from the last (each completion walks up to the root).
    for i in (0..bvh.nodes.len() as u32).rev() {
        assert_eq!(small.bv(i), full.bv(i), "node {i}");
        assert_eq!(small.is_leaf(i), full.is_leaf(i), "node {i}");
        if full.is_leaf(i) {
            assert_eq!(small.leaf_triangles(i), full.leaf_triangles(i), "node {i}");
        } else {
            assert_eq!(
                [small.left(i), small.right(i)],
                [full.left(i), full.right(i)]
            );
        }
    }
    small.clear_cache();
    let dm = full.decoded_mesh();
    assert_eq!(small.decoded_mesh().triangles, dm.triangles);
    let mut stats = TraversalStats::default();
    let rays = test_rays(&dm, 7, 300);
    for ray in &rays {
        assert_eq!(
            query::closest_hit(&small, ray, f32::INFINITY, &mut stats),
            query::closest_hit(&full, ray, f32::INFINITY, &mut stats)
        );
        let s = small.cache_stats();
        assert!(s.cached_bytes <= tenth, "{s:?}");
    }
    // The first 4 clusters' nodes, round after round, in both directions:
    // they fit the budget (15 clusters), so each is decoded once.
    // (The counters are cumulative; the thread's pins may still hold some
    // of these clusters.)
    small.clear_cache();
    let before = small.cache_stats().decodes;
    let mut after_first = 0;
    for round in 0..6 {
        for i in 0..4 * 256 {
            let i = if round % 2 == 0 { i } else { 4 * 256 - 1 - i };
            small.bv(i);
        }
        if round == 0 {
            after_first = small.cache_stats().decodes;
            assert!(after_first - before <= 4, "{:?}", small.cache_stats());
        }
    }
    assert_eq!(small.cache_stats().decodes, after_first);
}

#[test]
fn eight_threads_with_a_tiny_cache_agree_with_one() {
    let mesh = statue(3000);
    let bvh = tree(&mesh, Layout::CacheEfficient, 1);
    let one = RacBvh::encode(&bvh, &mesh, &opts(256, Some(16))).unwrap();
    let dm = one.decoded_mesh();
    let rays = test_rays(&dm, 11, 400);
    let mut stats = TraversalStats::default();
    let want: Vec<_> = rays
        .iter()
        .map(|r| query::closest_hit(&one, r, f32::INFINITY, &mut stats))
        .collect();
    let shared = RacBvh::from_bytes(&one.to_bytes(), 2 * 256 * 46).unwrap();
    std::thread::scope(|s| {
        for t in 0..8 {
            let (shared, rays, want) = (&shared, &rays, &want);
            s.spawn(move || {
                let mut stats = TraversalStats::default();
                for k in (0..rays.len()).map(|k| (k * 7 + t * 13) % rays.len()) {
                    assert_eq!(
                        query::closest_hit(shared, &rays[k], f32::INFINITY, &mut stats),
                        want[k],
                        "thread {t} ray {k}"
                    );
                }
            });
        }
    });
    let s = shared.cache_stats();
    assert!(s.cached_bytes <= s.budget_bytes, "{s:?}");
}

/// The codec's own errors for a short or foreign file, and the random-access
/// API on damaged bytes: `try_` accessors give errors, never panics (the
/// shared suite checks that reading or verifying damaged files fails).
#[test]
fn container_errors_and_random_access_on_damaged_bytes() {
    let mesh = statue(2000);
    let bvh = tree(&mesh, Layout::CacheEfficient, 2);
    let rac = RacBvh::encode(&bvh, &mesh, &opts(256, Some(16))).unwrap();
    let bytes = rac.to_bytes();
    let back = RacBvh::from_bytes(&bytes, 1 << 20).unwrap();
    for i in (0..bvh.nodes.len() as u32).step_by(7) {
        assert_eq!(back.bv(i), rac.bv(i));
    }
    assert_eq!(
        RacBvh::from_bytes(b"nonsense bytes", 1).unwrap_err(),
        RacError::Format(FormatError::Truncated {
            section: "header",
            need: 312,
            have: 14
        })
    );
    let mut bad = bytes.clone();
    bad[0] ^= 1;
    assert_eq!(
        RacBvh::from_bytes(&bad, 1).unwrap_err(),
        RacError::Format(FormatError::BadMagic { format: "RACBVH" })
    );
    let mut rng = Rng(77);
    for _ in 0..200 {
        let mut bad = bytes.clone();
        let at = rng.below(bad.len());
        bad[at] ^= 1 << rng.below(8);
        if let Ok(t) = RacBvh::from_bytes(&bad, 1 << 16) {
            for i in (0..t.node_count() as u32).step_by(13) {
                let _ = t.try_bv(i);
            }
        }
    }
    let missing = RacBvh::open(&std::env::temp_dir().join("cbvh-no-such-file.rac"), 1 << 20);
    assert!(matches!(missing, Err(RacError::Io(_))), "{missing:?}");
}

#[test]
fn triangles_of_two_trees_do_not_mix_in_the_per_thread_cache() {
    // Same triangle ids in both trees, different geometry; a dropped tree's
    // successor must not see its cached triangles either.
    let (a, b) = (statue(3_000), soup(4, 3_000, 5.0));
    let ra = RacBvh::encode(&tree(&a, Layout::DepthFirst, 1), &a, &opts(256, None)).unwrap();
    let rb = RacBvh::encode(&tree(&b, Layout::DepthFirst, 1), &b, &opts(256, None)).unwrap();
    let (da, db) = (ra.decoded_mesh(), rb.decoded_mesh());
    let corners = |m: &Mesh, id: u32| m.triangle_vertices(id as usize);
    let n = a.triangles.len().min(b.triangles.len()) as u32;
    for round in 0..3 {
        for id in (0..n).step_by(7) {
            assert_eq!(
                NodeCursor::triangle(&ra, id).map(|v| v.to_array()),
                corners(&da, id)
            );
            assert_eq!(
                NodeCursor::triangle(&rb, id).map(|v| v.to_array()),
                corners(&db, id)
            );
        }
        if round == 1 {
            let rc = RacBvh::encode(&tree(&b, Layout::VanEmdeBoas, 1), &b, &opts(1024, Some(12)))
                .unwrap();
            let dc = rc.decoded_mesh();
            for id in (0..n).step_by(7) {
                assert_eq!(
                    NodeCursor::triangle(&rc, id).map(|v| v.to_array()),
                    corners(&dc, id)
                );
            }
        }
    }
}

/// Every node's box, children and triangles as read through `rac`, in
/// `order`, against `full` (a cache holding the whole tree).
fn check_nodes_against(rac: &RacBvh, full: &RacBvh, order: impl Iterator<Item = u32>) {
    for i in order {
        assert_eq!(rac.bv(i), full.bv(i), "node {i}");
        assert_eq!(rac.is_leaf(i), full.is_leaf(i), "node {i}");
        if full.is_leaf(i) {
            assert_eq!(rac.leaf_triangles(i), full.leaf_triangles(i), "node {i}");
        } else {
            assert_eq!([rac.left(i), rac.right(i)], [full.left(i), full.right(i)]);
        }
    }
}

/// The decoded bytes of every cluster of `rac` (touching every node with an
/// unlimited cache).
fn decoded_bytes(rac: &RacBvh) -> usize {
    let whole = RacBvh::from_bytes(&rac.to_bytes(), usize::MAX).unwrap();
    for i in 0..whole.node_count() as u32 {
        whole.bv(i);
    }
    whole.cache_stats().cached_bytes
}

/// Issue 32: the node cache exists only when the budget cannot hold every
/// cluster, takes all of the budget but the cluster cache's share, and is
/// counted in the cache's bytes.
#[test]
fn the_node_cache_takes_its_share_only_of_a_budget_smaller_than_the_tree() {
    use cbvh::codec::racbvh::CLUSTER_CACHE_PERCENT;
    let mesh = statue(3000);
    let bvh = tree(&mesh, Layout::DepthFirst, 1);
    let full = RacBvh::encode(&bvh, &mesh, &opts(256, Some(16))).unwrap();
    let whole = decoded_bytes(&full);
    let bytes = full.to_bytes();
    for budget in [usize::MAX, 64 << 20, whole] {
        let rac = RacBvh::from_bytes(&bytes, budget).unwrap();
        assert_eq!(rac.node_cache_capacity(), 0, "budget {budget}");
        assert_eq!(rac.cache_stats().node_bytes, 0);
    }
    for budget in [whole / 2, whole / 10, 4096, 1000] {
        let rac = RacBvh::from_bytes(&bytes, budget).unwrap();
        let s = rac.cache_stats();
        assert_eq!(s.budget_bytes, budget);
        assert!(rac.node_cache_capacity() > 0, "budget {budget}");
        // At least 36 bytes a node (8 words and a key).
        assert!(s.node_bytes >= 36 * rac.node_cache_capacity(), "{s:?}");
        assert!(
            s.node_bytes <= budget - budget * CLUSTER_CACHE_PERCENT / 100,
            "{s:?}"
        );
        // Within one set's bytes of its share.
        assert!(
            s.node_bytes + 300 > budget - budget * CLUSTER_CACHE_PERCENT / 100,
            "{s:?}"
        );
        assert_eq!(s.cached_bytes, s.node_bytes, "nothing decoded yet");
        assert_eq!(s.live_bytes, s.node_bytes);
    }
    // A tiny budget: no room for a set.
    let rac = RacBvh::from_bytes(&bytes, 100).unwrap();
    assert_eq!(rac.node_cache_capacity(), 0);
}

/// Issue 32: with budgets of a tenth of the tree and of 4 KiB, in depth-first
/// and cache-efficient layouts, with one and several triangles a leaf (the
/// node cache keeps a leaf's ids), every query equals brute force, every
/// node equals the full cache's, and the caches stay within the budget.
#[test]
fn tiny_budgets_with_a_node_cache_answer_as_brute_force() {
    let mesh = statue(1000);
    for (layout, leaf) in [(Layout::DepthFirst, 1), (Layout::CacheEfficient, 4)] {
        let bvh = tree(&mesh, layout, leaf);
        let full = RacBvh::encode(&bvh, &mesh, &opts(256, Some(16))).unwrap();
        let dm = full.decoded_mesh();
        let bytes = full.to_bytes();
        let whole = decoded_bytes(&full);
        for budget in [whole / 10, 4096] {
            let rac = RacBvh::from_bytes(&bytes, budget).unwrap();
            check_nodes_against(&rac, &full, (0..rac.node_count() as u32).rev());
            check_structure(&rac, &dm);
            check_queries(&rac, &dm, 5);
            // A tree with a node cache against one without.
            let other = soup(9, 300, 3.0);
            let ro = RacBvh::encode(
                &tree(&other, Layout::DepthFirst, 1),
                &other,
                &opts(256, None),
            )
            .unwrap();
            check_bvtt(&rac, &dm, &ro, &ro.decoded_mesh(), 5);
            let s = rac.cache_stats();
            assert!(s.cached_bytes <= budget, "{s:?}");
            assert!(rac.node_cache_capacity() > 0, "budget {budget}");
            assert!(s.node_misses > 0, "{s:?}");
            assert!(
                s.decodes > rac.cluster_count() as u64,
                "a budget of {budget} must have evicted: {s:?}"
            );
        }
    }
}

/// Issue 32: nodes beyond the node cache's capacity evict each other,
/// while a working set that fits, read round after round, misses only in
/// its first round and then decodes nothing.
#[test]
fn the_node_cache_evicts_and_keeps_a_working_set_that_fits() {
    let mesh = statue(3000);
    let bvh = tree(&mesh, Layout::DepthFirst, 1);
    let full = RacBvh::encode(&bvh, &mesh, &opts(256, Some(16))).unwrap();
    let rac = RacBvh::from_bytes(&full.to_bytes(), 8192).unwrap();
    let cap = rac.node_cache_capacity();
    let n = rac.node_count();
    assert!(cap > 64 && cap < n / 4, "capacity {cap} of {n} nodes");
    // Every node, twice: the second sweep misses at least the nodes the
    // table cannot hold.
    let sweep = || {
        let before = rac.cache_stats().node_misses;
        check_nodes_against(&rac, &full, 0..n as u32);
        rac.cache_stats().node_misses - before
    };
    let first = sweep();
    let second = sweep();
    assert!(first >= n as u64, "{first}");
    assert!(
        second >= (n - cap) as u64,
        "{second} misses of {n} nodes, {cap} held"
    );
    // A quarter of the capacity, spread over the tree, read in rounds.
    let set: Vec<u32> = (0..cap as u32 / 4)
        .map(|k| k * (n as u32 / (cap as u32 / 4)))
        .collect();
    rac.clear_cache();
    for round in 0..5 {
        let before = rac.cache_stats();
        for &i in &set {
            rac.bv(i);
            rac.is_leaf(i);
        }
        let after = rac.cache_stats();
        if round > 0 {
            assert_eq!(after.node_misses, before.node_misses, "round {round}");
            assert_eq!(after.decodes, before.decodes, "round {round}");
        }
    }
}

/// Four threads running two-tree traversals and rays against one tree with
/// a node cache and several triangles a leaf agree with one thread and the
/// full cache, within the budget.
#[test]
fn threads_sharing_a_node_cache_agree_with_the_full_cache() {
    let mesh = statue(1500);
    let bvh = tree(&mesh, Layout::CacheEfficient, 3);
    let full = RacBvh::encode(&bvh, &mesh, &opts(256, Some(16))).unwrap();
    let dm = full.decoded_mesh();
    let budget = 8 * 1024;
    let shared = RacBvh::from_bytes(&full.to_bytes(), budget).unwrap();
    assert!(shared.node_cache_capacity() > 0);
    let other = soup(3, 200, 4.0);
    let ro = RacBvh::encode(
        &tree(&other, Layout::DepthFirst, 1),
        &other,
        &opts(256, None),
    )
    .unwrap();
    let rays = test_rays(&dm, 3, 60);
    let poses = test_poses(&dm, 3);
    let mut stats = TraversalStats::default();
    let want_rays: Vec<_> = rays
        .iter()
        .map(|r| query::closest_hit(&full, r, f32::INFINITY, &mut stats))
        .collect();
    let want_pairs: Vec<_> = poses
        .iter()
        .map(|p| query::bvtt_pairs(&full, &ro, p, 0.02, &mut stats))
        .collect();
    std::thread::scope(|s| {
        for t in 0..4 {
            let (shared, ro, rays, poses) = (&shared, &ro, &rays, &poses);
            let (want_rays, want_pairs) = (&want_rays, &want_pairs);
            s.spawn(move || {
                let mut stats = TraversalStats::default();
                for round in 0..2 {
                    for k in (0..rays.len()).map(|k| (k * 7 + t * 13 + round) % rays.len()) {
                        assert_eq!(
                            query::closest_hit(shared, &rays[k], f32::INFINITY, &mut stats),
                            want_rays[k],
                            "thread {t} ray {k}"
                        );
                    }
                    for (k, p) in poses.iter().enumerate() {
                        assert_eq!(
                            query::bvtt_pairs(shared, ro, p, 0.02, &mut stats),
                            want_pairs[k],
                            "thread {t} pose {k}"
                        );
                    }
                }
            });
        }
    });
    let s = shared.cache_stats();
    assert!(s.cached_bytes <= budget, "{s:?}");
    assert!(
        s.node_misses > 0 && s.decodes > shared.cluster_count() as u64,
        "{s:?}"
    );
}

/// The sims' `racbvh-10pct` on a codec file opens it with a small cache and
/// asks for a tenth of what the tree decodes to: the measure must not
/// depend on the cache it is taken through (it once read the 1 MiB cache's
/// contents and gave a 150 M-triangle statue a 0.1 MiB budget).
#[test]
fn a_tenth_of_the_tree_is_measured_whatever_the_cache() {
    use cbvh::codec::Codec;
    let mesh = statue(3000);
    let bvh = tree(&mesh, Layout::DepthFirst, 1);
    let full = RacBvh::encode(&bvh, &mesh, &opts(256, Some(16))).unwrap();
    let whole = decoded_bytes(&full);
    let bytes = full.to_bytes();
    for budget in [usize::MAX, whole / 2, 4096, 1000] {
        let rac = RacBvh::from_bytes(&bytes, budget).unwrap();
        assert_eq!(rac.decoded_bytes().unwrap(), whole, "budget {budget}");
        let tenth = Codec::with_cache_budget_of(&rac, &|d| d / 10)
            .expect("a cached codec")
            .unwrap();
        assert_eq!(
            tenth.cache_stats().budget_bytes,
            whole / 10,
            "budget {budget}"
        );
    }
    // A memory-mapped file: the tenth shares the map (the file may even be
    // gone from its directory) and decodes every node as the encoder's
    // tree does.
    let path = std::env::temp_dir().join(format!("cbvh-rac-tenth-{}.rac", std::process::id()));
    Codec::save(&full, &path).unwrap();
    let mapped = RacBvh::open(&path, 1 << 20).unwrap();
    std::fs::remove_file(&path).unwrap();
    let tenth = Codec::with_cache_budget_of(&mapped, &|d| d / 10)
        .expect("a cached codec")
        .unwrap();
    assert_eq!(tenth.cache_stats().budget_bytes, whole / 10);
    tenth.verify().unwrap();
    assert_eq!(tenth.to_bytes(), bytes);
    for i in 0..full.node_count() as u32 {
        assert_eq!(tenth.bv(i), full.bv(i), "node {i}");
    }
    assert_eq!(tenth.decoded_mesh(), full.decoded_mesh());
}
