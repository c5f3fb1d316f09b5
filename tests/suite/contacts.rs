//! cbvh's own contacts: the triangle-pair kernel against parry's
//! triangle-triangle queries, patch fidelity on static poses against parry's
//! per-pair contacts, both argument orders of every native pair, and bodies
//! that must come to rest in rapier with contact patches.

use std::collections::BTreeSet;

use cbvh::build::BuildOptions;
use cbvh::contact::orient::oriented_axis;
use cbvh::contact::{
    ContactSink, PairContact, PairKernel, PatchOptions, PatchSet, pair_contact, triangles_intersect,
};
use cbvh::geom::Triangle;
use cbvh::mesh::Mesh;
use cbvh::parry::{CbvhShape, ContactMode, Dispatcher, cbvh_cbvh, parry_trimesh, pose_from_parry};
use cbvh::scene::{Kind, generate};
use glam::Vec3A;
use parry3d::math::{Pose, Vector};
use parry3d::query::{
    ClosestPoints, ContactManifold, DefaultQueryDispatcher, PersistentQueryDispatcher,
};
use parry3d::shape::{Cuboid, Shape, SharedShape, TriMesh};
use proptest::prelude::*;
use rapier3d::prelude::{ColliderBuilder, NarrowPhase, PhysicsWorld, RigidBodyBuilder};

fn ptri(t: &Triangle) -> parry3d::shape::Triangle {
    let v = |p: Vec3A| Vector::new(p.x, p.y, p.z);
    parry3d::shape::Triangle::new(v(t[0]), v(t[1]), v(t[2]))
}

fn vec3(v: Vector) -> Vec3A {
    Vec3A::new(v.x, v.y, v.z)
}

/// The signed separation of two triangles along the unit axis `n` (from A
/// to B): how far B's projection starts past A's.
fn separation_along(a: &Triangle, b: &Triangle, n: Vec3A) -> f32 {
    let max_a = a.iter().map(|p| n.dot(*p)).fold(f32::MIN, f32::max);
    let min_b = b.iter().map(|p| n.dot(*p)).fold(f32::MAX, f32::min);
    min_b - max_a
}

/// Compares the kernel with parry on one pair. Returns whether the pair was
/// in contact.
fn check_pair(a: &Triangle, b: &Triangle, prediction: f32) -> Result<bool, TestCaseError> {
    let ours = pair_contact(a, b, prediction);
    let (ta, tb) = (ptri(a), ptri(b));
    let parry =
        parry3d::query::contact(&Pose::IDENTITY, &ta, &Pose::IDENTITY, &tb, prediction).unwrap();
    let size = a.iter().chain(b).map(|p| p.length()).fold(1.0f32, f32::max);
    let tol = 2e-4 * size;
    // Pairs within rounding of the prediction boundary may go either way.
    let exact = cbvh::contact::kernel::closest_points(a, b).2;
    let boundary =
        triangles_intersect(a, b) && prediction.abs() <= tol || (exact - prediction).abs() <= tol;
    match (&ours, &parry) {
        (Some(o), Some(p)) if p.dist > 0.0 && o.dist <= 0.0 && edges_cross(a, b) => {
            // Parry's GJK reports a hair of separation for a thin overlap
            // that an edge crossing the other triangle proves (seen at a
            // depth of 0.0014 against parry's +1.9e-5): ours must overlap.
            Ok(true)
        }
        (Some(o), Some(p)) => {
            prop_assert!(
                (o.dist - p.dist).abs() <= tol,
                "distance {} vs parry's {}",
                o.dist,
                p.dist
            );
            let pn = vec3(p.normal1);
            let angle = o.normal.dot(pn).clamp(-1.0, 1.0).acos().to_degrees();
            // Where two axes give the same depth the normal is ambiguous:
            // then parry's normal must give our depth too.
            let ambiguous = (separation_along(a, b, pn) - o.dist).abs() <= tol;
            prop_assert!(
                angle <= 1.0 || ambiguous || o.dist > 0.0 && (o.dist - p.dist).abs() <= tol,
                "normal {} vs parry's {} ({angle}°), dist {}",
                o.normal,
                pn,
                o.dist
            );
            if o.dist > 0.0 {
                // Separated: the closest points agree in distance.
                if let ClosestPoints::WithinMargin(p1, p2) = parry3d::query::closest_points(
                    &Pose::IDENTITY,
                    &ta,
                    &Pose::IDENTITY,
                    &tb,
                    prediction,
                )
                .unwrap()
                {
                    let d = (vec3(p2) - vec3(p1)).length();
                    prop_assert!((d - o.dist).abs() <= tol, "closest {d} vs {}", o.dist);
                }
            }
            Ok(true)
        }
        (None, None) => Ok(false),
        _ => {
            prop_assert!(
                boundary,
                "verdicts differ: ours {:?}, parry {:?}",
                ours.map(|o| o.dist),
                parry.map(|p| p.dist)
            );
            Ok(false)
        }
    }
}

