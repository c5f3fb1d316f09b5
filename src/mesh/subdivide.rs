//! Midpoint subdivision: every triangle split into four through its edge
//! midpoints, shared edges sharing their midpoint.
//!
//! It raises a mesh's resolution without changing its shape (the new
//! triangles lie in the old ones' planes), which is how a user tests a
//! scan at the papers' resolution when only a coarser file is at hand:
//! a 75 k bunny subdivided three times has 4.8 M triangles whose contact
//! regions hold as many triangle pairs as a 4.8 M scan's. A closed mesh
//! stays closed (a midpoint is made once per edge), so its mass properties
//! are unchanged.

use std::collections::HashMap;
use std::collections::hash_map::Entry;

use super::Mesh;

/// The most triangles, and the most vertices, a subdivided mesh may have:
/// both are numbered by `u32`.
pub const MAX_SUBDIVIDED: u64 = u32::MAX as u64;

/// The triangles of `triangles` subdivided `times` times (`4^times` as
/// many), or `None` above [`MAX_SUBDIVIDED`]: the check a front end makes
/// from a requested or a header's count before any work.
pub fn subdivided_triangles(triangles: u64, times: u32) -> Option<u64> {
    4u64.checked_pow(times)
        .and_then(|f| triangles.checked_mul(f))
        .filter(|&t| t <= MAX_SUBDIVIDED)
}

/// Why [`Mesh::subdivided`] refused a mesh.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SubdivideError {
    /// Four times the triangles would be more than [`MAX_SUBDIVIDED`].
    #[error(
        "subdividing {triangles} triangles would give {} of them, more than the {MAX_SUBDIVIDED} \
         a mesh can number",
        4 * *triangles as u64
    )]
    TooManyTriangles {
        /// The mesh's triangles.
        triangles: usize,
    },
    /// The midpoints would take the vertices past [`MAX_SUBDIVIDED`].
    #[error(
        "subdividing {triangles} triangles over {vertices} vertices would give more than the \
         {MAX_SUBDIVIDED} vertices a mesh can number"
    )]
    TooManyVertices {
        /// The mesh's triangles.
        triangles: usize,
        /// The mesh's vertices.
        vertices: usize,
    },
}

