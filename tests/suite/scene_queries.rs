//! rapier's scene queries (`QueryPipeline`, from the broad phase) on a
//! world whose one collider is a cbvh shape, every codec, against an exact
//! reference: a loop over the shape's own triangles (`parry3d`'s
//! `Triangle`, in the collider's frame) with parry's per-triangle queries,
//! taking the smallest time of impact, the smallest distance, or any
//! intersection. The mesh is a generated scanned statue of a few thousand
//! triangles, posed off the origin and rotated. A parry `TriMesh` of the
//! same triangles runs the same queries, as what a user would otherwise
//! have, and is held to the same reference.
//!
//! Every query is one of a few hundred seeded random ones; the hit counts
//! are asserted to be substantial so that a query answering nothing
//! fails, and any disagreement with the reference is listed and fails.
//! The reference of the scenes of the same triangles (every codec that
//! keeps the mesh's corners, and the `TriMesh`) is computed once.
//!
//! parry's own per-triangle linear cast sometimes answers a time at which
//! the shapes are still millimetres apart (a cube cast at the 12 000
//! triangle statue, `stop_at_penetration: false`: 2 casts in 1 500). The
//! linear reference visits the triangles in the order the swept boxes
//! meet and stops past its best hit, so such a triangle seldom answers
//! it; when cbvh (or the `TriMesh`) answers one, the test checks that the
//! plain minimum over the triangles gives the same time and lists it as
//! parry's (this is issue 49's one clbvh disagreement in 1 500 cube
//! casts).

use std::collections::HashMap;
use std::fmt::Write as _;

use cbvh::Mesh;
use cbvh::build::BuildOptions;
use cbvh::codec::racbvh::RacOptions;
use cbvh::codec::{AnyOptions, CodecKind};
use cbvh::parry::{CbvhShape, Dispatcher};
use cbvh::scene::{Kind, generate};
use parry3d::bounding_volume::{Aabb, BoundingVolume};
use parry3d::math::{Pose, Real, Vector};
use parry3d::query::{
    DefaultQueryDispatcher, NonlinearRigidMotion, PointQuery, QueryDispatcher, Ray, RayCast,
    ShapeCastHit, ShapeCastOptions, ShapeCastStatus,
};
use parry3d::shape::{Ball, Capsule, Cuboid, FeatureId, Shape, SharedShape, TriMesh, Triangle};
use rapier3d::prelude::{
    ColliderBuilder, ColliderHandle, NarrowPhase, PhysicsWorld, QueryFilter, QueryPipeline,
};

use crate::common::Rng;

/// The "scanned" statue every test queries: ~3000 triangles.
fn statue() -> Mesh {
    generate(Kind::Statue, 3000, 21, &mut |_, _| {}).expect("generate")
}

/// Every codec of the registry, RACBVH with its default (16-bit) vertices:
/// the reference is each shape's own triangles, so quantized corners are
/// the geometry under test.
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

fn triangles_of(shape: &CbvhShape) -> Vec<Triangle> {
    (0..shape.triangle_count() as u32)
        .map(|id| shape.parry_triangle(id))
        .collect()
}

/// A parry `TriMesh` of a triangle soup, triangle `i` being `tris[i]`.
fn soup_trimesh(tris: &[Triangle]) -> TriMesh {
    let vertices = tris.iter().flat_map(|t| [t.a, t.b, t.c]).collect();
    let indices = (0..tris.len() as u32)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    TriMesh::new(vertices, indices).unwrap()
}

/// Where the statue's collider sits: off the origin and turned, so that
/// every query crosses a frame change.
fn collider_pose() -> Pose {
    Pose::new(Vector::new(1.5, -0.7, 2.0), Vector::new(0.3, -0.5, 0.2))
}

/// A world with one fixed collider, cbvh's dispatcher installed as rapier
/// users install it, stepped once so that the broad phase holds the
/// collider.
struct Scene {
    name: String,
    world: PhysicsWorld,
    handle: ColliderHandle,
    /// The cbvh shape, when the collider is one (for the fallback check).
    cbvh: Option<CbvhShape>,
}

impl Scene {
    fn new(name: String, shape: SharedShape, cbvh: Option<CbvhShape>) -> Self {
        let mut world = PhysicsWorld {
            narrow_phase: NarrowPhase::with_query_dispatcher(Dispatcher::default().then_default()),
            ..Default::default()
        };
        let handle = world
            .colliders
            .insert(ColliderBuilder::new(shape).position(collider_pose()));
        world.step();
        Self {
            name,
            world,
            handle,
            cbvh,
        }
    }

    fn queries(&self) -> QueryPipeline<'_> {
        self.world.broad_phase.as_query_pipeline(
            self.world.narrow_phase.query_dispatcher(),
            &self.world.bodies,
            &self.world.colliders,
            QueryFilter::default(),
        )
    }

    /// The compatibility `Bvh` was never built: every query ran natively.
    fn assert_native(&self) {
        if let Some(c) = &self.cbvh {
            assert!(!c.fallback_bvh_built(), "{}: fallback Bvh built", self.name);
        }
    }
}

