//! `statue`: the stand-in for the scanned statues (Lucy, St. Matthew).
//!
//! One closed surface, star-shaped about its centre: a cube-sphere grid
//! (equal-angle warp; shared edge vertices, so closed) is pushed onto an
//! upright rounded column (a superellipsoid of exponent 4: flat shoulders,
//! flat base) and then displaced along the rays from the centre by
//! - a body profile: shoulders, a narrow waist, hips, and a robe that
//!   flares into a flat base resting on `y = 0`;
//! - smooth lobes: a flat-topped head, a raised arm (Lucy's torch arm),
//!   a lowered arm and hand, two wings swept out and back from the
//!   shoulder blades, breast, knee, and a groove between the legs;
//! - drapery folds (sinusoidal ridges around the body that sway with
//!   height, strongest on the lower robe);
//! - fine value-noise detail whose octaves go down to a few cells of the
//!   grid, with amplitude proportional to wavelength, so that the surface
//!   stays visibly detailed at any resolution.
//!
//! Y is up; the figure faces +z and is about 2 units tall, 0.75 wide.
//! Because every vertex moves along its own ray and the radius stays
//! positive, the surface cannot intersect itself (each triangle stays in
//! the cone of its three rays, and the cones do not overlap), and the
//! grid's outward counter-clockwise winding is kept. The seed jitters the
//! lobes (position, size, height), the number and phase of the folds, and
//! the detail noise.
//!
//! The grid has `nx : ny : nz` close to the column's proportions, so cells
//! are nearly square; the three counts are searched near the ideal so
//! that `4(nx·ny + ny·nz + nz·nx)` is within a fraction of a percent of
//! the request. Vertices number `T/2 + 2`.

use std::f32::consts::PI;

use glam::Vec3;

use super::grid::BoxGrid;
use super::noise::Fbm;
use super::parts::{Part, choose_grid};
use super::rng::Rng;
use super::shapes::{Shape, warp};

/// A smooth bump `amp · exp(−|(e − centre) ⊙ inv|^(2·order))` on the base
/// surface (order 2 gives a flat-topped bump).
#[derive(Clone, Debug)]
struct Lobe {
    centre: Vec3,
    inv: Vec3,
    amp: f32,
    flat: bool,
}

/// The statue's radius function (see the module docs).
#[derive(Clone, Debug)]
pub(crate) struct Statue {
    /// Centre of the rays.
    centre: Vec3,
    /// Height of the flat base.
    floor: f32,
    lobes: Vec<Lobe>,
    detail: Fbm,
    /// Number of folds around the body (an integer, for continuity).
    folds: f32,
    fold_phase: f32,
}

/// Half extents of the base body: a rounded column (superellipsoid of
/// exponent 4).
const BODY: Vec3 = Vec3::new(0.30, 0.80, 0.21);

#[inline]
fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Polynomial smooth minimum with blend width `k`.
#[inline]
fn smin(a: f32, b: f32, k: f32) -> f32 {
    let h = (k - (a - b).abs()).max(0.0) / k;
    a.min(b) - h * h * k * 0.25
}

#[inline]
fn bell(x: f32, centre: f32, width: f32) -> f32 {
    let t = (x - centre) / width;
    (-t * t).exp()
}

