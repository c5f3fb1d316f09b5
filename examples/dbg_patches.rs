use cbvh::build::BuildOptions;
use cbvh::parry::droptest::{self, Placement};
use cbvh::parry::{CbvhShape, Dispatcher};
use cbvh::scene::{Kind, generate};
use parry3d::math::Vector;
use parry3d::shape::SharedShape;
use rapier3d::prelude::*;

fn main() {
    let mut statue = generate(Kind::Statue, 200_000, 1, &mut |_, _| {}).unwrap();
    let mut turbine = generate(Kind::Turbine, 100_000, 1, &mut |_, _| {}).unwrap();
    for v in &mut turbine.vertices {
        *v = [v[1], -v[0], v[2]];
    }
    droptest::place(&mut statue, &turbine, &Placement::default());
    let a = CbvhShape::plain(&statue, &BuildOptions::default()).unwrap();
    let b = CbvhShape::plain(&turbine, &BuildOptions::default()).unwrap();
    let (sa, sb) = (a.clone(), b.clone());
    let mut world = PhysicsWorld {
        gravity: Vector::new(0.0, -9.81, 0.0),
        ..Default::default()
    };
    let angle: f32 = std::env::var("ANGLE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(5.0);
    let gap: f32 = std::env::var("GAP")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(0.1);
    let mode = if std::env::var("PAIRS").is_ok() {
        cbvh::parry::ContactMode::PerTrianglePair
    } else {
        cbvh::parry::ContactMode::Patches(cbvh::contact::PatchOptions {
            max_angle_deg: angle,
            gap_fraction: gap,
        })
    };
    world.narrow_phase = NarrowPhase::with_query_dispatcher(Dispatcher::new(mode).then_default());
    if std::env::var("NOCLUSTER").is_ok() {
        world.integration_parameters.contact_clustering = false;
    }
    world.integration_parameters.contact_recycling = false;
    let base = world.bodies.insert(RigidBodyBuilder::fixed());
    let d = world
        .bodies
        .insert(RigidBodyBuilder::dynamic().can_sleep(false));
    world.colliders.insert_with_parent(
        ColliderBuilder::new(SharedShape::new(b)).friction(0.6),
        base,
        &mut world.bodies,
    );
    world.colliders.insert_with_parent(
        ColliderBuilder::new(SharedShape::new(a))
            .density(1.0)
            .friction(0.6),
        d,
        &mut world.bodies,
    );
    for step in 0..140 {
        world.step();
        let mut s = String::new();
        for pair in world.narrow_phase.contact_pairs() {
            let c1 = &world.colliders[pair.collider1];
            for m in pair.manifolds() {
                if m.points.is_empty() {
                    continue;
                }
                let n = c1.position().rotation * m.local_n1;
                let md = m.points.iter().map(|p| p.dist).fold(f32::MAX, f32::min);
                s += &format!(
                    " [{:.2},{:.2},{:.2}]{:.4}/{}/{}",
                    n.x,
                    n.y,
                    n.z,
                    md,
                    m.points.len(),
                    m.data.solver_contacts.len()
                );
            }
            s = format!("c1={:?} {}", pair.collider1, s);
        }
        let t = world.bodies[d].translation();
        let v = world.bodies[d].linvel();
        let w = world.bodies[d].angvel();
        if step == 60 && std::env::var("CMP").is_ok() {
            let p1 = world.bodies[d].position();
            let p2 = world.bodies[base].position();
            compare(&sa, &sb, &statue, &turbine, &p1.inv_mul(p2), 0.02);
        }
        let mut sc = 0;
        let mut mind = f32::MAX;
        let mut nman = 0;
        let mut ny = 0.0;
        for pair in world.narrow_phase.contact_pairs() {
            for m in pair.manifolds() {
                nman += 1;
                sc += m.data.solver_contacts.len();
                for c in &m.data.solver_contacts {
                    mind = mind.min(c.dist);
                    ny += m.data.normal.y;
                }
            }
        }
        if step % 10 == 0 || (step > 50 && step < 60) {
            println!(
                "{step} y={:.4} vy={:.3} w={:.3} manifolds={nman} solver_contacts={sc} min_dist={mind:.4} sum_ny={ny:.2}",
                t.y,
                v.y,
                w.length()
            );
        }
    }
}

#[allow(dead_code)]
pub fn compare(
    a: &CbvhShape,
    b: &CbvhShape,
    ma: &cbvh::Mesh,
    mb: &cbvh::Mesh,
    pos12: &parry3d::math::Pose,
    pred: f32,
) {
    use parry3d::query::{ContactManifold, DefaultQueryDispatcher, PersistentQueryDispatcher};
    let mut ms: Vec<ContactManifold<(), ()>> = Vec::new();
    Dispatcher::new(cbvh::parry::ContactMode::PerTrianglePair)
        .contact_manifolds(pos12, a, b, pred, &mut ms, &mut None)
        .unwrap();
    let _ = DefaultQueryDispatcher;
    let (mut bad, mut total, mut missing) = (0, 0, 0);
    for m in ms.iter().filter(|m| !m.points.is_empty()) {
        total += 1;
        let ta = ma
            .triangle_vertices(m.subshape1 as usize)
            .map(glam::Vec3A::from);
        let tb = mb.triangle_vertices(m.subshape2 as usize).map(|p| {
            let q = *pos12 * parry3d::math::Vector::from(p);
            glam::Vec3A::from(q.to_array())
        });
        let md = m.points.iter().map(|p| p.dist).fold(f32::MAX, f32::min);
        match cbvh::contact::pair_contact(&ta, &tb, pred) {
            None => {
                missing += 1;
                if missing < 5 {
                    println!(
                        "missing pair {} {} parry dist {md}",
                        m.subshape1, m.subshape2
                    );
                }
            }
            Some(c) => {
                let n = glam::Vec3A::from(m.local_n1.to_array());
                let ang = c.normal.dot(n).clamp(-1.0, 1.0).acos().to_degrees();
                if md < 0.0 || c.dist < 0.0 {
                    bad += 1;
                    if bad < 15 {
                        println!(
                            "pair {} {}: ours n={} d={} feat={:?} npts={} | parry n={} d={} npts={}",
                            m.subshape1,
                            m.subshape2,
                            c.normal,
                            c.dist,
                            c.feature,
                            c.points().len(),
                            n,
                            md,
                            m.points.len()
                        );
                    }
                }
            }
        }
    }
    println!("total {total} bad {bad} missing {missing}");
}