/// Each codec's scene with its triangles, then parry's `TriMesh` of the
/// plain codec's triangles (the last entry, `cbvh: None`).
fn scenes(mesh: &Mesh) -> Vec<(Scene, Vec<Triangle>)> {
    let mut out: Vec<(Scene, Vec<Triangle>)> = all_codecs(mesh)
        .into_iter()
        .map(|s| {
            let tris = triangles_of(&s);
            let name = s.codec().name().to_string();
            (Scene::new(name, SharedShape::new(s.clone()), Some(s)), tris)
        })
        .collect();
    let tris = out[0].1.clone();
    out.push((
        Scene::new(
            "parry TriMesh".into(),
            SharedShape::new(soup_trimesh(&tris)),
            None,
        ),
        tris,
    ));
    out
}

/// The exact answers: parry's queries on each triangle of the collider,
/// posed as the collider is.
struct Reference<'a> {
    pose: Pose,
    tris: &'a [Triangle],
    /// Each triangle's box, in the collider's frame (to skip triangles a
    /// query cannot reach; the boxes are loosened so that this is exact).
    boxes: Vec<Aabb>,
}

impl<'a> Reference<'a> {
    fn new(tris: &'a [Triangle]) -> Self {
        Self {
            pose: collider_pose(),
            tris,
            boxes: tris.iter().map(|t| t.compute_local_aabb()).collect(),
        }
    }

    /// The triangles whose box meets `local` (a box in the collider's frame).
    fn near(&self, local: &Aabb) -> impl Iterator<Item = &Triangle> {
        self.tris
            .iter()
            .zip(&self.boxes)
            .filter(move |(_, b)| b.intersects(local))
            .map(|(t, _)| t)
    }

    /// Smallest time of impact of `ray`, with the normals of the triangles
    /// hit at that time (within `tol`).
    fn ray(&self, ray: &Ray, max_toi: Real, solid: bool, tol: Real) -> Option<(Real, Vec<Vector>)> {
        let hits: Vec<_> = self
            .tris
            .iter()
            .filter_map(|t| t.cast_ray_and_get_normal(&self.pose, ray, max_toi, solid))
            .collect();
        let min = hits
            .iter()
            .map(|h| h.time_of_impact)
            .min_by(f32::total_cmp)?;
        let normals = hits
            .iter()
            .filter(|h| h.time_of_impact <= min + tol)
            .map(|h| h.normal)
            .collect();
        Some((min, normals))
    }

    /// Smallest distance from `p` to a triangle's projection, with the
    /// feature of each triangle at that distance (within `tol`).
    fn project(&self, p: Vector, solid: bool, tol: Real) -> (Real, Vec<FeatureId>) {
        let d: Vec<(Real, FeatureId)> = self
            .tris
            .iter()
            .map(|t| {
                let pr = t.project_point(&self.pose, p, solid);
                let (_, f) = t.project_point_and_get_feature(&self.pose, p);
                ((pr.point - p).length(), f)
            })
            .collect();
        let min = d.iter().map(|x| x.0).min_by(f32::total_cmp).unwrap();
        let features = d.iter().filter(|x| x.0 <= min + tol).map(|x| x.1).collect();
        (min, features)
    }

    fn contains(&self, p: Vector) -> bool {
        self.tris
            .iter()
            .any(|t| PointQuery::contains_point(t, &self.pose, p))
    }

    /// Whether `shape` at `pos` intersects any triangle, and the smallest
    /// distance to one (to tell a grazing disagreement from a wrong one).
    fn intersects(&self, pos: &Pose, shape: &dyn Shape, margin: Real) -> (bool, Real) {
        let local = shape.compute_aabb(&self.pose.inv_mul(pos)).loosened(margin);
        let pos12 = pos.inv_mul(&self.pose);
        let mut dist = Real::MAX;
        for t in self.near(&local) {
            if DefaultQueryDispatcher
                .intersection_test(&pos12, shape, t)
                .unwrap()
                .intersecting
            {
                return (true, 0.0);
            }
            dist = dist.min(
                DefaultQueryDispatcher
                    .distance(&pos12, shape, t)
                    .unwrap()
                    .distance,
            );
        }
        (false, dist)
    }

    /// The smallest signed distance from `shape` at `pos` to a triangle
    /// (negative: the depth of the deepest penetration), within `reach`.
    fn signed_distance(&self, pos: &Pose, shape: &dyn Shape, reach: Real) -> Real {
        let local = shape.compute_aabb(&self.pose.inv_mul(pos)).loosened(reach);
        let pos12 = pos.inv_mul(&self.pose);
        self.near(&local)
            .filter_map(|t| {
                DefaultQueryDispatcher
                    .contact(&pos12, shape, t, reach)
                    .unwrap()
            })
            .map(|c| c.dist)
            .fold(reach, Real::min)
    }

    /// Whether a triangle's box (world frame) meets `aabb`.
    fn any_box_meets(&self, aabb: &Aabb) -> bool {
        self.tris
            .iter()
            .any(|t| t.compute_aabb(&self.pose).intersects(aabb))
    }