/// Whether an edge of one triangle crosses the other triangle, in `f64`:
/// an oracle for "the triangles intersect" independent of both the kernel
/// and parry (strict crossings only, so it never claims a touching pair).
fn edges_cross(a: &Triangle, b: &Triangle) -> bool {
    let d = |v: Vec3A| [v.x as f64, v.y as f64, v.z as f64];
    let sub = |x: [f64; 3], y: [f64; 3]| [x[0] - y[0], x[1] - y[1], x[2] - y[2]];
    let dot = |x: [f64; 3], y: [f64; 3]| x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
    let cross = |x: [f64; 3], y: [f64; 3]| {
        [
            x[1] * y[2] - x[2] * y[1],
            x[2] * y[0] - x[0] * y[2],
            x[0] * y[1] - x[1] * y[0],
        ]
    };
    let seg_crosses = |p0: [f64; 3], p1: [f64; 3], t: [[f64; 3]; 3]| {
        let n = cross(sub(t[1], t[0]), sub(t[2], t[0]));
        let (d0, d1) = (dot(n, sub(p0, t[0])), dot(n, sub(p1, t[0])));
        if d0 * d1 >= 0.0 {
            return false;
        }
        let s = d0 / (d0 - d1);
        let x = [
            p0[0] + (p1[0] - p0[0]) * s,
            p0[1] + (p1[1] - p0[1]) * s,
            p0[2] + (p1[2] - p0[2]) * s,
        ];
        (0..3).all(|k| dot(n, cross(sub(t[(k + 1) % 3], t[k]), sub(x, t[k]))) > 0.0)
    };
    let (ta, tb) = (a.map(d), b.map(d));
    (0..3)
        .any(|k| seg_crosses(ta[k], ta[(k + 1) % 3], tb) || seg_crosses(tb[k], tb[(k + 1) % 3], ta))
}

fn triangle() -> impl Strategy<Value = Triangle> {
    prop::array::uniform9(-1.0f32..1.0).prop_map(|c| {
        [
            Vec3A::new(c[0], c[1], c[2]),
            Vec3A::new(c[3], c[4], c[5]),
            Vec3A::new(c[6], c[7], c[8]),
        ]
    })
}

fn area(t: &Triangle) -> f32 {
    (t[1] - t[0]).cross(t[2] - t[0]).length()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(600))]

    /// Random pairs, overlapping or apart.
    #[test]
    fn kernel_agrees_with_parry_on_random_pairs(
        a in triangle(),
        b in triangle(),
        shift in prop::array::uniform3(-1.5f32..1.5),
        prediction in 0.0f32..0.3,
    ) {
        prop_assume!(area(&a) > 1e-2 && area(&b) > 1e-2);
        let b = b.map(|p| p + Vec3A::from(shift));
        check_pair(&a, &b, prediction)?;
    }

    /// Near-touching pairs: B moved along the pair's normal to within ±2 %
    /// of contact, from either side.
    #[test]
    fn kernel_agrees_with_parry_on_near_touching_pairs(
        a in triangle(),
        b in triangle(),
        gap in -0.02f32..0.02,
        prediction in 0.0f32..0.05,
    ) {
        prop_assume!(area(&a) > 1e-2 && area(&b) > 1e-2);
        let Some(c) = pair_contact(&a, &b, 10.0) else {
            return Ok(());
        };
        let b = b.map(|p| p + c.normal * (gap - c.dist));
        check_pair(&a, &b, prediction)?;
    }
}

fn mesh_of(kind: Kind, tris: usize, seed: u64) -> Mesh {
    generate(kind, tris, seed, &mut |_, _| {}).expect("generate")
}

fn tri_of(m: &Mesh, i: u32) -> Triangle {
    m.triangle_vertices(i as usize).map(Vec3A::from)
}

fn moved(t: &Triangle, pose: &Pose) -> Triangle {
    t.map(|p| vec3(*pose * Vector::new(p.x, p.y, p.z)))
}