impl Statue {
    fn new(seed: u64, grid: BoxGrid) -> Self {
        let mut rng = Rng::new(seed, 0x57A7);
        let mut lobe = |c: [f32; 3], sigma: [f32; 3], amp: f32, flat: bool| {
            let centre =
                Vec3::from(c) + Vec3::new(rng.jitter(0.02), rng.jitter(0.02), rng.jitter(0.015));
            let inv = Vec3::from(sigma.map(|s| if s > 0.0 { 1.0 / s } else { 0.0 }));
            let inv = inv * rng.range(0.9, 1.1);
            Lobe {
                centre,
                inv,
                amp: amp * rng.range(0.85, 1.15),
                flat,
            }
        };
        let (a, b, c) = (BODY.x, BODY.y, BODY.z);
        let lobes = vec![
            // Head, on the flat shoulder line.
            lobe([0.0, b, 0.03], [0.085, 0.2, 0.085], 0.27, true),
            // Raised right arm holding a torch, up and out from the shoulder.
            lobe([0.8 * a, 0.93 * b, 0.0], [0.05, 0.05, 0.06], 0.55, false),
            // Lowered left arm along the side, the hand gathering the robe.
            lobe([-a, 0.25 * b, 0.3 * c], [0.05, 0.22, 0.06], 0.06, false),
            lobe([-0.7 * a, -0.05 * b, c], [0.07, 0.06, 0.07], 0.10, false),
            // Wings swept up, out and back from the shoulder blades.
            lobe([0.75 * a, 0.6 * b, -c], [0.08, 0.2, 0.06], 0.38, false),
            lobe([-0.75 * a, 0.6 * b, -c], [0.08, 0.2, 0.06], 0.38, false),
            // Breast, knee and the groove between the legs.
            lobe([0.0, 0.55 * b, c], [0.12, 0.08, 0.1], 0.04, false),
            lobe([0.35 * a, -0.45 * b, c], [0.07, 0.1, 0.08], 0.05, false),
            lobe([0.0, -0.65 * b, c], [0.025, 0.3, 0.1], -0.035, false),
        ];
        // Detail octaves down to about four cells per wavelength.
        let cell = std::f32::consts::FRAC_PI_2 * BODY.y / grid.ny as f32;
        let freq = 3.0;
        let finest = 1.0 / (4.0 * cell);
        let octaves = ((finest / freq).log2().floor() as i32 + 1).clamp(1, 10) as u32;
        Statue {
            centre: Vec3::new(0.0, 0.81, 0.0),
            floor: 0.0,
            lobes,
            detail: Fbm {
                seed: rng.next_u32(),
                octaves,
                freq,
                amp: 0.018,
                lacunarity: 2.0,
                gain: 0.5,
            },
            folds: (14 + rng.below(5)) as f32,
            fold_phase: rng.range(0.0, 2.0 * PI),
        }
    }

    /// Grid axis lengths (as for an ellipsoid of the body's size).
    pub(crate) fn lens(&self) -> Vec3 {
        lens()
    }

    /// Maps a point of the cube's surface to the statue's surface.
    #[inline]
    pub(crate) fn map(&self, q: Vec3) -> Vec3 {
        let dir = warp(q).normalize();
        // The rounded column: |x/a|⁴ + |y/b|⁴ + |z/c|⁴ = 1 along the ray.
        let s = dir / BODY;
        let s2 = s * s;
        let r0 = 1.0 / (s2.dot(s2)).sqrt().sqrt();
        let e = dir * r0;
        let y = e.y / BODY.y;
        let side = 1.0 - dir.y * dir.y;
        // Body profile: shoulders, waist, hips and a robe flaring to the base.
        let profile = 0.08 * bell(y, 0.78, 0.12) - 0.18 * bell(y, 0.2, 0.22)
            + 0.05 * bell(y, -0.2, 0.2)
            + 0.22 * smoothstep(-0.45, -1.0, y);
        let mut d = r0 * profile * side;
        for l in &self.lobes {
            let t = ((e - l.centre) * l.inv).length_squared();
            d += l.amp * (-(if l.flat { t * t } else { t })).exp();
        }
        // Drapery folds: ridges around the body that sway with height,
        // strongest on the lower robe.
        let theta = e.z.atan2(e.x);
        let sway = 3.0 * y + 1.3 * (5.0 * y + self.fold_phase).sin();
        let fold_amp = (0.005 + 0.015 * smoothstep(0.3, -0.7, y)) * side;
        d += fold_amp * (self.folds * theta + sway).sin();
        d += self.detail.sample(e);
        let mut r = (r0 + d).max(0.3 * r0);
        if dir.y < 0.0 {
            r = smin(r, (self.centre.y - self.floor) / -dir.y, 0.03);
        }
        self.centre + dir * r
    }
}

fn lens() -> Vec3 {
    BODY * std::f32::consts::FRAC_PI_2
}

/// The statue's grid for `tris` triangles.
pub(crate) fn grid(tris: usize) -> BoxGrid {
    choose_grid(lens(), tris as f64, 3)
}

/// The statue as a one-part scene.
pub(crate) fn plan(tris: usize, seed: u64) -> (Vec<Part>, Vec<BoxGrid>) {
    let g = grid(tris);
    let statue = Statue::new(seed, g);
    (
        vec![Part::at(Shape::Statue(Box::new(statue)), Vec3::ZERO)],
        vec![g],
    )
}
