//! `plant`: a power-plant-like CAD scene for the robot to fall into.
//!
//! A floor slab (8.4 × 6.4 units, top at `y = 0.2`) carries a 5 × 4 grid of
//! bays, each holding one seeded item with empty space around it: a
//! vertical tank with a domed roof, a spherical tank on a skirt, a
//! building with a roof unit, a horizontal tank (capsule) on saddles, a
//! chimney stack on a plinth, or a pump with a pipe that rises, bends
//! through an elbow and runs sideways. Two pipe racks (posts, a beam and
//! three long pipes each) run along x between the rows, and a pipe
//! bridge runs along z.
//!
//! Every part (boxes, capped cylinders, capsules, spheres, elbows with
//! flat ends) is a separate closed, outward-oriented component; parts
//! that touch overlap, so the union is not manifold.

use std::f32::consts::{FRAC_PI_2, PI};

use glam::{Mat3, Vec3};

use super::grid::BoxGrid;
use super::parts::{Part, plan as plan_parts};
use super::rng::Rng;
use super::shapes::Shape;

/// Top of the floor slab.
const FLOOR: f32 = 0.2;

fn cube(half: [f32; 3], pos: [f32; 3]) -> Part {
    Part::at(Shape::Box { half: half.into() }, pos.into())
}

fn pipe(a: Vec3, b: Vec3, radius: f32) -> Part {
    Part::between(a, b, |half_len| Shape::Cylinder { radius, half_len })
}

/// Items of one bay centred at `(x, z)`.
fn bay(rng: &mut Rng, x: f32, z: f32, parts: &mut Vec<Part>) {
    let f = FLOOR;
    match rng.below(6) {
        0 => {
            let (r, h) = (rng.range(0.35, 0.5), rng.range(0.35, 0.8));
            parts.push(Part::at(
                Shape::Cylinder {
                    radius: r,
                    half_len: h,
                },
                Vec3::new(x, f + h, z),
            ));
            parts.push(Part::at(
                Shape::Ellipsoid {
                    radii: Vec3::new(r, 0.4 * r, r),
                },
                Vec3::new(x, f + 2.0 * h, z),
            ));
        }
        1 => {
            let r = rng.range(0.4, 0.55);
            parts.push(Part::at(
                Shape::Cylinder {
                    radius: 0.6 * r,
                    half_len: 0.25,
                },
                Vec3::new(x, f + 0.25, z),
            ));
            parts.push(Part::at(
                Shape::Ellipsoid {
                    radii: Vec3::splat(r),
                },
                Vec3::new(x, f + 0.4 + r, z),
            ));
        }
        2 => {
            let h = rng.range(0.3, 0.7);
            parts.push(cube([0.55, h, 0.5], [x, f + h, z]));
            parts.push(cube(
                [0.2, 0.08, 0.15],
                [
                    x + rng.jitter(0.25),
                    f + 2.0 * h + 0.08,
                    z + rng.jitter(0.2),
                ],
            ));
        }
        3 => {
            let (r, l) = (rng.range(0.25, 0.35), rng.range(0.3, 0.45));
            let along_x = rng.below(2) == 0;
            let rot = if along_x {
                Mat3::from_rotation_z(FRAC_PI_2)
            } else {
                Mat3::from_rotation_x(FRAC_PI_2)
            };
            let y = f + 0.12 + r;
            parts.push(Part::new(
                Shape::Capsule {
                    radius: r,
                    half_len: l,
                },
                rot,
                Vec3::new(x, y, z),
            ));
            for s in [-1.0, 1.0] {
                let o = s * 0.7 * l;
                let (dx, dz) = if along_x { (o, 0.0) } else { (0.0, o) };
                let half = if along_x {
                    [0.06, 0.1, 0.8 * r]
                } else {
                    [0.8 * r, 0.1, 0.06]
                };
                parts.push(cube(half, [x + dx, f + 0.1, z + dz]));
            }
        }
        4 => {
            let h = rng.range(0.8, 1.2);
            parts.push(cube([0.3, 0.1, 0.3], [x, f + 0.1, z]));
            parts.push(Part::at(
                Shape::Cylinder {
                    radius: 0.14,
                    half_len: h,
                },
                Vec3::new(x, f + 0.2 + h, z),
            ));
        }
        _ => {
            parts.push(cube([0.25, 0.15, 0.2], [x, f + 0.15, z]));
            let (r, bend) = (0.07, 0.2);
            let top = f + rng.range(0.7, 1.1);
            let x0 = x + 0.1;
            parts.push(pipe(Vec3::new(x0, f + 0.3, z), Vec3::new(x0, top, z), r));
            // The elbow turns +y into +x; rotate it about y to aim elsewhere.
            let yaw = PI * 0.5 * rng.below(4) as f32;
            let rot = Mat3::from_rotation_y(yaw);
            parts.push(Part::new(
                Shape::Elbow {
                    radius: r,
                    bend,
                    angle: FRAC_PI_2,
                },
                rot,
                Vec3::new(x0, top, z),
            ));
            let start = Vec3::new(x0, top, z) + rot * Vec3::new(bend, bend, 0.0);
            parts.push(pipe(start, start + rot * Vec3::new(0.5, 0.0, 0.0), r));
        }
    }
}

/// The plant's parts for `seed`.
pub(crate) fn parts(seed: u64) -> Vec<Part> {
    let mut rng = Rng::new(seed, 0x91A);
    let mut parts = vec![cube([4.2, 0.1, 3.2], [0.0, 0.1, 0.0])];
    for j in 0..4 {
        for i in 0..5 {
            let x = -3.2 + 1.6 * i as f32 + rng.jitter(0.1);
            let z = -2.4 + 1.6 * j as f32 + rng.jitter(0.1);
            bay(&mut rng, x, z, &mut parts);
        }
    }
    // Pipe racks along x between the rows.
    for z in [-1.6, 1.6] {
        let y = 1.5 + rng.jitter(0.1);
        for x in [-3.9, 0.0, 3.9] {
            parts.push(cube(
                [0.05, 0.5 * (y - FLOOR), 0.05],
                [x, 0.5 * (y + FLOOR), z],
            ));
        }
        parts.push(cube([4.0, 0.04, 0.18], [0.0, y + 0.04, z]));
        for (dz, r) in [(-0.1, 0.05), (0.0, 0.04), (0.1, 0.06)] {
            let yy = y + 0.08 + r;
            parts.push(pipe(
                Vec3::new(-4.1, yy, z + dz),
                Vec3::new(4.1, yy, z + dz),
                r,
            ));
        }
    }
    // A pipe bridge along z over the middle.
    let y = 2.0;
    for z in [-3.0, 3.0] {
        parts.push(cube(
            [0.06, 0.5 * (y - FLOOR), 0.06],
            [0.8, 0.5 * (y + FLOOR), z],
        ));
    }
    parts.push(pipe(
        Vec3::new(0.8, y + 0.1, -3.1),
        Vec3::new(0.8, y + 0.1, 3.1),
        0.09,
    ));
    parts
}

/// The plant at `tris` triangles.
pub(crate) fn plan(tris: usize, seed: u64) -> (Vec<Part>, Vec<BoxGrid>) {
    let parts = parts(seed);
    let grids = plan_parts(&parts, tris);
    (parts, grids)
}
