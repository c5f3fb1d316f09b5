//! Scaled shapes (`CbvhShape::scaled`, parry's `Shape::scale_dyn`): a
//! scaled view of a compressed tree answers every query as the shape of
//! the mesh with its vertices scaled first. Every codec, uniform,
//! non-uniform and mirrored factors, against a parry `TriMesh` of the
//! scaled triangles (the per-triangle reference) and, for mass and edge
//! flags, against the flags and mass computed from the scaled mesh itself.

use cbvh::Mesh;
use cbvh::build::BuildOptions;
use cbvh::codec::racbvh::RacOptions;
use cbvh::codec::{AnyOptions, CodecKind};
use cbvh::contact::edges::EdgeFlags;
use cbvh::geom::Triangle;
use cbvh::parry::{CbvhShape, ContactMode, Dispatcher};
use cbvh::scene::{Kind, generate};
use glam::Vec3A;
use parry3d::math::{Pose, Vector};
use parry3d::query::{
    DefaultQueryDispatcher, PointQuery, QueryDispatcher, Ray, RayCast, ShapeCastOptions,
};
use parry3d::shape::{Ball, Shape, SharedShape, TriMesh};
use rapier3d::prelude::{ColliderBuilder, NarrowPhase, PhysicsWorld, RigidBodyBuilder};

use crate::common::Rng;

/// The factors under test: uniform, non-uniform, mirrored on one axis,
/// mirrored and non-uniform, mirrored on all three.
const SCALES: [[f32; 3]; 5] = [
    [2.5, 2.5, 2.5],
    [0.5, 3.0, 1.25],
    [-1.5, 1.5, 1.5],
    [2.0, -0.5, 1.0],
    [-0.75, -0.75, -0.75],
];

fn all_codecs(mesh: &Mesh) -> Vec<CbvhShape> {
    let options = AnyOptions {
        racbvh: RacOptions {
            cluster_nodes: 256,
            ..Default::default()
        },
        ..Default::default()
    };
    CodecKind::ALL
        .iter()
        .map(|&k| CbvhShape::build(mesh, &BuildOptions::default(), k, &options).unwrap())
        .collect()
}

fn triangles_of(shape: &CbvhShape) -> Vec<[Vector; 3]> {
    (0..shape.triangle_count() as u32)
        .map(|id| {
            let t = shape.parry_triangle(id);
            [t.a, t.b, t.c]
        })
        .collect()
}

/// A parry `TriMesh` of a triangle soup, triangle `i` being `tris[i]`.
fn soup_trimesh(tris: &[[Vector; 3]]) -> TriMesh {
    let vertices = tris.iter().flatten().copied().collect();
    let indices = (0..tris.len() as u32)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    TriMesh::new(vertices, indices).unwrap()
}

/// `mesh` with its vertices scaled by `s`, the winding reversed for a
/// mirror so that the solid keeps its outward side (the reference for
/// the mass of a scaled solid).
fn scaled_mesh(mesh: &Mesh, s: [f32; 3]) -> Mesh {
    let vertices = mesh
        .vertices
        .iter()
        .map(|v| [v[0] * s[0], v[1] * s[1], v[2] * s[2]])
        .collect();
    let mirrored = s[0] * s[1] * s[2] < 0.0;
    let triangles = mesh
        .triangles
        .iter()
        .map(|&[a, b, c]| if mirrored { [a, c, b] } else { [a, b, c] })
        .collect();
    Mesh::new(vertices, triangles)
}

fn close(a: f32, b: f32, rel: f32) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()).max(1.0)
}

