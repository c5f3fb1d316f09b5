//! Mass properties at density 1, computed once when a codec is encoded and
//! stored in its file, so that a shape opened from a file needs no mesh.
//!
//! The integration is parry's `MassProperties::from_trimesh`'s (the solid
//! the triangles enclose, as tetrahedra from a point near the mesh), summed
//! in `f64` instead of parry's `f32`, whose error grows with the triangle
//! count (3.5 % of the mass on a 50 M-triangle statue): a shape from a file
//! and a parry `TriMesh` of the same small mesh get the same figures to
//! about 1e-6, a large one gets the right ones ([`MassProps::of_mesh`]). A
//! model built out of core sums its chunks the same way
//! ([`MassAccumulator`]). The parry layer turns the stored tensor into
//! principal axes with parry's own `MassProperties::with_inertia_matrix`.

use crate::mesh::Mesh;

/// The mean of `vertices` (the origin for none), summed in `f64`: the
/// reference point every mass sum takes ([`MassProps::of_mesh`], the
/// out-of-core builders' [`MassAccumulator`]s).
pub fn vertex_mean(vertices: &[[f32; 3]]) -> [f32; 3] {
    let mut s = [0f64; 3];
    for p in vertices {
        for k in 0..3 {
            s[k] += f64::from(p[k]);
        }
    }
    let n = vertices.len().max(1) as f64;
    s.map(|x| (x / n) as f32)
}

/// Mass properties of a mesh at density 1.
///
/// # Layout
/// 13 little-endian `f32`, 52 bytes:
/// | bytes | field |
/// |---|---|
/// | 0–3 | `mass`: the enclosed volume (0 for a mesh without volume) |
/// | 4–15 | `com`: centre of mass x, y, z |
/// | 16–51 | `inertia`: the 3 × 3 inertia tensor about `com`, column-major |
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct MassProps {
    /// Mass at density 1 (the enclosed volume; 0 when there is none).
    pub mass: f32,
    /// Centre of mass.
    pub com: [f32; 3],
    /// Inertia tensor about the centre of mass, column-major.
    pub inertia: [f32; 9],
}

const _: () = assert!(std::mem::size_of::<MassProps>() == 52);

/// Bytes of [`MassProps`] in a file.
pub const MASS_BYTES: usize = 52;

impl MassProps {
    /// No mass (a mesh without volume, or an empty one).
    pub const ZERO: MassProps = MassProps {
        mass: 0.0,
        com: [0.0; 3],
        inertia: [0.0; 9],
    };

    /// Signed-volume integration over `mesh` (the solid it encloses, as
    /// parry's `MassProperties::from_trimesh` at density 1), summed in
    /// `f64` ([`MassAccumulator`], about the mean of the vertices, in
    /// fixed chunks of triangles added in order: the same bits whatever
    /// the threads); [`MassProps::ZERO`] where the figures are not
    /// [`physical`](Self::physical).
    ///
    /// parry sums in `f32`, one triangle after the other, which is exact
    /// enough for thousands of triangles and not for millions: on a
    /// 50 M-triangle statue its mass is 3.5 % low and its centre of mass
    /// 4.5 mm off (of 2 m); this sum agrees with parry's to about 1e-6 on
    /// small meshes and stays right on large ones.
    pub fn of_mesh(mesh: &Mesh) -> MassProps {
        use rayon::prelude::*;
        if mesh.vertices.is_empty() || mesh.triangles.is_empty() {
            return MassProps::ZERO;
        }
        let reference = vertex_mean(&mesh.vertices);
        const CHUNK: usize = 1 << 16;
        let v = |i: u32| mesh.vertices[i as usize];
        mesh.triangles
            .par_chunks(CHUNK)
            .map(|ts| {
                let mut acc = MassAccumulator::new(reference);
                for t in ts {
                    acc.add(v(t[0]), v(t[1]), v(t[2]));
                }
                acc
            })
            .collect::<Vec<_>>()
            .iter()
            .fold(MassAccumulator::new(reference), |mut a, b| {
                a.merge(b);
                a
            })
            .finish()
    }

    /// The bytes as stored.
    pub fn to_bytes(&self) -> [u8; MASS_BYTES] {
        let mut out = [0u8; MASS_BYTES];
        let vals = std::iter::once(self.mass)
            .chain(self.com)
            .chain(self.inertia);
        for (k, x) in vals.enumerate() {
            out[4 * k..4 * k + 4].copy_from_slice(&x.to_le_bytes());
        }
        out
    }

