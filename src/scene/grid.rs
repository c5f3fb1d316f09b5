//! The topology shared by every generated part except the isosurface: the
//! surface of an `nx × ny × nz` box, subdivided into quads and split into
//! triangles. Vertices on the box's edges and corners are shared by the
//! faces meeting there, so the grid is a closed surface (a sphere
//! topologically) whatever the map that later bends it into shape.
//!
//! Vertices and triangles are numbered so that each can be computed from
//! its index alone (no neighbour lookups), which lets generators fill
//! disjoint chunks of pre-sized buffers in parallel and deterministically.
//!
//! Vertex layout: the bottom cap (`j = 0`, an `(nx+1) × (nz+1)` grid), then
//! `ny − 1` rings of `2(nx + nz)` vertices around the box, then the top cap
//! (`j = ny`). Triangle layout: the side quads ring by ring, then the bottom
//! cap, then the top cap. Triangles wind counter-clockwise seen from
//! outside the box: the outward orientation that every orientation-
//! preserving map keeps.

use glam::Vec3;

/// The box-surface grid: `nx`, `ny`, `nz` cells along x, y, z (each ≥ 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct BoxGrid {
    /// Cells along x.
    pub nx: u32,
    /// Cells along y.
    pub ny: u32,
    /// Cells along z.
    pub nz: u32,
}

impl BoxGrid {
    /// A grid with the given cell counts (each clamped to ≥ 1).
    pub(crate) fn new(nx: u32, ny: u32, nz: u32) -> Self {
        Self {
            nx: nx.max(1),
            ny: ny.max(1),
            nz: nz.max(1),
        }
    }

    /// Number of triangles: `4(nx·ny + ny·nz + nz·nx)`.
    pub(crate) fn triangles(&self) -> u64 {
        Self::triangles_of(self.nx as u64, self.ny as u64, self.nz as u64)
    }

    /// [`BoxGrid::triangles`] for arbitrary cell counts.
    #[inline]
    pub(crate) fn triangles_of(nx: u64, ny: u64, nz: u64) -> u64 {
        4 * (nx * ny + ny * nz + nz * nx)
    }

    /// Number of vertices: `2(nx·ny + ny·nz + nz·nx) + 2` (Euler: closed,
    /// genus 0).
    pub(crate) fn vertices(&self) -> u64 {
        let (x, y, z) = (self.nx as u64, self.ny as u64, self.nz as u64);
        2 * (x * y + y * z + z * x) + 2
    }

    #[inline]
    fn cap(&self) -> u64 {
        (self.nx as u64 + 1) * (self.nz as u64 + 1)
    }

    #[inline]
    fn ring(&self) -> u64 {
        2 * (self.nx as u64 + self.nz as u64)
    }

    /// The `(i, k)` grid position of perimeter position `p` (`0..ring()`),
    /// walking +x along `k = 0`, +z along `i = nx`, −x along `k = nz`,
    /// −z along `i = 0`.
    #[inline]
    fn ring_ik(&self, p: u32) -> (u32, u32) {
        let (nx, nz) = (self.nx, self.nz);
        if p < nx {
            (p, 0)
        } else if p < nx + nz {
            (nx, p - nx)
        } else if p < 2 * nx + nz {
            (nx - (p - nx - nz), nz)
        } else {
            (0, nz - (p - 2 * nx - nz))
        }
    }

    /// Index of vertex `(i, j, k)`, which must lie on the box surface.
    #[inline]
    fn vertex_id(&self, i: u32, j: u32, k: u32) -> u32 {
        let (nx, ny, nz) = (self.nx, self.ny, self.nz);
        if j == 0 {
            i * (nz + 1) + k
        } else if j == ny {
            (self.cap() + (ny as u64 - 1) * self.ring()) as u32 + i * (nz + 1) + k
        } else {
            let p = if k == 0 {
                i
            } else if i == nx {
                nx + k
            } else if k == nz {
                nx + nz + (nx - i)
            } else {
                2 * nx + nz + (nz - k)
            };
            (self.cap() + (j as u64 - 1) * self.ring()) as u32 + p
        }
    }

    /// Grid position `(i, j, k)` of vertex `v` (`v < vertices()`).
    #[inline]
    pub(crate) fn vertex_ijk(&self, v: u64) -> [u32; 3] {
        let cap = self.cap();
        let nz1 = self.nz as u64 + 1;
        if v < cap {
            return [(v / nz1) as u32, 0, (v % nz1) as u32];
        }
        let r = v - cap;
        let ring = self.ring();
        let rings = (self.ny as u64 - 1) * ring;
        if r < rings {
            let (i, k) = self.ring_ik((r % ring) as u32);
            [i, (r / ring) as u32 + 1, k]
        } else {
            let t = r - rings;
            [(t / nz1) as u32, self.ny, (t % nz1) as u32]
        }
    }

