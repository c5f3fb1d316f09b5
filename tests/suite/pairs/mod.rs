//! The harness of `native_pairs.rs`: a query pair (two sides and a pose),
//! asked through cbvh's dispatcher and, with each cbvh shape replaced by a
//! parry `TriMesh` of the same mesh, through parry's
//! `DefaultQueryDispatcher`, and the answers compared.

use std::collections::BTreeMap;

use cbvh::Mesh;
use cbvh::build::BuildOptions;
use cbvh::parry::cbvh_cbvh::{neighbours_of, pair_facing};
use cbvh::parry::cones::{EdgeCone, PairRule};
use cbvh::parry::patches::drop_opposed_manifolds;
use cbvh::parry::{CbvhShape, ContactMode, Dispatcher, parry_trimesh, pose_from_parry};
use cbvh::scene::{Kind, generate};
use glam::{DVec3, Vec3A};
use parry3d::math::{Pose, Vector};
use parry3d::query::details::NormalConstraints;
use parry3d::query::{
    ClosestPoints, Contact, ContactManifold, DefaultQueryDispatcher, PersistentQueryDispatcher,
    QueryDispatcher,
};
use parry3d::shape::{CompositeShape, Shape, TriMesh, Triangle};

/// A mesh as a cbvh shape and as a parry `TriMesh`, with a few surface
/// points (triangle centroids) and their outward normals.
pub struct Model {
    pub cbvh: CbvhShape,
    pub parry: TriMesh,
    /// Length of the box diagonal.
    pub size: f32,
    pub surface: Vec<(Vector, Vector)>,
}

impl Model {
    pub fn new(kind: Kind, tris: usize, seed: u64) -> Self {
        let mesh = generate(kind, tris, seed, &mut |_, _| {}).expect("generate");
        Self::of(&mesh)
    }

    pub fn of(mesh: &Mesh) -> Self {
        let (lo, hi) = mesh.bounds().expect("a non-empty mesh");
        let size = (Vector::from(hi) - Vector::from(lo)).length();
        let n = mesh.triangles.len();
        let surface = (0..8)
            .map(|k| {
                let [a, b, c] = mesh.triangle_vertices(k * n / 8 + n / 16).map(Vector::from);
                ((a + b + c) / 3.0, (b - a).cross(c - a).normalize())
            })
            .collect();
        Self {
            cbvh: CbvhShape::plain(mesh, &BuildOptions::default()).unwrap(),
            parry: parry_trimesh(mesh).unwrap(),
            size,
            surface,
        }
    }
}

/// One side of a query pair.
#[derive(Clone, Copy)]
pub enum Side<'a> {
    /// A cbvh shape (parry gets the model's `TriMesh`).
    Cbvh(&'a Model),
    /// A parry `TriMesh` on both sides of the comparison.
    TriMesh(&'a Model),
    /// A convex shape, the same on both sides.
    Convex(&'a dyn Shape),
}

impl<'a> Side<'a> {
    /// The shape handed to cbvh's dispatcher.
    pub fn cbvh(self) -> &'a dyn Shape {
        match self {
            Side::Cbvh(m) => &m.cbvh,
            Side::TriMesh(m) => &m.parry,
            Side::Convex(s) => s,
        }
    }

    /// The shape handed to parry's dispatcher.
    pub fn parry(self) -> &'a dyn Shape {
        match self {
            Side::Cbvh(m) | Side::TriMesh(m) => &m.parry,
            Side::Convex(s) => s,
        }
    }

    /// Calls `f` with part `id` of this side: a triangle of a mesh, or the
    /// convex shape itself (whose only part is 0).
    fn with_part<R>(self, id: u32, f: impl FnOnce(&dyn Shape) -> R) -> R {
        match self {
            Side::Cbvh(m) | Side::TriMesh(m) => f(&m.parry.triangle(id)),
            Side::Convex(s) => {
                assert_eq!(id, 0, "a convex shape has one part, 0");
                f(s)
            }
        }
    }

    /// Triangle `id` of a mesh side.
    fn triangle(self, id: u32) -> Option<Triangle> {
        match self {
            Side::Cbvh(m) | Side::TriMesh(m) => Some(m.parry.triangle(id)),
            Side::Convex(_) => None,
        }
    }

    /// Distance from `p` (in this side's frame) to the side's surface.
    fn surface_distance(self, p: Vector) -> f32 {
        (self.parry().project_local_point(p, false).point - p).length()
    }

    pub fn name(self) -> &'static str {
        match self {
            Side::Cbvh(_) => "cbvh",
            Side::TriMesh(_) => "TriMesh",
            Side::Convex(s) => {
                if s.as_ball().is_some() {
                    "ball"
                } else if s.as_cuboid().is_some() {
                    "cuboid"
                } else {
                    "polyhedron"
                }
            }
        }
    }
}