    /// Reads stored bytes (`b` holds at least [`MASS_BYTES`]), refusing
    /// figures no body can have ([`physical`](Self::physical)): the reason
    /// as the error.
    pub fn from_bytes(b: &[u8]) -> Result<MassProps, &'static str> {
        let f = |k: usize| {
            let w = b.get(4 * k..4 * k + 4).ok_or("fewer than 52 bytes")?;
            Ok::<f32, &'static str>(f32::from_le_bytes([w[0], w[1], w[2], w[3]]))
        };
        let mut vals = [0f32; 13];
        for (k, v) in vals.iter_mut().enumerate() {
            *v = f(k)?;
        }
        let m = MassProps {
            mass: vals[0],
            com: [vals[1], vals[2], vals[3]],
            inertia: std::array::from_fn(|k| vals[4 + k]),
        };
        m.physical().map(|()| m)
    }

    /// Whether a body can have these figures, and if not why: every value
    /// finite; no mass and no inertia, or a positive mass with an inertia
    /// tensor that a distribution of positive mass has. That is: `I` is
    /// symmetric and `C = tr(I)/2 · 1 − I` (the second moments `∫ r rᵀ dm`)
    /// is positive semi-definite, which also makes `I` positive
    /// semi-definite with principal moments obeying the triangle
    /// inequality. Rounding is allowed for, relative to the trace.
    pub fn physical(&self) -> Result<(), &'static str> {
        let vals = std::iter::once(self.mass)
            .chain(self.com)
            .chain(self.inertia);
        if vals.into_iter().any(|x| !x.is_finite()) {
            return Err("a value is not finite");
        }
        if self.mass < 0.0 {
            return Err("the mass is negative");
        }
        let i: [f64; 9] = self.inertia.map(f64::from);
        let at = |r: usize, c: usize| i[3 * c + r];
        let trace = at(0, 0) + at(1, 1) + at(2, 2);
        if self.mass == 0.0 {
            return if i.iter().all(|&x| x == 0.0) {
                Ok(())
            } else {
                Err("no mass, but an inertia")
            };
        }
        if trace <= 0.0 {
            return Err("a mass without inertia");
        }
        let tol = 1e-5 * trace;
        for (r, c) in [(0, 1), (0, 2), (1, 2)] {
            if (at(r, c) - at(c, r)).abs() > tol {
                return Err("the inertia tensor is not symmetric");
            }
        }
        let cm = |r: usize, c: usize| {
            let sym = 0.5 * (at(r, c) + at(c, r));
            if r == c { 0.5 * trace - sym } else { -sym }
        };
        // Every principal minor of C non-negative (up to rounding).
        let minor2 = |a: usize, b: usize| cm(a, a) * cm(b, b) - cm(a, b) * cm(a, b);
        let det = cm(0, 0) * minor2(1, 2) - cm(0, 1) * (cm(1, 0) * cm(2, 2) - cm(1, 2) * cm(2, 0))
            + cm(0, 2) * (cm(1, 0) * cm(2, 1) - cm(1, 1) * cm(2, 0));
        let ok = (0..3).all(|k| cm(k, k) >= -tol)
            && [(0, 1), (0, 2), (1, 2)]
                .iter()
                .all(|&(a, b)| minor2(a, b) >= -tol * trace)
            && det >= -tol * trace * trace;
        if ok {
            Ok(())
        } else {
            Err("no distribution of positive mass has this inertia tensor")
        }
    }
}

/// Mass properties summed triangle by triangle, in `f64`, for a mesh that
/// is never whole in memory (the out-of-core builder's): each triangle
/// adds its tetrahedron from a fixed reference point (the volume, its
/// first and second moments), and [`finish`](Self::finish) moves the
/// second moments to the centre of mass. The result is the same body as
/// [`MassProps::of_mesh`]'s up to rounding (that one follows parry in
/// `f32`); the sum depends on the order the triangles come in, so a
/// caller that wants the same bits every run adds them in a fixed order.
#[derive(Clone, Copy, Debug)]
pub struct MassAccumulator {
    reference: [f64; 3],
    volume: f64,
    first: [f64; 3],
    /// `∫ x_i x_j dV` about the reference, row-major.
    second: [f64; 9],
}

impl MassAccumulator {
    /// An empty sum about `reference` (a point near the mesh, such as the
    /// mean of its vertices: the nearer, the less rounding).
    pub fn new(reference: [f32; 3]) -> Self {
        Self {
            reference: reference.map(f64::from),
            volume: 0.0,
            first: [0.0; 3],
            second: [0.0; 9],
        }
    }