#[test]
fn scaled_triangles_boxes_rays_and_projections_match_the_scaled_mesh() {
    let mesh = generate(Kind::Statue, 1500, 3, &mut |_, _| {}).unwrap();
    for shape in all_codecs(&mesh) {
        let name = shape.codec().name();
        let base = triangles_of(&shape);
        for s in SCALES {
            let sv = Vector::from_array(s);
            let scaled = shape.scaled(sv).expect("finite non-zero scale");
            assert_eq!(scaled.scale(), Vec3A::from_array(s));
            // Triangles: exactly the corners times the factors, by id.
            let tris = triangles_of(&scaled);
            for (t, b) in tris.iter().zip(&base) {
                assert_eq!(*t, [b[0] * sv, b[1] * sv, b[2] * sv], "{name} {s:?}");
            }
            let reference = soup_trimesh(&tris);
            // The box holds every triangle and is the unscaled box scaled.
            let (got, want) = (scaled.compute_local_aabb(), reference.local_aabb());
            assert!(
                got.mins.cmple(want.mins).all() && got.maxs.cmpge(want.maxs).all(),
                "{name} {s:?}: box {got:?} misses triangles {want:?}"
            );
            let slack = 0.02 * (want.maxs - want.mins).length();
            assert!(
                (got.mins - want.mins).length() < slack && (got.maxs - want.maxs).length() < slack,
                "{name} {s:?}: box {got:?} vs {want:?}"
            );
            // Rays from all around towards the middle.
            let centre = (want.mins + want.maxs) * 0.5;
            let radius = (want.maxs - want.mins).length();
            let mut rng = Rng(17);
            let mut hits = 0;
            for _ in 0..150 {
                let origin = centre + Vector::from(rng.vec(-1.0, 1.0)) * radius;
                let target = centre + Vector::from(rng.vec(-0.1, 0.1)) * radius;
                let ray = Ray::new(origin, (target - origin).normalize());
                let w = reference.cast_local_ray_and_get_normal(&ray, f32::MAX, true);
                let g = scaled.cast_local_ray_and_get_normal(&ray, f32::MAX, true);
                match (w, g) {
                    (Some(w), Some(g)) => {
                        hits += 1;
                        assert!(
                            close(w.time_of_impact, g.time_of_impact, 1e-5),
                            "{name} {s:?}: ray toi {} vs {}",
                            g.time_of_impact,
                            w.time_of_impact
                        );
                        // The normal of the triangle hit (either side).
                        assert!(
                            w.normal.dot(g.normal).abs() > 0.999 || g.feature != w.feature,
                            "{name} {s:?}: normal {:?} vs {:?}",
                            g.normal,
                            w.normal
                        );
                    }
                    (None, None) => {}
                    (w, g) => panic!("{name} {s:?}: ray {ray:?}: {g:?} vs {w:?}"),
                }
            }
            assert!(hits > 50, "{name} {s:?}: only {hits} rays hit");
            // Projections of points around (distance only: ties between
            // triangles may pick another triangle).
            for _ in 0..60 {
                let p = centre + Vector::from(rng.vec(-0.8, 0.8)) * radius;
                let w = reference.project_local_point(p, false);
                let g = scaled.project_local_point(p, false);
                let (dw, dg) = ((w.point - p).length(), (g.point - p).length());
                assert!(
                    close(dw, dg, 1e-5),
                    "{name} {s:?}: projection of {p:?}: {dg} vs {dw}"
                );
            }
        }
    }
}