/// A closure as a kernel sink that takes every pair with its points.
struct Sink<'a, F: FnMut(&PairContact)>(&'a mut F);

impl<F: FnMut(&PairContact)> ContactSink for Sink<'_, F> {
    fn contact(&mut self, c: &PairContact) {
        (self.0)(c)
    }
}

/// Static poses of a statue against a turbine: resting, sliding,
/// interpenetrating. Every pair parry reports within the prediction that
/// the oriented rule accepts (an axis both triangles' features accept,
/// within the prediction: see `cbvh::contact::orient`) lies in a patch;
/// the deepest penetration is the deepest accepted pair's; patch normals
/// stand for their pairs; no manifold has more than four points.
#[test]
fn patches_cover_every_pair_parry_reports() {
    let statue = mesh_of(Kind::Statue, 3000, 3);
    let turbine = mesh_of(Kind::Turbine, 3000, 4);
    let (t1, t2) = (
        parry_trimesh(&statue).unwrap(),
        parry_trimesh(&turbine).unwrap(),
    );
    let c1 = CbvhShape::plain(&statue, &BuildOptions::default()).unwrap();
    let c2 = CbvhShape::plain(&turbine, &BuildOptions::default()).unwrap();
    let poses = [
        Pose::from_translation(Vector::new(0.0, -1.2, 0.0)),
        Pose::from_translation(Vector::new(0.7, -0.9, 0.3)),
        Pose::new(Vector::new(-0.4, -1.0, 0.2), Vector::new(0.3, 0.8, -0.2)),
        Pose::new(Vector::new(0.2, -0.5, -0.6), Vector::new(-1.0, 0.1, 0.5)),
    ];
    let opts = PatchOptions::default();
    let cos = opts.max_angle_deg.to_radians().cos();
    let mut covered = 0;
    for pos12 in poses {
        for prediction in [0.0, 0.02] {
            // parry's per-pair manifolds, and its exact deepest contact.
            let mut pm: Vec<ContactManifold<(), ()>> = Vec::new();
            DefaultQueryDispatcher
                .contact_manifolds(&pos12, &t1, &t2, prediction, &mut pm, &mut None)
                .unwrap();
            let facing = cbvh_cbvh::pair_facing(&pose_from_parry(&pos12), &c1, &c2);
            let oriented = |i: u32, j: u32| {
                let b = moved(&tri_of(&turbine, j), &pos12);
                let (fa, fb) = (c1.edge_flags_of(i), c2.edge_flags_of(j));
                oriented_axis(&tri_of(&statue, i), fa, &b, fb, &facing, prediction)
                    .filter(|o| o.sep <= prediction)
            };
            let parry_pairs: BTreeSet<(u32, u32)> = pm
                .iter()
                .filter(|m| m.points.iter().any(|p| p.dist <= prediction))
                .map(|m| (m.subshape1, m.subshape2))
                .filter(|&(i, j)| oriented(i, j).is_some())
                .collect();
            let parry_deepest = parry_pairs
                .iter()
                .filter_map(|&(i, j)| oriented(i, j).map(|o| o.sep))
                .fold(f32::INFINITY, f32::min);

            let set = cbvh_cbvh::patches(&pos12, &c1, &c2, &prediction, &opts, true, None);
            let members: BTreeSet<(u32, u32)> = set
                .patches
                .iter()
                .flat_map(|p| p.members.iter().copied())
                .collect();
            // Pairs of a patch dropped for pushing one region against a
            // kept patch's opposite normal (`PatchSet::drop_opposed`).
            let dropped: BTreeSet<(u32, u32)> = set
                .dropped
                .iter()
                .flat_map(|p| p.members.iter().copied())
                .collect();
            for d in &set.dropped {
                let cos = cbvh::contact::patch::OPPOSED_DEG.to_radians().cos();
                assert!(
                    set.patches
                        .iter()
                        .any(|k| -k.normal.dot(d.normal) >= cos && k.bounds.intersects(&d.bounds)),
                    "a dropped patch opposes no kept one at {pos12:?}"
                );
            }
            let missing: Vec<_> = parry_pairs
                .difference(&members)
                .filter(|k| !dropped.contains(k))
                .collect();
            assert!(
                missing.is_empty(),
                "{} of {} parry pairs in no patch at {pos12:?}, e.g. {:?}",
                missing.len(),
                parry_pairs.len(),
                &missing[..missing.len().min(5)]
            );
            covered += parry_pairs.len();
            if parry_pairs.is_empty() {
                continue;
            }
            let ours = set
                .patches
                .iter()
                .chain(&set.dropped)
                .map(|p| p.deepest.dist)
                .fold(f32::INFINITY, f32::min);
            assert!(
                (ours - parry_deepest).abs() <= 1e-4 * parry_deepest.abs().max(1e-2),
                "deepest {ours} vs parry's {parry_deepest} at {pos12:?}"
            );
            for p in &set.patches {
                for &(i, j) in &p.members {
                    let b = moved(&tri_of(&turbine, j), &pos12);
                    // The normal the patch mode's kernel gave the pair (it
                    // takes the separating-axis bound for separated pairs).
                    let mut kernel = PairKernel::new(prediction)
                        .exact_separation(false)
                        .oriented(Some(facing));
                    let mut c = None;
                    let mut sink = |x: &cbvh::contact::PairContact| c = Some(*x);
                    let (fa, fb) = (c1.edge_flags_of(i), c2.edge_flags_of(j));
                    kernel.push_flagged(
                        (i, &tri_of(&statue, i), fa),
                        (j, &b, fb),
                        prediction,
                        &mut Sink(&mut sink),
                    );
                    kernel.flush_into(&mut Sink(&mut sink));
                    let c = c.unwrap();
                    assert!(
                        c.normal.dot(p.normal) >= cos - 1e-6,
                        "pair ({i}, {j}) normal {} vs patch {}",
                        c.normal,
                        p.normal
                    );
                }
            }
            // The manifolds rapier gets: one per patch, at most 4 points.
            let mut ms: Vec<ContactManifold<(), ()>> = Vec::new();
            Dispatcher::default()
                .contact_manifolds(&pos12, &c1, &c2, prediction, &mut ms, &mut None)
                .unwrap();
            assert_eq!(ms.len(), set.patches.len());
            assert!(
                ms.iter()
                    .all(|m| !m.points.is_empty() && m.points.len() <= 4)
            );
            assert!(
                ms.len() <= parry_pairs.len(),
                "{} manifolds for {} pairs",
                ms.len(),
                parry_pairs.len()
            );
        }
    }
    assert!(covered > 50, "the poses must produce contacts: {covered}");
    assert!(!c1.fallback_bvh_built() && !c2.fallback_bvh_built());
}

