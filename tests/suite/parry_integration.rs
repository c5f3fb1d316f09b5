//! The parry / rapier integration: cbvh shapes give parry's contacts, rapier
//! steps them without the fallback, ray casts and balls behave.

use cbvh::Mesh;
use cbvh::build::BuildOptions;
use cbvh::codec::{AnyOptions, CodecKind};
use cbvh::parry::{CbvhShape, ContactMode, Dispatcher, parry_trimesh};
use cbvh::sim::droptest::{self, DropScene, Placement, RunSpec, ShapeKind};

/// The per-triangle-pair mode: parry's own contacts, pair by pair.
fn pairs() -> Dispatcher {
    Dispatcher::new(ContactMode::PerTrianglePair)
}
use cbvh::scene::{Kind, generate};
use parry3d::math::{Pose, Vector};
use parry3d::query::{
    ContactManifold, DefaultQueryDispatcher, PersistentQueryDispatcher, QueryDispatcher, Ray,
    RayCast,
};
use parry3d::shape::SharedShape;
use rapier3d::prelude::{ColliderBuilder, PhysicsWorld, QueryFilter, RigidBodyBuilder};

fn mesh_of(kind: Kind, tris: usize, seed: u64) -> Mesh {
    generate(kind, tris, seed, &mut |_, _| {}).expect("generate")
}

#[test]
fn manifolds_persist_between_calls() {
    let a = mesh_of(Kind::Statue, 2000, 1);
    let c = CbvhShape::plain(&a, &BuildOptions::default()).unwrap();
    let pos12 = Pose::from_translation(Vector::new(0.05, 0.02, 0.0));
    // Patches with the full prediction at every call: at an unchanged pose
    // the motion bound would shrink it, and fewer points would be asked for.
    let patches = Dispatcher::new(ContactMode::Patches(cbvh::contact::PatchOptions {
        motion_factor: None,
        ..Default::default()
    }));
    for d in [pairs(), patches] {
        let mut manifolds: Vec<ContactManifold<(), u32>> = Vec::new();
        let mut ws = None;
        d.contact_manifolds(&pos12, &c, &c, 0.01, &mut manifolds, &mut ws)
            .unwrap();
        assert!(!manifolds.is_empty());
        // Mark each contact, then update at the same pose: the data survives.
        for m in &mut manifolds {
            for p in &mut m.points {
                p.data = 7;
            }
        }
        d.contact_manifolds(&pos12, &c, &c, 0.01, &mut manifolds, &mut ws)
            .unwrap();
        let marked = manifolds
            .iter()
            .flat_map(|m| &m.points)
            .filter(|p| p.data == 7)
            .count();
        let all = manifolds.iter().map(|m| m.points.len()).sum::<usize>();
        // Patches carry every point's data (their ids are the pair and the
        // point); parry's per-pair manifolds carry those whose feature ids
        // repeat.
        let patches = d.mode != ContactMode::PerTrianglePair;
        assert!(
            all > 0 && (marked == all || !patches && marked > 0),
            "{:?}: warm-start data must be carried over ({marked} of {all})",
            d.mode
        );
    }
}

#[test]
fn intersection_and_contact_queries() {
    let a = mesh_of(Kind::Robot, 2000, 1);
    let c = CbvhShape::plain(&a, &BuildOptions::default()).unwrap();
    let t = SharedShape::new(parry_trimesh(&a).unwrap());
    let near = Pose::from_translation(Vector::new(0.01, 0.0, 0.0));
    let far = Pose::from_translation(Vector::new(100.0, 0.0, 0.0));
    let d = Dispatcher::default().chain(DefaultQueryDispatcher);
    assert!(d.intersection_test(&near, &c, &c).unwrap().intersecting);
    assert!(!d.intersection_test(&far, &c, &c).unwrap().intersecting);
    assert!(d.contact(&far, &c, &c, 0.1).unwrap().is_none());
    // Against a ball: same answer as parry's TriMesh.
    let ball = parry3d::shape::Ball::new(0.05);
    let (lo, hi) = a.bounds().unwrap();
    for k in 0..20 {
        let f = k as f32 / 19.0;
        let p = Vector::new(
            lo[0] + (hi[0] - lo[0]) * f,
            lo[1] + (hi[1] - lo[1]) * 0.5,
            0.5 * (lo[2] + hi[2]),
        );
        let pose = Pose::from_translation(p);
        let got = d.intersection_test(&pose, &c, &ball).unwrap().intersecting;
        let want = DefaultQueryDispatcher
            .intersection_test(&pose, t.as_ref(), &ball)
            .unwrap()
            .intersecting;
        assert_eq!(got, want, "ball at {p:?}");
    }
    assert!(!c.fallback_bvh_built());
}