/// A query pair: shape 2 placed in shape 1's frame by `pos12`.
#[derive(Clone, Copy)]
pub struct Case<'a> {
    pub s1: Side<'a>,
    pub s2: Side<'a>,
    pub pos12: Pose,
    pub prediction: f32,
    /// Length scale for tolerances.
    pub scale: f32,
}

impl Case<'_> {
    pub fn flipped(&self) -> Self {
        Self {
            s1: self.s2,
            s2: self.s1,
            pos12: self.pos12.inverse(),
            ..*self
        }
    }

    fn at(&self) -> String {
        format!(
            "{} vs {} at {:?}",
            self.s1.name(),
            self.s2.name(),
            self.pos12
        )
    }

    fn tol(&self) -> f32 {
        1e-4 * self.scale.max(1.0)
    }
}

/// What the queries found, so that a test can insist its poses exercised
/// every answer in every order.
#[derive(Default, Debug)]
pub struct Tally {
    pub manifold_pairs: usize,
    pub contacts: usize,
    pub intersecting: usize,
    pub disjoint: usize,
    pub within_margin: usize,
    /// Pairs with parry's unconstrained points that cbvh's constraints
    /// (back faces, internal edges) leave without any.
    pub constrained_away: usize,
    /// Manifolds of the reference that the guard against one region pushed
    /// both ways empties (`cbvh::parry::patches::drop_opposed_manifolds`).
    pub opposed_dropped: usize,
}

/// A contact point: both local points, the manifold normal, the distance.
type Point = [f32; 10];
type Points = BTreeMap<(u32, u32), Vec<Point>>;

/// Contact points by sub-shape pair, for manifolds that have points.
fn points_of(manifolds: &[ContactManifold<(), ()>]) -> Points {
    let mut out = Points::new();
    for m in manifolds.iter().filter(|m| !m.points.is_empty()) {
        let n = m.local_n1;
        let pts = m.points.iter().map(|p| {
            let (a, b) = (p.local_p1, p.local_p2);
            [a.x, a.y, a.z, b.x, b.y, b.z, n.x, n.y, n.z, p.dist]
        });
        out.entry((m.subshape1, m.subshape2))
            .or_default()
            .extend(pts);
    }
    out
}

fn manifolds_of(
    d: &dyn PersistentQueryDispatcher<(), ()>,
    case: &Case,
    g1: &dyn Shape,
    g2: &dyn Shape,
    prediction: f32,
) -> Points {
    let mut m = Vec::new();
    let mut ws = None;
    d.contact_manifolds(&case.pos12, g1, g2, prediction, &mut m, &mut ws)
        .unwrap();
    points_of(&m)
}

/// Whether the two point sets match one to one within `tol`.
fn same_points(a: &[Point], b: &[Point], tol: f32) -> bool {
    let mut unused: Vec<&Point> = b.iter().collect();
    a.len() == b.len()
        && a.iter().all(|p| {
            let hit = unused
                .iter()
                .position(|q| p.iter().zip(q.iter()).all(|(x, y)| (x - y).abs() <= tol));
            hit.map(|k| unused.swap_remove(k)).is_some()
        })
}

