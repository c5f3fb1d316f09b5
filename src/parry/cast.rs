//! Nonlinear shape casts (rapier's CCD sweeps) with a cbvh shape on either
//! side, on the cbvh tree: a best-first search whose node bound is the
//! first time the node's bounding ball can meet the other shape's, by
//! conservative advancement on the two motions (`ball_toi`). The best time
//! found so far bounds every later leaf.
//!
//! Against another shape, a leaf goes to the dispatcher for the triangle
//! against that shape. Two cbvh shapes are searched together, over pairs
//! of nodes of both trees ([`cast_nonlinear_pair`]), and a pair of
//! triangles is cast by cbvh's own conservative advancement on the
//! kernel's exact triangle distance (`triangle_pair_toi`): parry's cast
//! of two triangles costs tens of microseconds, and a closed scan swept
//! against a part has thousands of pairs in its leaves.
//!
//! The answer follows parry's semantics for its own shapes, one triangle
//! at a time: with `stop_at_penetration`, a pair overlapping at `start`
//! hits at `start`; without it, parry's directional rule (a pair in
//! contact at `start` hits only if it would tunnel) decides. Where parry's
//! iteration on a triangle fails (it steps into the triangle, which it
//! does for fast bodies against thin walls), the time is brought back to
//! the first contact by bisection (`first_contact`).
//!
//! Two cbvh shapes cast without `stop_at_penetration` (rapier's CCD)
//! skip the triangle pairs in contact at `start`: such a pair can only
//! answer `start`, which rapier discards, and which would hide another
//! pair's later first contact. A parry `TriMesh` cast the same way answers
//! `start`.

use parry3d::bounding_volume::Aabb as PAabb;
use parry3d::math::{Pose, Real, Vector};
use parry3d::query::{NonlinearRigidMotion, QueryDispatcher, ShapeCastHit, ShapeCastStatus};
use parry3d::shape::{Shape, TriMesh};

use glam::Vec3A;

use super::shape::{CbvhShape, to_parry_triangle};
use crate::contact::{triangle_closest_points, triangles_intersect};
use crate::cursor::TraversalStats;
use crate::geom::{Aabb, Triangle};
use crate::query::{bvtt_best, find_best};

/// Most steps of [`ball_toi`]'s conservative advancement.
const ADVANCE_STEPS: usize = 64;

/// Most steps of [`advance_to_contact`].
const CLOSE_STEPS: usize = 32;

/// Most steps of [`triangle_pair_toi`].
const TRIANGLE_STEPS: usize = 128;

/// The gap, relative to `1 + the pair's size`, at which
/// [`triangle_pair_toi`] calls two triangles touching.
const TOUCH_TOLERANCE: Real = 1e-6;

/// Bisection steps that bring a cast parry reports as
/// [`ShapeCastStatus::Failed`] back to its first contact (`first_contact`).
const REFINE_STEPS: usize = 24;

/// The fastest any point within `radius` of `local` (in the moving body's
/// frame) moves under `m`: its linear speed plus the spin times the
/// farthest such point's distance from the centre of rotation.
fn speed_bound(m: &NonlinearRigidMotion, local: Vector, radius: Real) -> Real {
    m.linvel.length() + m.angvel.length() * ((local - m.local_center).length() + radius)
}

/// A motion with its pose at the cast's start worked out once: a search
/// asks for that pose for every node and triangle pair it meets, and most
/// of those in contact answer there. (`position_at_time` builds a
/// rotation from the spin each time; it was a third of the time of a
/// closed scan swept while resting on a part.)
struct Posed<'a> {
    m: &'a NonlinearRigidMotion,
    start: Real,
    at_start: Pose,
}

impl<'a> Posed<'a> {
    fn new(m: &'a NonlinearRigidMotion, start: Real) -> Self {
        Posed {
            m,
            start,
            at_start: m.position_at_time(start),
        }
    }

    /// The pose at `t`.
    fn at(&self, t: Real) -> Pose {
        if t == self.start {
            self.at_start
        } else {
            self.m.position_at_time(t)
        }
    }
}

