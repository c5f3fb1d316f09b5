//! Every pair the cbvh dispatcher answers natively — cbvh vs cbvh, cbvh vs a
//! convex shape (ball, cuboid, convex polyhedron), cbvh vs parry `TriMesh` —
//! in both orders, against parry's own answer (`DefaultQueryDispatcher`) for
//! the same geometry with each cbvh shape replaced by a parry `TriMesh` of
//! the same mesh: contact manifolds, contact, intersection test, distance
//! and closest points. The per-pair mode gives parry's convex-convex code
//! cbvh's normal constraints (oriented axes, active-edge cones), so its
//! manifolds are compared with parry's under the same constraints (see
//! `pairs::check_manifolds`).
//!
//! Each geometry is queried as `(a, b, pos12)` and flipped, as
//! `(b, a, pos12⁻¹)`, with rotated and translated poses: a path that uses
//! `pos12` where it needs its inverse (or the other way round) finds the
//! wrong triangles in one of the two orders.

use crate::pairs;

use cbvh::Mesh;
use cbvh::scene::{Kind, generate};
use pairs::*;
use parry3d::math::{Pose, Vector};
use parry3d::shape::{Ball, ConvexPolyhedron, Cuboid, Shape};

/// A rotation by `angle` about a fixed, skewed axis, as a scaled axis.
fn turn(angle: f32) -> Vector {
    Vector::new(0.3, 0.8, -0.5).normalize() * angle
}

/// Poses of a convex shape of radius `r` around the model's surface
/// points: sunk into the surface, just off it (within `prediction`), and
/// further off (beyond it), each rotated.
fn convex_poses(m: &Model, r: f32, prediction: f32) -> Vec<Pose> {
    let mut poses = Vec::new();
    for (k, &(p, n)) in m.surface.iter().enumerate() {
        let offset = [-0.4 * r, r + 0.5 * prediction, r + 3.0 * prediction][k % 3];
        poses.push(Pose::new(p + n * offset, turn(0.7 + k as f32)));
    }
    poses
}

/// The statue and the convex shapes (ball, cuboid, convex polyhedron) of
/// radius `r`; the cases' prediction is a fifth of `r`.
struct ConvexScene {
    statue: Model,
    r: f32,
    ball: Ball,
    cuboid: Cuboid,
    polyhedron: ConvexPolyhedron,
}

impl ConvexScene {
    fn new() -> Self {
        let statue = Model::new(Kind::Statue, 1200, 3);
        let r = 0.04 * statue.size;
        let hull: Vec<Vector> = (0..12)
            .map(|k| {
                let a = k as f32 * 2.4;
                Vector::new(a.cos(), (k as f32 / 5.5) - 1.0, a.sin()) * r
            })
            .collect();
        Self {
            r,
            ball: Ball::new(r),
            cuboid: Cuboid::new(Vector::new(r, 0.6 * r, 0.8 * r)),
            polyhedron: ConvexPolyhedron::from_convex_hull(&hull).unwrap(),
            statue,
        }
    }

    fn convexes(&self) -> [&dyn Shape; 3] {
        [&self.ball, &self.cuboid, &self.polyhedron]
    }

    /// The statue against `convex` at the poses of [`convex_poses`].
    fn cases<'a>(&'a self, convex: &'a dyn Shape) -> Vec<Case<'a>> {
        let prediction = 0.2 * self.r;
        convex_poses(&self.statue, self.r, prediction)
            .into_iter()
            .map(|pos12| Case {
                s1: Side::Cbvh(&self.statue),
                s2: Side::Convex(convex),
                pos12,
                prediction,
                scale: self.statue.size,
            })
            .collect()
    }
}

#[test]
fn cbvh_vs_convex_in_both_orders_equals_parry() {
    let scene = ConvexScene::new();
    for convex in scene.convexes() {
        let tallies = check_both_orders(&scene.cases(convex), true);
        let name = Side::Convex(convex).name();
        for (order, t) in ["cbvh first", "cbvh second"].iter().zip(&tallies) {
            assert!(
                t.manifold_pairs > 0 && t.contacts > 0 && t.intersecting > 0,
                "{name}, {order}: the poses must touch: {t:?}"
            );
            assert!(
                t.within_margin > 0 && t.disjoint > 0,
                "{name}, {order}: some poses must be apart: {t:?}"
            );
        }
    }
}

