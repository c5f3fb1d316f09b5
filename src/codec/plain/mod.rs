//! The plain codec: the uncompressed reference every comparison is made
//! against (the papers' "Ori."). See [`node::PlainNode`] for the node
//! layout and [`file`](mod@file) for the self-contained file.
//!
//! Its nodes, vertices and triangles live in memory advised for
//! transparent huge pages ([`huge`](crate::codec::common::huge)), like
//! CLBVH's and Embree's, so that speed comparisons between them are about
//! layouts, not page sizes.

mod contract;
mod cursor;
mod encode;
mod error;
pub mod file;
mod node;
mod verify;

pub use error::PlainError;
pub use node::PlainNode;

use crate::codec::ByteSize;
use crate::codec::common::MassProps;
use crate::contact::EdgeFlags;

/// The uncompressed BVH with its mesh.
///
/// With one triangle per leaf (the default), a leaf stores the triangle's
/// original id directly, as in RACBVH Listing 1, and `leaf_ids` is empty.
/// With several, a leaf's `left` is the first slot of its run in `leaf_ids`.
#[derive(Clone, Debug)]
pub struct PlainBvh {
    nodes: Vec<PlainNode>,
    vertices: Vec<[f32; 3]>,
    triangles: Vec<[u32; 3]>,
    leaf_ids: Vec<u32>,
    /// Mass properties at density 1, computed from the mesh.
    mass: MassProps,
    /// Active edges by triangle id, computed when encoded.
    edges: EdgeFlags,
}

impl PlainBvh {
    /// Height of the tree (a single leaf has height 1), in O(nodes). On a
    /// tree that was not verified, each node is counted once, at the first
    /// depth it is reached, and children out of range are skipped, so the
    /// walk always ends.
    pub fn height(&self) -> usize {
        let mut seen = vec![false; self.nodes.len()];
        let mut level = vec![0u32];
        let mut height = 0;
        while !level.is_empty() {
            let mut next = Vec::new();
            let mut reached = false;
            for i in level {
                match seen.get_mut(i as usize) {
                    Some(s) if !*s => *s = true,
                    _ => continue,
                }
                reached = true;
                let n = &self.nodes[i as usize];
                if !n.is_leaf() {
                    next.extend([n.left, n.right]);
                }
            }
            height += usize::from(reached);
            level = next;
        }
        height
    }

    /// Mass properties at density 1 (computed from the mesh when built,
    /// stored in the file).
    pub fn mass(&self) -> MassProps {
        self.mass
    }

    /// Active edges by triangle id (stored in the file).
    pub fn edge_flags(&self) -> &EdgeFlags {
        &self.edges
    }

    /// The nodes, root first.
    pub fn nodes(&self) -> &[PlainNode] {
        &self.nodes
    }

    /// The mesh's vertices.
    pub fn vertices(&self) -> &[[f32; 3]] {
        &self.vertices
    }

    /// The mesh's triangles, in original order.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }
}

impl ByteSize for PlainBvh {
    fn bytes_by_part(&self) -> Vec<(&'static str, usize)> {
        vec![
            ("nodes", self.nodes.len() * size_of::<PlainNode>()),
            ("vertices", self.vertices.len() * 12),
            ("triangles", self.triangles.len() * 12),
            ("leaf_ids", self.leaf_ids.len() * 4),
            ("edge-flags", self.edges.bytes()),
        ]
    }
}
