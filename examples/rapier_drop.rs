//! A cbvh shape in rapier, end to end: load a mesh (or a cbvh codec file,
//! or generate a statue), make it a RACBVH shape, drop it on a floor that is
//! a cbvh shape too (or parry's `TriMesh` with `--trimesh-floor`), and print
//! where it comes to rest. The README's "Using it in rapier" snippet is this
//! program's core.
//!
//! ```sh
//! cargo run --release --features sims --example rapier_drop
//! cargo run --release --features sims --example rapier_drop -- my_mesh.ply --trimesh-floor
//! cargo run --release --features sims --example rapier_drop -- s.rac     # written by `cbvh build ... -o s.rac`
//! ```

use cbvh::Mesh;
use cbvh::build::BuildOptions;
use cbvh::codec::{AnyOptions, CodecKind};
use cbvh::parry::{CbvhShape, Dispatcher};
use rapier3d::prelude::*;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    cbvh::logger::init_stderr();
    let args: Vec<String> = std::env::args().skip(1).collect();
    let trimesh_floor = args.iter().any(|a| a == "--trimesh-floor");
    let path = args.iter().find(|a| !a.starts_with("--"));

    // The dropped body: a codec file needs no mesh (it stores its own mass
    // properties); a mesh or a generated statue is compressed here.
    let body_shape = match path {
        Some(p) if CodecKind::of_file(p.as_ref()).is_some() => CbvhShape::open(p.as_ref())?,
        _ => {
            let mesh = match path {
                Some(p) => cbvh::mesh::load(p)?,
                None => {
                    cbvh::scene::generate(cbvh::scene::Kind::Statue, 50_000, 1, &mut |_, _| {})?
                }
            };
            mesh.validate("the dropped mesh")?;
            CbvhShape::build(
                &mesh,
                &BuildOptions::default(),
                CodecKind::Racbvh,
                &AnyOptions::default(),
            )?
        }
    };
    let b = body_shape.local_aabb();
    let size = (b.max - b.min).max_element();

    // A floor twice the body's size, its top at y = 0.
    let (c, r) = ((b.min + b.max) * 0.5, size.max(1e-3));
    let floor = Mesh::cuboid(
        [c.x - 2.0 * r, -0.1 * r, c.z - 2.0 * r],
        [c.x + 2.0 * r, 0.0, c.z + 2.0 * r],
    );
    let floor_shape = if trimesh_floor {
        SharedShape::trimesh(
            floor
                .vertices
                .iter()
                .map(|v| Vector::from_array(*v))
                .collect(),
            floor.triangles.clone(),
        )?
    } else {
        SharedShape::new(CbvhShape::plain(&floor, &BuildOptions::default())?)
    };

    let mut world = PhysicsWorld {
        gravity: Vector::new(0.0, -9.81, 0.0),
        ..Default::default()
    };
    // The one extra line: cbvh's dispatcher for pairs with a cbvh shape,
    // parry's for everything else.
    world.narrow_phase = NarrowPhase::with_query_dispatcher(Dispatcher::chained());
    let ground = world.bodies.insert(RigidBodyBuilder::fixed());
    world.colliders.insert_with_parent(
        ColliderBuilder::new(floor_shape),
        ground,
        &mut world.bodies,
    );
    // Start with the body's lowest point a tenth of its size above the floor.
    let start = 0.1 * size - b.min.y;
    let body = world.bodies.insert(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(0.0, start, 0.0))
            .can_sleep(false),
    );
    world.colliders.insert_with_parent(
        ColliderBuilder::new(SharedShape::new(body_shape.clone())).density(1.0),
        body,
        &mut world.bodies,
    );
    let steps = 180;
    for _ in 0..steps {
        world.step();
    }
    let rb = &world.bodies[body];
    let (y, speed) = (rb.translation().y, rb.linvel().length());
    println!(
        "{} triangles ({}), floor {}: dropped from y = {start:.4}; after {steps} steps at 60 Hz \
         final height y = {y:.4}, speed {speed:.4}",
        body_shape.triangle_count(),
        body_shape.codec().name(),
        if trimesh_floor {
            "parry TriMesh"
        } else {
            "cbvh plain"
        },
    );
    if body_shape.fallback_bvh_built() {
        return Err("the parry fallback Bvh was built: the dispatcher was bypassed".into());
    }
    Ok(())
}