impl Mesh {
    /// The mesh with every triangle split into four at its edge midpoints
    /// (see the module docs): four times the triangles, plus one vertex per
    /// distinct edge. Triangle `t`'s four parts are `4t..4t + 4`, the
    /// centre one last, each wound as `t` is.
    ///
    /// # Errors
    /// If the result would have more than [`MAX_SUBDIVIDED`] triangles or
    /// vertices (checked before anything is allocated for the triangles;
    /// the vertices as their midpoints are made).
    ///
    /// # Panics
    /// If a triangle refers to a missing vertex (a validated mesh never
    /// does).
    pub fn subdivided(&self) -> Result<Mesh, SubdivideError> {
        let too_many = SubdivideError::TooManyTriangles {
            triangles: self.triangles.len(),
        };
        let tris = subdivided_triangles(self.triangles.len() as u64, 1).ok_or(too_many)? as usize;
        let mut vertices = self.vertices.clone();
        // Each edge of a closed mesh is seen twice; about 1.5 edges per triangle.
        let mut midpoint: HashMap<(u32, u32), u32> =
            HashMap::with_capacity(self.triangles.len() * 3 / 2 + 16);
        let mut mid = |a: u32, b: u32, vertices: &mut Vec<[f32; 3]>| -> Option<u32> {
            let key = (a.min(b), a.max(b));
            match midpoint.entry(key) {
                Entry::Occupied(e) => Some(*e.get()),
                Entry::Vacant(e) => {
                    let (p, q) = (vertices[key.0 as usize], vertices[key.1 as usize]);
                    let m = [
                        0.5 * (p[0] + q[0]),
                        0.5 * (p[1] + q[1]),
                        0.5 * (p[2] + q[2]),
                    ];
                    // At most MAX_SUBDIVIDED vertices: ids below u32::MAX.
                    let id = u32::try_from(vertices.len())
                        .ok()
                        .filter(|&id| id < u32::MAX)?;
                    vertices.push(m);
                    Some(*e.insert(id))
                }
            }
        };
        let too_many = || SubdivideError::TooManyVertices {
            triangles: self.triangles.len(),
            vertices: self.vertices.len(),
        };
        let mut triangles = Vec::with_capacity(tris);
        for &[a, b, c] in &self.triangles {
            let ab = mid(a, b, &mut vertices).ok_or_else(too_many)?;
            let bc = mid(b, c, &mut vertices).ok_or_else(too_many)?;
            let ca = mid(c, a, &mut vertices).ok_or_else(too_many)?;
            triangles.extend_from_slice(&[[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        }
        Ok(Mesh::new(vertices, triangles))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::boundary_edges;
    use crate::mesh::tests::tetrahedron;

    fn area_vector(m: &Mesh, t: usize) -> [f64; 3] {
        let [p, q, r] = m.triangle_vertices(t).map(|v| v.map(f64::from));
        let (u, v) = (
            [q[0] - p[0], q[1] - p[1], q[2] - p[2]],
            [r[0] - p[0], r[1] - p[1], r[2] - p[2]],
        );
        [
            0.5 * (u[1] * v[2] - u[2] * v[1]),
            0.5 * (u[2] * v[0] - u[0] * v[2]),
            0.5 * (u[0] * v[1] - u[1] * v[0]),
        ]
    }

    /// A closed tetrahedron stays closed: 4 → 16 triangles, 4 + 6 vertices
    /// (one per edge), no boundary edge; each part has a quarter of its
    /// parent's area and the parent's orientation.
    #[test]
    fn a_closed_mesh_stays_closed_with_one_midpoint_per_edge() {
        let m = tetrahedron();
        let s = m.subdivided().unwrap();
        assert_eq!(s.triangle_count(), 16);
        assert_eq!(s.vertex_count(), 10);
        assert_eq!(boundary_edges(&s), 0);
        s.validate("subdivided").unwrap();
        for t in 0..m.triangle_count() {
            let parent = area_vector(&m, t);
            for k in 0..4 {
                let part = area_vector(&s, 4 * t + k);
                for axis in 0..3 {
                    assert!(
                        (part[axis] * 4.0 - parent[axis]).abs() < 1e-6,
                        "triangle {t} part {k}: {part:?} is not a quarter of {parent:?}"
                    );
                }
            }
        }
        // Twice: 64 triangles, 10 + 24 vertices (the 24 edges of the 16).
        let s2 = s.subdivided().unwrap();
        assert_eq!((s2.triangle_count(), s2.vertex_count()), (64, 34));
        assert_eq!(boundary_edges(&s2), 0);
    }

    /// The count a front end checks before any work: 4^times as many
    /// triangles, refused above `MAX_SUBDIVIDED` (and on overflow).
    #[test]
    fn subdivided_counts_stop_at_the_numbering_limit() {
        assert_eq!(subdivided_triangles(100, 0), Some(100));
        assert_eq!(subdivided_triangles(100, 3), Some(6400));
        assert_eq!(subdivided_triangles(1 << 30, 1), None);
        assert_eq!(subdivided_triangles((1 << 30) - 1, 1), Some((1 << 32) - 4));
        assert_eq!(subdivided_triangles(1, 16), None);
        assert_eq!(subdivided_triangles(1, 40), None);
        assert_eq!(subdivided_triangles(200_000_000, 2), Some(3_200_000_000));
        assert_eq!(subdivided_triangles(200_000_000, 3), None);
    }

    /// An open mesh keeps its boundary, each boundary edge split in two.
    #[test]
    fn an_open_mesh_keeps_its_boundary() {
        let m = Mesh::new(
            vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![[0, 1, 2]],
        );
        assert_eq!(boundary_edges(&m), 3);
        let s = m.subdivided().unwrap();
        assert_eq!(boundary_edges(&s), 6);
        assert_eq!(s.vertices[3], [0.5, 0.0, 0.0]);
    }
}
