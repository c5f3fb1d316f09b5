//! What the i-HCCMesh encoder requires of the canonical tree it is given,
//! checked before it reads the tree: a [`CanonicalBvh`] is plain data with
//! public fields, and one the builder did not make (or that was changed
//! since) gives [`HccError::BadTree`], not a panic, a walk that never ends
//! or a file that silently drops triangles.

use super::error::HccError;
use crate::build::CanonicalBvh;

/// Checks that `bvh` is a tree over the mesh's `triangles` triangles as
/// the encoder walks it, from the root (node 0) with an explicit stack:
/// every child index names a node; no node is reached twice (no cycle, no
/// shared subtree); every leaf reached holds between 1 and `leaf_limit`
/// triangles (what its leaf word stores: 1, or a multi-triangle leaf's
/// count) from within `leaf_triangles`; and those leaves hold every
/// triangle id below `triangles` exactly once. Nodes the root does not
/// reach are not read.
///
/// For a mesh with triangles; without, the encoder reads no node.
pub(super) fn check_tree(
    bvh: &CanonicalBvh,
    triangles: usize,
    leaf_limit: usize,
) -> Result<(), HccError> {
    let bad = |node: u32, what| Err(HccError::BadTree { node, what });
    if bvh.nodes.is_empty() {
        return bad(0, "the tree has no nodes");
    }
    // Bit sets: nodes reached, triangles found.
    let mut reached = vec![0u64; bvh.nodes.len().div_ceil(64)];
    let mut found = vec![0u64; triangles.div_ceil(64)];
    test_and_set(&mut reached, 0);
    let mut in_leaves = 0usize;
    let mut stack = vec![0u32];
    while let Some(i) = stack.pop() {
        // In range: checked before it was pushed.
        let node = &bvh.nodes[i as usize];
        if !node.is_leaf() {
            for c in node.children() {
                if c as usize >= bvh.nodes.len() {
                    return bad(i, "a child index is out of range");
                }
                if test_and_set(&mut reached, c as usize) {
                    return bad(i, "a child is reached twice (two parents, or a cycle)");
                }
                stack.push(c);
            }
            continue;
        }
        let range = node.leaf_range();
        if range.is_empty() {
            return bad(i, "a leaf holds no triangle");
        }
        if range.len() > leaf_limit {
            return bad(
                i,
                "a leaf holds more triangles than the tree's leaves store",
            );
        }
        let Some(ids) = bvh.leaf_triangles.get(range) else {
            return bad(i, "a leaf's triangle slots are out of range");
        };
        for &t in ids {
            if t as usize >= triangles {
                return bad(i, "a leaf names a triangle the mesh does not have");
            }
            if test_and_set(&mut found, t as usize) {
                return bad(i, "a triangle is in two leaves, or twice in one");
            }
        }
        in_leaves += ids.len();
    }
    if in_leaves != triangles {
        return bad(0, "a triangle of the mesh is in no leaf");
    }
    Ok(())
}

/// Sets bit `i` of `set`; returns whether it was set already.
fn test_and_set(set: &mut [u64], i: usize) -> bool {
    let (word, bit) = (&mut set[i / 64], 1u64 << (i % 64));
    let was = *word & bit != 0;
    *word |= bit;
    was
}

#[cfg(test)]
mod tests {
    use super::super::{HccBvh, HccOptions};
    use super::*;
    use crate::build::{BuildOptions, LEAF_FLAG, build};
    use crate::scene::rng::Rng;
    use crate::scene::{Kind, generate};

    fn tree(leaf: usize) -> (crate::Mesh, CanonicalBvh) {
        let mesh = generate(Kind::Statue, 1000, 5, &mut |_, _| {}).unwrap();
        let opts = BuildOptions {
            max_leaf_triangles: leaf,
            ..Default::default()
        };
        let bvh = build(&mesh, &opts, &|_, _| {}).unwrap();
        (mesh, bvh)
    }

    fn first(bvh: &CanonicalBvh, leaf: bool) -> usize {
        bvh.nodes.iter().position(|n| n.is_leaf() == leaf).unwrap()
    }

    /// Each way a canonical tree can be broken gives `BadTree` from
    /// `encode`, which panicked (or dropped triangles) on them before.
    #[test]
    fn encode_rejects_corrupt_canonical_trees() {
        let (mesh, good) = tree(1);
        HccBvh::encode(&good, &mesh).unwrap();
        let inner = first(&good, false);
        let leaf = first(&good, true);
        let n = good.nodes.len() as u32;
        type Corruption<'a> = (&'a str, &'a dyn Fn(&mut CanonicalBvh));
        let corruptions: [Corruption; 8] = [
            ("child out of range", &|b| b.nodes[inner].a = n + 7),
            ("both children one node", &|b| {
                b.nodes[inner].b = b.nodes[inner].a
            }),
            ("a cycle to the root", &|b| b.nodes[inner].b = 0),
            ("leaf slots out of range", &|b| {
                b.nodes[leaf].a = b.leaf_triangles.len() as u32
            }),
            ("an empty leaf", &|b| b.nodes[leaf].b = LEAF_FLAG),
            ("two triangles in a one-triangle leaf", &|b| {
                b.nodes[leaf].b = LEAF_FLAG | 2
            }),
            ("a triangle twice", &|b| {
                b.leaf_triangles[1] = b.leaf_triangles[0]
            }),
            ("no nodes", &|b| b.nodes.clear()),
        ];
        for (what, corrupt) in corruptions {
            let mut bad = good.clone();
            corrupt(&mut bad);
            let got = HccBvh::encode(&bad, &mesh);
            assert!(
                matches!(got, Err(HccError::BadTree { .. })),
                "{what}: {got:?}"
            );
        }
    }

    /// Random bit flips in the nodes and the leaf slots: `encode` never
    /// panics, and what it accepts verifies.
    #[test]
    fn encode_never_panics_on_corrupt_canonical_trees() {
        let mut rng = Rng::new(0x2545_F491, 0);
        for leaf in [1, 4] {
            let (mesh, good) = tree(leaf);
            let options = HccOptions {
                vertex_bits: (leaf > 1).then_some(16),
                ..Default::default()
            };
            let mut rejected = 0;
            for round in 0..150 {
                let mut b = good.clone();
                let r = rng.next_u64();
                let bit = 1u32 << (r % 32);
                let i = (r >> 8) as usize;
                match round % 3 {
                    0 => b.nodes[i % good.nodes.len()].a ^= bit,
                    1 => b.nodes[i % good.nodes.len()].b ^= bit,
                    _ => b.leaf_triangles[i % good.leaf_triangles.len()] ^= bit,
                }
                match HccBvh::encode_with(&b, &mesh, &options) {
                    Ok(h) => h.verify().unwrap(),
                    Err(_) => rejected += 1,
                }
            }
            assert!(
                rejected > 100,
                "leaf {leaf}: only {rejected} of 150 rejected"
            );
        }
    }
}
