//! Building a [`PlainBvh`] from the canonical tree.

use super::node::PlainNode;
use super::{PlainBvh, PlainError};
use crate::build::{CanonicalBvh, LEAF_FLAG};
use crate::codec::common::FormatError;
use crate::codec::common::MassProps;
use crate::codec::common::edges;
use crate::codec::common::huge::huge;
use crate::contact::EdgeFlags;
use crate::mesh::Mesh;

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
}
