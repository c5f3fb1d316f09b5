//! Mesh statistics reported by `cbvh info`: degenerate triangles and
//! boundary edges.

use super::Mesh;

/// The numbers `cbvh info` prints about a mesh.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct MeshStats {
    /// Number of triangles.
    pub triangles: usize,
    /// Number of vertices.
    pub vertices: usize,
    /// Minimum corner of the vertex bounds.
    pub bounds_min: [f32; 3],
    /// Maximum corner of the vertex bounds.
    pub bounds_max: [f32; 3],
    /// Triangles with zero area (repeated indices or collinear corners).
    pub degenerate_triangles: usize,
    /// Edges used by exactly one triangle; 0 means the mesh is closed.
    pub boundary_edges: usize,
}

impl MeshStats {
    /// Computes the statistics of `mesh`.
    pub fn of(mesh: &Mesh) -> Self {
        let (bounds_min, bounds_max) = mesh.bounds().unwrap_or(([0.0; 3], [0.0; 3]));
        Self {
            triangles: mesh.triangle_count(),
            vertices: mesh.vertex_count(),
            bounds_min,
            bounds_max,
            degenerate_triangles: degenerate_triangles(mesh),
            boundary_edges: boundary_edges(mesh),
        }
    }
}

/// Whether the triangle with corners `a`, `b`, `c` has zero area
/// (computed in f64 so that tiny but valid triangles are not miscounted).
pub fn is_degenerate(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> bool {
    let d = |p: [f32; 3], q: [f32; 3]| {
        [
            p[0] as f64 - q[0] as f64,
            p[1] as f64 - q[1] as f64,
            p[2] as f64 - q[2] as f64,
        ]
    };
    let u = d(b, a);
    let v = d(c, a);
    let n = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    n[0] == 0.0 && n[1] == 0.0 && n[2] == 0.0
}

/// Number of zero-area triangles: repeated vertex indices, or corners on
/// one line. Triangles with out-of-range indices are counted too.
pub fn degenerate_triangles(mesh: &Mesh) -> usize {
    let n = mesh.vertices.len();
    mesh.triangles
        .iter()
        .filter(|t| {
            if t.iter().any(|&i| i as usize >= n) || t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                return true;
            }
            let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
            is_degenerate(a, b, c)
        })
        .count()
}

/// Number of undirected edges used by exactly one triangle (by vertex index).
/// A closed (watertight) mesh has none. Edges of index-degenerate triangles
/// that collapse to a point are skipped.
pub fn boundary_edges(mesh: &Mesh) -> usize {
    let mut edges: Vec<u64> = Vec::with_capacity(mesh.triangles.len() * 3);
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if a == b {
                continue;
            }
            let (lo, hi) = if a < b { (a, b) } else { (b, a) };
            edges.push(((lo as u64) << 32) | hi as u64);
        }
    }
    edges.sort_unstable();
    let mut boundary = 0;
    let mut i = 0;
    while i < edges.len() {
        let mut j = i + 1;
        while j < edges.len() && edges[j] == edges[i] {
            j += 1;
        }
        if j - i == 1 {
            boundary += 1;
        }
        i = j;
    }
    boundary
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::mesh::tests::tetrahedron as tetra;

    #[test]
    fn closed_tetrahedron_has_no_boundary() {
        let s = MeshStats::of(&tetra());
        assert_eq!(s.boundary_edges, 0);
        assert_eq!(s.degenerate_triangles, 0);
        assert_eq!(s.bounds_max, [1.0, 1.0, 1.0]);
    }

    #[test]
    fn open_and_degenerate_are_counted() {
        let mut m = tetra();
        m.triangles.pop();
        m.vertices.push([2.0, 0.0, 0.0]);
        m.triangles.push([0, 1, 4]); // collinear corners
        m.triangles.push([2, 2, 3]); // repeated index
        assert_eq!(degenerate_triangles(&m), 2);
        // Removing one face of a tetrahedron opens 0-2, 0-3 and 2-3; the
        // collinear triangle adds 1-4 and 0-4 (0-1 is then used 3 times);
        // the repeated-index one uses 2-3 twice more, closing it.
        assert_eq!(boundary_edges(&m), 4);
    }
}