#[test]
fn ray_casts_match_trimesh_directly_and_through_rapier() {
    let m = mesh_of(Kind::Statue, 2000, 9);
    let c = CbvhShape::plain(&m, &BuildOptions::default()).unwrap();
    let t = parry_trimesh(&m).unwrap();
    let mut world_c = PhysicsWorld::default();
    let mut world_t = PhysicsWorld::default();
    world_c
        .colliders
        .insert(ColliderBuilder::new(SharedShape::new(c.clone())));
    world_t
        .colliders
        .insert(ColliderBuilder::new(SharedShape::new(t.clone())));
    world_c.step();
    world_t.step();
    let mut hits = 0;
    for k in 0..64 {
        let a = k as f32 * 0.37;
        let origin = Vector::new(3.0 * a.cos(), 1.0 + 0.02 * k as f32, 3.0 * a.sin());
        let dir = (Vector::new(0.0, 1.0, 0.0) - origin).normalize();
        let ray = Ray::new(origin, dir);
        let want = t.cast_local_ray_and_get_normal(&ray, 100.0, true);
        let got = c.cast_local_ray_and_get_normal(&ray, 100.0, true);
        match (want, got) {
            (Some(w), Some(g)) => {
                hits += 1;
                assert!((w.time_of_impact - g.time_of_impact).abs() < 1e-5);
                assert!((w.normal - g.normal).length() < 1e-4);
                assert_eq!(w.feature, g.feature);
            }
            (None, None) => {}
            (w, g) => panic!("TriMesh {w:?} vs cbvh {g:?}"),
        }
        let wr = world_t
            .cast_ray(&ray, 100.0, true, QueryFilter::default())
            .map(|h| h.1);
        let gr = world_c
            .cast_ray(&ray, 100.0, true, QueryFilter::default())
            .map(|h| h.1);
        assert_eq!(wr.is_some(), gr.is_some());
        if let (Some(w), Some(g)) = (wr, gr) {
            assert!((w - g).abs() < 1e-5);
        }
    }
    assert!(hits > 10);
    assert!(!c.fallback_bvh_built());
}

#[test]
fn a_ball_comes_to_rest_on_a_cbvh_floor() {
    // A 2 x 2 floor of 8 triangles (two layers so that it is closed below).
    let floor = Mesh::new(
        vec![
            [-1.0, 0.0, -1.0],
            [1.0, 0.0, -1.0],
            [1.0, 0.0, 1.0],
            [-1.0, 0.0, 1.0],
            [-1.0, -0.1, -1.0],
            [1.0, -0.1, -1.0],
            [1.0, -0.1, 1.0],
            [-1.0, -0.1, 1.0],
        ],
        vec![[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7]],
    );
    let shape = CbvhShape::plain(&floor, &BuildOptions::default()).unwrap();
    let mut world = PhysicsWorld {
        narrow_phase: rapier3d::prelude::NarrowPhase::with_query_dispatcher(Dispatcher::chained()),
        ..Default::default()
    };
    world
        .colliders
        .insert(ColliderBuilder::new(SharedShape::new(shape.clone())));
    let ball = world
        .bodies
        .insert(RigidBodyBuilder::dynamic().translation(Vector::new(0.1, 1.0, -0.2)));
    world
        .colliders
        .insert_with_parent(ColliderBuilder::ball(0.1), ball, &mut world.bodies);
    for _ in 0..240 {
        world.step();
    }
    let b = &world.bodies[ball];
    assert!(
        (b.translation().y - 0.1).abs() < 0.02,
        "ball at {:?}",
        b.translation()
    );
    assert!(
        b.linvel().length() < 0.05,
        "ball still moving: {:?}",
        b.linvel()
    );
    assert!(!shape.fallback_bvh_built());
}

/// A 2 000-triangle statue placed above a 2 000-triangle turbine, for
/// `steps` steps at 60 Hz.
fn small_drop_scene(steps: usize) -> DropScene {
    let mut statue = mesh_of(Kind::Statue, 2000, 1);
    let turbine = mesh_of(Kind::Turbine, 2000, 1);
    droptest::place(&mut statue, &turbine, &Placement::default());
    DropScene {
        dropped: statue,
        dropped_file: None,
        length_unit: 1.0,
        base: turbine,
        steps,
        dt: 1.0 / 60.0,
        contact_recycling: false,
        codec_options: AnyOptions::default(),
        build_options: BuildOptions::default(),
    }
}

