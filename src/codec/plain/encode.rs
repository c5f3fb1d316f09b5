//! Building a [`PlainBvh`] from the canonical tree.

use super::node::PlainNode;
use crate::build::{CanonicalBvh, LEAF_FLAG};
use crate::codec::ByteSize;
use crate::codec::common::MassProps;
use crate::mesh::Mesh;

/// The uncompressed BVH with its mesh.
///
/// With one triangle per leaf (the default), a leaf stores the triangle's
/// original id directly, as in RACBVH Listing 1, and `leaf_ids` is empty.
/// With several, a leaf's `left` is the first slot of its run in `leaf_ids`.
#[derive(Clone, Debug)]
pub struct PlainBvh {
    pub(super) nodes: Vec<PlainNode>,
    pub(super) vertices: Vec<[f32; 3]>,
    pub(super) triangles: Vec<[u32; 3]>,
    pub(super) leaf_ids: Vec<u32>,
    /// Mass properties at density 1, computed from the mesh.
    pub(super) mass: MassProps,
}

impl PlainBvh {
    /// Encodes `bvh` (built over `mesh`).
    pub fn new(bvh: &CanonicalBvh, mesh: &Mesh) -> Self {
        let single = bvh.max_leaf_triangles == 1;
        let nodes = bvh
            .nodes
            .iter()
            .map(|n| {
                let (left, right) = if !n.is_leaf() {
                    (n.a, n.b)
                } else if single && n.leaf_range().len() == 1 {
                    (bvh.leaf_triangles[n.a as usize], LEAF_FLAG | 1)
                } else {
                    (n.a, n.b)
                };
                PlainNode {
                    min: n.min,
                    max: n.max,
                    left,
                    right,
                }
            })
            .collect();
        Self {
            nodes,
            vertices: mesh.vertices.clone(),
            triangles: mesh.triangles.clone(),
            leaf_ids: if single {
                Vec::new()
            } else {
                bvh.leaf_triangles.clone()
            },
            mass: MassProps::of_mesh(mesh),
        }
    }

    /// Mass properties at density 1 (computed from the mesh when built,
    /// stored in the file).
    pub fn mass(&self) -> MassProps {
        self.mass
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
        ]
    }
}
