//! parry's `TriMesh` as the baseline.

use parry3d::math::Vector;
use parry3d::shape::{TriMesh, TriMeshBuilderError};

use crate::mesh::Mesh;

/// parry's `TriMesh` over `mesh`, built the way `SharedShape::trimesh`
/// builds it (default flags), as a rapier user would.
pub fn parry_trimesh(mesh: &Mesh) -> Result<TriMesh, TriMeshBuilderError> {
    let vertices = mesh
        .vertices
        .iter()
        .map(|v| Vector::new(v[0], v[1], v[2]))
        .collect();
    TriMesh::new(vertices, mesh.triangles.clone())
}

/// The memory of a parry `TriMesh` by part, counted like cbvh's codecs
/// (element counts times element sizes): its BVH, vertices, indices, and
/// the optional pseudo-normals, topology and connected components
/// (`other`), as `TriMesh::heap_memory_size` totals them.
pub fn trimesh_bytes_by_part(t: &TriMesh) -> Vec<(&'static str, usize)> {
    let bvh = t.bvh().heap_memory_size();
    let vertices = size_of_val(t.vertices());
    let indices = size_of_val(t.indices());
    let other = t
        .heap_memory_size()
        .saturating_sub(bvh + vertices + indices);
    vec![
        ("bvh", bvh),
        ("vertices", vertices),
        ("triangles", indices),
        ("other", other),
    ]
}