/// A time no later than the first at which the ball of radius `r1` about
/// `c1` (in the frame moving with `m1`) meets the ball of radius `r2` about
/// `c2` (moving with `m2`), by conservative advancement; `Real::MAX` when
/// they do not meet before `end`.
///
/// Each step advances by the gap over the largest closing speed of the two
/// centres, so it never steps past a contact, rotation or not. (parry's
/// nonlinear cast of two balls is not a bound for a spinning body: it ends
/// with "no hit" when the balls are apart along one normal at the end of
/// the interval, while an arc can bring them together in between, and a
/// node pruned that way hides the first contact.)
#[allow(clippy::too_many_arguments)]
fn ball_toi(m1: &Posed, c1: Vector, r1: Real, m2: &Posed, c2: Vector, r2: Real, end: Real) -> Real {
    let closing = speed_bound(m1.m, c1, 0.0) + speed_bound(m2.m, c2, 0.0);
    let reach = r1 + r2;
    let tolerance = 1e-5 * reach.max(1e-3);
    let mut t = m1.start;
    for _ in 0..ADVANCE_STEPS {
        let w1 = m1.at(t) * c1;
        let w2 = m2.at(t) * c2;
        let gap = (w1 - w2).length() - reach;
        if gap <= tolerance {
            return t;
        }
        if closing <= 0.0 {
            return Real::MAX;
        }
        t += gap / closing;
        if t > end {
            return Real::MAX;
        }
    }
    // Still apart after every step (a grazing approach): `t` is before
    // any contact, so it is a bound.
    t
}

/// Whether `g1` (moving with `m1`) and `g2` (with `m2`) overlap at `t`.
fn intersect_at<D: ?Sized + QueryDispatcher>(
    dispatcher: &D,
    m1: &NonlinearRigidMotion,
    g1: &dyn Shape,
    m2: &NonlinearRigidMotion,
    g2: &dyn Shape,
    t: Real,
) -> Option<bool> {
    let pos12 = m1.position_at_time(t).inv_mul(&m2.position_at_time(t));
    // parry's contact query, not its intersection test or its distance:
    // those two answer an overlap for a cuboid or a capsule millimetres
    // from a triangle (the contact query measures the gap there).
    let reach =
        g1.compute_local_bounding_sphere().radius + g2.compute_local_bounding_sphere().radius;
    dispatcher
        .contact(&pos12, g1, g2, reach)
        .ok()
        .map(|c| c.is_some_and(|c| c.dist <= 0.0))
}

