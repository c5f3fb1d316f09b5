//! The shapes that parts are made of: maps from the box grid's cube
//! `[-1, 1]³` onto a surface. Every map is continuous, injective on the
//! cube's surface and orientation-preserving, so a mapped [`BoxGrid`]
//! stays a closed surface wound counter-clockwise seen from outside.
//!
//! [`BoxGrid`]: super::grid::BoxGrid

use std::f32::consts::{FRAC_PI_2, FRAC_PI_4};

use glam::Vec3;

use super::statue::Statue;

/// A turbine blade: a thin, cambered, twisted and tapered slab with sharp
/// leading and trailing edges, running radially along +x from `r0` to `r1`;
/// its chord lies in the z (tangential) / y (axial) plane at the pitch angle.
#[derive(Clone, Debug)]
pub(crate) struct Blade {
    /// Radius of the root.
    pub r0: f32,
    /// Radius of the tip.
    pub r1: f32,
    /// Chord length at root and tip.
    pub chord: (f32, f32),
    /// Maximum thickness at root and tip.
    pub thick: (f32, f32),
    /// Pitch angle (radians) at root and tip: the twist.
    pub pitch: (f32, f32),
    /// Camber height as a fraction of the chord.
    pub camber: f32,
    /// Sweep: tangential offset of the tip, in units.
    pub sweep: f32,
}

/// One shape in its own frame. Grid axis y is the shape's long axis.
#[derive(Clone, Debug)]
pub(crate) enum Shape {
    /// An axis-aligned box with the given half extents.
    Box { half: Vec3 },
    /// An ellipsoid with the given semi-axes (a cube-sphere).
    Ellipsoid { radii: Vec3 },
    /// A closed cylinder along y, from `-half_len` to `half_len`.
    Cylinder { radius: f32, half_len: f32 },
    /// A capsule along y: a cylinder of `half_len` with hemispherical ends.
    Capsule { radius: f32, half_len: f32 },
    /// A bent pipe with flat ends: starts at the origin heading +y and
    /// bends towards +x around a circle of radius `bend` by `angle` radians.
    Elbow { radius: f32, bend: f32, angle: f32 },
    /// A turbine blade.
    Blade(Blade),
    /// The statue.
    Statue(Box<Statue>),
}

/// The equal-angle cube-sphere warp: spreads cube-sphere cells evenly.
#[inline]
pub(crate) fn warp(q: Vec3) -> Vec3 {
    Vec3::new(
        (q.x * FRAC_PI_4).tan(),
        (q.y * FRAC_PI_4).tan(),
        (q.z * FRAC_PI_4).tan(),
    )
}

/// Shirley–Chiu concentric map of the square `[-1, 1]²` onto the unit disc
/// (orientation-preserving; the square's border goes to the circle).
#[inline]
pub(crate) fn square_to_disc(a: f32, b: f32) -> (f32, f32) {
    if a == 0.0 && b == 0.0 {
        return (0.0, 0.0);
    }
    let (r, phi) = if a.abs() > b.abs() {
        (a, FRAC_PI_4 * (b / a))
    } else {
        (b, FRAC_PI_2 - FRAC_PI_4 * (a / b))
    };
    let (s, c) = phi.sin_cos();
    (r * c, r * s)
}

impl Shape {
    /// Maps a point of the cube `[-1, 1]³` (on its surface) to the shape.
    #[inline]
    pub(crate) fn map(&self, q: Vec3) -> Vec3 {
        match self {
            Shape::Box { half } => q * *half,
            Shape::Ellipsoid { radii } => warp(q).normalize() * *radii,
            Shape::Cylinder { radius, half_len } => {
                let (x, z) = square_to_disc(q.x, q.z);
                Vec3::new(radius * x, half_len * q.y, radius * z)
            }
            Shape::Capsule { radius, half_len } => {
                let (x, z) = square_to_disc(q.x, q.z);
                // rho = 1 on the walls, < 1 on the end caps (|q.y| = 1).
                let rho = q.x.abs().max(q.z.abs());
                let (s, c) = (rho * FRAC_PI_2).sin_cos();
                let k = if rho > 0.0 { radius * s / rho } else { 0.0 };
                Vec3::new(k * x, half_len * q.y + q.y.signum() * radius * c, k * z)
            }
            Shape::Elbow {
                radius,
                bend,
                angle,
            } => {
                let (x, z) = square_to_disc(q.x, q.z);
                let (s, c) = ((q.y + 1.0) * 0.5 * angle).sin_cos();
                let centre = Vec3::new(bend * (1.0 - c), bend * s, 0.0);
                centre + Vec3::new(c, -s, 0.0) * (radius * x) + Vec3::Z * (radius * z)
            }
            Shape::Blade(b) => b.map(q),
            Shape::Statue(s) => s.map(q),
        }
    }

