//! The builder's trees (shape, layouts, options) through the plain codec.
//! What every codec must do (brute-force parity, conservative boxes, edge
//! cases, files, corruption) is in the shared suite, `codec_suite.rs`.

use crate::common;

use cbvh::build::{BuildOptions, Layout, build};
use cbvh::codec::plain::PlainBvh;
use cbvh::{Mesh, TraversalStats, query};
use common::*;
use proptest::prelude::*;

fn plain(mesh: &Mesh, layout: Layout, leaf: usize) -> PlainBvh {
    let bvh = tree(mesh, layout, leaf);
    assert_eq!(bvh.layout, layout);
    // A binary tree, every inner node with two children: one node fewer
    // inner nodes than leaves. Every leaf holds 1 to `leaf` triangles (the
    // empty mesh: one empty leaf), and together they hold every triangle.
    let n = mesh.triangles.len();
    let sizes: Vec<usize> = bvh
        .nodes
        .iter()
        .filter(|node| node.is_leaf())
        .map(|node| node.leaf_range().len())
        .collect();
    assert_eq!(
        bvh.nodes.len(),
        2 * sizes.len() - 1,
        "nodes for {} leaves",
        sizes.len()
    );
    assert_eq!(sizes.iter().sum::<usize>(), n, "triangles in the leaves");
    assert!(
        sizes.iter().all(|&s| s <= leaf && (s >= 1 || n == 0)),
        "leaf sizes {sizes:?} with at most {leaf} a leaf"
    );
    assert!(sizes.len() >= n.div_ceil(leaf).max(1));
    if leaf == 1 {
        assert_eq!(bvh.nodes.len(), (2 * n).max(2) - 1);
    }
    // Parents agree with children.
    for (i, n) in bvh.nodes.iter().enumerate() {
        if !n.is_leaf() {
            for c in n.children() {
                assert_eq!(bvh.parents[c as usize], i as u32);
            }
        }
    }
    PlainBvh::new(&bvh, mesh)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// `plain` asserts the tree's shape: binary, leaves of 1 to `leaf`
    /// triangles holding every triangle once, parents agreeing.
    #[test]
    fn trees_are_binary_with_bounded_leaves(seed in any::<u64>(), n in 0usize..300, leaf in 1usize..5) {
        let mesh = soup(seed, n, 10.0);
        for layout in Layout::ALL {
            plain(&mesh, layout, leaf);
        }
    }
}

#[test]
fn every_layout_gives_the_same_answers() {
    let mesh = soup(7, 500, 5.0);
    let trees: Vec<PlainBvh> = Layout::ALL.iter().map(|&l| plain(&mesh, l, 1)).collect();
    let mut stats = TraversalStats::default();
    for ray in test_rays(&mesh, 3, 200) {
        let hits: Vec<_> = trees
            .iter()
            .map(|t| query::closest_hit(t, &ray, f32::INFINITY, &mut stats))
            .collect();
        assert!(
            hits.windows(2).all(|w| w[0] == w[1]),
            "layouts disagree: {hits:?}"
        );
    }
    let pairs: Vec<_> = trees
        .iter()
        .map(|t| query::bvtt_pairs(t, t, &cbvh::geom::Pose::IDENTITY, 0.01, &mut stats))
        .collect();
    assert!(!pairs[0].is_empty());
    assert!(pairs.windows(2).all(|w| w[0] == w[1]));
}

#[test]
fn layouts_are_permutations_with_root_first() {
    let mesh = soup(11, 3000, 5.0);
    for layout in Layout::ALL {
        let bvh = build(
            &mesh,
            &BuildOptions {
                layout,
                ..Default::default()
            },
            &|_, _| {},
        )
        .unwrap();
        assert_eq!(bvh.parents[0], u32::MAX);
        // Every node but the root has exactly one parent, and parents come first
        // in every layout we produce.
        for (i, &p) in bvh.parents.iter().enumerate().skip(1) {
            assert!((p as usize) < i, "{layout}: parent {p} after child {i}");
        }
        let mut ids = bvh.leaf_triangles.clone();
        ids.sort_unstable();
        assert!(ids.iter().enumerate().all(|(k, &id)| k as u32 == id));
    }
}

#[test]
fn bad_options_are_errors() {
    let mesh = soup(1, 3, 1.0);
    let e = build(
        &mesh,
        &BuildOptions {
            max_leaf_triangles: 0,
            ..Default::default()
        },
        &|_, _| {},
    );
    assert!(e.unwrap_err().to_string().contains("max_leaf_triangles"));
    let bad = Mesh::new(vec![[0.0; 3]], vec![[0, 0, 5]]);
    let e = build(&bad, &BuildOptions::default(), &|_, _| {}).unwrap_err();
    assert!(e.to_string().contains("vertex index 5"), "{e}");
}