#[test]
fn scaled_distances_contacts_and_casts_match_the_scaled_mesh() {
    let a = generate(Kind::Statue, 1200, 4, &mut |_, _| {}).unwrap();
    let b = generate(Kind::Robot, 1000, 5, &mut |_, _| {}).unwrap();
    let d = Dispatcher::default().then_default();
    let ball = Ball::new(0.05);
    let shapes_a = all_codecs(&a);
    let shapes_b = all_codecs(&b);
    for (sa, sb) in shapes_a.iter().zip(&shapes_b) {
        let name = sa.codec().name();
        for (k, s) in SCALES.into_iter().enumerate() {
            let sv = Vector::from_array(s);
            let (ca, cb) = (
                sa.scaled(sv).unwrap(),
                sb.scaled(Vector::splat(0.7)).unwrap(),
            );
            let (ta, tb) = (
                soup_trimesh(&triangles_of(&ca)),
                soup_trimesh(&triangles_of(&cb)),
            );
            let size = (ta.local_aabb().maxs - ta.local_aabb().mins).length();
            for j in 0..4 {
                let offset = Vector::new(0.25 + 0.12 * j as f32, 0.1 * k as f32, 0.05) * size;
                let pos12 = Pose::new(offset, Vector::new(0.0, 0.4 * j as f32, 0.1));
                // Mesh-mesh distance and intersection.
                let w = DefaultQueryDispatcher
                    .distance(&pos12, &ta, &tb)
                    .unwrap()
                    .distance;
                let g = d.distance(&pos12, &ca, &cb).unwrap().distance;
                assert!(close(w, g, 1e-4), "{name} {s:?}: mesh distance {g} vs {w}");
                let w = DefaultQueryDispatcher
                    .intersection_test(&pos12, &ta, &tb)
                    .unwrap();
                let g = d.intersection_test(&pos12, &ca, &cb).unwrap();
                assert_eq!(w.intersecting, g.intersecting, "{name} {s:?}: intersection");
                // Ball: distance, contact depth within a prediction, and a
                // linear cast towards the mesh's middle.
                let pb = Pose::from_translation(offset * 0.6);
                let w = DefaultQueryDispatcher
                    .distance(&pb, &ta, &ball)
                    .unwrap()
                    .distance;
                let g = d.distance(&pb, &ca, &ball).unwrap().distance;
                assert!(close(w, g, 1e-4), "{name} {s:?}: ball distance {g} vs {w}");
                let w = DefaultQueryDispatcher
                    .contact(&pb, &ta, &ball, 0.5 * size)
                    .unwrap();
                let g = d.contact(&pb, &ca, &ball, 0.5 * size).unwrap();
                match (w, g) {
                    (Some(w), Some(g)) => {
                        assert!(
                            close(w.dist, g.dist, 1e-4),
                            "{name} {s:?}: contact {g:?} vs {w:?}"
                        )
                    }
                    (None, None) => {}
                    (w, g) => panic!("{name} {s:?}: contact {g:?} vs {w:?}"),
                }
                let vel = -offset.normalize();
                let opts = ShapeCastOptions::with_max_time_of_impact(2.0 * size);
                let w = DefaultQueryDispatcher
                    .cast_shapes(&pb, vel, &ta, &ball, opts)
                    .unwrap();
                let g = d.cast_shapes(&pb, vel, &ca, &ball, opts).unwrap();
                match (w, g) {
                    (Some(w), Some(g)) => assert!(
                        close(w.time_of_impact, g.time_of_impact, 1e-4),
                        "{name} {s:?}: cast {} vs {}",
                        g.time_of_impact,
                        w.time_of_impact
                    ),
                    (None, None) => {}
                    (w, g) => panic!("{name} {s:?}: cast {g:?} vs {w:?}"),
                }
            }
            assert!(!ca.fallback_bvh_built() && !cb.fallback_bvh_built());
        }
    }
}

/// A closed, non-symmetric solid: a box with one corner pulled out, so
/// that the centre of mass is off the origin and the inertia tensor has
/// off-diagonal terms.
fn lopsided_solid() -> Mesh {
    let mut vertices = vec![];
    for k in 0..8 {
        let v = [
            if k & 1 == 0 { -0.5 } else { 0.5 },
            if k & 2 == 0 { -0.3 } else { 0.3 },
            if k & 4 == 0 { -0.2 } else { 0.2 },
        ];
        vertices.push(if k == 7 { [1.1, 0.8, 0.6] } else { v });
    }
    // Outward-wound faces of the (distorted) cube, two triangles a face.
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let triangles = quads
        .iter()
        .flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]])
        .collect();
    let mesh = Mesh::new(vertices, triangles);
    let shape = CbvhShape::plain(&mesh, &BuildOptions::default()).unwrap();
    assert!(shape.mass_properties(1.0).mass() > 0.0, "wound outward");
    mesh
}

#[test]
fn scaled_mass_properties_are_the_scaled_solids() {
    let mesh = lopsided_solid();
    let shape = CbvhShape::plain(&mesh, &BuildOptions::default()).unwrap();
    for s in SCALES {
        let got = shape
            .scaled(Vector::from_array(s))
            .unwrap()
            .mass_properties(2.0);
        let want = CbvhShape::plain(&scaled_mesh(&mesh, s), &BuildOptions::default())
            .unwrap()
            .mass_properties(2.0);
        assert!(
            close(got.mass(), want.mass(), 1e-4),
            "{s:?}: mass {got:?} vs {want:?}"
        );
        assert!(
            (got.local_com - want.local_com).length() < 1e-4,
            "{s:?}: centre of mass {:?} vs {:?}",
            got.local_com,
            want.local_com
        );
        let (gi, wi) = (
            got.reconstruct_inertia_matrix(),
            want.reconstruct_inertia_matrix(),
        );
        let scale = wi.to_cols_array().iter().fold(0f32, |m, x| m.max(x.abs()));
        for (g, w) in gi.to_cols_array().iter().zip(wi.to_cols_array()) {
            assert!(
                (g - w).abs() <= 1e-4 * scale,
                "{s:?}: inertia {gi:?} vs {wi:?}"
            );
        }
    }
}