    /// Adds the triangle `(a, b, c)` (wound counter-clockwise seen from
    /// outside for a positive volume).
    pub fn add(&mut self, a: [f32; 3], b: [f32; 3], c: [f32; 3]) {
        let r = self.reference;
        let rel = |p: [f32; 3]| [0, 1, 2].map(|k| f64::from(p[k]) - r[k]);
        let p = [rel(a), rel(b), rel(c)];
        let det = p[0][0] * (p[1][1] * p[2][2] - p[1][2] * p[2][1])
            - p[0][1] * (p[1][0] * p[2][2] - p[1][2] * p[2][0])
            + p[0][2] * (p[1][0] * p[2][1] - p[1][1] * p[2][0]);
        let v = det / 6.0;
        let sum = [0, 1, 2].map(|k| p[0][k] + p[1][k] + p[2][k]);
        self.volume += v;
        for (f, s) in self.first.iter_mut().zip(sum) {
            *f += v * s / 4.0;
        }
        // The tetrahedron with corners 0, a, b, c:
        // ∫ x_i x_j dV = V/20 (Σ p_i p_j + Σ p_i · Σ p_j).
        for i in 0..3 {
            for j in 0..3 {
                let pp = p[0][i] * p[0][j] + p[1][i] * p[1][j] + p[2][i] * p[2][j];
                self.second[3 * i + j] += v / 20.0 * (pp + sum[i] * sum[j]);
            }
        }
    }

    /// Adds another sum about the same reference.
    pub fn merge(&mut self, o: &MassAccumulator) {
        debug_assert_eq!(self.reference, o.reference);
        self.volume += o.volume;
        for k in 0..3 {
            self.first[k] += o.first[k];
        }
        for k in 0..9 {
            self.second[k] += o.second[k];
        }
    }

