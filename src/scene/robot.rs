//! `robot`: a small articulated humanoid standing in for the Hubo robot.
//!
//! Boxes (feet, pelvis, torso, backpack, hands), spheres (joints, head),
//! capsules (limbs) and cylinders (waist, neck, eye cameras), posed by
//! seeded joint angles: hip and knee pitch, shoulder swing and abduction,
//! elbow bend, head yaw. About 1.4 units tall, facing +z, with the lower
//! foot's sole at `y = 0`.
//!
//! Every part is a separate closed, outward-oriented component; parts
//! overlap at the joints, so the union is not manifold.

use glam::{Mat3, Quat, Vec3};

use super::grid::BoxGrid;
use super::parts::{Part, plan as plan_parts};
use super::rng::Rng;
use super::shapes::Shape;

fn ball(r: f32, pos: Vec3) -> Part {
    Part::at(
        Shape::Ellipsoid {
            radii: Vec3::splat(r),
        },
        pos,
    )
}

fn limb(a: Vec3, b: Vec3, radius: f32) -> Part {
    Part::between(a, b, |half_len| Shape::Capsule { radius, half_len })
}

/// A box whose local +y is turned onto `up`.
fn block(half: Vec3, up: Vec3, pos: Vec3) -> Part {
    let rot = Mat3::from_quat(Quat::from_rotation_arc(Vec3::Y, up.normalize()));
    Part::new(Shape::Box { half }, rot, pos)
}

/// `-y` pitched by `pitch` about x (positive swings forward, towards +z)
/// and then rolled by `roll` about z.
fn down(pitch: f32, roll: f32) -> Vec3 {
    Mat3::from_rotation_z(roll) * Mat3::from_rotation_x(-pitch) * Vec3::NEG_Y
}

/// The robot's parts for `seed`.
pub(crate) fn parts(seed: u64) -> Vec<Part> {
    let mut rng = Rng::new(seed, 0x80B);
    let mut parts = Vec::new();
    let mut lowest = f32::INFINITY;
    // Legs.
    for side in [-1.0f32, 1.0] {
        let hip = Vec3::new(0.1 * side, 0.68, 0.0);
        let pitch = rng.jitter(0.3);
        let knee_bend = rng.range(0.0, 0.4);
        let knee = hip + 0.3 * down(pitch, 0.0);
        let ankle = knee + 0.29 * down(pitch - knee_bend, 0.0);
        parts.push(ball(0.075, hip));
        parts.push(limb(hip, knee, 0.07));
        parts.push(ball(0.065, knee));
        parts.push(limb(knee, ankle, 0.055));
        parts.push(ball(0.045, ankle));
        let foot = ankle + Vec3::new(0.0, -0.05, 0.04);
        parts.push(Part::at(
            Shape::Box {
                half: Vec3::new(0.06, 0.03, 0.11),
            },
            foot,
        ));
        lowest = lowest.min(foot.y - 0.03);
    }
    // Body.
    parts.push(Part::at(
        Shape::Box {
            half: Vec3::new(0.16, 0.07, 0.1),
        },
        Vec3::new(0.0, 0.72, 0.0),
    ));
    parts.push(Part::at(
        Shape::Cylinder {
            radius: 0.09,
            half_len: 0.07,
        },
        Vec3::new(0.0, 0.83, 0.0),
    ));
    parts.push(Part::at(
        Shape::Box {
            half: Vec3::new(0.19, 0.17, 0.12),
        },
        Vec3::new(0.0, 1.03, 0.0),
    ));
    parts.push(Part::at(
        Shape::Box {
            half: Vec3::new(0.14, 0.12, 0.05),
        },
        Vec3::new(0.0, 1.02, -0.16),
    ));
    // Arms.
    for side in [-1.0f32, 1.0] {
        let shoulder = Vec3::new(0.26 * side, 1.14, 0.0);
        let swing = rng.jitter(0.6);
        let abduct = side * rng.range(0.05, 0.35);
        let bend = rng.range(0.2, 1.2);
        let elbow = shoulder + 0.22 * down(swing, abduct);
        let fore = down(swing + bend, abduct);
        let wrist = elbow + 0.2 * fore;
        parts.push(ball(0.07, shoulder));
        parts.push(limb(shoulder, elbow, 0.05));
        parts.push(ball(0.055, elbow));
        parts.push(limb(elbow, wrist, 0.045));
        parts.push(block(
            Vec3::new(0.03, 0.06, 0.045),
            -fore,
            wrist + 0.06 * fore,
        ));
    }
    // Neck and head, turned by a seeded yaw.
    parts.push(Part::at(
        Shape::Cylinder {
            radius: 0.04,
            half_len: 0.05,
        },
        Vec3::new(0.0, 1.23, 0.0),
    ));
    let head = Vec3::new(0.0, 1.34, 0.0);
    let yaw = Mat3::from_rotation_y(rng.jitter(0.5));
    parts.push(Part::new(
        Shape::Ellipsoid {
            radii: Vec3::new(0.11, 0.1, 0.1),
        },
        yaw,
        head,
    ));
    for side in [-1.0f32, 1.0] {
        let a = head + yaw * Vec3::new(0.045 * side, 0.01, 0.07);
        let b = head + yaw * Vec3::new(0.045 * side, 0.01, 0.12);
        parts.push(Part::between(a, b, |half_len| Shape::Cylinder {
            radius: 0.022,
            half_len,
        }));
    }
    for p in &mut parts {
        p.pos.y -= lowest;
    }
    parts
}

/// The robot at `tris` triangles.
pub(crate) fn plan(tris: usize, seed: u64) -> (Vec<Part>, Vec<BoxGrid>) {
    let parts = parts(seed);
    let grids = plan_parts(&parts, tris);
    (parts, grids)
}