/// A run of `kind` in the default (patch) contact mode.
fn patch_run(kind: ShapeKind) -> RunSpec {
    RunSpec {
        kind,
        mode: ContactMode::default(),
    }
}

#[test]
fn drop_test_steps_without_the_fallback_and_agrees_with_parry() {
    let scene = small_drop_scene(60);
    let parry = droptest::run(&scene, patch_run(ShapeKind::Parry), &mut |_, _| {}).unwrap();
    let plain = droptest::run(
        &scene,
        patch_run(ShapeKind::Cbvh(CodecKind::Plain)),
        &mut |_, _| {},
    )
    .unwrap();
    // RACBVH with a cache of a tenth of its decompressed size lands the same
    // way, on its own traversals.
    let rac = droptest::run(
        &scene,
        patch_run(ShapeKind::CbvhTenthCache(CodecKind::Racbvh)),
        &mut |_, _| {},
    )
    .unwrap();
    assert!(!rac.fallback_bvh_built);
    assert!(rac.bytes_per_triangle < plain.bytes_per_triangle / 3.0);
    assert!((rac.final_translation[1] - plain.final_translation[1]).abs() < 0.1 * 2.0);
    assert!(
        !plain.fallback_bvh_built,
        "the native path must not build parry's Bvh"
    );
    assert!(plain.steps_in_contact > 0 && parry.steps_in_contact > 0);
    assert!(plain.bytes_per_triangle < parry.bytes_per_triangle);
    // Both land: the body fell and stopped near the same height.
    let size = 2.0;
    let dy = (plain.final_translation[1] - parry.final_translation[1]).abs();
    assert!(
        dy < 0.1 * size,
        "heights {} vs {}",
        plain.final_translation[1],
        parry.final_translation[1]
    );
    assert!(
        plain.final_translation[1] < -0.01,
        "the statue must fall onto the turbine"
    );
}

#[test]
fn shape_mass_and_bounds() {
    let m = mesh_of(Kind::Statue, 2000, 2);
    let c = CbvhShape::plain(&m, &BuildOptions::default()).unwrap();
    let t = parry_trimesh(&m).unwrap();
    use parry3d::shape::Shape;
    let (mc, mt) = (c.mass_properties(2.0), t.mass_properties(2.0));
    assert!(
        (mc.mass() - mt.mass()).abs() <= 1e-4 * mt.mass(),
        "{} vs {}",
        mc.mass(),
        mt.mass()
    );
    assert!((mc.local_com - mt.local_com).length() < 1e-4);
    let (ac, at) = (c.compute_local_aabb(), t.local_aabb());
    assert!((ac.mins - at.mins).length() < 1e-6 && (ac.maxs - at.maxs).length() < 1e-6);
    let cl = c.clone_dyn();
    assert!(cl.as_shape::<CbvhShape>().is_some());
    assert_eq!(c.shape_type(), parry3d::shape::ShapeType::Custom);
}