    /// Smallest time of impact of a linear cast, as the query pipeline
    /// poses it: the triangle is shape 1, the cast shape shape 2.
    ///
    /// The triangles are cast in the order their boxes are first reached
    /// by the moving shape's box (loosened by the target distance and
    /// `margin`), and the loop stops once that time passes the best hit:
    /// a shape cannot come within the target distance of a triangle
    /// before its loosened box meets the triangle's box (the shape only
    /// translates), so the answer is the minimum over every triangle.
    fn cast(
        &self,
        pos: &Pose,
        vel: Vector,
        shape: &dyn Shape,
        options: ShapeCastOptions,
        margin: Real,
    ) -> Option<ShapeCastHit> {
        let pos12 = self.pose.inv_mul(pos);
        let vel12 = self.pose.rotation.inverse() * vel;
        let start = shape
            .compute_aabb(&pos12)
            .loosened(options.target_distance + margin);
        // When the box moving from `start` with `vel12` first meets `b`.
        let entry = |b: &Aabb| -> Option<Real> {
            let (mut t0, mut t1): (Real, Real) = (0.0, options.max_time_of_impact);
            for k in 0..3 {
                let (lo, hi) = (b.mins[k] - start.maxs[k], b.maxs[k] - start.mins[k]);
                let v = vel12[k];
                if v == 0.0 {
                    if lo > 0.0 || hi < 0.0 {
                        return None;
                    }
                } else {
                    let (a, c) = (lo / v, hi / v);
                    t0 = t0.max(a.min(c));
                    t1 = t1.min(a.max(c));
                }
            }
            (t0 <= t1).then_some(t0)
        };
        let mut order: Vec<(Real, &Triangle)> = self
            .tris
            .iter()
            .zip(&self.boxes)
            .filter_map(|(t, b)| Some((entry(b)?, t)))
            .collect();
        order.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut best: Option<ShapeCastHit> = None;
        for (reach, t) in order {
            if best.is_some_and(|b| b.time_of_impact < reach) {
                break;
            }
            let hit = DefaultQueryDispatcher
                .cast_shapes(&pos12, vel12, t, shape, options)
                .unwrap();
            if let Some(h) = hit
                && best.is_none_or(|b| h.time_of_impact < b.time_of_impact)
            {
                best = Some(h);
            }
        }
        best
    }

    /// The plain minimum of parry's per-triangle casts over every triangle
    /// whose box the swept shape's box meets: what a loop over the
    /// triangles without [`Reference::cast`]'s stop answers, parry's false
    /// early hits included.
    fn cast_exhaustive(
        &self,
        pos: &Pose,
        vel: Vector,
        shape: &dyn Shape,
        options: ShapeCastOptions,
        margin: Real,
    ) -> Option<ShapeCastHit> {
        let pos12 = self.pose.inv_mul(pos);
        let vel12 = self.pose.rotation.inverse() * vel;
        let start = shape.compute_aabb(&pos12);
        let mut end = start;
        end.mins += vel12 * options.max_time_of_impact;
        end.maxs += vel12 * options.max_time_of_impact;
        let swept = start
            .merged(&end)
            .loosened(options.target_distance + margin);
        self.near(&swept)
            .filter_map(|t| {
                DefaultQueryDispatcher
                    .cast_shapes(&pos12, vel12, t, shape, options)
                    .unwrap()
            })
            .min_by(|a, b| a.time_of_impact.total_cmp(&b.time_of_impact))
    }

    /// Smallest time of impact of a nonlinear cast of `shape`, centred on
    /// its pose's origin and moving with `motion` (whose local centre is
    /// that origin), skipping casts that failed to converge as cbvh does.
    /// The second value counts the triangles whose cast failed.
    #[allow(clippy::too_many_arguments)]
    fn cast_nonlinear(
        &self,
        motion: &NonlinearRigidMotion,
        shape: &dyn Shape,
        start: Real,
        end: Real,
        stop_at_penetration: bool,
        margin: Real,
    ) -> (Option<ShapeCastHit>, usize) {
        let r = shape.compute_local_bounding_sphere().radius;
        let at = |t: Real| {
            self.pose
                .inverse_transform_point(motion.position_at_time(t).translation)
        };
        let (a, b) = (at(start), at(end));
        let swept = Aabb::new(a.min(b), a.max(b)).loosened(r + margin);
        let m1 = NonlinearRigidMotion::identity().prepend(self.pose);
        let mut failed = 0;
        let best = self
            .near(&swept)
            .filter_map(|t| {
                let hit = DefaultQueryDispatcher
                    .cast_shapes_nonlinear(&m1, t, motion, shape, start, end, stop_at_penetration)
                    .unwrap()?;
                if hit.status == ShapeCastStatus::Failed {
                    failed += 1;
                    return None;
                }
                Some(hit)
            })
            .min_by(|a, b| a.time_of_impact.total_cmp(&b.time_of_impact));
        (best, failed)
    }
}

/// Reference answers shared by the scenes of the same triangles (the
/// codecs that keep the mesh's corners, and parry's `TriMesh` of them):
/// the queries come from the same seeds and bounds, so they are the same
/// queries, and the per-triangle reference, the slow part, runs once.
struct Answers<T> {
    /// The triangle sets seen (corners as bits, sorted).
    sets: Vec<Vec<[[u32; 3]; 3]>>,
    /// `(set, shape, query)` to the answer.
    memo: HashMap<(usize, usize, usize), T>,
}

impl<T: Clone> Answers<T> {
    fn new() -> Self {
        Self {
            sets: vec![],
            memo: HashMap::new(),
        }
    }