/// A patch set takes the pairs interior to a patch without their points
/// (`ContactSink::absorb`); the patches it gives rapier are the same as when
/// it gets every pair's points: same normals, deepest points, reduced points
/// and member pairs. A fine statue pressed into a fine flat mesh, where many
/// pairs are interior.
#[test]
fn absorbed_pairs_do_not_change_the_patches() {
    let statue = mesh_of(Kind::Statue, 20_000, 7);
    let floor = grid(160, 2.0);
    let c1 = CbvhShape::plain(&floor, &BuildOptions::default()).unwrap();
    let c2 = CbvhShape::plain(&statue, &BuildOptions::default()).unwrap();
    // The statue's lowest point 2 mm below the floor's plane.
    let low = statue
        .vertices
        .iter()
        .map(|v| v[1])
        .fold(f32::INFINITY, f32::min);
    let pos12 = Pose::from_translation(Vector::new(0.05, -low - 0.002, -0.03));
    let prediction = 0.01;
    let opts = PatchOptions::default();
    let size = 1.0;
    let mut all = PatchSet::new(&opts, size, true);
    let mut summary = PatchSet::new(&opts, size, true);
    let mut k_all = PairKernel::new(prediction).exact_separation(false);
    let mut k_sum = PairKernel::new(prediction).exact_separation(false);
    let mut stats = cbvh::TraversalStats::default();
    cbvh_cbvh::for_each_pair(&c1, &c2, &pos12, prediction, &mut stats, |i, a, j, b| {
        let b = moved(b, &pos12);
        k_all.push(i, a, j, &b, &mut |c| all.add(c));
        k_sum.push_into(i, a, j, &b, &mut summary);
        std::ops::ControlFlow::Continue(())
    });
    k_all.flush(&mut |c| all.add(c));
    k_sum.flush_into(&mut summary);
    assert_eq!(k_all.stats.contacts, k_sum.stats.contacts);
    assert_eq!(k_all.stats.absorbed, 0);
    assert!(
        k_sum.stats.absorbed * 10 > k_sum.stats.contacts,
        "interior pairs are absorbed: {} of {}",
        k_sum.stats.absorbed,
        k_sum.stats.contacts
    );
    let view = |s: &PatchSet| {
        s.patches
            .iter()
            .map(|p| {
                let (pts, n) = p.reduced();
                let mut members = p.members.clone();
                members.sort_unstable();
                (
                    p.normal.to_array(),
                    p.pairs,
                    members,
                    pts[..n]
                        .iter()
                        .map(|q| (q.p1.to_array(), q.p2.to_array(), q.dist, q.i, q.j))
                        .collect::<Vec<_>>(),
                )
            })
            .collect::<Vec<_>>()
    };
    let (a, b) = (view(&all), view(&summary));
    assert!(!a.is_empty());
    assert_eq!(a, b);
}

