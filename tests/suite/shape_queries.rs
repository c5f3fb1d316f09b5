//! `CbvhShape`'s own queries against parry's `TriMesh` of the same mesh:
//! point projection (point, inside flag, triangle and feature) and mass
//! properties (mass, centre of mass and the full inertia tensor).

use cbvh::Mesh;
use cbvh::build::BuildOptions;
use cbvh::codec::racbvh::RacOptions;
use cbvh::codec::{AnyOptions, CodecKind};
use cbvh::parry::{CbvhShape, parry_trimesh};
use cbvh::scene::{Kind, generate};
use parry3d::math::Vector;
use parry3d::query::{PointProjection, PointQuery};
use parry3d::shape::{FeatureId, Shape, TriMesh};

fn mesh_of(kind: Kind, tris: usize, seed: u64) -> Mesh {
    generate(kind, tris, seed, &mut |_, _| {}).expect("generate")
}

/// The shapes under test: every codec of the registry (RACBVH with `f32`
/// vertices, so that its triangles are the mesh's).
fn cbvh_shapes(mesh: &Mesh) -> Vec<CbvhShape> {
    let options = AnyOptions {
        racbvh: RacOptions {
            vertex_bits: None,
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

/// Query points around a closed mesh, by kind: on triangles (inside a
/// face, on an edge, on a vertex), just inside and just outside the
/// surface, and far outside.
fn probe_points(mesh: &Mesh) -> Vec<(&'static str, Vector)> {
    let (lo, hi) = mesh.bounds().unwrap();
    let (lo, hi) = (Vector::from(lo), Vector::from(hi));
    let size = (hi - lo).length();
    let n = mesh.triangles.len();
    let mut points = Vec::new();
    for k in 0..24 {
        let [a, b, c] = mesh.triangle_vertices((k * 7919) % n).map(Vector::from);
        let normal = (b - a).cross(c - a).normalize();
        let centroid = (a + b + c) / 3.0;
        points.push(("on a face", 0.2 * a + 0.3 * b + 0.5 * c));
        points.push(("on an edge", 0.35 * a + 0.65 * b));
        points.push(("on a vertex", c));
        points.push(("just inside", centroid - normal * 0.004 * size));
        points.push(("just outside", centroid + normal * 0.004 * size));
    }
    for k in 0..8 {
        let corner = Vector::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        );
        points.push(("far outside", corner + (corner - (lo + hi) * 0.5) * 1.5));
    }
    points
}

/// cbvh's projection `got` of `p` equals parry's `want`, or, when several
/// triangles are equally close (a shared vertex or edge), is the
/// projection on another of them: the triangle it names must then be as
/// close, and the point must be that triangle's own projection.
fn check_projection(
    t: &TriMesh,
    p: Vector,
    want: &PointProjection,
    got: &PointProjection,
    at: &str,
) {
    let tol = 1e-5 * (p.length() + 1.0);
    assert_eq!(
        want.is_inside, got.is_inside,
        "is_inside, {at}: parry {want:?} vs cbvh {got:?}"
    );
    if got.subshape == want.subshape {
        assert!(
            (want.point - got.point).length() <= tol,
            "point, {at}: parry {want:?} vs cbvh {got:?}"
        );
        return;
    }
    assert!(
        (got.subshape as usize) < t.indices().len(),
        "{at}: no triangle {}",
        got.subshape
    );
    let own = t.triangle(got.subshape).project_local_point(p, false).point;
    let (dw, dg) = ((want.point - p).length(), (own - p).length());
    assert!(
        (own - got.point).length() <= tol && (dw - dg).abs() <= tol,
        "{at}: parry {want:?} ({dw} away) vs cbvh {got:?}, whose triangle's own projection is \
         {own:?} ({dg} away)"
    );
}

/// `project_local_point` (solid or not) and
/// `project_local_point_and_get_feature` give parry's `TriMesh`'s answer:
/// the closest point (not a corner of the closest triangle), whether the
/// point is inside, the triangle (`PointProjection::subshape`) and the
/// triangle's feature the point lies on.
#[test]
fn point_projection_subshape_feature_and_is_inside_match_trimesh() {
    for (kind, seed) in [(Kind::Statue, 4), (Kind::Robot, 7)] {
        let mesh = mesh_of(kind, 1500, seed);
        for c in cbvh_shapes(&mesh) {
            // Against the mesh as the codec decodes it, probed on its own
            // surface: quantized codecs (hcc-ooc always) move vertices, so a
            // point on the input's surface is not on theirs, and tree-order
            // codecs renumber triangles.
            let decoded = c.codec().decoded_mesh();
            let t = parry_trimesh(&decoded).unwrap();
            let mut same_triangle = 0;
            let mut inside = 0;
            for (what, p) in probe_points(&decoded) {
                let at = format!("{:?}, {what} point {p:?}", c.codec());
                for solid in [false, true] {
                    let want = t.project_local_point(p, solid);
                    let got = c.project_local_point(p, solid);
                    check_projection(&t, p, &want, &got, &format!("{at}, solid {solid}"));
                    inside += usize::from(got.is_inside);
                }
                let (want, wf) = t.project_local_point_and_get_feature(p);
                let (got, gf) = c.project_local_point_and_get_feature(p);
                check_projection(&t, p, &want, &got, &at);
                let feature = if got.subshape == want.subshape {
                    same_triangle += 1;
                    wf
                } else {
                    let tri = t.triangle(got.subshape);
                    tri.project_local_point_and_get_feature(p).1
                };
                assert_eq!(
                    gf, feature,
                    "feature, {at}: parry {want:?} {wf:?}, cbvh {got:?}"
                );
                assert_ne!(gf, FeatureId::Unknown, "{at}");
                let d = c.distance_to_local_point(p, false);
                assert!(
                    (d - (want.point - p).length()).abs() <= 1e-5 * (p.length() + 1.0),
                    "distance, {at}: {d} vs {want:?}"
                );
            }
            // Most answers name parry's own triangle (the rest are ties),
            // and the points on the surface count as inside, as parry's do.
            assert!(same_triangle >= 64, "{:?}: {same_triangle}", c.codec());
            assert!(inside >= 2 * 3 * 24, "{:?}: {inside} inside", c.codec());
        }
    }
}

/// The inertia tensor of `m` about its centre of mass, in the local frame,
/// and its size (largest entry) for tolerances.
fn inertia(m: &parry3d::mass_properties::MassProperties) -> ([f32; 9], f32) {
    let t = m.reconstruct_inertia_matrix().to_cols_array();
    let size = t.iter().fold(0.0f32, |a, x| a.max(x.abs()));
    (t, size)
}

/// Mass, centre of mass and the full inertia tensor (principal inertia and
/// frame together) equal parry's `TriMesh`'s at density 1 and another
/// density. parry computes a `TriMesh`'s mass properties from its vertices
/// and triangles whatever its flags (`MassProperties::from_trimesh`, a
/// solid by signed volume), so the default flags are the right comparison.
#[test]
fn mass_properties_equal_trimesh() {
    for (kind, seed) in [(Kind::Statue, 2), (Kind::Robot, 3)] {
        let mesh = mesh_of(kind, 1500, seed);
        let t = parry_trimesh(&mesh).unwrap();
        for c in cbvh_shapes(&mesh) {
            for density in [1.0, 2.5, 0.3] {
                let at = format!("{kind:?}, {:?}, density {density}", c.codec());
                let (want, got) = (t.mass_properties(density), c.mass_properties(density));
                assert!(want.mass() > 0.0, "{at}: a solid");
                let rel = |a: f32, b: f32| (a - b).abs() <= 1e-4 * a.abs().max(b.abs());
                assert!(
                    rel(want.mass(), got.mass()),
                    "mass, {at}: {want:?} vs {got:?}"
                );
                assert!(
                    (want.local_com - got.local_com).length() <= 1e-5,
                    "centre of mass, {at}: {want:?} vs {got:?}"
                );
                let ((wt, size), (gt, _)) = (inertia(&want), inertia(&got));
                assert!(
                    wt.iter()
                        .zip(&gt)
                        .all(|(a, b)| (a - b).abs() <= 1e-4 * size),
                    "inertia tensor, {at}: parry {wt:?} vs cbvh {gt:?}"
                );
            }
        }
    }
}

/// A 2 × 1 × 0.5 box at density 3 against the closed-form solid box:
/// mass `ρ·a·b·c`, inertia `m(b² + c²)/12` and so on about the centre.
#[test]
fn mass_properties_of_a_box_are_a_solid_box() {
    let (a, b, c) = (2.0f32, 1.0f32, 0.5f32);
    let mesh = Mesh::cuboid([1.0, -3.0, 0.25], [a + 1.0, b - 3.0, c + 0.25]);
    for shape in cbvh_shapes(&mesh) {
        let density = 3.0;
        let m = shape.mass_properties(density);
        let mass = density * a * b * c;
        assert!((m.mass() - mass).abs() <= 1e-4 * mass, "{m:?}");
        let centre = Vector::new(1.0 + a / 2.0, -3.0 + b / 2.0, 0.25 + c / 2.0);
        assert!((m.local_com - centre).length() <= 1e-5, "{m:?}");
        let want = [
            mass * (b * b + c * c) / 12.0,
            mass * (a * a + c * c) / 12.0,
            mass * (a * a + b * b) / 12.0,
        ];
        let (got, _) = inertia(&m);
        for (i, row) in got.chunks(3).enumerate() {
            for (j, &x) in row.iter().enumerate() {
                let w = if i == j { want[i] } else { 0.0 };
                assert!(
                    (x - w).abs() <= 1e-4 * want[0],
                    "inertia [{i}][{j}] {x} vs {w}: {m:?}"
                );
            }
        }
    }
}