    /// The index of `tris`' set (in any order).
    fn set_of(&mut self, tris: &[Triangle]) -> usize {
        let mut set: Vec<[[u32; 3]; 3]> = tris
            .iter()
            .map(|t| [t.a, t.b, t.c].map(|p| p.to_array().map(f32::to_bits)))
            .collect();
        set.sort_unstable();
        match self.sets.iter().position(|s| *s == set) {
            Some(i) => i,
            None => {
                self.sets.push(set);
                self.sets.len() - 1
            }
        }
    }

    fn get(&mut self, key: (usize, usize, usize), compute: impl FnOnce() -> T) -> T {
        self.memo.entry(key).or_insert_with(compute).clone()
    }
}

/// The statue's centre and half diagonal, in the world.
fn world_bounds(tris: &[Triangle]) -> (Vector, Real) {
    let pose = collider_pose();
    let b = tris
        .iter()
        .map(|t| t.compute_aabb(&pose))
        .reduce(|a, b| a.merged(&b))
        .unwrap();
    (b.center(), b.half_extents().length())
}

fn unit(rng: &mut Rng) -> Vector {
    loop {
        let v = Vector::from(rng.vec(-1.0, 1.0));
        if v.length() > 0.1 && v.length() <= 1.0 {
            return v.normalize();
        }
    }
}

/// Disagreements with the reference, per scene, and how many queries hit.
#[derive(Default)]
struct Tally {
    queries: usize,
    hits: usize,
    /// Disagreements at a tie the tolerance cannot separate (a point at
    /// the distance bound, a shape grazing a triangle): listed, allowed.
    ties: Vec<String>,
    /// Casts that report a later time than the first contact (the shapes
    /// already closer than the target distance just before it).
    late: Vec<String>,
    /// Casts that report an earlier time than the first contact, which
    /// parry's own per-triangle cast reports too (the plain minimum over
    /// every triangle whose box the swept shape meets): parry's false
    /// hits, which cbvh and parry's `TriMesh` inherit alike. Listed,
    /// allowed.
    parry: Vec<String>,
    /// Casts that report an earlier time than the reference where the
    /// shapes do touch (within the target distance): a first contact the
    /// reference misses, where parry's per-triangle cast of the triangle
    /// touched fails (the reference drops failed casts; cbvh brings them
    /// back to the contact). Listed, allowed.
    missed: Vec<String>,
    wrong: Vec<String>,
}

impl Tally {
    fn report(&self, what: &str, scene: &str, summary: &mut String) {
        writeln!(
            summary,
            "{what:<28} {scene:<14} {:>5} queries {:>5} hits {:>3} ties {:>3} late \
             {:>3} parry's {:>3} missed {:>3} disagreements",
            self.queries,
            self.hits,
            self.ties.len(),
            self.late.len(),
            self.parry.len(),
            self.missed.len(),
            self.wrong.len()
        )
        .unwrap();
        for t in self.missed.iter().take(2) {
            writeln!(summary, "    the reference's miss: {t}").unwrap();
        }
        for t in self.parry.iter().take(3) {
            writeln!(summary, "    parry's own early hit: {t}").unwrap();
        }
        for t in self.ties.iter().take(2) {
            writeln!(summary, "    tie: {t}").unwrap();
        }
        for t in self.late.iter().take(3) {
            writeln!(summary, "    LATE: {t}").unwrap();
        }
        for w in self.wrong.iter().take(5) {
            writeln!(summary, "    DISAGREES: {w}").unwrap();
        }
    }
}

/// Prints the summary and fails on any disagreement of a cbvh scene (late
/// casts included).
fn finish(results: &[(String, String, Tally)], min_hits: usize) {
    finish_with(results, min_hits, 0.0);
}

/// As [`finish`], allowing late casts up to `late_share` of the hits.
fn finish_with(results: &[(String, String, Tally)], min_hits: usize, late_share: f32) {
    let mut summary = String::new();
    for (what, scene, t) in results {
        t.report(what, scene, &mut summary);
    }
    eprintln!("{summary}");
    for (what, scene, t) in results {
        assert!(
            t.hits >= min_hits,
            "{what}, {scene}: only {} of {} queries hit\n{summary}",
            t.hits,
            t.queries
        );
        if scene != "parry TriMesh" {
            assert!(
                t.wrong.is_empty(),
                "{what}, {scene}: {} disagreements\n{summary}",
                t.wrong.len()
            );
            assert!(
                t.late.len() as f32 <= late_share * t.hits as f32,
                "{what}, {scene}: {} late casts of {} hits\n{summary}",
                t.late.len(),
                t.hits
            );
        }
    }
}

fn close(a: Real, b: Real, tol: Real) -> bool {
    (a - b).abs() <= tol
}

