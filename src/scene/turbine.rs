//! `turbine`: the stand-in for the CAD turbine model.
//!
//! A rotor with its axis along +y: a shaft, a back disc, a hub with a nose
//! cone, and 16 to 20 blades (the count depends on the seed). Each blade
//! is a thin, cambered, tapered slab twisted from root to tip, with sharp
//! leading and trailing edges; the hub and disc are capped cylinders with
//! sharp rims. The blades lie roughly in the xz plane, tips at radius 2
//! (about 4 units across); the shaft's bottom is at `y = 0`.
//!
//! Every part is a separate closed, outward-oriented component; parts
//! overlap where they join, so the union is not manifold.

use std::f32::consts::TAU;

use glam::{Mat3, Vec3};

use super::grid::BoxGrid;
use super::parts::{Part, plan as plan_parts};
use super::rng::Rng;
use super::shapes::{Blade, Shape};

/// The turbine's parts for `seed`.
pub(crate) fn parts(seed: u64) -> Vec<Part> {
    let mut rng = Rng::new(seed, 0x7B);
    let blades = 16 + rng.below(5);
    let hub_y = 1.02;
    let mut parts = vec![
        Part::at(
            Shape::Cylinder {
                radius: 0.16,
                half_len: 0.4,
            },
            Vec3::new(0.0, 0.4, 0.0),
        ),
        Part::at(
            Shape::Cylinder {
                radius: 0.8,
                half_len: 0.05,
            },
            Vec3::new(0.0, 0.78, 0.0),
        ),
        Part::at(
            Shape::Cylinder {
                radius: 0.55,
                half_len: 0.22,
            },
            Vec3::new(0.0, hub_y, 0.0),
        ),
        Part::at(
            Shape::Ellipsoid {
                radii: Vec3::new(0.45, 0.32, 0.45),
            },
            Vec3::new(0.0, hub_y + 0.22, 0.0),
        ),
    ];
    let blade = Blade {
        r0: 0.45,
        r1: 2.0,
        chord: (0.55, 0.30),
        thick: (0.07, 0.025),
        pitch: (rng.range(0.9, 1.0), rng.range(0.3, 0.4)),
        camber: 0.05,
        sweep: 0.12,
    };
    let phase = rng.range(0.0, TAU);
    for k in 0..blades {
        let angle = phase + TAU * k as f32 / blades as f32;
        parts.push(Part::new(
            Shape::Blade(blade.clone()),
            Mat3::from_rotation_y(angle),
            Vec3::new(0.0, hub_y, 0.0),
        ));
    }
    parts
}

/// The turbine at `tris` triangles.
pub(crate) fn plan(tris: usize, seed: u64) -> (Vec<Part>, Vec<BoxGrid>) {
    let parts = parts(seed);
    let grids = plan_parts(&parts, tris);
    (parts, grids)
}