/// Whether the two triangles (the second placed by `pos12`) are more than
/// `margin` apart, proven in f64 by a separating axis (a face normal or
/// the cross product of two edges): then no contact within `margin` exists.
fn separated_beyond(t1: &Triangle, t2: &Triangle, pos12: &Pose, margin: f32) -> bool {
    let (rot, shift) = (pos12.rotation.as_dquat(), pos12.translation.as_dvec3());
    let v1 = [t1.a, t1.b, t1.c].map(|v| v.as_dvec3());
    let v2 = [t2.a, t2.b, t2.c].map(|v| rot * v.as_dvec3() + shift);
    let edges = |v: &[DVec3; 3]| [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
    let (e1, e2) = (edges(&v1), edges(&v2));
    let mut axes = vec![e1[0].cross(e1[1]), e2[0].cross(e2[1])];
    axes.extend(e1.iter().flat_map(|a| e2.iter().map(move |b| a.cross(*b))));
    axes.into_iter().any(|axis| {
        let Some(n) = axis.try_normalize() else {
            return false;
        };
        let span = |v: &[DVec3; 3]| {
            let d = v.map(|p| n.dot(p));
            (d[0].min(d[1]).min(d[2]), d[0].max(d[1]).max(d[2]))
        };
        let ((lo1, hi1), (lo2, hi2)) = (span(&v1), span(&v2));
        (lo2 - hi1).max(lo1 - hi2) > margin as f64
    })
}

fn close(a: Vector, b: Vector, tol: f32) -> bool {
    (a - b).length() <= tol
}

/// The same sub-shape pairs carry contact points, the same number each,
/// agreeing within the tolerance: every point with `strict`, else the
/// points within the prediction (those rapier's solver uses).
///
/// cbvh's per-pair mode hands each triangle pair to parry's convex-convex
/// code with normal constraints: the oriented-axis rule for two cbvh
/// triangles (`cbvh::parry::cones::PairRule`), a cbvh triangle's active-edge
/// cone (`EdgeCone`) against a convex shape or a `TriMesh` triangle. So the
/// reference of each pair, for every pair parry's own traversal or cbvh's
/// finds, is parry's convex-convex manifold of those two parts with the
/// same constraints, at cbvh's exact pose (parry's composite-shape code
/// places some parts by `pos12` inverted twice, so the last bit of the pose
/// may differ, and a manifold can jump with that). This checks that cbvh
/// finds every pair parry's traversal does, names it right in both orders,
/// and gives the rule the right triangles, flags, frames and facing; the
/// rule itself is checked against mechanics in `physics.rs` and
/// `orientation.rs`. How many pairs parry reports that the constraints
/// drop (back faces, internal edges) is counted in the tally. Over all
/// pairs, cbvh then empties one of two manifolds that push one region
/// both ways (`drop_opposed_manifolds`); the reference goes through the
/// same guard.
///
/// parry's GJK also judges some triangle pairs touching (distance 0,
/// contact points with a zero normal) that are millimetres apart; a pair
/// cbvh leaves out is excused when parry's points claim contact within the
/// prediction but a separating axis (checked here in f64) proves the
/// triangles further apart than that.
fn check_manifolds(case: &Case, strict: bool, tally: &mut Tally) {
    let chain = Dispatcher::new(ContactMode::PerTrianglePair).then_default();
    let tol = case.tol();
    for prediction in [0.0, case.prediction] {
        let kept = |mut p: Points| {
            if !strict {
                for pts in p.values_mut() {
                    pts.retain(|q| q[9] <= prediction);
                }
                p.retain(|_, pts| !pts.is_empty());
            }
            p
        };
        let (s1, s2) = (case.s1, case.s2);
        let want = manifolds_of(
            &DefaultQueryDispatcher,
            case,
            s1.parry(),
            s2.parry(),
            prediction,
        );
        let got = manifolds_of(&chain, case, s1.cbvh(), s2.cbvh(), prediction);
        // The reference of every pair either side finds, then the guard
        // against one region pushed both ways over all of them, as cbvh
        // applies it to its manifolds.
        let mut reference: Vec<ContactManifold<(), ()>> = want
            .keys()
            .chain(got.keys())
            .collect::<std::collections::BTreeSet<_>>()
            .into_iter()
            .map(|k| {
                let mut m = constrained_manifold(case, *k, prediction);
                m.subshape1 = k.0;
                m.subshape2 = k.1;
                m
            })
            .collect();
        tally.opposed_dropped +=
            drop_opposed_manifolds(&case.pos12, centre(s1), centre(s2), &mut reference);
        let exact_all = kept(points_of(&reference));
        let (want, got) = (kept(want), kept(got));
        let at = format!("{}, prediction {prediction}", case.at());
        for k in want.keys().chain(got.keys()) {
            let (w, g) = (want.get(k), got.get(k));
            let (w, g) = (w.map_or(&[][..], |w| w), g.map_or(&[][..], |g| g));
            let exact = exact_all.get(k).map_or(&[][..], |e| e);
            if same_points(exact, g, tol) {
                if g.is_empty() && !w.is_empty() {
                    tally.constrained_away += 1;
                }
                continue;
            }
            let parry_wrong = g.is_empty()
                && w.iter().all(|p| p[9] <= prediction + tol)
                && s1
                    .triangle(k.0)
                    .zip(s2.triangle(k.1))
                    .is_some_and(|(t1, t2)| separated_beyond(&t1, &t2, &case.pos12, prediction));
            assert!(
                parry_wrong,
                "contact points of pair {k:?}, {at}:\n  parry unconstrained {w:?}\n  parry with cbvh's constraints at cbvh's pose {exact:?}\n  cbvh {g:?}"
            );
        }
        tally.manifold_pairs += got.len();
    }
}

/// What is called with a part and its own normal constraints.
type PartFn<'f> = dyn FnMut(&dyn Shape, Option<&dyn NormalConstraints>) + 'f;

/// A cbvh side's triangle `id` as cbvh's contact code takes it.
fn cbvh_triangle(m: &Model, id: u32) -> [Vec3A; 3] {
    let t = m.parry.triangle(id);
    [t.a, t.b, t.c].map(|v| Vec3A::from(v.to_array()))
}

/// The centre of a side's box, in its own frame, as cbvh's facing takes it.
fn centre(side: Side) -> Vector {
    match side {
        Side::Cbvh(m) => Vector::from(m.cbvh.local_aabb().center().to_array()),
        Side::TriMesh(m) => m.parry.local_aabb().center(),
        Side::Convex(s) => s.compute_local_aabb().center(),
    }
}

/// parry's convex-convex manifold of the parts `k` of `case`, with the
/// normal constraints cbvh's per-pair mode gives parry for them (see
/// [`check_manifolds`]); a `TriMesh` part brings its own pseudo-normals.
fn constrained_manifold(case: &Case, k: (u32, u32), prediction: f32) -> ContactManifold<(), ()> {
    let mut m = ContactManifold::new();
    let pos12 = case.pos12;
    let pose = pose_from_parry(&pos12);
    // The other side's centre in a cbvh side's frame.
    let toward = |own_is_1: bool| {
        let c = if own_is_1 {
            pos12 * centre(case.s2)
        } else {
            pos12.inverse() * centre(case.s1)
        };
        Vec3A::from(c.to_array())
    };
    let cone = |side: Side, id: u32, own_is_1: bool| match side {
        Side::Cbvh(mm) => EdgeCone::new(
            &cbvh_triangle(mm, id),
            mm.cbvh.edge_flags_of(id),
            mm.cbvh.facing(toward(own_is_1)),
        ),
        _ => None,
    };
    let run = |p1: &dyn Shape,
               p2: &dyn Shape,
               c1: Option<&dyn NormalConstraints>,
               c2: Option<&dyn NormalConstraints>,
               m: &mut ContactManifold<(), ()>| {
        DefaultQueryDispatcher
            .contact_manifold_convex_convex(&pos12, p1, p2, c1, c2, prediction, m)
            .unwrap();
    };
    match (case.s1, case.s2) {
        (Side::Cbvh(m1), Side::Cbvh(m2)) => {
            let rule = PairRule {
                a: cbvh_triangle(m1, k.0),
                fa: m1.cbvh.edge_flags_of(k.0),
                b: cbvh_triangle(m2, k.1).map(|v| pose.transform_point(v)),
                fb: m2.cbvh.edge_flags_of(k.1),
                facing: pair_facing(&pose, &m1.cbvh, &m2.cbvh),
                prediction,
                ids: k,
                neighbours: Some(neighbours_of(&m1.cbvh, &m2.cbvh, &pose)),
            };
            run(
                &m1.parry.triangle(k.0),
                &m2.parry.triangle(k.1),
                Some(&rule),
                None,
                &mut m,
            );
        }
        (s1, s2) => {
            let (mut k1, mut k2) = (cone(s1, k.0, true), cone(s2, k.1, false));
            // A TriMesh part with its pseudo-normals, any other part bare.
            let with = |side: Side, id: u32, f: &mut PartFn| match side {
                Side::TriMesh(t) => t
                    .parry
                    .map_part_at(id, &mut |_, part, normals| f(part, normals)),
                other => other.with_part(id, |part| f(part, None)),
            };
            let go =
                |k1: &Option<EdgeCone>, k2: &Option<EdgeCone>, m: &mut ContactManifold<(), ()>| {
                    let c1 = k1.as_ref().map(|c| c as &dyn NormalConstraints);
                    let c2 = k2.as_ref().map(|c| c as &dyn NormalConstraints);
                    with(s1, k.0, &mut |p1, n1| {
                        with(s2, k.1, &mut |p2, n2| {
                            run(p1, p2, c1.or(n1), c2.or(n2), m);
                        })
                    });
                };
            go(&k1, &k2, &mut m);
            // As the dispatcher does: a normal that leaned over a shared
            // edge goes no further than the neighbour's face normal, and
            // the manifold is computed again.
            let wanted = |c: &Option<EdgeCone>| c.as_ref().is_some_and(|c| c.wanted() != 0);
            if wanted(&k1) || wanted(&k2) {
                for (c, side, id) in [(&mut k1, s1, k.0), (&mut k2, s2, k.1)] {
                    if let (Some(c), Side::Cbvh(mm)) = (c.as_mut(), side) {
                        c.complete(&mm.cbvh, id, &cbvh_triangle(mm, id));
                    }
                }
                m = ContactManifold::new();
                go(&k1, &k2, &mut m);
            }
        }
    }
    m
}

/// Whether `c` is a contact between the two shapes of `case`: its points
/// lie on the shapes' surfaces, and its normal and distance agree with them.
fn is_a_contact(case: &Case, c: &Contact) -> bool {
    let tol = case.tol();
    let p2 = case.pos12.transform_point(c.point2);
    case.s1.surface_distance(c.point1) <= tol
        && case.s2.surface_distance(c.point2) <= tol
        && ((p2 - c.point1).dot(c.normal1) - c.dist).abs() <= tol
        && (c.normal1.length() - 1.0).abs() <= 1e-3
}

fn check_contact(case: &Case, tally: &mut Tally) {
    let chain = Dispatcher::new(ContactMode::PerTrianglePair).then_default();
    let (p, c) = (case.s1, case.s2);
    let want = DefaultQueryDispatcher
        .contact(&case.pos12, p.parry(), c.parry(), case.prediction)
        .unwrap();
    let got = chain
        .contact(&case.pos12, p.cbvh(), c.cbvh(), case.prediction)
        .unwrap();
    match (want, got) {
        (None, None) => {}
        (Some(w), Some(g)) => {
            let tol = case.tol();
            assert!(
                (w.dist - g.dist).abs() <= tol,
                "contact distance, {}: parry {w:?} vs cbvh {g:?}",
                case.at()
            );
            // Equal points, or a tie between parts at the same depth: then
            // cbvh's contact must still be one between the two shapes.
            let same = close(w.point1, g.point1, tol)
                && close(w.point2, g.point2, tol)
                && close(w.normal1, g.normal1, 1e-3);
            assert!(
                same || is_a_contact(case, &g),
                "contact, {}: parry {w:?} vs cbvh {g:?}",
                case.at()
            );
            tally.contacts += 1;
        }
        (w, g) => panic!("contact, {}: parry {w:?} vs cbvh {g:?}", case.at()),
    }
}

fn check_intersection(case: &Case, tally: &mut Tally) {
    let chain = Dispatcher::new(ContactMode::PerTrianglePair).then_default();
    let want = DefaultQueryDispatcher
        .intersection_test(&case.pos12, case.s1.parry(), case.s2.parry())
        .unwrap();
    let got = chain
        .intersection_test(&case.pos12, case.s1.cbvh(), case.s2.cbvh())
        .unwrap();
    assert_eq!(
        want.intersecting,
        got.intersecting,
        "intersection test, {}",
        case.at()
    );
    tally.intersecting += usize::from(got.intersecting);
}

fn check_distance(case: &Case) {
    let chain = Dispatcher::new(ContactMode::PerTrianglePair).then_default();
    let want = DefaultQueryDispatcher
        .distance(&case.pos12, case.s1.parry(), case.s2.parry())
        .unwrap();
    let got = chain
        .distance(&case.pos12, case.s1.cbvh(), case.s2.cbvh())
        .unwrap();
    assert!(
        (want.distance - got.distance).abs() <= case.tol(),
        "distance, {}: parry {want:?} vs cbvh {got:?}",
        case.at()
    );
    // The parts named are ones at that distance (several may tie).
    let parts = case.s1.with_part(got.subshape1, |a| {
        case.s2.with_part(got.subshape2, |b| {
            DefaultQueryDispatcher
                .distance(&case.pos12, a, b)
                .unwrap()
                .distance
        })
    });
    assert!(
        (parts - got.distance).abs() <= case.tol(),
        "distance, {}: parts {} and {} are {parts} apart, not {}",
        case.at(),
        got.subshape1,
        got.subshape2,
        got.distance
    );
}

fn check_closest_points(case: &Case, max_dist: f32, tally: &mut Tally) {
    let chain = Dispatcher::new(ContactMode::PerTrianglePair).then_default();
    let want = DefaultQueryDispatcher
        .closest_points(&case.pos12, case.s1.parry(), case.s2.parry(), max_dist)
        .unwrap();
    let got = chain
        .closest_points(&case.pos12, case.s1.cbvh(), case.s2.cbvh(), max_dist)
        .unwrap();
    let tol = case.tol();
    match (want, got) {
        (ClosestPoints::Intersecting, ClosestPoints::Intersecting) => {}
        (ClosestPoints::Disjoint, ClosestPoints::Disjoint) => tally.disjoint += 1,
        (ClosestPoints::WithinMargin(w1, w2), ClosestPoints::WithinMargin(g1, g2)) => {
            let dw = (w1 - case.pos12.transform_point(w2)).length();
            let dg = (g1 - case.pos12.transform_point(g2)).length();
            assert!(
                (dw - dg).abs() <= tol,
                "closest points, {}, max_dist {max_dist}: parry {dw} apart, cbvh {dg}",
                case.at()
            );
            // The same points, or (a tie) points on the two surfaces.
            let same = close(w1, g1, tol) && close(w2, g2, tol);
            let on_surfaces =
                case.s1.surface_distance(g1) <= tol && case.s2.surface_distance(g2) <= tol;
            assert!(
                same || on_surfaces,
                "closest points, {}, max_dist {max_dist}: parry {w1:?} {w2:?} vs cbvh {g1:?} {g2:?}",
                case.at()
            );
            tally.within_margin += 1;
        }
        (w, g) => panic!(
            "closest points, {}, max_dist {max_dist}: parry {w:?} vs cbvh {g:?}",
            case.at()
        ),
    }
}

/// Runs every query on `case` and on its flip; returns the tallies of the
/// two orders.
pub fn check_both_orders(cases: &[Case], strict: bool) -> [Tally; 2] {
    let mut tallies = [Tally::default(), Tally::default()];
    for case in cases {
        for (order, case) in [*case, case.flipped()].iter().enumerate() {
            let tally = &mut tallies[order];
            check_manifolds(case, strict, tally);
            check_contact(case, tally);
            check_intersection(case, tally);
            check_distance(case);
            for max_dist in [case.prediction, case.scale] {
                check_closest_points(case, max_dist, tally);
            }
        }
    }
    for m in cases.iter().flat_map(|c| [c.s1, c.s2]) {
        if let Side::Cbvh(m) = m {
            assert!(
                !m.cbvh.fallback_bvh_built(),
                "the native path built parry's Bvh"
            );
        }
    }
    tallies
}

/// The sub-shapes an intersection test names intersect. Returns how many
/// intersections were checked.
pub fn check_intersection_parts(case: &Case) -> usize {
    let got = Dispatcher::new(ContactMode::PerTrianglePair)
        .then_default()
        .intersection_test(&case.pos12, case.s1.cbvh(), case.s2.cbvh())
        .unwrap();
    if !got.intersecting {
        return 0;
    }
    let parts = case.s1.with_part(got.subshape1, |a| {
        case.s2.with_part(got.subshape2, |b| {
            DefaultQueryDispatcher
                .intersection_test(&case.pos12, a, b)
                .unwrap()
                .intersecting
        })
    });
    assert!(
        parts,
        "intersection test, {}: parts {} and {} do not intersect",
        case.at(),
        got.subshape1,
        got.subshape2
    );
    1
}

/// The sub-shapes a contact names have that contact. Returns how many
/// contacts were checked.
pub fn check_contact_parts(case: &Case) -> usize {
    let Some(got) = Dispatcher::new(ContactMode::PerTrianglePair)
        .then_default()
        .contact(&case.pos12, case.s1.cbvh(), case.s2.cbvh(), case.prediction)
        .unwrap()
    else {
        return 0;
    };
    let parts = case.s1.with_part(got.subshape1, |a| {
        case.s2.with_part(got.subshape2, |b| {
            DefaultQueryDispatcher
                .contact(&case.pos12, a, b, case.prediction)
                .unwrap()
        })
    });
    assert!(
        parts.is_some_and(|p| (p.dist - got.dist).abs() <= case.tol()),
        "contact, {}: parts {} and {} give {parts:?}, not {got:?}",
        case.at(),
        got.subshape1,
        got.subshape2
    );
    1
}

/// Every case and its flip.
pub fn both_orders<'a>(cases: &[Case<'a>]) -> impl Iterator<Item = Case<'a>> {
    cases.iter().flat_map(|c| [*c, c.flipped()])
}