/// `cast_ray`, `cast_ray_and_get_normal` and `intersect_ray`, solid and
/// not, from outside and from inside the statue's box, with unbounded and
/// short maximum times.
#[test]
fn rays_match_the_per_triangle_reference() {
    let mesh = statue();
    let mut results = vec![];
    let mut answers = Answers::new();
    for (scene, tris) in scenes(&mesh) {
        let reference = Reference::new(&tris);
        let set = answers.set_of(&tris);
        let (centre, radius) = world_bounds(&tris);
        let tol = 1e-5 * radius;
        let q = scene.queries();
        let mut t = [Tally::default(), Tally::default(), Tally::default()];
        let mut rng = Rng(0x5eed_0001);
        for k in 0..400 {
            let origin = if k % 4 == 3 {
                centre + Vector::from(rng.vec(-0.5, 0.5)) * radius
            } else {
                centre + unit(&mut rng) * 1.5 * radius
            };
            let target = centre + Vector::from(rng.vec(-0.4, 0.4)) * radius;
            let ray = Ray::new(origin, (target - origin).normalize());
            let max_toi = if k % 5 == 4 { 1.2 * radius } else { Real::MAX };
            let solid = k % 2 == 0;
            let want = answers.get((set, 0, k), || reference.ray(&ray, max_toi, solid, tol));
            let at = format!("ray {ray:?} max {max_toi} solid {solid}");
            // cast_ray
            let got = q.cast_ray(&ray, max_toi, solid);
            t[0].queries += 1;
            match (&want, got) {
                (Some((w, _)), Some((h, g))) => {
                    t[0].hits += 1;
                    assert_eq!(h, scene.handle);
                    if !close(*w, g, tol) {
                        t[0].wrong.push(format!("{at}: toi {g} vs {w}"));
                    }
                }
                (None, None) => {}
                (w, g) => t[0].wrong.push(format!("{at}: {g:?} vs {w:?}")),
            }
            // cast_ray_and_get_normal: the time, and the normal of one of
            // the triangles hit first.
            let got = q.cast_ray_and_get_normal(&ray, max_toi, solid);
            t[1].queries += 1;
            match (&want, got) {
                (Some((w, normals)), Some((_, g))) => {
                    t[1].hits += 1;
                    if !close(*w, g.time_of_impact, tol) {
                        t[1].wrong.push(format!("{at}: toi {g:?} vs {w}"));
                    } else if !normals.iter().any(|n| n.dot(g.normal) > 0.9999) {
                        t[1].wrong
                            .push(format!("{at}: normal {:?} vs {normals:?}", g.normal));
                    }
                }
                (None, None) => {}
                (w, g) => t[1].wrong.push(format!("{at}: {g:?} vs {w:?}")),
            }
            // intersect_ray: the one collider, with its hit.
            let got: Vec<_> = q.intersect_ray(ray, max_toi, solid).collect();
            t[2].queries += 1;
            match (&want, got.as_slice()) {
                (Some((w, _)), [(h, _, g)]) => {
                    t[2].hits += 1;
                    assert_eq!(*h, scene.handle);
                    if !close(*w, g.time_of_impact, tol) {
                        t[2].wrong.push(format!("{at}: toi {g:?} vs {w}"));
                    }
                }
                (None, []) => {}
                (w, g) => t[2].wrong.push(format!("{at}: {} hits vs {w:?}", g.len())),
            }
        }
        scene.assert_native();
        for (what, t) in ["cast_ray", "cast_ray_and_get_normal", "intersect_ray"]
            .into_iter()
            .zip(t)
        {
            results.push((what.to_string(), scene.name.clone(), t));
        }
    }
    finish(&results, 150);
}

/// `project_point` (solid or not, unbounded and bounded),
/// `project_point_and_get_feature` and `intersect_point` (points on the
/// surface, just off it, and anywhere).
#[test]
fn points_match_the_per_triangle_reference() {
    let mesh = statue();
    let mut results = vec![];
    let mut answers = Answers::new();
    for (scene, tris) in scenes(&mesh) {
        let reference = Reference::new(&tris);
        let set = answers.set_of(&tris);
        let (centre, radius) = world_bounds(&tris);
        let tol = 1e-5 * radius;
        let q = scene.queries();
        let pose = collider_pose();
        let mut t = [Tally::default(), Tally::default(), Tally::default()];
        let mut rng = Rng(0x5eed_0002);
        for k in 0..300 {
            let p = centre + Vector::from(rng.vec(-1.2, 1.2)) * radius;
            let solid = k % 2 == 0;
            let max_dist = if k % 3 == 2 { 0.15 * radius } else { Real::MAX };
            let (w, _) = answers.get((set, 0, k), || reference.project(p, solid, tol));
            let at = format!("point {p:?} solid {solid} max {max_dist}");
            // project_point: the distance; `None` beyond `max_dist`.
            t[0].queries += 1;
            match q.project_point(p, max_dist, solid) {
                Some((h, g)) => {
                    t[0].hits += 1;
                    assert_eq!(h, scene.handle);
                    let d = (g.point - p).length();
                    if !close(w, d, tol) {
                        t[0].wrong.push(format!("{at}: distance {d} vs {w}"));
                    }
                }
                None if w >= max_dist - tol => {}
                None => t[0].wrong.push(format!("{at}: none vs {w}")),
            }
            // project_point_and_get_feature: distance and the feature of a
            // closest triangle.
            t[1].queries += 1;
            match q.project_point_and_get_feature(p, Real::MAX) {
                Some((_, g, f)) => {
                    t[1].hits += 1;
                    let d = (g.point - p).length();
                    let (w, features) =
                        answers.get((set, 1, k), || reference.project(p, false, tol));
                    if !close(w, d, tol) {
                        t[1].wrong.push(format!("{at}: distance {d} vs {w}"));
                    } else if !features.contains(&f) {
                        t[1].wrong
                            .push(format!("{at}: feature {f:?} vs {features:?}"));
                    }
                }
                None => t[1].wrong.push(format!("{at}: none")),
            }
            // intersect_point: on a triangle (a point of its face), just
            // off it, or the random point.
            let i = rng.below(tris.len());
            let tri = tris[i];
            let on = pose * (0.2 * tri.a + 0.3 * tri.b + 0.5 * tri.c);
            let n = pose.rotation * tri.normal().unwrap_or(Vector::Y);
            let probe = match k % 3 {
                0 => on,
                1 => on + n * 1e-3 * radius,
                _ => p,
            };
            let want = reference.contains(probe);
            let got: Vec<_> = q.intersect_point(probe).map(|(h, _)| h).collect();
            t[2].queries += 1;
            t[2].hits += usize::from(!got.is_empty());
            if want == got.is_empty() {
                t[2].wrong
                    .push(format!("{probe:?}: {} colliders vs {want}", got.len()));
            }
        }
        scene.assert_native();
        for (what, t) in [
            "project_point",
            "project_point_and_get_feature",
            "intersect_point",
        ]
        .into_iter()
        .zip(t)
        {
            results.push((what.to_string(), scene.name.clone(), t));
        }
    }
    finish(&results, 60);
}