    /// Typical lengths of the shape along the grid's three axes, i.e. the
    /// lengths that `nx`, `ny`, `nz` cells should divide evenly.
    pub(crate) fn lens(&self) -> Vec3 {
        match self {
            Shape::Box { half } => *half * 2.0,
            Shape::Ellipsoid { radii } => *radii * FRAC_PI_2,
            Shape::Cylinder { radius, half_len } => {
                let around = radius * FRAC_PI_2;
                Vec3::new(around, 2.0 * half_len, around)
            }
            Shape::Capsule { radius, half_len } => {
                let around = radius * FRAC_PI_2;
                Vec3::new(around, 2.0 * half_len + 0.5 * radius, around)
            }
            Shape::Elbow {
                radius,
                bend,
                angle,
            } => {
                let around = radius * FRAC_PI_2;
                Vec3::new(around, bend * angle, around)
            }
            Shape::Blade(b) => Vec3::new(
                0.5 * (b.chord.0 + b.chord.1),
                b.r1 - b.r0,
                0.5 * (b.thick.0 + b.thick.1),
            ),
            Shape::Statue(s) => s.lens(),
        }
    }
}

impl Blade {
    /// The blade map: grid x runs along the chord, y along the span and z
    /// across the thickness.
    #[inline]
    fn map(&self, q: Vec3) -> Vec3 {
        let s = 0.5 * (q.y + 1.0);
        let lerp = |a: (f32, f32)| a.0 + (a.1 - a.0) * s;
        let chord = lerp(self.chord);
        let thick = lerp(self.thick);
        let pitch = lerp(self.pitch);
        let x = q.x;
        // Chordwise coordinate and a rounded-nose, thin-tail thickness law
        // that keeps a small finite thickness at both edges (sharp edges,
        // but no coincident vertices).
        let u = 0.5 * chord * x;
        let half = 0.5 * thick * (0.06 + 0.94 * (1.0 - x * x) * (1.0 - 0.3 * x));
        let v = self.camber * chord * (1.0 - x * x) + q.z * half;
        let (sn, cs) = pitch.sin_cos();
        let radial = self.r0 + (self.r1 - self.r0) * s;
        let tangential = u * cs - v * sn + self.sweep * s * s;
        let axial = u * sn + v * cs;
        Vec3::new(radial, axial, tangential)
    }
}

/// Surface-area proxy for the grid: `lx·ly + ly·lz + lz·lx`, so that a grid
/// with cells of side `h` has about `4·area_half / h²` triangles.
pub(crate) fn area_half(l: Vec3) -> f64 {
    let (x, y, z) = (l.x as f64, l.y as f64, l.z as f64);
    x * y + y * z + z * x
}

#[cfg(test)]
mod tests {
    use super::super::grid::BoxGrid;
    use super::super::grid::tests::{grid_mesh, signed_volume};
    use super::*;
    use crate::mesh::{boundary_edges, degenerate_triangles};

    #[test]
    fn shapes_are_closed_and_outward() {
        let blade = Blade {
            r0: 0.4,
            r1: 2.0,
            chord: (0.5, 0.3),
            thick: (0.06, 0.03),
            pitch: (0.9, 0.4),
            camber: 0.05,
            sweep: 0.1,
        };
        let shapes = [
            (
                Shape::Box {
                    half: Vec3::new(1.0, 2.0, 0.5),
                },
                8.0,
            ),
            (
                Shape::Ellipsoid {
                    radii: Vec3::new(1.0, 2.0, 0.5),
                },
                4.0 / 3.0 * std::f64::consts::PI,
            ),
            (
                Shape::Cylinder {
                    radius: 0.5,
                    half_len: 1.0,
                },
                std::f64::consts::PI * 0.5,
            ),
            (
                Shape::Capsule {
                    radius: 0.5,
                    half_len: 1.0,
                },
                std::f64::consts::PI * (0.5 + 0.5 / 3.0),
            ),
            (
                Shape::Elbow {
                    radius: 0.2,
                    bend: 1.0,
                    angle: FRAC_PI_2,
                },
                std::f64::consts::PI * 0.04 * FRAC_PI_2 as f64,
            ),
            (Shape::Blade(blade), 0.0),
        ];
        for (s, volume) in &shapes {
            let g = BoxGrid::new(24, 40, 24);
            let m = grid_mesh(g, |q| s.map(q));
            m.validate("shape").unwrap();
            assert_eq!(boundary_edges(&m), 0, "{s:?}");
            assert_eq!(degenerate_triangles(&m), 0, "{s:?}");
            let v = signed_volume(&m);
            assert!(v > 0.0, "{s:?}: volume {v}");
            if *volume > 0.0 {
                assert!(
                    (v / volume - 1.0).abs() < 0.03,
                    "{s:?}: volume {v}, expected {volume}"
                );
            }
        }
    }
}