/// A cast parry reports as [`ShapeCastStatus::Failed`]: its conservative
/// advancement stepped into the other shape, and its time is one where the
/// two already overlap. When the two are apart at `start`, the first
/// contact lies between, and bisection on the overlap test finds it (the
/// last time found apart, so the shapes touch without overlapping). When
/// they overlap at `start` the failure says nothing about a later contact:
/// `None`, as a converged cast that starts in contact and separates.
#[allow(clippy::too_many_arguments)]
fn first_contact<D: ?Sized + QueryDispatcher>(
    dispatcher: &D,
    m1: &NonlinearRigidMotion,
    g1: &dyn Shape,
    m2: &NonlinearRigidMotion,
    g2: &dyn Shape,
    start: Real,
    mut hit: ShapeCastHit,
) -> Option<ShapeCastHit> {
    if intersect_at(dispatcher, m1, g1, m2, g2, start)? {
        return None;
    }
    let (mut lo, mut hi) = (start, hit.time_of_impact);
    for _ in 0..REFINE_STEPS {
        let mid = 0.5 * (lo + hi);
        if intersect_at(dispatcher, m1, g1, m2, g2, mid)? {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hit.time_of_impact = lo;
    hit.status = ShapeCastStatus::Converged;
    Some(hit)
}

/// parry's iteration stops within a time tolerance of the contact, which
/// a fast body turns into a gap (about a millimetre at 360 m/s): advances
/// `hit` conservatively on the distance between the whole shapes, at most
/// the gap over the fastest closing speed of their points per step, so
/// that it ends touching and never past the first contact. Any answer but
/// a penetration at `start` is advanced (parry's iteration may also end
/// `OutOfIterations`, short of the contact).
#[allow(clippy::too_many_arguments)]
fn advance_to_contact<D: ?Sized + QueryDispatcher>(
    dispatcher: &D,
    m1: &NonlinearRigidMotion,
    g1: &dyn Shape,
    m2: &NonlinearRigidMotion,
    g2: &dyn Shape,
    start: Real,
    end: Real,
    hit: &mut ShapeCastHit,
) {
    // A penetration at the start stays: there is nothing to advance.
    if hit.status == ShapeCastStatus::PenetratingOrWithinTargetDist || hit.time_of_impact <= start {
        return;
    }
    let s1 = g1.compute_local_bounding_sphere();
    let s2 = g2.compute_local_bounding_sphere();
    let closing = speed_bound(m1, s1.center, s1.radius) + speed_bound(m2, s2.center, s2.radius);
    if closing <= 0.0 {
        return;
    }
    let tolerance = 1e-6 * (1.0 + s1.radius.min(s2.radius));
    let mut t = hit.time_of_impact;
    for _ in 0..CLOSE_STEPS {
        let pos12 = m1.position_at_time(t).inv_mul(&m2.position_at_time(t));
        let Ok(d) = dispatcher.distance(&pos12, g1, g2) else {
            return;
        };
        if d.distance <= tolerance {
            break;
        }
        let next = t + d.distance / closing;
        if next >= end {
            break;
        }
        t = next;
    }
    hit.time_of_impact = t;
}

/// One pair of leaves (a triangle and the other shape, or two
/// triangles): the dispatcher's cast, a failed one brought back to the
/// first contact or dropped if the pair overlapped from the start (taking
/// its time would clamp a resting body's motion on every step, freezing
/// it).
#[allow(clippy::too_many_arguments)]
fn leaf_cast<D: ?Sized + QueryDispatcher>(
    dispatcher: &D,
    m1: &NonlinearRigidMotion,
    g1: &dyn Shape,
    m2: &NonlinearRigidMotion,
    g2: &dyn Shape,
    start: Real,
    end: Real,
    stop_at_penetration: bool,
) -> Option<ShapeCastHit> {
    let hit = dispatcher
        .cast_shapes_nonlinear(m1, g1, m2, g2, start, end, stop_at_penetration)
        .ok()
        .flatten()?;
    if hit.status == ShapeCastStatus::Failed {
        first_contact(dispatcher, m1, g1, m2, g2, start, hit)
    } else {
        Some(hit)
    }
}

/// The farthest corner of `tri` from the centre of rotation of `m`: the
/// lever arm that bounds how fast a spin moves the triangle's points.
fn lever(m: &NonlinearRigidMotion, tri: &Triangle) -> Real {
    let c = Vec3A::from(m.local_center.to_array());
    tri.iter().map(|p| (*p - c).length()).fold(0.0, Real::max)
}

/// The time of first contact of triangle `t1` (in shape 1's frame, moving
/// with `m1`) and `t2` (shape 2's, with `m2`) in `[start, end)`, by
/// conservative advancement on the kernel's exact triangle distance.
///
/// Each step takes the two triangles' closest points and advances by their
/// gap over the fastest the gap can close: the relative linear speed along
/// the separating direction plus each spin times its lever arm. The slab
/// between the closest points separates the two until both sides have
/// crossed it, so the step never passes a contact, rotation or not; a
/// closing bound that is not positive means the two never meet. A pure
/// translation face-on converges in one step. A grazing approach under a
/// fast spin (tens of radians a second) can use up the steps; the time
/// reached is still before any contact and is answered, early, as
/// [`ShapeCastStatus::OutOfIterations`] (5 of 138 hits of the unit test's
/// triangles spun at 40 rad/s).
///
/// Pairs in contact at `start` hit at `start` with `stop_at_penetration`
/// and are skipped without it (see the module docs). parry's cast of two
/// triangles gives the same time, but through GJK and a bisection per
/// step, tens of microseconds a pair: a closed scan swept against a part
/// with thousands of pairs in its leaves took seconds a step.
#[allow(clippy::too_many_arguments)]
fn triangle_pair_toi(
    p1: &Posed,
    t1: &Triangle,
    p2: &Posed,
    t2: &Triangle,
    end: Real,
    stop_at_penetration: bool,
) -> Option<ShapeCastHit> {
    let (m1, m2) = (p1.m, p2.m);
    let (lever1, lever2) = (lever(m1, t1), lever(m2, t2));
    let relvel = m1.linvel - m2.linvel;
    let size = t1
        .iter()
        .chain(t2.iter())
        .map(|p| (*p - t1[0]).length())
        .fold(0.0, Real::max);
    // Rounding in the transformed corners is relative to the coordinates'
    // magnitude: a gap below it cannot be told from a touch.
    let magnitude = t1
        .iter()
        .map(|p| p.abs().max_element())
        .fold(0.0, Real::max);
    let tolerance = TOUCH_TOLERANCE * (1.0 + size) + 8.0 * Real::EPSILON * magnitude;
    // The separating direction of the last step, in shape 1's frame: the
    // contact normal once the gap is too small to give one.
    let mut dir1 = Vector::X;
    let mut t = p1.start;
    for step in 0..=TRIANGLE_STEPS {
        let pos1 = p1.at(t);
        let pos12 = pos1.inv_mul(&p2.at(t));
        let t2_in_1 = t2.map(|p| Vec3A::from((pos12 * Vector::from(p)).to_array()));
        let hit = |p1: Vec3A, q: Vec3A, dir1: Vector, status| ShapeCastHit {
            time_of_impact: t,
            normal1: dir1,
            normal2: pos12.rotation.inverse() * -dir1,
            witness1: Vector::from(p1.to_array()),
            witness2: pos12.inverse() * Vector::from(q.to_array()),
            status,
            subshape1: 0,
            subshape2: 0,
        };
        if step == 0 && triangles_intersect(t1, &t2_in_1) {
            let status = ShapeCastStatus::PenetratingOrWithinTargetDist;
            return stop_at_penetration.then(|| hit(t1[0], t1[0], dir1, status));
        }
        let (p1, q, gap) = triangle_closest_points(t1, &t2_in_1);
        if gap > Real::EPSILON * magnitude.max(1.0) {
            dir1 = Vector::from(((q - p1) / gap).to_array());
        }
        if gap <= tolerance {
            if step == 0 {
                let status = ShapeCastStatus::PenetratingOrWithinTargetDist;
                return stop_at_penetration.then(|| hit(p1, q, dir1, status));
            }
            return Some(hit(p1, q, dir1, ShapeCastStatus::Converged));
        }
        if step == TRIANGLE_STEPS {
            // Still apart after every step (a grazing, spinning approach):
            // `t` is before any contact, so it is a safe, early answer.
            return Some(hit(p1, q, dir1, ShapeCastStatus::OutOfIterations));
        }
        // The slab between the closest points, fixed in the world, keeps
        // the two apart until both sides have crossed it. A spin moves a
        // point across it at most at the spin's part across the slab's
        // normal times the lever arm.
        let n = pos1.rotation * dir1;
        let closing = relvel.dot(n)
            + n.cross(m1.angvel).length() * lever1
            + n.cross(m2.angvel).length() * lever2;
        if closing <= 0.0 {
            return None;
        }
        t += gap / closing;
        if t >= end {
            return None;
        }
    }
    unreachable!("the loop returns on its last step")
}

/// Casts two cbvh shapes against each other: a branch-and-bound over
/// pairs of nodes of both trees, a pair's bound the first time the two
/// nodes' bounding balls can meet (`ball_toi`), and triangle pairs at
/// the leaves. (Casting each triangle of one tree against the whole other
/// shape would search the other tree once per triangle near it.)
#[allow(clippy::too_many_arguments)]
pub fn cast_nonlinear_pair<D: ?Sized + QueryDispatcher>(
    dispatcher: &D,
    s1: &CbvhShape,
    m1: &NonlinearRigidMotion,
    s2: &CbvhShape,
    m2: &NonlinearRigidMotion,
    start: Real,
    end: Real,
    stop_at_penetration: bool,
) -> Option<ShapeCastHit> {
    let mut stats = TraversalStats::default();
    let (p1, p2) = (Posed::new(m1, start), Posed::new(m2, start));
    let found = with_cursor!(s1, |a| with_cursor!(s2, |b| bvtt_best(
        a,
        b,
        end,
        &mut stats,
        |x: &Aabb, y: &Aabb| ball_toi(
            &p1,
            x.center().into(),
            x.half_extents().length(),
            &p2,
            y.center().into(),
            y.half_extents().length(),
            end,
        ),
        |_, ti, _, tj, best| {
            // The best time found so far bounds every later pair's search.
            triangle_pair_toi(&p1, ti, &p2, tj, best.min(end), stop_at_penetration)
                .map(|h| (h.time_of_impact, h))
        }
    )));
    found.map(|(i, j, _, mut hit)| {
        advance_to_contact(dispatcher, m1, s1, m2, s2, start, end, &mut hit);
        hit.subshape1 = i;
        hit.subshape2 = j;
        hit
    })
}

/// Casts `mesh` (moving with `m_mesh`) against parry's `TriMesh` `tm`
/// (moving with `m_tm`) pair by pair: each cbvh triangle the search reaches
/// queries the `TriMesh`'s own tree for the triangles it can meet before
/// the best time so far, and each pair is cast by [`triangle_pair_toi`].
/// (Casting a cbvh triangle against the whole `TriMesh` through parry
/// answers the sweep's start for a pair in contact there, which rapier
/// discards, and that answer hid the later first contact: a cbvh bar spun
/// into a `TriMesh` strip went through it.)
#[allow(clippy::too_many_arguments)]
fn cast_nonlinear_trimesh(
    mesh: &CbvhShape,
    m_mesh: &NonlinearRigidMotion,
    tm: &TriMesh,
    m_tm: &NonlinearRigidMotion,
    mesh_first: bool,
    start: Real,
    end: Real,
    stop_at_penetration: bool,
) -> Option<ShapeCastHit> {
    let sphere = tm.compute_local_bounding_sphere();
    let tm_speed = speed_bound(m_tm, sphere.center, sphere.radius);
    let (p_mesh, p_tm) = (Posed::new(m_mesh, start), Posed::new(m_tm, start));
    // The mesh's frame in the TriMesh's, at `start`.
    let pose = p_tm.at_start.inv_mul(&p_mesh.at_start);
    let mut stats = TraversalStats::default();
    let found = with_cursor!(mesh, |c| find_best(
        c,
        end,
        &mut stats,
        |b: &Aabb| ball_toi(
            &p_mesh,
            b.center().into(),
            b.half_extents().length(),
            &p_tm,
            sphere.center,
            sphere.radius,
            end,
        ),
        |_, tri, best| {
            let mut best = best.min(end);
            // Everything the triangle can reach before `best`, in the
            // TriMesh's frame: its ball at `start` grown by the fastest the
            // two can close over that time.
            let centre = (tri[0] + tri[1] + tri[2]) / 3.0;
            let radius = tri
                .iter()
                .map(|p| (*p - centre).length())
                .fold(0.0, Real::max);
            let centre = Vector::from(centre.to_array());
            let reach =
                radius + (speed_bound(m_mesh, centre, radius) + tm_speed) * (best - start).max(0.0);
            let c = pose * centre;
            let region = PAabb::new(c - Vector::splat(reach), c + Vector::splat(reach));
            let mut hit: Option<ShapeCastHit> = None;
            for j in tm.bvh().intersect_aabb(&region) {
                let pt = tm.triangle(j);
                let tj: Triangle = [pt.a, pt.b, pt.c].map(|p| Vec3A::from(p.to_array()));
                let h = if mesh_first {
                    triangle_pair_toi(&p_mesh, tri, &p_tm, &tj, best, stop_at_penetration)
                } else {
                    triangle_pair_toi(&p_tm, &tj, &p_mesh, tri, best, stop_at_penetration)
                };
                if let Some(mut h) = h
                    && h.time_of_impact < best
                {
                    best = h.time_of_impact;
                    if mesh_first {
                        h.subshape2 = j;
                    } else {
                        h.subshape1 = j;
                    }
                    hit = Some(h);
                }
            }
            hit.map(|h| (h.time_of_impact, h))
        }
    ));
    found.map(|(id, _, mut hit)| {
        if mesh_first {
            hit.subshape1 = id;
        } else {
            hit.subshape2 = id;
        }
        hit
    })
}

/// Casts `mesh` (moving with `m_mesh`) against `other` (moving with
/// `m_other`). `mesh_first` says the mesh is shape 1 of the query, so the
/// hit's sides follow the caller's order.
#[allow(clippy::too_many_arguments)]
pub fn cast_nonlinear<D: ?Sized + QueryDispatcher>(
    dispatcher: &D,
    mesh: &CbvhShape,
    m_mesh: &NonlinearRigidMotion,
    other: &dyn Shape,
    m_other: &NonlinearRigidMotion,
    mesh_first: bool,
    start: Real,
    end: Real,
    stop_at_penetration: bool,
) -> Option<ShapeCastHit> {
    if let Some(tm) = other.as_shape::<TriMesh>() {
        return cast_nonlinear_trimesh(
            mesh,
            m_mesh,
            tm,
            m_other,
            mesh_first,
            start,
            end,
            stop_at_penetration,
        );
    }
    let sphere = other.compute_local_bounding_sphere();
    let (p_mesh, p_other) = (Posed::new(m_mesh, start), Posed::new(m_other, start));
    let mut stats = TraversalStats::default();
    let found = with_cursor!(mesh, |c| find_best(
        c,
        end,
        &mut stats,
        |b: &Aabb| ball_toi(
            &p_mesh,
            b.center().into(),
            b.half_extents().length(),
            &p_other,
            sphere.center,
            sphere.radius,
            end,
        ),
        |_, tri, best| {
            let end = best.min(end);
            let t = to_parry_triangle(tri);
            let (m1, g1, m2, g2): (_, &dyn Shape, _, &dyn Shape) = if mesh_first {
                (m_mesh, &t, m_other, other)
            } else {
                (m_other, other, m_mesh, &t)
            };
            leaf_cast(dispatcher, m1, g1, m2, g2, start, end, stop_at_penetration)
                .map(|h| (h.time_of_impact, h))
        }
    ));
    found.map(|(id, _, mut hit)| {
        if mesh_first {
            advance_to_contact(
                dispatcher, m_mesh, mesh, m_other, other, start, end, &mut hit,
            );
        } else {
            advance_to_contact(
                dispatcher, m_other, other, m_mesh, mesh, start, end, &mut hit,
            );
        }
        if mesh_first {
            hit.subshape1 = id;
        } else {
            hit.subshape2 = id;
        }
        hit
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fixed sequence (splitmix64), so every run checks the same cases.
    struct Cases(u64);

    impl Cases {
        fn next(&mut self) -> f32 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
        }
        fn signed(&mut self, r: f32) -> f32 {
            (2.0 * self.next() - 1.0) * r
        }
        fn vector(&mut self, r: f32) -> Vector {
            Vector::new(self.signed(r), self.signed(r), self.signed(r))
        }
        fn triangle(&mut self) -> Triangle {
            let c = self.vector(0.3);
            [0, 1, 2].map(|_| Vec3A::from((c + self.vector(0.5)).to_array()))
        }
    }

    fn toi(
        m1: &NonlinearRigidMotion,
        t1: &Triangle,
        m2: &NonlinearRigidMotion,
        t2: &Triangle,
        start: Real,
        end: Real,
        stop_at_penetration: bool,
    ) -> Option<ShapeCastHit> {
        let (p1, p2) = (Posed::new(m1, start), Posed::new(m2, start));
        triangle_pair_toi(&p1, t1, &p2, t2, end, stop_at_penetration)
    }

    fn world(m: &NonlinearRigidMotion, t: Real, tri: &Triangle) -> Triangle {
        let pose = m.position_at_time(t);
        tri.map(|p| Vec3A::from((pose * Vector::from(p)).to_array()))
    }

    fn overlap(
        m1: &NonlinearRigidMotion,
        t1: &Triangle,
        m2: &NonlinearRigidMotion,
        t2: &Triangle,
        t: Real,
    ) -> bool {
        triangles_intersect(&world(m1, t, t1), &world(m2, t, t2))
    }

    /// Against a dense sampling of the two motions with the kernel's exact
    /// overlap test: a converged time is a touch with no overlap before
    /// it, and "no hit" means no sampled overlap at all. Spins up to 40
    /// rad/s and closing speeds up to 20 m/s over a second.
    #[test]
    fn triangle_pair_toi_is_the_first_contact_of_spinning_triangles() {
        let mut cases = Cases(49);
        let (start, end) = (0.0, 1.0);
        let samples = 1000;
        let (mut hits, mut early, mut misses) = (0, 0, 0);
        for case in 0..300 {
            let (t1, t2) = (cases.triangle(), cases.triangle());
            let p1 = Pose::new(cases.vector(0.3), cases.vector(3.0));
            let p2 = Pose::new(
                cases.vector(0.3) + Vector::new(4.0, 0.0, 0.0),
                cases.vector(3.0),
            );
            let spin = if case % 3 == 0 { 0.0 } else { 40.0 };
            let m1 = NonlinearRigidMotion::new(
                p1,
                cases.vector(0.2),
                cases.vector(0.5) + Vector::new(6.0, 0.0, 0.0),
                cases.vector(spin),
            );
            let m2 = NonlinearRigidMotion::new(
                p2,
                cases.vector(0.2),
                cases.vector(0.5),
                cases.vector(spin),
            );
            if overlap(&m1, &t1, &m2, &t2, start) {
                continue;
            }
            let first = (0..=samples)
                .map(|k| start + (end - start) * k as Real / samples as Real)
                .find(|&t| overlap(&m1, &t1, &m2, &t2, t));
            match toi(&m1, &t1, &m2, &t2, start, end, false) {
                Some(hit) => {
                    hits += 1;
                    let t = hit.time_of_impact;
                    let (_, _, gap) =
                        triangle_closest_points(&world(&m1, t, &t1), &world(&m2, t, &t2));
                    let sampled = first.unwrap_or(end);
                    assert!(
                        t <= sampled,
                        "case {case}: answer {t} after an overlap at {sampled}"
                    );
                    if hit.status == ShapeCastStatus::OutOfIterations {
                        // A grazing approach under a fast spin: a safe,
                        // early answer.
                        early += 1;
                        continue;
                    }
                    assert_eq!(hit.status, ShapeCastStatus::Converged, "case {case}");
                    assert!(gap < 1e-4, "case {case}: gap {gap} at the answer {t}");
                    // The witnesses are the touching points, in each shape's frame.
                    let w1 = m1.position_at_time(t) * hit.witness1;
                    let w2 = m2.position_at_time(t) * hit.witness2;
                    assert!(
                        (w1 - w2).length() < 1e-3,
                        "case {case}: witnesses {w1} {w2}"
                    );
                }
                None => {
                    misses += 1;
                    assert_eq!(
                        first, None,
                        "case {case}: no hit, but an overlap at {first:?}"
                    );
                }
            }
        }
        // Both outcomes are exercised.
        eprintln!("{hits} hits ({early} early), {misses} misses");
        assert!(hits > 50 && misses > 50, "{hits} hits, {misses} misses");
        assert!(early * 20 <= hits, "{early} of {hits} hits stopped early");
    }

    /// A pair touching or overlapping at the start hits there when the
    /// cast stops at penetration, and is skipped when it does not.
    #[test]
    fn triangle_pair_toi_in_contact_at_the_start() {
        let t1: Triangle = [Vec3A::ZERO, Vec3A::X, Vec3A::Y];
        let t2: Triangle = [
            Vec3A::new(0.2, 0.2, -0.5),
            Vec3A::new(0.3, 0.2, 0.5),
            Vec3A::new(0.2, 0.3, 0.5),
        ];
        let still = NonlinearRigidMotion::constant_position(Pose::IDENTITY);
        let moving =
            NonlinearRigidMotion::new(Pose::IDENTITY, Vector::ZERO, Vector::Z, Vector::ZERO);
        let stop = toi(&still, &t1, &moving, &t2, 0.0, 1.0, true).expect("hit");
        assert_eq!(stop.time_of_impact, 0.0);
        assert_eq!(stop.status, ShapeCastStatus::PenetratingOrWithinTargetDist);
        assert!(toi(&still, &t1, &moving, &t2, 0.0, 1.0, false).is_none());
    }

    /// A face-on translation lands exactly: a triangle 1 m above a floor
    /// triangle falling at 4 m/s touches it at a quarter of a second.
    #[test]
    fn triangle_pair_toi_of_a_falling_triangle_is_the_analytic_time() {
        let floor: Triangle = [
            Vec3A::new(-5.0, 0.0, -5.0),
            Vec3A::new(5.0, 0.0, -5.0),
            Vec3A::new(0.0, 0.0, 5.0),
        ];
        let falling: Triangle = [
            Vec3A::new(0.0, 1.0, 0.0),
            Vec3A::new(1.0, 1.5, 0.0),
            Vec3A::new(0.0, 1.5, 1.0),
        ];
        let still = NonlinearRigidMotion::constant_position(Pose::IDENTITY);
        let fall = NonlinearRigidMotion::new(
            Pose::IDENTITY,
            Vector::ZERO,
            Vector::new(0.0, -4.0, 0.0),
            Vector::ZERO,
        );
        let hit = toi(&still, &floor, &fall, &falling, 0.0, 1.0, false).expect("hit");
        assert!(
            (hit.time_of_impact - 0.25).abs() < 1e-6,
            "{}",
            hit.time_of_impact
        );
        assert!((hit.normal1 - Vector::Y).length() < 1e-5, "{}", hit.normal1);
        assert!(toi(&still, &floor, &fall, &falling, 0.0, 0.2, false).is_none());
    }
}