/// Files a cast's answer `got` (time of impact) against the reference's
/// `want`, `sd(t)` being the signed distance to the mesh of the shape at
/// time `t`, and `tol` the time tolerance. A later time than the
/// reference's (or none) is a tie when the reference's is no contact
/// (parry's per-triangle cast stopped short on a triangle the trees prune
/// by its box: the shape is still farther than the target distance there)
/// and the shape is not within the target distance just before the
/// answer; otherwise it is late (a first contact missed). An earlier time
/// than every triangle's, or a hit where no triangle is hit, is the
/// reference's miss when the shapes touch there (signed distance within
/// the target distance), a tie when they are within the penetration
/// tolerance, and otherwise wrong, unless `exhaustive()` (parry's per-triangle casts without the
/// reference's pruning) answers it too: then it is parry's.
#[allow(clippy::too_many_arguments)]
fn judge(
    t: &mut Tally,
    at: &str,
    want: Option<Real>,
    got: Option<Real>,
    target: Real,
    radius: Real,
    tol: Real,
    sd: impl Fn(Real) -> Real,
    exhaustive: impl Fn() -> Option<Real>,
) {
    t.queries += 1;
    t.hits += usize::from(got.is_some());
    let (contact, penetration) = (1e-5 * radius, 5e-4 * radius);
    match (want, got) {
        (None, None) => {}
        (Some(w), Some(g)) if close(w, g, tol) => {}
        (Some(w), g) if g.is_none_or(|g| g > w) => {
            let before = g.map(|g| sd((g - tol).max(0.0)));
            let there = sd(w);
            let line =
                format!("{at}: {g:?} vs {w} (signed distance {there} there, {before:?} before)");
            let settled = before.is_none_or(|d| d >= target - penetration);
            if settled && there > target + contact {
                t.ties.push(line);
            } else {
                t.late.push(line);
            }
        }
        (w, g) => {
            let line = format!("{at}: {g:?} vs {w:?}");
            if let Some(g) = g
                && sd(g) <= target + contact
            {
                t.missed
                    .push(format!("{line} (signed distance {} there)", sd(g)));
                return;
            }
            // Earlier, with the shapes within the tolerance a late answer
            // is judged by: a tie the tolerance cannot separate.
            if let (Some(_), Some(g)) = (w, g)
                && sd(g) <= target + penetration
            {
                t.ties
                    .push(format!("{line} (signed distance {} there)", sd(g)));
                return;
            }
            let e = exhaustive();
            match (e, g) {
                (Some(e), Some(g)) if close(e, g, tol) => t.parry.push(format!(
                    "{line} (signed distance {} there; parry's own minimum {e})",
                    sd(g)
                )),
                _ => t.wrong.push(match g {
                    Some(g) => format!("{line} (signed distance {} there)", sd(g)),
                    None => line,
                }),
            }
        }
    }
}

