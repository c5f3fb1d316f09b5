//! `statue`: the stand-in for the scanned statues (Lucy, St. Matthew).
//!
//! One closed surface, star-shaped about its centre: a cube-sphere grid
//! (shared edge vertices, so closed) is pushed onto an upright ellipsoid
//! and then displaced along the rays from the centre by
//! - smooth lobes: head, shoulders, a raised arm, a lowered arm and hand,
//!   two wings swept up and back, a knee, with a pinched neck and waist
//!   and a groove between the legs;
//! - drapery folds (sinusoidal ridges around the body that sway with
//!   height, strongest on the lower robe), and a robe that flares into
//!   a flat base resting on `y = 0`;
//! - fine value-noise detail whose octaves go down to a few cells of the
//!   grid, with amplitude proportional to wavelength, so that the surface
//!   stays visibly detailed at any resolution.
//!
//! Y is up; the figure faces +z and is about 2.1 units tall, 1 wide.
//! Because every vertex moves along its own ray and the radius stays
//! positive, the surface cannot intersect itself, and the grid's outward
//! counter-clockwise winding is kept.

use std::f32::consts::PI;

use glam::Vec3;

use super::grid::BoxGrid;
use super::noise::Fbm;
use super::rng::Rng;
use super::parts::{Part, choose_grid};
use super::shapes::{Shape, warp};

/// A smooth bump `amp · exp(−|(e − centre) ⊙ inv|²)` on the ellipsoid.
#[derive(Clone, Debug)]
struct Lobe {
    centre: Vec3,
    inv: Vec3,
    amp: f32,
}

/// The statue's radius function (see the module docs).
#[derive(Clone, Debug)]
pub(crate) struct Statue {
    /// Semi-axes of the base ellipsoid.
    axes: Vec3,
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

/// Semi-axes of the base ellipsoid.
const AXES: Vec3 = Vec3::new(0.34, 1.05, 0.26);

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

impl Statue {
    fn new(seed: u64, grid: BoxGrid) -> Self {
        let mut rng = Rng::new(seed, 0x57A7);
        let mut lobe = |c: [f32; 3], sigma: [f32; 3], amp: f32| {
            let centre = Vec3::from(c) + Vec3::new(rng.jitter(0.02), rng.jitter(0.02), rng.jitter(0.015));
            let inv = Vec3::from(sigma.map(|s| if s > 0.0 { 1.0 / s } else { 0.0 }));
            let inv = inv * rng.range(0.9, 1.1);
            Lobe {
                centre,
                inv,
                amp: amp * rng.range(0.85, 1.15),
            }
        };
        let lobes = vec![
            // Head, neck, shoulders.
            lobe([0.0, 0.98, 0.04], [0.10, 0.12, 0.10], 0.14),
            lobe([0.0, 0.74, 0.0], [0.0, 0.06, 0.0], -0.05),
            lobe([0.26, 0.58, 0.0], [0.12, 0.08, 0.12], 0.09),
            lobe([-0.26, 0.58, 0.0], [0.12, 0.08, 0.12], 0.09),
            // Raised right arm holding a torch.
            lobe([0.27, 0.66, 0.03], [0.06, 0.06, 0.06], 0.55),
            // Lowered left arm and the hand gathering the robe.
            lobe([-0.33, 0.15, 0.08], [0.06, 0.25, 0.06], 0.08),
            lobe([-0.2, -0.05, 0.2], [0.07, 0.07, 0.07], 0.12),
            // Wings swept up and back.
            lobe([0.16, 0.45, -0.22], [0.10, 0.22, 0.08], 0.28),
            lobe([-0.16, 0.45, -0.22], [0.10, 0.22, 0.08], 0.28),
            // Waist, knee, and the groove between the legs.
            lobe([0.0, 0.15, 0.0], [0.0, 0.12, 0.0], -0.03),
            lobe([0.1, -0.38, 0.2], [0.08, 0.10, 0.08], 0.06),
            lobe([0.0, -0.6, 0.22], [0.03, 0.3, 0.1], -0.03),
        ];
        // Detail octaves down to about four cells per wavelength.
        let cell = std::f32::consts::FRAC_PI_2 * AXES.y / grid.ny as f32;
        let freq = 3.0;
        let finest = 1.0 / (4.0 * cell);
        let octaves = ((finest / freq).log2().floor() as i32 + 1).clamp(1, 10) as u32;
        Statue {
            axes: AXES,
            centre: Vec3::new(0.0, 0.95, 0.0),
            floor: 0.0,
            lobes,
            detail: Fbm {
                seed: rng.next_u32(),
                octaves,
                freq,
                amp: 0.022,
                lacunarity: 2.0,
                gain: 0.5,
            },
            folds: (14 + rng.below(5)) as f32,
            fold_phase: rng.range(0.0, 2.0 * PI),
        }
    }

    /// Grid axis lengths (as for an ellipsoid).
    pub(crate) fn lens(&self) -> Vec3 {
        lens()
    }

    /// Maps a point of the cube's surface to the statue's surface.
    #[inline]
    pub(crate) fn map(&self, q: Vec3) -> Vec3 {
        let e = warp(q).normalize() * self.axes;
        let r0 = e.length();
        let dir = e / r0;
        let mut d = 0.0;
        for l in &self.lobes {
            let t = (e - l.centre) * l.inv;
            d += l.amp * (-t.length_squared()).exp();
        }
        let y = e.y / self.axes.y;
        let side = 1.0 - dir.y * dir.y;
        // Folds: ridges around the body, swaying with height.
        let theta = e.z.atan2(e.x);
        let sway = 3.0 * y + 1.3 * (5.0 * y + self.fold_phase).sin();
        let fold_amp = (0.006 + 0.016 * smoothstep(0.3, -0.6, y)) * side;
        d += fold_amp * (self.folds * theta + sway).sin();
        // The robe flares towards the base.
        d += 0.10 * smoothstep(-0.35, -0.95, y) * side;
        d += self.detail.sample(e);
        let mut r = (r0 + d).max(0.3 * r0);
        if dir.y < 0.0 {
            r = smin(r, (self.centre.y - self.floor) / -dir.y, 0.03);
        }
        self.centre + dir * r
    }
}

fn lens() -> Vec3 {
    AXES * std::f32::consts::FRAC_PI_2
}

/// The statue's grid for `tris` triangles.
pub(crate) fn grid(tris: usize) -> BoxGrid {
    choose_grid(lens(), tris as f64, 3)
}

/// The statue as a one-part scene.
pub(crate) fn plan(tris: usize, seed: u64) -> (Vec<Part>, Vec<BoxGrid>) {
    let g = grid(tris);
    let statue = Statue::new(seed, g);
    (vec![Part::at(Shape::Statue(Box::new(statue)), Vec3::ZERO)], vec![g])
}