    /// Position of grid point `(i, j, k)` on the box `[-1, 1]³`
    /// (exactly ±1 on the faces).
    #[inline]
    pub(crate) fn unit(&self, [i, j, k]: [u32; 3]) -> Vec3 {
        Vec3::new(
            -1.0 + 2.0 * i as f32 / self.nx as f32,
            -1.0 + 2.0 * j as f32 / self.ny as f32,
            -1.0 + 2.0 * k as f32 / self.nz as f32,
        )
    }

    /// Vertex indices (local to the grid) of triangle `t`
    /// (`t < triangles()`).
    #[inline]
    pub(crate) fn triangle(&self, t: u64) -> [u32; 3] {
        let ring = self.ring();
        let sides = 2 * ring * self.ny as u64;
        if t < sides {
            let q = t / 2;
            let j = (q / ring) as u32;
            let p = (q % ring) as u32;
            let p1 = if p as u64 + 1 == ring { 0 } else { p + 1 };
            let (i0, k0) = self.ring_ik(p);
            let (i1, k1) = self.ring_ik(p1);
            let a = self.vertex_id(i0, j, k0);
            let c = self.vertex_id(i1, j + 1, k1);
            if t.is_multiple_of(2) {
                [a, c, self.vertex_id(i1, j, k1)]
            } else {
                [a, self.vertex_id(i0, j + 1, k0), c]
            }
        } else {
            let capq = self.nx as u64 * self.nz as u64;
            let r = t - sides;
            let top = r >= 2 * capq;
            let r = if top { r - 2 * capq } else { r };
            let q = r / 2;
            let i = (q / self.nz as u64) as u32;
            let k = (q % self.nz as u64) as u32;
            let j = if top { self.ny } else { 0 };
            let a = self.vertex_id(i, j, k);
            let b = self.vertex_id(i + 1, j, k);
            let c = self.vertex_id(i + 1, j, k + 1);
            let d = self.vertex_id(i, j, k + 1);
            match (top, r.is_multiple_of(2)) {
                (false, true) => [a, b, c],
                (false, false) => [a, c, d],
                (true, true) => [a, c, b],
                (true, false) => [a, d, c],
            }
        }
    }
}

/// The grid's tests, and the helpers the scene's other tests share.
#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::mesh::{Mesh, boundary_edges, degenerate_triangles};

    /// The mesh of grid `g` with every vertex of the cube `[-1, 1]³` moved
    /// by `map` (the identity: the cube itself), one vertex and triangle
    /// after the other.
    pub(crate) fn grid_mesh(g: BoxGrid, map: impl Fn(Vec3) -> Vec3) -> Mesh {
        let vertices = (0..g.vertices())
            .map(|v| map(g.unit(g.vertex_ijk(v))).to_array())
            .collect();
        let triangles = (0..g.triangles()).map(|t| g.triangle(t)).collect();
        Mesh::new(vertices, triangles)
    }

    /// The volume `m` encloses, summed in `f64`: positive when its
    /// triangles wind counter-clockwise seen from outside.
    pub(crate) fn signed_volume(m: &Mesh) -> f64 {
        m.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| Vec3::from(m.vertices[i as usize]).as_dvec3());
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    #[test]
    fn grids_are_closed_outward_and_roundtrip() {
        for (nx, ny, nz) in [(1, 1, 1), (1, 2, 3), (3, 1, 2), (4, 5, 6), (7, 2, 1)] {
            let g = BoxGrid::new(nx, ny, nz);
            let m = grid_mesh(g, |q| q);
            assert_eq!(m.triangles.len() as u64, g.triangles());
            m.validate("grid").unwrap();
            assert_eq!(boundary_edges(&m), 0, "{g:?}");
            assert_eq!(degenerate_triangles(&m), 0, "{g:?}");
            assert!(
                (signed_volume(&m) - 8.0).abs() < 1e-4,
                "{g:?}: {}",
                signed_volume(&m)
            );
            for v in 0..g.vertices() {
                let [i, j, k] = g.vertex_ijk(v);
                assert_eq!(g.vertex_id(i, j, k) as u64, v);
            }
            // No duplicated positions.
            let mut p: Vec<[u32; 3]> = (0..g.vertices()).map(|v| g.vertex_ijk(v)).collect();
            p.sort();
            p.dedup();
            assert_eq!(p.len() as u64, g.vertices());
        }
    }
}