/// Named query shapes.
type QueryShapes = Vec<(&'static str, Box<dyn Shape>)>;

/// The query shapes: a ball, a box and a capsule, sized from the statue.
fn query_shapes(radius: Real) -> QueryShapes {
    vec![
        ("ball", Box::new(Ball::new(0.04 * radius))),
        (
            "cuboid",
            Box::new(Cuboid::new(Vector::new(0.05, 0.03, 0.02) * radius)),
        ),
        (
            "capsule",
            Box::new(Capsule::new_y(0.04 * radius, 0.02 * radius)),
        ),
    ]
}

/// The option sets of the linear casts: parry's defaults, and the
/// character controller's (a target distance, no stop at penetration),
/// and the two mixed.
fn cast_options(k: usize, radius: Real, max_toi: Real) -> ShapeCastOptions {
    let (target_distance, stop_at_penetration) = match k % 4 {
        0 => (0.0, true),
        1 => (0.01 * radius, false),
        2 => (0.0, false),
        _ => (0.01 * radius, true),
    };
    ShapeCastOptions {
        max_time_of_impact: max_toi,
        target_distance,
        stop_at_penetration,
        compute_impact_geometry_on_penetration: true,
    }
}

/// A random pose near the statue: outside it, on its surface's band, or
/// inside its box.
fn start_pose(rng: &mut Rng, centre: Vector, radius: Real) -> Pose {
    let d = rng.f32(0.2, 1.4);
    Pose::new(
        centre + unit(rng) * d * radius,
        Vector::from(rng.vec(-3.0, 3.0)),
    )
}

/// `n` linear casts of each of `shapes(radius)` at `mesh` in every scene,
/// at speeds other than 1, under four option sets.
fn linear_casts(
    mesh: &Mesh,
    shapes: fn(Real) -> QueryShapes,
    n: usize,
) -> Vec<(String, String, Tally)> {
    let mut results = vec![];
    let mut answers = Answers::new();
    for (scene, tris) in scenes(mesh) {
        let reference = Reference::new(&tris);
        let set = answers.set_of(&tris);
        let (centre, radius) = world_bounds(&tris);
        let q = scene.queries();
        for (i, (name, shape)) in shapes(radius).into_iter().enumerate() {
            let mut t = Tally::default();
            let mut rng = Rng(0x5eed_0003);
            for k in 0..n {
                let pos = start_pose(&mut rng, centre, radius);
                let target = centre + Vector::from(rng.vec(-0.4, 0.4)) * radius;
                let speed = rng.f32(0.5, 2.0);
                let vel = (target - pos.translation).normalize_or_zero() * speed;
                let options = cast_options(k, radius, 2.5 * radius / speed);
                let want = answers.get((set, i, k), || {
                    reference.cast(&pos, vel, &*shape, options, 1e-3 * radius)
                });
                let got = q.cast_shape(&pos, vel, &*shape, options);
                let tol = 1e-4 * radius / speed;
                let at = format!("{name} at {pos:?} vel {vel:?} {options:?}");
                if let Some((h, _)) = got {
                    assert_eq!(h, scene.handle);
                }
                let sd = |toi: Real| {
                    let p = Pose::from_parts(pos.translation + vel * toi, pos.rotation);
                    reference.signed_distance(&p, &*shape, 0.1 * radius)
                };
                judge(
                    &mut t,
                    &at,
                    want.map(|w| w.time_of_impact),
                    got.map(|g| g.1.time_of_impact),
                    options.target_distance,
                    radius,
                    tol,
                    sd,
                    || {
                        reference
                            .cast_exhaustive(&pos, vel, &*shape, options, 1e-3 * radius)
                            .map(|h| h.time_of_impact)
                    },
                );
            }
            results.push((format!("cast_shape {name}"), scene.name.clone(), t));
        }
        scene.assert_native();
    }
    results
}

/// `cast_shape` (linear) with a ball, a box and a capsule.
#[test]
fn linear_shape_casts_match_the_per_triangle_reference() {
    finish(&linear_casts(&statue(), query_shapes, 250), 100);
}

/// The case: 1500 linear casts of a cube at a scanned statue (here
/// a generated one of 12 000 triangles), where clbvh was once seen to
/// disagree with the reference on one hit.
#[test]
fn fifteen_hundred_cube_casts_at_a_statue_match_the_reference() {
    let mesh = generate(Kind::Statue, 12_000, 5, &mut |_, _| {}).expect("generate");
    let cube = |radius: Real| -> QueryShapes {
        vec![("cube", Box::new(Cuboid::new(Vector::splat(0.03 * radius))))]
    };
    finish(&linear_casts(&mesh, cube, 1500), 1000);
}

/// `intersect_shape` (any triangle intersecting) and
/// `intersect_aabb_conservative` (the collider whenever a triangle's box
/// meets the query box).
#[test]
fn shape_and_box_intersections_match_the_per_triangle_reference() {
    let mesh = statue();
    let mut results = vec![];
    for (scene, tris) in scenes(&mesh) {
        let reference = Reference::new(&tris);
        let (centre, radius) = world_bounds(&tris);
        let q = scene.queries();
        let collider_box = scene.world.colliders[scene.handle].compute_aabb();
        for (name, shape) in query_shapes(radius) {
            let mut t = Tally::default();
            let mut rng = Rng(0x5eed_0004);
            for _ in 0..300 {
                // Larger shapes than the casts', near the surface.
                let pos = start_pose(&mut rng, centre, 0.8 * radius);
                let big = shape.scale_dyn(Vector::splat(3.0), 8).unwrap();
                let (want, dist) = reference.intersects(&pos, &*big, 1e-3 * radius);
                let got: Vec<_> = q.intersect_shape(pos, &*big).map(|(h, _)| h).collect();
                t.queries += 1;
                t.hits += usize::from(!got.is_empty());
                if want == got.is_empty() {
                    let at = format!(
                        "{name} at {pos:?}: {} colliders vs {want} (distance {dist})",
                        got.len()
                    );
                    if dist <= 1e-5 * radius {
                        t.ties.push(at);
                    } else {
                        t.wrong.push(at);
                    }
                }
            }
            results.push((format!("intersect_shape {name}"), scene.name.clone(), t));
        }
        let mut t = Tally::default();
        let mut rng = Rng(0x5eed_0005);
        for _ in 0..300 {
            let c = centre + Vector::from(rng.vec(-1.2, 1.2)) * radius;
            let h = Vector::from(rng.vec(0.01, 0.2)) * radius;
            let aabb = Aabb::new(c - h, c + h);
            let want = reference.any_box_meets(&aabb);
            let got = q.intersect_aabb_conservative(aabb).count() == 1;
            t.queries += 1;
            t.hits += usize::from(got);
            if want && !got {
                t.wrong.push(format!("{aabb:?}: missed"));
            }
            if got && !aabb.intersects(&collider_box.loosened(0.1 * radius)) {
                t.wrong.push(format!("{aabb:?}: far from the collider"));
            }
        }
        results.push(("intersect_aabb_conservative".into(), scene.name.clone(), t));
        scene.assert_native();
    }
    finish(&results, 60);
}

/// `cast_shape_nonlinear`: the shapes moving and spinning, started outside
/// and near the surface, stopping at penetration or not.
fn nonlinear_casts() -> Vec<(String, String, Tally)> {
    let mesh = statue();
    let mut results = vec![];
    let mut answers = Answers::new();
    for (scene, tris) in scenes(&mesh) {
        let reference = Reference::new(&tris);
        let set = answers.set_of(&tris);
        let (centre, radius) = world_bounds(&tris);
        let q = scene.queries();
        let mut failed = 0;
        // parry's own `TriMesh` of the same triangles, the arbiter of an
        // answer earlier than the per-triangle reference: parry's
        // composite cast reports it too.
        let soup = soup_trimesh(&tris);
        let still = NonlinearRigidMotion::constant_position(collider_pose());
        for (i, (name, shape)) in query_shapes(radius).into_iter().enumerate() {
            let mut t = Tally::default();
            let mut rng = Rng(0x5eed_0006);
            for k in 0..120 {
                let pos = start_pose(&mut rng, centre, radius);
                let target = centre + Vector::from(rng.vec(-0.4, 0.4)) * radius;
                let linvel = (target - pos.translation) * rng.f32(0.5, 1.5);
                let angvel = Vector::from(rng.vec(-4.0, 4.0));
                let motion = NonlinearRigidMotion::new(pos, Vector::ZERO, linvel, angvel);
                let stop = k % 2 == 0;
                let (start, end) = (0.0, 1.0);
                let (want, f) = answers.get((set, i, k), || {
                    reference.cast_nonlinear(&motion, &*shape, start, end, stop, 1e-3 * radius)
                });
                failed += f;
                let got = q.cast_shape_nonlinear(&motion, &*shape, start, end, stop);
                let tol = 1e-4 * radius / linvel.length().max(radius);
                let at = format!("{name} {motion:?} stop {stop}");
                let sd = |toi: Real| {
                    reference.signed_distance(&motion.position_at_time(toi), &*shape, 0.1 * radius)
                };
                judge(
                    &mut t,
                    &at,
                    want.map(|w| w.time_of_impact),
                    got.map(|g| g.1.time_of_impact),
                    0.0,
                    radius,
                    tol,
                    sd,
                    || {
                        DefaultQueryDispatcher
                            .cast_shapes_nonlinear(
                                &motion, &*shape, &still, &soup, start, end, stop,
                            )
                            .ok()
                            .flatten()
                            .map(|h| h.time_of_impact)
                    },
                );
            }
            results.push((
                format!("cast_shape_nonlinear {name}"),
                scene.name.clone(),
                t,
            ));
        }
        eprintln!(
            "{}: {failed} per-triangle nonlinear casts failed",
            scene.name
        );
        scene.assert_native();
    }
    results
}

/// Nonlinear casts never answer earlier than the first contact, nor hit
/// where no triangle is hit, and answer the first contact's time in at
/// least four casts of five that hit; the late answers (a first contact
/// missed: 1 to 8 of about 80 hits per codec and shape, parry's
/// `TriMesh` 2 to 4) are listed: see the ignored test below.
#[test]
fn nonlinear_shape_casts_are_never_early() {
    finish_with(&nonlinear_casts(), 40, 0.2);
}

/// Nonlinear casts find the first contact: no late answer at all. Fails
/// on 1 cast of about 80 hits for the capsule in every codec (the shape
/// 19 mm deep just before the answer, parry's per-triangle cast of the
/// triangle first touched converging past it), and for the ball in racbvh
/// and hcc-ooc; parry's own `TriMesh` is late 2 to 4 times per shape. The
/// tree search's node bound, conservative advancement on the two motions'
/// closing speed (`src/parry/cast.rs`), misses nothing: before it, with
/// parry's ball cast as the node test (which answers `None` for balls that
/// do meet when the motion is mostly across the first closest-points
/// axis), every codec was late 1 to 8 times per shape.
#[test]
#[ignore = "parry's per-triangle nonlinear cast converges past the first contact in 1 of ~80 capsule casts"]
fn nonlinear_shape_casts_find_the_first_contact() {
    finish_with(&nonlinear_casts(), 40, 0.0);
}