/// The patch set does not depend on the thread count.
#[test]
fn patches_do_not_depend_on_the_thread_count() {
    let statue = mesh_of(Kind::Statue, 4000, 5);
    let turbine = mesh_of(Kind::Turbine, 4000, 6);
    let c1 = CbvhShape::plain(&statue, &BuildOptions::default()).unwrap();
    let c2 = CbvhShape::plain(&turbine, &BuildOptions::default()).unwrap();
    let pos12 = Pose::from_translation(Vector::new(0.1, -1.1, 0.05));
    let run = |threads| {
        crate::common::in_pool(threads, || {
            let s = cbvh_cbvh::patches(
                &pos12,
                &c1,
                &c2,
                &0.01,
                &PatchOptions::default(),
                true,
                None,
            );
            s.patches
                .iter()
                .map(|p| {
                    let (pts, n) = p.reduced();
                    (
                        p.normal.to_array(),
                        p.members.clone(),
                        pts[..n]
                            .iter()
                            .map(|q| (q.p1.to_array(), q.dist))
                            .collect::<Vec<_>>(),
                    )
                })
                .collect::<Vec<_>>()
        })
    };
    let one = run(1);
    assert!(!one.is_empty());
    assert_eq!(one, run(2));
    assert_eq!(one, run(3));
}

/// Under a motion bound, a pair's prediction comes from its own triangle's
/// box, not from the leaf it sits in: the plain, hcc and clbvh trees (one
/// triangle a leaf, small leaves, eight-wide leaves of quantized boxes)
/// find the same contact pairs, so a body rolls the same on each. With
/// the leaf's box, CLBVH's larger leaves let pairs up to the whole
/// prediction in, and an icosphere rolled 12 % below 5/7 g sin θ on it
/// against 8 % on plain.
#[test]
fn every_codec_finds_the_same_pairs_under_a_motion_bound() {
    use cbvh::codec::{AnyOptions, CodecKind};
    use cbvh::contact::MotionBound;
    let statue = mesh_of(Kind::Statue, 6000, 5);
    let turbine = mesh_of(Kind::Turbine, 6000, 6);
    let shape = |m: &Mesh, k| {
        CbvhShape::build(m, &BuildOptions::default(), k, &AnyOptions::default()).unwrap()
    };
    let now = Pose::from_parts(
        Vector::new(0.1, -1.1, 0.05),
        parry3d::math::Rotation::from_rotation_y(0.3),
    );
    let last = Pose::from_parts(
        Vector::new(0.1, -1.09, 0.05),
        parry3d::math::Rotation::from_rotation_y(0.297),
    );
    let bound = MotionBound::new(
        0.05,
        &pose_from_parry(&now),
        &pose_from_parry(&last),
        2.0,
        0.002,
    );
    let pairs = |kind, prediction: &dyn Fn(&CbvhShape, &CbvhShape) -> cbvh::contact::PatchSet| {
        let (c1, c2) = (shape(&statue, kind), shape(&turbine, kind));
        let set = prediction(&c1, &c2);
        set.patches
            .iter()
            .flat_map(|p| p.members.iter().copied())
            .collect::<BTreeSet<(u32, u32)>>()
    };
    let opts = PatchOptions::default();
    let bounded =
        |a: &CbvhShape, b: &CbvhShape| cbvh_cbvh::patches(&now, a, b, &bound, &opts, true, None);
    let constant =
        |a: &CbvhShape, b: &CbvhShape| cbvh_cbvh::patches(&now, a, b, &0.05f32, &opts, true, None);
    let plain = pairs(CodecKind::Plain, &bounded);
    let all = pairs(CodecKind::Plain, &constant);
    assert!(
        plain.len() > 20,
        "the pose must give contacts: {}",
        plain.len()
    );
    assert!(
        plain.len() < all.len(),
        "the motion bound must cut pairs the constant prediction keeps: {} of {}",
        plain.len(),
        all.len()
    );
    for kind in [CodecKind::Hcc, CodecKind::Clbvh] {
        assert_eq!(pairs(kind, &bounded), plain, "{kind:?}");
    }
}

