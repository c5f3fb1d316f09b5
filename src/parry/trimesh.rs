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

/// The papers' interference figure for two parry `TriMesh`es (`b` placed by
/// `pos12` in `a`'s frame): parry's own two-tree traversal
/// (`Bvh::leaf_pairs`) and cbvh's exact triangle-triangle test, so that the
/// traversal is what differs from cbvh's [`interference`](super::cbvh_cbvh::interference).
pub fn trimesh_interference(pos12: &parry3d::math::Pose, a: &TriMesh, b: &TriMesh) -> u64 {
    use parry3d::bounding_volume::BoundingVolume;
    let mut t = crate::contact::Interference::default();
    let pairs = a.bvh().leaf_pairs(b.bvh(), |n1, n2| {
        n1.aabb().intersects(&n2.aabb().transform_by(pos12))
    });
    let g = |p: Vector| glam::Vec3A::from(p.to_array());
    for (i, j) in pairs {
        let ta = a.triangle(i);
        let tb = b.triangle(j);
        t.push(
            &[g(ta.a), g(ta.b), g(ta.c)],
            &[g(*pos12 * tb.a), g(*pos12 * tb.b), g(*pos12 * tb.c)],
        );
    }
    t.flush();
    t.intersecting
}