    /// The mass properties; [`MassProps::ZERO`] without volume or where
    /// the figures are not [`physical`](MassProps::physical) (an open
    /// surface), as [`MassProps::of_mesh`].
    pub fn finish(&self) -> MassProps {
        if self.volume == 0.0 || !self.volume.is_finite() {
            return MassProps::ZERO;
        }
        let m = self.volume;
        let d = self.first.map(|f| f / m);
        // Second moments about the centre of mass, then the inertia
        // tr(S)·1 − S; a negative volume (wound inside out) flips signs.
        let s: [f64; 9] = std::array::from_fn(|k| self.second[k] - m * d[k / 3] * d[k % 3]);
        let trace = s[0] + s[4] + s[8];
        let sign = m.signum();
        let inertia: [f32; 9] = std::array::from_fn(|k| {
            let (i, j) = (k % 3, k / 3); // column-major
            let diag = if i == j { trace } else { 0.0 };
            ((diag - s[3 * i + j]) * sign) as f32
        });
        let out = MassProps {
            mass: (m * sign) as f32,
            com: [0, 1, 2].map(|k| (self.reference[k] + d[k]) as f32),
            inertia,
        };
        if out.physical().is_ok() {
            out
        } else {
            MassProps::ZERO
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube() -> Mesh {
        // A unit cube from the origin.
        let mut m = crate::sim::slide::cube_mesh(1.0);
        m.vertices.iter_mut().flatten().for_each(|c| *c += 0.5);
        m
    }

    #[test]
    fn a_million_triangle_box_has_the_mass_of_a_box() {
        // The cube [-1, 1]³, each face a 290 × 290 grid: 1 009 200
        // triangles, where an f32 sum drifts.
        let n = 290u32;
        let (mut vertices, mut triangles) = (Vec::new(), Vec::new());
        for k in 0..3 {
            for sign in [1.0f32, -1.0] {
                let base = vertices.len() as u32;
                for j in 0..=n {
                    for i in 0..=n {
                        let mut p = [0f32; 3];
                        p[k] = sign;
                        p[(k + 1) % 3] = -1.0 + 2.0 * i as f32 / n as f32;
                        p[(k + 2) % 3] = -1.0 + 2.0 * j as f32 / n as f32;
                        vertices.push(p);
                    }
                }
                let at = |i: u32, j: u32| base + j * (n + 1) + i;
                for j in 0..n {
                    for i in 0..n {
                        let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                        if sign > 0.0 {
                            triangles.extend([[a, b, c], [a, c, d]]);
                        } else {
                            triangles.extend([[a, c, b], [a, d, c]]);
                        }
                    }
                }
            }
        }
        let m = MassProps::of_mesh(&Mesh::new(vertices, triangles));
        assert!((m.mass - 8.0).abs() < 1e-5, "{m:?}");
        assert!(m.com.iter().all(|c| c.abs() < 1e-6), "{m:?}");
        for (k, &x) in m.inertia.iter().enumerate() {
            let want = if k % 4 == 0 { 16.0 / 3.0 } else { 0.0 };
            assert!((x - want).abs() < 1e-4, "{m:?}");
        }
    }

    #[test]
    fn the_accumulator_agrees_with_of_mesh() {
        for mesh in [
            cube(),
            crate::scene::generate(crate::scene::Kind::Robot, 3000, 1, &mut |_, _| {}).unwrap(),
        ] {
            let want = MassProps::of_mesh(&mesh);
            let mut acc = MassAccumulator::new([0.3, -0.2, 0.1]);
            let (half, rest) = mesh.triangles.split_at(mesh.triangles.len() / 2);
            let mut other = acc;
            for t in half {
                acc.add(
                    mesh.vertices[t[0] as usize],
                    mesh.vertices[t[1] as usize],
                    mesh.vertices[t[2] as usize],
                );
            }
            for t in rest {
                other.add(
                    mesh.vertices[t[0] as usize],
                    mesh.vertices[t[1] as usize],
                    mesh.vertices[t[2] as usize],
                );
            }
            acc.merge(&other);
            let got = acc.finish();
            assert!(want.mass > 0.0);
            assert!(
                (got.mass - want.mass).abs() <= 1e-4 * want.mass,
                "{got:?} {want:?}"
            );
            let scale = want.inertia.iter().fold(0f32, |a, x| a.max(x.abs()));
            for k in 0..3 {
                assert!((got.com[k] - want.com[k]).abs() < 1e-4, "{got:?} {want:?}");
            }
            for k in 0..9 {
                assert!(
                    (got.inertia[k] - want.inertia[k]).abs() <= 1e-3 * scale,
                    "{got:?} {want:?}"
                );
            }
        }
        // Inside out: the same body.
        let mut flipped = cube();
        flipped.triangles.iter_mut().for_each(|t| t.swap(1, 2));
        let mut acc = MassAccumulator::new([0.0; 3]);
        for t in &flipped.triangles {
            acc.add(
                flipped.vertices[t[0] as usize],
                flipped.vertices[t[1] as usize],
                flipped.vertices[t[2] as usize],
            );
        }
        let got = acc.finish();
        assert!(
            (got.mass - 1.0).abs() < 1e-6 && (got.inertia[0] - 1.0 / 6.0).abs() < 1e-6,
            "{got:?}"
        );
        // An open surface: no mass.
        let mut acc = MassAccumulator::new([0.0; 3]);
        acc.add([0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        assert_eq!(acc.finish(), MassProps::ZERO);
    }

    #[test]
    fn a_closed_mesh_is_physical_and_round_trips() {
        let m = MassProps::of_mesh(&cube());
        assert!((m.mass - 1.0).abs() < 1e-5, "{m:?}");
        // A unit cube: I = m (1 + 1) / 12 on the diagonal.
        assert!((m.inertia[0] - 1.0 / 6.0).abs() < 1e-5, "{m:?}");
        assert_eq!(m.physical(), Ok(()));
        assert_eq!(MassProps::from_bytes(&m.to_bytes()), Ok(m));
    }

    #[test]
    fn figures_no_body_has_are_refused() {
        let m = MassProps::of_mesh(&cube());
        let with = |f: &dyn Fn(&mut MassProps)| {
            let mut x = m;
            f(&mut x);
            MassProps::from_bytes(&x.to_bytes())
        };
        assert!(with(&|x| x.mass = f32::NAN).is_err());
        assert!(with(&|x| x.mass = -1.0).is_err());
        assert!(with(&|x| x.com[1] = f32::INFINITY).is_err());
        // A principal moment larger than the other two together.
        assert!(with(&|x| x.inertia[0] = 1.0).is_err());
        // A negative moment.
        assert!(with(&|x| x.inertia[4] = -0.1).is_err());
        // Not symmetric.
        assert!(with(&|x| x.inertia[1] = 0.05).is_err());
        // A product of inertia too large for any distribution.
        assert!(
            with(&|x| {
                x.inertia[1] = 0.15;
                x.inertia[3] = 0.15;
            })
            .is_err()
        );
        // Mass without inertia, inertia without mass.
        assert!(with(&|x| x.inertia = [0.0; 9]).is_err());
        assert!(with(&|x| x.mass = 0.0).is_err());
        assert_eq!(MassProps::ZERO.physical(), Ok(()));
        // A valid rotation of the tensor's frame stays valid: a small
        // product of inertia.
        assert!(
            with(&|x| {
                x.inertia[1] = 0.01;
                x.inertia[3] = 0.01;
            })
            .is_ok()
        );
    }

    #[test]
    fn an_open_surface_gets_no_mass_rather_than_an_impossible_one() {
        // One triangle far from the others: the signed volumes from the
        // geometric centre do not describe a body.
        let mut mesh = cube();
        mesh.triangles.truncate(7);
        let m = MassProps::of_mesh(&mesh);
        assert_eq!(m.physical(), Ok(()), "{m:?}");
    }
}
