//! Building a [`PlainBvh`] from the canonical tree.

use super::PlainError;
use super::node::PlainNode;
use crate::build::{CanonicalBvh, LEAF_FLAG};
use crate::codec::ByteSize;
use crate::codec::common::FormatError;
use crate::codec::common::MassProps;
use crate::codec::common::edges;
use crate::codec::common::huge::huge;
use crate::contact::EdgeFlags;
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
    /// Active edges by triangle id, computed when encoded.
    pub(super) edges: EdgeFlags,
}

impl PlainBvh {
    /// Encodes `bvh` (built over `mesh`), as [`PlainBvh::encode`] does.
    ///
    /// # Panics
    /// If the tree and the mesh do not fit the plain layout (see
    /// [`PlainBvh::encode`]); a tree built over the mesh by
    /// [`build`](crate::build::build) always fits.
    pub fn new(bvh: &CanonicalBvh, mesh: &Mesh) -> Self {
        Self::encode(bvh, mesh).unwrap_or_else(|e| panic!("plain: {e}"))
    }

    /// Encodes `bvh` (built over `mesh`). Fails if the tree has no nodes,
    /// has [`LEAF_FLAG`] nodes or more (a child index would read as a leaf),
    /// references another number of triangles than the mesh has, or if the
    /// mesh has more vertices or triangles than the file's 32-bit counts
    /// hold.
    pub fn encode(bvh: &CanonicalBvh, mesh: &Mesh) -> Result<Self, PlainError> {
        let misfit =
            |field: &'static str, why: String| PlainError::from(FormatError::Header { field, why });
        let nodes = bvh.nodes.len();
        if nodes == 0 || nodes >= LEAF_FLAG as usize {
            return Err(misfit(
                "node count",
                format!("{nodes} nodes; the plain layout holds 1 to 2^31 - 1"),
            ));
        }
        if bvh.triangle_count() != mesh.triangles.len() {
            return Err(misfit(
                "triangle count",
                format!(
                    "the tree holds {} triangles, the mesh {}: encode a tree built over this mesh",
                    bvh.triangle_count(),
                    mesh.triangles.len()
                ),
            ));
        }
        for (field, n) in [
            ("vertex count", mesh.vertices.len()),
            ("triangle count", mesh.triangles.len()),
        ] {
            if u32::try_from(n).is_err() {
                return Err(misfit(
                    field,
                    format!("{n} does not fit the file's 32-bit count"),
                ));
            }
        }
        let single = bvh.max_leaf_triangles == 1;
        let nodes = bvh.nodes.iter().map(|n| {
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
        });
        let mut out = Self {
            nodes: huge(nodes),
            vertices: huge(mesh.vertices.iter().copied()),
            triangles: huge(mesh.triangles.iter().copied()),
            leaf_ids: if single {
                Vec::new()
            } else {
                bvh.leaf_triangles.clone()
            },
            mass: MassProps::of_mesh(mesh),
            edges: EdgeFlags::default(),
        };
        out.edges = edges::of_cursor(&out);
        Ok(out)
    }

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