type Flat = Vec<(u32, u32, [f32; 3], [f32; 3], f32)>;

fn flat(ms: &[ContactManifold<(), ()>], swap: bool) -> Flat {
    let mut v: Flat = ms
        .iter()
        .flat_map(|m| {
            m.points.iter().map(move |p| {
                let (a, b) = (p.local_p1.to_array(), p.local_p2.to_array());
                if swap {
                    (m.subshape2, m.subshape1, b, a, p.dist)
                } else {
                    (m.subshape1, m.subshape2, a, b, p.dist)
                }
            })
        })
        .collect();
    v.sort_by(|x, y| x.partial_cmp(y).unwrap());
    v
}

fn manifolds(
    d: &Dispatcher,
    pos12: &Pose,
    g1: &dyn Shape,
    g2: &dyn Shape,
) -> Vec<ContactManifold<(), ()>> {
    let mut ms = Vec::new();
    d.clone()
        .then_default()
        .contact_manifolds(pos12, g1, g2, 0.01, &mut ms, &mut None)
        .unwrap();
    ms
}

fn deepest(ms: &[ContactManifold<(), ()>]) -> f32 {
    ms.iter()
        .flat_map(|m| &m.points)
        .map(|p| p.dist)
        .fold(f32::INFINITY, f32::min)
}

/// Manifolds of `(g1, g2)` and of `(g2, g1)` describe the same patches: the
/// same deepest distance, and every normal of one order (in shape 1's
/// frame) has an opposite counterpart in the other within a degree.
fn assert_same_patches(
    ab: &[ContactManifold<(), ()>],
    ba: &[ContactManifold<(), ()>],
    pos12: &Pose,
    what: &str,
) {
    assert!(
        (deepest(ab) - deepest(ba)).abs() < 1e-5,
        "{what}: deepest {} vs {}",
        deepest(ab),
        deepest(ba)
    );
    assert!(
        ab.len().abs_diff(ba.len()) <= 1,
        "{what}: {} vs {} patches",
        ab.len(),
        ba.len()
    );
    let cos1 = 1f32.to_radians().cos();
    for m in ab {
        assert!(
            ba.iter()
                .any(|n| (pos12.rotation * n.local_n1).dot(-m.local_n1) >= cos1),
            "{what}: normal {:?} has no counterpart",
            m.local_n1
        );
        assert!(m.points.len() <= 4);
    }
}