#[test]
fn scaled_edge_flags_are_the_scaled_triangles_flags() {
    let mesh = generate(Kind::Statue, 1500, 8, &mut |_, _| {}).unwrap();
    for shape in all_codecs(&mesh) {
        let name = shape.codec().name();
        for s in SCALES {
            let scaled = shape.scaled(Vector::from_array(s)).unwrap();
            let tris: Vec<Triangle> = triangles_of(&scaled)
                .iter()
                .map(|t| t.map(Vec3A::from))
                .collect();
            let want = EdgeFlags::compute(tris.len(), |id| tris[id as usize]);
            let got = scaled.edge_flags();
            let differ = (0..tris.len() as u32)
                .filter(|&id| got.get(id) != want.get(id))
                .count();
            assert_eq!(differ, 0, "{name} {s:?}: {differ} triangles' flags differ");
            assert_eq!(got.is_closed(), want.is_closed(), "{name} {s:?}");
            assert_eq!(got.outward(), want.outward(), "{name} {s:?}: outward side");
        }
    }
}

/// A strip folded by `bend_deg` about the line `x = 0`: two 1 x 1 quads,
/// the second tilted up by the bend.
fn folded_strip(bend_deg: f32) -> Mesh {
    let (sin, cos) = bend_deg.to_radians().sin_cos();
    Mesh::new(
        vec![
            [-1.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 1.0],
            [-1.0, 0.0, 1.0],
            [cos, sin, 0.0],
            [cos, sin, 1.0],
        ],
        vec![[0, 2, 1], [0, 3, 2], [1, 2, 5], [1, 5, 4]],
    )
}

#[test]
fn a_non_uniform_scale_sharpens_a_flat_fold_into_an_active_edge() {
    // 3 degrees is flat (below the 5-degree default): the fold edge is
    // inactive. Stretched 20 times along y, the fold is about 46 degrees.
    let shape = CbvhShape::plain(&folded_strip(3.0), &BuildOptions::default()).unwrap();
    let fold_active = |s: &CbvhShape| {
        // The fold edge is the one from (0,0,0) to (0,0,1) in each triangle
        // that has it; any active bit on it counts.
        (0..s.triangle_count() as u32).any(|id| {
            let t = s.parry_triangle(id);
            let corners = [t.a, t.b, t.c];
            (0..3).any(|e| {
                let (p, q) = (corners[e], corners[(e + 1) % 3]);
                let on_fold = p.x.abs() < 1e-6 && q.x.abs() < 1e-6;
                on_fold && s.edge_flags_of(id) & (0b1001 << e) != 0
            })
        })
    };
    assert!(!fold_active(&shape), "a 3-degree fold is flat");
    assert!(
        !fold_active(&shape.scaled(Vector::splat(20.0)).unwrap()),
        "a uniform scale keeps the angle"
    );
    assert!(
        fold_active(&shape.scaled(Vector::new(1.0, 20.0, 1.0)).unwrap()),
        "a 20x stretch across the fold makes it a 46-degree edge"
    );
}