/// Poses of `b` against `a`: `b`'s centre on a surface point of `a`
/// (overlapping), and `b` beside `a` with a gap, each rotated.
fn mesh_poses(a: &Model, b: &Model) -> Vec<Pose> {
    let bc = {
        let bb = b.parry.local_aabb();
        (bb.mins + bb.maxs) * 0.5
    };
    let ab = a.parry.local_aabb();
    let mut poses = Vec::new();
    for (k, &(p, _)) in a.surface.iter().enumerate().take(3) {
        let rot = Pose::new(Vector::ZERO, turn(0.5 + 1.3 * k as f32));
        let centre = rot.transform_point(bc);
        poses.push(Pose::new(p - centre, turn(0.5 + 1.3 * k as f32)));
    }
    // Beside `a` along x, rotated, with a gap of 2 % of the size.
    let rot = Pose::new(Vector::ZERO, turn(2.0));
    let moved = b.parry.aabb(&rot);
    let shift = Vector::new(ab.maxs.x - moved.mins.x + 0.02 * a.size, 0.1, -0.05);
    poses.push(Pose::new(shift, turn(2.0)));
    poses
}

/// Poses of a small `b` at `a`'s surface points, alternately half sunk
/// and just clear of the surface, each rotated. `b` is far from `a`'s
/// origin there, so a path that places it by `pos12` where it needs the
/// inverse looks for it somewhere else entirely.
fn surface_poses(a: &Model, b: &Model) -> Vec<Pose> {
    let bb = b.parry.local_aabb();
    let (bc, r) = ((bb.mins + bb.maxs) * 0.5, 0.5 * b.size);
    a.surface
        .iter()
        .enumerate()
        .map(|(k, &(p, n))| {
            let axis = turn(1.1 + 0.9 * k as f32);
            let centre = Pose::new(Vector::ZERO, axis).transform_point(bc);
            let lift = if k % 2 == 0 { 0.0 } else { r + 0.02 * a.size };
            Pose::new(p + n * lift - centre, axis)
        })
        .collect()
}

/// The statue, the robot, and the robot at a fifth of its size: meshes for
/// the mesh-mesh pairs.
fn statue_and_robots() -> (Model, Model, Model) {
    let robot = generate(Kind::Robot, 1000, 5, &mut |_, _| {}).unwrap();
    let small = Mesh::new(
        robot.vertices.iter().map(|v| v.map(|x| 0.2 * x)).collect(),
        robot.triangles.clone(),
    );
    (
        Model::new(Kind::Statue, 1000, 3),
        Model::of(&robot),
        Model::of(&small),
    )
}

/// The statue against the robot (poses of [`mesh_poses`]) and the small
/// robot (poses of [`surface_poses`]), the robots as cbvh shapes or as
/// parry `TriMesh`es.
fn mesh_cases<'a>(a: &'a Model, b: &'a Model, small: &'a Model, cbvh: bool) -> Vec<Case<'a>> {
    let side = |m| {
        if cbvh {
            Side::Cbvh(m)
        } else {
            Side::TriMesh(m)
        }
    };
    let poses = mesh_poses(a, b).into_iter().map(|p| (b, p));
    let small_poses = surface_poses(a, small).into_iter().map(|p| (small, p));
    poses
        .chain(small_poses)
        .map(|(b, pos12)| Case {
            s1: Side::Cbvh(a),
            s2: side(b),
            pos12,
            prediction: 0.01 * a.size,
            scale: a.size,
        })
        .collect()
}

/// cbvh vs cbvh: contact points within the prediction, as rapier uses
/// them (see the next test for the points beyond it).
#[test]
fn cbvh_vs_cbvh_in_both_orders_equals_parry() {
    let (a, b, small) = statue_and_robots();
    let tallies = check_both_orders(&mesh_cases(&a, &b, &small, true), false);
    for (order, t) in ["statue first", "robot first"].iter().zip(tallies) {
        assert!(
            t.manifold_pairs > 0 && t.contacts > 0 && t.intersecting > 0 && t.within_margin > 0,
            "{order}: {t:?}"
        );
    }
}

/// parry's GJK sometimes gives a triangle pair a manifold whose points all
/// lie beyond the prediction. cbvh's per-pair mode no longer culls pairs
/// with a face-plane test, but parry's own two-tree traversal bounds each
/// node's box after the transform more loosely than cbvh's triangle boxes,
/// so it still reaches some pairs that cbvh's traversal (boxes within the
/// prediction) does not; all their points lie beyond the prediction, which
/// rapier's solver ignores.
#[test]
#[ignore = "parry's looser transformed boxes reach pairs beyond the prediction that cbvh's traversal skips (e.g. statue 596 / robot 790, all points beyond 0.018)"]
fn cbvh_vs_cbvh_manifolds_equal_parry_beyond_the_prediction() {
    let (a, b, small) = statue_and_robots();
    check_both_orders(&mesh_cases(&a, &b, &small, true), true);
}