/// Every native pair in both argument orders, in both modes: the same
/// contacts with the roles swapped (for cbvh against cbvh, where the two
/// orders run the kernel from different sides, the same deepest point and
/// normals opposite).
#[test]
fn both_argument_orders_give_the_same_contacts() {
    let floor = grid(16, 2.0);
    let cf = CbvhShape::plain(&floor, &BuildOptions::default()).unwrap();
    let tf: TriMesh = parry_trimesh(&floor).unwrap();
    let boxm = box_mesh([0.3, 0.2, 0.25]);
    let cb = CbvhShape::plain(&boxm, &BuildOptions::default()).unwrap();
    let cuboid = Cuboid::new(Vector::new(0.3, 0.2, 0.25));
    // Shape 2 sunk 0.01 into the floor, turned and moved off the origin.
    let pos12 = Pose::new(Vector::new(0.13, 0.19, -0.07), Vector::new(0.0, 0.4, 0.0));
    let inv = pos12.inverse();
    for d in [
        Dispatcher::default(),
        Dispatcher::new(ContactMode::PerTrianglePair),
    ] {
        for (name, other) in [
            ("cuboid", &cuboid as &dyn Shape),
            ("trimesh", &tf as &dyn Shape),
        ] {
            let g2: &dyn Shape = if name == "cuboid" { other } else { &cb };
            let g1: &dyn Shape = if name == "cuboid" { &cf } else { other };
            let ab = manifolds(&d, &pos12, g1, g2);
            let ba = manifolds(&d, &inv, g2, g1);
            assert!(!ab.is_empty(), "{name} {:?}: no contact", d.mode);
            if d.mode != ContactMode::PerTrianglePair {
                // Patches: the inverse pose rounds differently, which may
                // move a pair across a patch boundary; the deepest point and
                // the patch normals agree.
                assert_same_patches(&ab, &ba, &pos12, name);
                continue;
            }
            // One manifold per pair: the same pairs and the same deepest
            // point (parry's clipping picks its reference face by argument
            // order, so the other points may differ).
            let keys = |v: &Flat| v.iter().map(|p| (p.0, p.1)).collect::<BTreeSet<_>>();
            let (x, y) = (flat(&ab, false), flat(&ba, true));
            assert_eq!(keys(&x), keys(&y), "{name}");
            assert!((deepest(&ab) - deepest(&ba)).abs() < 1e-5, "{name}");
        }
        // cbvh against cbvh.
        let ab = manifolds(&d, &pos12, &cf, &cb);
        let ba = manifolds(&d, &inv, &cb, &cf);
        assert!(!ab.is_empty() && !ba.is_empty());
        assert!(
            (deepest(&ab) - deepest(&ba)).abs() < 1e-5,
            "{} vs {}",
            deepest(&ab),
            deepest(&ba)
        );
        // The deepest contact's normal is the floor's, pointing up at the
        // box, in both orders (pairs at the rim of the contact region may
        // have sideways normals: their least overlap is sideways).
        let deepest_normal = |ms: &[ContactManifold<(), ()>]| {
            ms.iter()
                .min_by(|x, y| {
                    deepest(std::slice::from_ref(*x)).total_cmp(&deepest(std::slice::from_ref(*y)))
                })
                .map(|m| m.local_n1)
                .unwrap()
        };
        assert!(deepest_normal(&ab).y > 0.99, "{:?}", deepest_normal(&ab));
        assert!((pos12.rotation * deepest_normal(&ba)).y < -0.99);
    }
}

/// A flat `n × n` grid of `2n²` triangles over `[-w/2, w/2]²` at y = 0,
/// facing up.
fn grid(n: u32, w: f32) -> Mesh {
    let mut v = Vec::new();
    for z in 0..=n {
        for x in 0..=n {
            v.push([
                w * (x as f32 / n as f32 - 0.5),
                0.0,
                w * (z as f32 / n as f32 - 0.5),
            ]);
        }
    }
    let mut t = Vec::new();
    let at = |x: u32, z: u32| z * (n + 1) + x;
    for z in 0..n {
        for x in 0..n {
            t.push([at(x, z), at(x, z + 1), at(x + 1, z)]);
            t.push([at(x + 1, z), at(x, z + 1), at(x + 1, z + 1)]);
        }
    }
    Mesh::new(v, t)
}

/// A closed box mesh (12 triangles, outward) with half extents `h`,
/// centred at the origin.
fn box_mesh(h: [f32; 3]) -> Mesh {
    Mesh::cuboid([-h[0], -h[1], -h[2]], h)
}

/// Drops `body` (a collider builder for a dynamic body) flat from 0.05
/// above `floor` (top at y = 0) and steps 300 times at 60 Hz with the
/// default (patch) dispatcher. Returns (tilt in degrees, horizontal drift,
/// final speed, final height, the floor's fallback flag).
fn drop_flat(floor: SharedShape, body: ColliderBuilder, half_height: f32) -> (f32, f32, f32, f32) {
    let mut world = PhysicsWorld {
        narrow_phase: NarrowPhase::with_query_dispatcher(Dispatcher::chained()),
        ..Default::default()
    };
    world.colliders.insert(ColliderBuilder::new(floor));
    let h = world.bodies.insert(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(0.0, half_height + 0.05, 0.0))
            .can_sleep(false),
    );
    world
        .colliders
        .insert_with_parent(body, h, &mut world.bodies);
    for _ in 0..300 {
        world.step();
    }
    let b = &world.bodies[h];
    let up = b.rotation() * Vector::Y;
    let tilt = up.y.clamp(-1.0, 1.0).acos().to_degrees();
    let t = b.translation();
    let drift = (t.x * t.x + t.z * t.z).sqrt();
    (tilt, drift, b.linvel().length(), t.y)
}

fn assert_rests_flat(what: &str, r: (f32, f32, f32, f32), size: f32, half_height: f32) {
    let (tilt, drift, speed, y) = r;
    assert!(tilt < 1.0, "{what}: tilted {tilt}°");
    assert!(drift < 0.01 * size, "{what}: drifted {drift}");
    assert!(speed < 1e-3, "{what}: still moving at {speed}");
    assert!(
        (y - half_height).abs() < 0.02 * size,
        "{what}: rests at {y}, expected {half_height}"
    );
}

