//! Triangle meshes: the [`Mesh`] type, its statistics, and file input/output.
//!
//! A [`Mesh`] is an indexed triangle mesh with `f32` vertex positions and
//! `[u32; 3]` triangles. Files are loaded by extension with [`load`]
//! (OFF, PLY ASCII/binary of either endianness, OBJ, STL ASCII/binary with
//! coincident vertices welded) and written with [`save`] (binary PLY, OBJ).
//! Polygons are fan-triangulated on input. [`Mesh::subdivided`] splits every
//! triangle into four, to test a scan at a higher resolution.
//!
//! Bad input never panics: every loader returns a [`MeshError`] that names
//! the file, the place (line for text formats, byte offset for binary ones)
//! and what is wrong.

mod error;
mod io;
mod stats;
mod subdivide;

pub use error::{MeshError, Place};
pub use io::{
    Encoding, Format, FormatDetail, PlyWriter, Streamed, TriangleBatches, estimate_counts,
    header_triangles, load, load_bytes, load_bytes_with_detail, load_with_detail, save, stream,
};
pub use stats::{MeshStats, boundary_edges, degenerate_triangles};
pub use subdivide::{MAX_SUBDIVIDED, SubdivideError, subdivided_triangles};

/// The largest coordinate magnitude cbvh accepts. Ray/triangle tests
/// multiply three coordinate differences, and `f32` overflows near 3.4e38:
/// beyond about 1e12 a scene would render empty or miss contacts without an
/// error, so [`Mesh::validate`] (run by the builder, the CLI and the sims
/// right after loading) rejects larger coordinates; loaders read them as
/// written.
pub const MAX_COORDINATE: f32 = 1e12;

/// An indexed triangle mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub vertices: Vec<[f32; 3]>,
    /// Triangles as indices into [`Mesh::vertices`].
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    /// Creates a mesh from vertices and triangles without validating it
    /// (see [`Mesh::validate`]).
    pub fn new(vertices: Vec<[f32; 3]>, triangles: Vec<[u32; 3]>) -> Self {
        Self {
            vertices,
            triangles,
        }
    }

    /// A closed axis-aligned box from corner `lo` to corner `hi`: 8
    /// vertices (vertex `k` is at `hi` along the axes whose bit is set in
    /// `k`: bit 0 x, bit 1 y, bit 2 z, and at `lo` along the others) and 12
    /// triangles, two a face, wound counter-clockwise seen from outside when
    /// `lo` is below `hi` on every axis.
    pub fn cuboid(lo: [f32; 3], hi: [f32; 3]) -> Self {
        let vertices = (0..8)
            .map(|k| {
                [
                    if k & 1 == 0 { lo[0] } else { hi[0] },
                    if k & 2 == 0 { lo[1] } else { hi[1] },
                    if k & 4 == 0 { lo[2] } else { hi[2] },
                ]
            })
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let triangles = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        Self::new(vertices, triangles)
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.vertices.len()
    }

    /// The three corner positions of triangle `t`.
    ///
    /// # Panics
    /// If `t` is out of range or the triangle refers to a missing vertex
    /// (a validated mesh never does).
    #[inline]
    pub fn triangle_vertices(&self, t: usize) -> [[f32; 3]; 3] {
        let [a, b, c] = self.triangles[t];
        [
            self.vertices[a as usize],
            self.vertices[b as usize],
            self.vertices[c as usize],
        ]
    }

    /// Axis-aligned bounds `(min, max)` of the vertices referenced or not;
    /// `None` for a mesh without vertices.
    pub fn bounds(&self) -> Option<([f32; 3], [f32; 3])> {
        let first = *self.vertices.first()?;
        let mut lo = first;
        let mut hi = first;
        for v in &self.vertices {
            for k in 0..3 {
                lo[k] = lo[k].min(v[k]);
                hi[k] = hi[k].max(v[k]);
            }
        }
        Some((lo, hi))
    }

    /// Checks what every consumer of a mesh relies on: at least one
    /// triangle, every index in range, every coordinate finite and at most
    /// [`MAX_COORDINATE`] in magnitude.
    /// `source` names the mesh in the error (a file path, or a generator).
    pub fn validate(&self, source: &str) -> Result<(), MeshError> {
        if let Some(vertex) = self
            .vertices
            .iter()
            .position(|v| !v.iter().all(|c| c.is_finite()))
        {
            return Err(MeshError::NonFinite {
                path: source.into(),
                place: Place::Unknown,
                vertex,
            });
        }
        if let Some(vertex) = self
            .vertices
            .iter()
            .position(|v| v.iter().any(|c| c.abs() > MAX_COORDINATE))
        {
            return Err(MeshError::CoordinateTooLarge {
                path: source.into(),
                vertex,
                value: self.vertices[vertex]
                    .into_iter()
                    .fold(0.0, |m: f32, c| m.max(c.abs())),
                limit: MAX_COORDINATE,
            });
        }
        if self.triangles.is_empty() {
            return Err(MeshError::NoFaces {
                path: source.into(),
            });
        }
        let n = self.vertices.len();
        for (face, tri) in self.triangles.iter().enumerate() {
            if let Some(&index) = tri.iter().find(|&&i| i as usize >= n) {
                return Err(MeshError::IndexOutOfRange {
                    path: source.into(),
                    place: Place::Unknown,
                    face,
                    index: index as u64,
                    vertices: n,
                });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::Mesh;

    /// A closed tetrahedron, outward-wound: the mesh module's test fixture.
    pub(crate) fn tetrahedron() -> Mesh {
        Mesh::new(
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
            ],
            vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
        )
    }
}
