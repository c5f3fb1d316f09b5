//! Any finite mesh in the supported range encodes and answers queries,
//! wherever it sits: RACBVH used to fail with "node N's box is not inside
//! its parent's" for a mesh small next to its distance from the origin
//! (grid points coincide in f32 there); and coordinates so large that f32
//! triangle tests overflow are rejected with the supported range instead of
//! rendering an empty image.

use crate::common;

use cbvh::build::{BuildOptions, build};
use cbvh::codec::racbvh::{RacBvh, RacOptions};
use cbvh::mesh::MeshError;
use cbvh::scene::{Kind, generate};
use cbvh::{Mesh, NodeCursor};
use common::*;

fn moved(mesh: &Mesh, size: f32, offset: f32) -> Mesh {
    let (lo, hi) = mesh.bounds().unwrap();
    let ext = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f32::max);
    let mut m = mesh.clone();
    for v in &mut m.vertices {
        for k in 0..3 {
            v[k] = (v[k] - lo[k]) / ext * size + offset;
        }
    }
    m
}

/// Encodes, verifies, round-trips and checks every box against the
/// triangles below it; with `queries`, also closest/any hits, overlaps and
/// closest points against brute force. (At 1e6 and beyond, f32 spacing
/// there is 0.06 and more, and the traversals' answers can differ from
/// brute force for the plain codec too; that is a query precision matter,
/// not an encoding one.)
fn check_racbvh(mesh: &Mesh, bits: u32, vertex_bits: Option<u32>, what: &str, queries: bool) {
    let bvh = build(mesh, &BuildOptions::default(), &|_, _| {}).unwrap();
    let opts = RacOptions {
        cluster_nodes: 256,
        bits,
        vertex_bits,
        ..Default::default()
    };
    let rac = RacBvh::encode(&bvh, mesh, &opts).unwrap_or_else(|e| panic!("{what}: {e}"));
    rac.verify().unwrap_or_else(|e| panic!("{what}: {e}"));
    let back = RacBvh::from_bytes(&rac.to_bytes(), 1 << 20).unwrap();
    back.verify().unwrap();
    let dm = rac.decoded_mesh();
    check_structure(&back, &dm);
    if queries {
        check_queries(&back, &dm, 11);
    }
    assert_eq!(back.triangle_count(), mesh.triangles.len());
}

#[test]
fn racbvh_encodes_a_statue_far_from_the_origin() {
    let statue = generate(Kind::Statue, 5000, 2, &mut |_, _| {}).unwrap();
    for offset in [1e4, 1e6, 1e7] {
        let m = moved(&statue, 1.7, offset);
        let q = offset < 1e5;
        check_racbvh(&m, 16, Some(16), &format!("statue at {offset}"), q);
        check_racbvh(&m, 16, None, &format!("lossless statue at {offset}"), q);
    }
}

#[test]
fn racbvh_encodes_a_100_unit_object_at_1e6_with_16_and_24_bits() {
    let robot = generate(Kind::Robot, 3000, 1, &mut |_, _| {}).unwrap();
    let m = moved(&robot, 100.0, 1e6);
    for bits in [16, 24] {
        check_racbvh(
            &m,
            bits,
            Some(bits),
            &format!("robot at 1e6, {bits} bits"),
            false,
        );
    }
}

#[test]
fn coordinates_beyond_the_supported_range_are_rejected_at_load() {
    // Loading reads the file as written; validating it (which the CLI,
    // the sims and the builder do before using it) names the range.
    let obj = "v 1e30 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\n";
    let mesh = cbvh::mesh::load_bytes(
        obj.as_bytes(),
        cbvh::mesh::Format::Obj,
        std::path::Path::new("far.obj"),
    )
    .unwrap();
    let err = mesh.validate("far.obj").unwrap_err();
    assert!(
        matches!(err, MeshError::CoordinateTooLarge { vertex: 0, .. }),
        "{err:?}"
    );
    let msg = err.to_string();
    assert!(msg.contains("far.obj") && msg.contains("1e12"), "{msg}");
    // The codec refuses such a mesh too, rather than encode nonsense.
    let m = Mesh::new(
        vec![[1e30, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        vec![[0, 1, 2]],
    );
    let err = build(&m, &BuildOptions::default(), &|_, _| {}).unwrap_err();
    assert!(err.to_string().contains("1e12"), "{err}");
}

// The ray tracer needs the `render` feature (`app` has it).
#[cfg(feature = "render")]
#[test]
fn a_mesh_at_the_limit_renders_like_one_near_the_origin() {
    let statue = generate(Kind::Statue, 2000, 4, &mut |_, _| {}).unwrap();
    let opts = cbvh::render::RenderOptions {
        width: 48,
        height: 36,
        ..Default::default()
    };
    let image = |m: &Mesh| {
        m.validate("test").unwrap();
        cbvh::render::render_meshes(&[(m, cbvh::geom::Pose::IDENTITY)], &opts).unwrap()
    };
    let near = image(&moved(&statue, 1.0, 0.0));
    // The statue is in the picture: its centre is not the background.
    assert_ne!(near.pixel(24, 18), near.pixel(0, 0));
    for (size, offset) in [
        (1e8, 0.0),
        (1e4, 1e8),
        (
            cbvh::mesh::MAX_COORDINATE * 0.5,
            cbvh::mesh::MAX_COORDINATE * 0.5,
        ),
    ] {
        // Far away (or huge), the same picture: it used to be empty, the
        // camera's view direction NaN once `centre + unit vector` rounded
        // back to the centre.
        let far = image(&moved(&statue, size, offset));
        let (a, b) = (near.pixel(24, 18), far.pixel(24, 18));
        let close = (0..3).all(|k| a[k].abs_diff(b[k]) <= 8);
        assert!(close, "size {size} at {offset}: {a:?} vs {b:?}");
    }
}
