//! Decomposition of the canonical tree into one high-level tree over
//! low-level trees (HCCMesh §3.1).
//!
//! The paper walks the tree bottom-up and makes a node a low-level root when
//! it has fewer than 512 vertices and its parent has more. The vertex count
//! of a subtree only grows towards the root, so the same roots are the
//! *highest* nodes whose subtree fits: this module walks top-down with an
//! explicit stack and checks each candidate with a bounded walk of its
//! subtree, stopping as soon as it is too big.
//!
//! A subtree fits when the i-HCCMesh of it can be addressed:
//! - fewer than 512 distinct vertices (9-bit vertex indices, as the paper);
//! - fewer than 8192 nodes (13-bit template positions in an
//!   inter-connection). The paper's models never reach it, but a mesh of
//!   many triangles over few vertices (a fan, repeated triangles) would;
//! - fewer than 16384 triangles (multi-triangle leaves: the blocks' bit
//!   offsets in a leaf word);
//! - at most 512 template leaves (9-bit inter-connection indices). Template
//!   leaves are exactly the inner nodes at depth 3, 7, 11… below the root,
//!   because templates partition the tree top-down in layers of height 4.
//!
//! The walk over each candidate stops at the first limit reached, so a
//! failing candidate costs at most about 8192 steps; the high-level tree has
//! about twice as many nodes as there are low-level trees.

use crate::build::CanonicalBvh;
use crate::mesh::Mesh;

use super::node::{
    MAX_TREE_INTERCONNECTIONS, MAX_TREE_NODES, MAX_TREE_TRIANGLES, MAX_TREE_VERTICES,
};
use super::template::MAX_HEIGHT;

/// The decomposition: which canonical nodes are low-level roots and which
/// belong to the high-level tree.
#[derive(Clone, Debug, Default)]
pub struct Decomposition {
    /// Canonical ids of the low-level roots, in high-level depth-first
    /// order (left before right).
    pub roots: Vec<u32>,
    /// Canonical ids of the high-level inner nodes, depth-first.
    pub high: Vec<u32>,
}

/// A low-level root that cannot be made small enough: a leaf of the
/// canonical tree that alone breaks a limit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LeafTooBig {
    /// The canonical node.
    pub node: u32,
    /// Its distinct vertices.
    pub vertices: usize,
}

/// Decomposes `bvh` (built over `mesh`, not empty).
pub fn decompose(bvh: &CanonicalBvh, mesh: &Mesh) -> Result<Decomposition, LeafTooBig> {
    let mut stamp = vec![0u32; mesh.vertices.len()];
    let mut generation = 0u32;
    let mut out = Decomposition::default();
    let mut stack = vec![0u32];
    let mut walk = Vec::new();
    while let Some(n) = stack.pop() {
        generation += 1;
        let fit = fits(bvh, mesh, n, &mut stamp, generation, &mut walk);
        let node = &bvh.nodes[n as usize];
        match fit {
            Ok(()) => out.roots.push(n),
            Err(vertices) if node.is_leaf() => {
                return Err(LeafTooBig { node: n, vertices });
            }
            Err(_) => {
                out.high.push(n);
                // Right pushed first so the left subtree's roots come first.
                stack.push(node.b);
                stack.push(node.a);
            }
        }
    }
    Ok(out)
}

/// Whether the subtree of `root` fits a low-level tree; on failure, the
/// distinct vertices counted when the walk stopped.
fn fits(
    bvh: &CanonicalBvh,
    mesh: &Mesh,
    root: u32,
    stamp: &mut [u32],
    generation: u32,
    walk: &mut Vec<(u32, u32)>,
) -> Result<(), usize> {
    let (mut vertices, mut nodes, mut template_leaves, mut triangles) = (0usize, 0, 0, 0);
    walk.clear();
    walk.push((root, 0));
    while let Some((n, depth)) = walk.pop() {
        nodes += 1;
        if nodes >= MAX_TREE_NODES {
            return Err(vertices);
        }
        let node = &bvh.nodes[n as usize];
        if node.is_leaf() {
            triangles += node.leaf_range().len();
            if triangles >= MAX_TREE_TRIANGLES {
                return Err(vertices);
            }
            for &t in &bvh.leaf_triangles[node.leaf_range()] {
                for v in mesh.triangles[t as usize] {
                    let s = &mut stamp[v as usize];
                    if *s != generation {
                        *s = generation;
                        vertices += 1;
                    }
                }
            }
            if vertices >= MAX_TREE_VERTICES {
                return Err(vertices);
            }
        } else {
            if depth as usize % MAX_HEIGHT == MAX_HEIGHT - 1 {
                template_leaves += 1;
                if template_leaves > MAX_TREE_INTERCONNECTIONS {
                    return Err(vertices);
                }
            }
            walk.push((node.a, depth + 1));
            walk.push((node.b, depth + 1));
        }
    }
    Ok(())
}