#[test]
fn distance_closest_points_and_casts_match_trimesh() {
    use parry3d::query::{ClosestPoints, ShapeCastOptions};
    let a = mesh_of(Kind::Robot, 2000, 5);
    let b = mesh_of(Kind::Statue, 2000, 6);
    let (ca, cb) = (
        CbvhShape::plain(&a, &BuildOptions::default()).unwrap(),
        CbvhShape::plain(&b, &BuildOptions::default()).unwrap(),
    );
    let (ta, tb) = (parry_trimesh(&a).unwrap(), parry_trimesh(&b).unwrap());
    let d = Dispatcher::default().chain(DefaultQueryDispatcher);
    let ball = parry3d::shape::Ball::new(0.1);
    for (k, x) in [1.5f32, 2.5, 0.9, 4.0].into_iter().enumerate() {
        let pos12 = Pose::new(
            Vector::new(x, 0.1 * k as f32, 0.2),
            Vector::new(0.0, 0.3 * k as f32, 0.0),
        );
        // cbvh vs cbvh, cbvh vs TriMesh and cbvh vs ball against TriMesh vs the same.
        let want = DefaultQueryDispatcher
            .distance(&pos12, &ta, &tb)
            .unwrap()
            .distance;
        let got = d.distance(&pos12, &ca, &cb).unwrap().distance;
        assert!(
            !ca.fallback_bvh_built() && !cb.fallback_bvh_built(),
            "cbvh-cbvh distance used the fallback"
        );
        assert!(
            (want - got).abs() <= 1e-5 * want.max(1.0),
            "distance {got} vs {want}"
        );
        let got = d.distance(&pos12, &ca, &tb).unwrap().distance;
        assert!(
            !ca.fallback_bvh_built() && !cb.fallback_bvh_built(),
            "cbvh-TriMesh distance used the fallback"
        );
        assert!(
            (want - got).abs() <= 1e-5 * want.max(1.0),
            "cbvh-trimesh distance {got} vs {want}"
        );
        let want_b = DefaultQueryDispatcher
            .distance(&pos12, &ta, &ball)
            .unwrap()
            .distance;
        let got_b = d.distance(&pos12, &ca, &ball).unwrap().distance;
        assert!(
            !ca.fallback_bvh_built() && !cb.fallback_bvh_built(),
            "cbvh-ball distance used the fallback"
        );
        assert!((want_b - got_b).abs() <= 1e-5 * want_b.max(1.0));
        for max_dist in [0.5f32, 3.0] {
            let w = DefaultQueryDispatcher
                .closest_points(&pos12, &ta, &tb, max_dist)
                .unwrap();
            let g = d.closest_points(&pos12, &ca, &cb, max_dist).unwrap();
            match (w, g) {
                (ClosestPoints::WithinMargin(w1, w2), ClosestPoints::WithinMargin(g1, g2)) => {
                    let dw = (w1 - pos12.transform_point(w2)).length();
                    let dg = (g1 - pos12.transform_point(g2)).length();
                    assert!((dw - dg).abs() <= 1e-5 * dw.max(1.0), "{dw} vs {dg}");
                }
                (w, g) => assert_eq!(
                    std::mem::discriminant(&w),
                    std::mem::discriminant(&g),
                    "closest points {w:?} vs {g:?}"
                ),
            }
        }
        // Linear cast of B towards A.
        let vel = Vector::new(-1.0, 0.0, 0.0);
        let opts = ShapeCastOptions::with_max_time_of_impact(10.0);
        let w = DefaultQueryDispatcher
            .cast_shapes(&pos12, vel, &ta, &tb, opts)
            .unwrap();
        let g = d.cast_shapes(&pos12, vel, &ca, &cb, opts).unwrap();
        match (w, g) {
            (Some(w), Some(g)) => assert!(
                (w.time_of_impact - g.time_of_impact).abs() <= 1e-4,
                "toi {} vs {}",
                w.time_of_impact,
                g.time_of_impact
            ),
            (None, None) => {}
            (w, g) => panic!("cast {w:?} vs {g:?}"),
        }
    }
    assert!(!ca.fallback_bvh_built() && !cb.fallback_bvh_built());
}

/// `--replay`: every shape's narrow phase timed again along the first
/// run's recorded trajectory, step for step: a time for every step where
/// that run had contact points, none where it made no call.
#[test]
fn a_replay_times_every_contact_step_of_the_first_runs_trajectory() {
    use cbvh::sim::droptest::Replay;
    let scene = small_drop_scene(40);
    let plain = droptest::run_replaying(
        &scene,
        patch_run(ShapeKind::Cbvh(CodecKind::Plain)),
        Replay::Own,
        droptest::REPLAY_ROUNDS,
        &mut |_, _| {},
    )
    .unwrap();
    assert_eq!(plain.trajectory.from, "plain");
    let contact_steps: Vec<usize> = (0..scene.steps)
        .filter(|&k| plain.contact_points_per_step[k] > 0)
        .collect();
    assert!(contact_steps.len() > 5, "{contact_steps:?}");
    // Before the first contact the bodies' boxes are apart: no call.
    let first = contact_steps[0];
    assert!(first >= 3, "contact from step {first}");
    for kind in [ShapeKind::Cbvh(CodecKind::Clbvh), ShapeKind::Parry] {
        let r = droptest::run_replaying(
            &scene,
            patch_run(kind),
            Replay::Along(&plain.trajectory),
            1,
            &mut |_, _| {},
        )
        .unwrap();
        assert_eq!(r.replay_along.as_deref(), Some("plain"));
        let ms = &r.replay_narrow_phase_ms_per_step;
        assert_eq!(ms.len(), scene.steps);
        assert!(contact_steps.iter().all(|&k| ms[k] > 0.0), "{ms:?}");
        assert!(ms[..3].iter().all(|&t| t == 0.0), "{ms:?}");
        assert!(r.replay_narrow_phase_ms.unwrap().median > 0.0);
    }
    let off = droptest::run(
        &scene,
        patch_run(ShapeKind::Cbvh(CodecKind::Plain)),
        &mut |_, _| {},
    )
    .unwrap();
    assert!(off.replay_along.is_none() && off.replay_narrow_phase_ms_per_step.is_empty());
}