#[test]
fn a_box_mesh_rests_flat_on_a_fine_flat_mesh() {
    let floor = CbvhShape::plain(&grid(48, 3.0), &BuildOptions::default()).unwrap();
    let boxm = CbvhShape::plain(&box_mesh([0.4, 0.15, 0.3]), &BuildOptions::default()).unwrap();
    let r = drop_flat(
        SharedShape::new(floor.clone()),
        ColliderBuilder::new(SharedShape::new(boxm.clone())),
        0.15,
    );
    assert_rests_flat("box mesh on a fine mesh", r, 0.8, 0.15);
    assert!(!floor.fallback_bvh_built() && !boxm.fallback_bvh_built());
}

#[test]
fn a_box_mesh_rests_flat_on_a_box_mesh() {
    let mut base = box_mesh([1.5, 0.1, 1.5]);
    for v in &mut base.vertices {
        v[1] -= 0.1;
    }
    let floor = CbvhShape::plain(&base, &BuildOptions::default()).unwrap();
    let boxm = CbvhShape::plain(&box_mesh([0.4, 0.15, 0.3]), &BuildOptions::default()).unwrap();
    let r = drop_flat(
        SharedShape::new(floor),
        ColliderBuilder::new(SharedShape::new(boxm)),
        0.15,
    );
    assert_rests_flat("box mesh on a box mesh", r, 0.8, 0.15);
}

#[test]
fn a_convex_cuboid_rests_flat_on_a_fine_flat_mesh() {
    let floor = CbvhShape::plain(&grid(48, 3.0), &BuildOptions::default()).unwrap();
    let r = drop_flat(
        SharedShape::new(floor),
        ColliderBuilder::cuboid(0.4, 0.15, 0.3),
        0.15,
    );
    assert_rests_flat("cuboid on a fine mesh", r, 0.8, 0.15);
}

/// Friction holds on a slope: a box mesh placed on a fine mesh tilted by
/// 20° (tan 20° = 0.36, below the friction coefficient 0.6) stays where it
/// was put, with patches as with parry's own meshes.
#[test]
fn friction_holds_a_box_mesh_on_a_slope() {
    let slope = 20f32.to_radians();
    let rot = glam::Quat::from_rotation_z(slope);
    let tilt = |m: &mut Mesh| {
        for v in &mut m.vertices {
            *v = (rot * glam::Vec3::from(*v)).to_array();
        }
    };
    let mut floor = grid(48, 3.0);
    tilt(&mut floor);
    let run = |floor_shape: SharedShape, body: SharedShape, d: Dispatcher| {
        let mut world = PhysicsWorld {
            narrow_phase: NarrowPhase::with_query_dispatcher(d.then_default()),
            ..Default::default()
        };
        world
            .colliders
            .insert(ColliderBuilder::new(floor_shape).friction(0.6));
        let up = rot * glam::Vec3::Y;
        let start = up * 0.151;
        let h = world.bodies.insert(
            RigidBodyBuilder::dynamic()
                .translation(Vector::new(start.x, start.y, start.z))
                .rotation(Vector::new(0.0, 0.0, slope))
                .can_sleep(false),
        );
        world.colliders.insert_with_parent(
            ColliderBuilder::new(body).friction(0.6),
            h,
            &mut world.bodies,
        );
        for _ in 0..240 {
            world.step();
        }
        let t = world.bodies[h].translation();
        (vec3(t) - Vec3A::from(start)).length()
    };
    let boxm = box_mesh([0.4, 0.15, 0.3]);
    let floor_c = SharedShape::new(CbvhShape::plain(&floor, &BuildOptions::default()).unwrap());
    let box_c = SharedShape::new(CbvhShape::plain(&boxm, &BuildOptions::default()).unwrap());
    let patches = run(floor_c.clone(), box_c.clone(), Dispatcher::default());
    let pairs = run(
        floor_c,
        box_c,
        Dispatcher::new(ContactMode::PerTrianglePair),
    );
    let parry = run(
        SharedShape::new(parry_trimesh(&floor).unwrap()),
        SharedShape::new(parry_trimesh(&boxm).unwrap()),
        Dispatcher::default(),
    );
    assert!(
        patches < 0.02 && pairs < 0.02 && parry < 0.02,
        "moved on the slope: patches {patches}, pairs {pairs}, parry {parry}"
    );
}