#[test]
fn cbvh_vs_trimesh_in_both_orders_equals_parry() {
    let (a, b, small) = statue_and_robots();
    let tallies = check_both_orders(&mesh_cases(&a, &b, &small, false), true);
    for (order, t) in ["cbvh first", "cbvh second"].iter().zip(tallies) {
        assert!(
            t.manifold_pairs > 0 && t.contacts > 0 && t.intersecting > 0 && t.within_margin > 0,
            "{order}: {t:?}"
        );
    }
}

#[test]
fn intersection_tests_name_intersecting_parts() {
    let scene = ConvexScene::new();
    let (a, b, small) = statue_and_robots();
    let mut cases = mesh_cases(&a, &b, &small, true);
    for convex in scene.convexes() {
        cases.extend(scene.cases(convex));
    }
    let checked: usize = both_orders(&cases)
        .map(|c| check_intersection_parts(&c))
        .sum();
    assert!(checked >= 20, "only {checked} intersections");
}

/// parry's `TriMesh` names its triangle; cbvh's intersection test with a
/// `TriMesh` (`cbvh_convex::intersection_test`) keeps only its own side's.
#[test]
fn intersection_tests_with_a_trimesh_name_its_triangle() {
    let (a, b, small) = statue_and_robots();
    let cases = mesh_cases(&a, &b, &small, false);
    let checked: usize = both_orders(&cases)
        .map(|c| check_intersection_parts(&c))
        .sum();
    assert!(checked >= 5, "only {checked} intersections");
}

/// parry's `TriMesh` contact names the triangles it is on
/// (`Contact::subshape1`, `subshape2`); cbvh's contact queries
/// (`cbvh_convex::contact`, `cbvh_cbvh::contact`) leave both at 0.
#[test]
fn contacts_name_their_parts() {
    let scene = ConvexScene::new();
    let (a, b, small) = statue_and_robots();
    let mut cases = mesh_cases(&a, &b, &small, true);
    cases.extend(mesh_cases(&a, &b, &small, false));
    for convex in scene.convexes() {
        cases.extend(scene.cases(convex));
    }
    let checked: usize = both_orders(&cases).map(|c| check_contact_parts(&c)).sum();
    assert!(checked >= 20, "only {checked} contacts");
}

/// The drop test's pair at a small size: a 3 k-triangle statue sunk into a
/// 3 k-triangle turbine at four poses, cbvh against cbvh and against the
/// turbine as a parry `TriMesh`, in both orders. Some pairs parry reports
/// must be left without points by the constraints (back faces, internal
/// edges), or the comparison would not test them.
#[test]
fn statue_in_turbine_in_both_orders_equals_parry_with_the_same_constraints() {
    let statue = Model::new(Kind::Statue, 3000, 3);
    let turbine = Model::new(Kind::Turbine, 3000, 4);
    let poses = [
        Pose::from_translation(Vector::new(0.0, -1.2, 0.0)),
        Pose::from_translation(Vector::new(0.7, -0.9, 0.3)),
        Pose::new(Vector::new(-0.4, -1.0, 0.2), Vector::new(0.3, 0.8, -0.2)),
        Pose::new(Vector::new(0.2, -0.5, -0.6), Vector::new(-1.0, 0.1, 0.5)),
    ];
    for (name, s2) in [
        ("cbvh", Side::Cbvh(&turbine)),
        ("TriMesh", Side::TriMesh(&turbine)),
    ] {
        let cases: Vec<Case> = poses
            .iter()
            .map(|&pos12| Case {
                s1: Side::Cbvh(&statue),
                s2,
                pos12,
                prediction: 0.02,
                scale: statue.size,
            })
            .collect();
        let tallies = check_both_orders(&cases, false);
        for (order, t) in ["statue first", "turbine first"].iter().zip(&tallies) {
            println!("turbine as {name}, {order}: {t:?}");
            assert!(
                t.manifold_pairs > 50 && t.intersecting > 0 && t.constrained_away > 0,
                "turbine as {name}, {order}: {t:?}"
            );
        }
    }
}