/// A ball dropped on a scaled floor comes to rest at the scaled floor's
/// height plus its radius, in both contact modes, for a uniform, a
/// non-uniform and a mirrored scale of a compressed floor.
#[test]
fn a_ball_rests_on_a_scaled_floor_in_rapier() {
    // A closed 2 x 0.2 x 2 slab, 8 x 8 cells on top.
    let n = 8;
    let mut vertices = vec![];
    let mut triangles = vec![];
    for j in 0..=n {
        for i in 0..=n {
            vertices.push([
                -1.0 + 2.0 * i as f32 / n as f32,
                0.0,
                -1.0 + 2.0 * j as f32 / n as f32,
            ]);
        }
    }
    let at = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    for j in 0..n {
        for i in 0..n {
            triangles.push([at(i, j), at(i, j + 1), at(i + 1, j + 1)]);
            triangles.push([at(i, j), at(i + 1, j + 1), at(i + 1, j)]);
        }
    }
    let base = vertices.len() as u32;
    for v in [
        [-1.0, -0.2, -1.0],
        [1.0, -0.2, -1.0],
        [1.0, -0.2, 1.0],
        [-1.0, -0.2, 1.0],
    ] {
        vertices.push(v);
    }
    triangles.push([base, base + 1, base + 2]);
    triangles.push([base, base + 2, base + 3]);
    // Each side fans from its first bottom corner over the top edge's n
    // segments, so that every top vertex on the rim is shared and the slab
    // is closed.
    let rim = |k: usize, i: usize| match k {
        0 => at(i, 0),
        1 => at(n, i),
        2 => at(n - i, n),
        _ => at(0, n - i),
    };
    for k in 0..4 {
        let (b0, b1) = (base + k as u32, base + ((k + 1) % 4) as u32);
        for i in 0..n {
            triangles.push([b0, rim(k, i), rim(k, i + 1)]);
        }
        triangles.push([b0, rim(k, n), b1]);
    }
    let mesh = Mesh::new(vertices, triangles);
    let options = AnyOptions::default();
    for kind in [CodecKind::Racbvh, CodecKind::Hcc, CodecKind::Clbvh] {
        let shape = CbvhShape::build(&mesh, &BuildOptions::default(), kind, &options).unwrap();
        assert!(shape.edge_flags().is_closed(), "the slab is closed");
        for s in [
            [3.0f32, 3.0, 3.0],
            [4.0, 0.5, 2.0],
            [-2.0, 1.0, 2.0],
            [2.0, -1.0, 2.0],
        ] {
            // With y mirrored the top is at 0 and the slab below is the
            // mirror's: the floor is then 0.2 * |sy| above; place it so
            // that the top is at 0 either way.
            let top = if s[1] < 0.0 { 0.2 * s[1].abs() } else { 0.0 };
            for mode in [ContactMode::default(), ContactMode::PerTrianglePair] {
                let scaled = shape.scaled(Vector::from_array(s)).unwrap();
                let mut world = PhysicsWorld {
                    narrow_phase: NarrowPhase::with_query_dispatcher(
                        Dispatcher::new(mode).then_default(),
                    ),
                    ..Default::default()
                };
                world.colliders.insert(
                    ColliderBuilder::new(SharedShape::new(scaled.clone()))
                        .translation(Vector::new(0.0, -top, 0.0)),
                );
                let ball = world
                    .bodies
                    .insert(RigidBodyBuilder::dynamic().translation(Vector::new(0.3, 0.6, -0.4)));
                world.colliders.insert_with_parent(
                    ColliderBuilder::ball(0.1),
                    ball,
                    &mut world.bodies,
                );
                for _ in 0..180 {
                    world.step();
                }
                let b = &world.bodies[ball];
                assert!(
                    (b.translation().y - 0.1).abs() < 0.01 && b.linvel().length() < 0.05,
                    "{} {s:?} {mode:?}: ball at {:?}, moving {:?}",
                    kind.name(),
                    b.translation(),
                    b.linvel()
                );
                assert!(!scaled.fallback_bvh_built());
            }
        }
    }
}

#[test]
fn scale_dyn_scales_and_refuses_a_zero_factor() {
    let mesh = lopsided_solid();
    let shape = CbvhShape::plain(&mesh, &BuildOptions::default()).unwrap();
    let boxed = shape.scale_dyn(Vector::new(2.0, 1.0, 1.0), 0).unwrap();
    let scaled = boxed.as_shape::<CbvhShape>().expect("a cbvh shape");
    assert_eq!(scaled.scale(), Vec3A::new(2.0, 1.0, 1.0));
    // Scaling again multiplies the factors.
    let again = scaled.scaled(Vector::new(0.5, 3.0, 1.0)).unwrap();
    assert_eq!(again.scale(), Vec3A::new(1.0, 3.0, 1.0));
    assert_eq!(
        again.parry_triangle(0).a,
        shape.parry_triangle(0).a * Vector::new(1.0, 3.0, 1.0)
    );
    for bad in [
        Vector::new(0.0, 1.0, 1.0),
        Vector::new(1.0, f32::NAN, 1.0),
        Vector::new(1.0, 1.0, f32::INFINITY),
    ] {
        assert!(shape.scale_dyn(bad, 0).is_none(), "{bad:?}");
        assert!(shape.scaled(bad).is_none(), "{bad:?}");
    }
}
