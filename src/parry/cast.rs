//! Nonlinear shape casts (rapier's CCD sweeps) with a cbvh shape on either
//! side, on the cbvh tree: a best-first search whose node bound is the
//! first time the node's bounding ball can meet the other shape's, by
//! conservative advancement on the two motions (`ball_toi`), and whose
//! leaves go to the dispatcher for the triangle against the other shape.
//! Two cbvh shapes are searched together, over pairs of nodes of both
//! trees ([`cast_nonlinear_pair`]).
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
//! skip the triangle pairs that intersect at `start`: such a pair can only
//! answer `start`, which rapier discards, and which would hide another
//! pair's later first contact. A parry `TriMesh` cast the same way answers
//! `start`.

use parry3d::math::{Real, Vector};
use parry3d::query::{NonlinearRigidMotion, QueryDispatcher, ShapeCastHit, ShapeCastStatus};
use parry3d::shape::Shape;

use glam::Vec3A;

use super::shape::{CbvhShape, to_parry_triangle};
use crate::contact::triangles_intersect;
use crate::cursor::TraversalStats;
use crate::geom::{Aabb, Triangle};
use crate::query::{bvtt_best, find_best};

/// Most steps of [`ball_toi`]'s conservative advancement.
const ADVANCE_STEPS: usize = 64;

/// Most steps of [`advance_to_contact`].
const CLOSE_STEPS: usize = 32;

/// Bisection steps that bring a cast parry reports as
/// [`ShapeCastStatus::Failed`] back to its first contact (`first_contact`).
const REFINE_STEPS: usize = 24;

/// The fastest any point within `radius` of `local` (in the moving body's
/// frame) moves under `m`: its linear speed plus the spin times the
/// farthest such point's distance from the centre of rotation.
fn speed_bound(m: &NonlinearRigidMotion, local: Vector, radius: Real) -> Real {
    m.linvel.length() + m.angvel.length() * ((local - m.local_center).length() + radius)
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
fn ball_toi(
    m1: &NonlinearRigidMotion,
    c1: Vector,
    r1: Real,
    m2: &NonlinearRigidMotion,
    c2: Vector,
    r2: Real,
    start: Real,
    end: Real,
) -> Real {
    let closing = speed_bound(m1, c1, 0.0) + speed_bound(m2, c2, 0.0);
    let reach = r1 + r2;
    let tolerance = 1e-5 * reach.max(1e-3);
    let mut t = start;
    for _ in 0..ADVANCE_STEPS {
        let w1 = m1.position_at_time(t) * c1;
        let w2 = m2.position_at_time(t) * c2;
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
    // Shape 2's triangles in shape 1's frame at `start`, for the overlap
    // test below.
    let pos12 = m1
        .position_at_time(start)
        .inv_mul(&m2.position_at_time(start));
    let to_1 = |t: &Triangle| t.map(|p| Vec3A::from((pos12 * Vector::from(p)).to_array()));
    let found = with_cursor!(s1, |a| with_cursor!(s2, |b| bvtt_best(
        a,
        b,
        end,
        &mut stats,
        |x: &Aabb, y: &Aabb| ball_toi(
            m1,
            x.center().into(),
            x.half_extents().length(),
            m2,
            y.center().into(),
            y.half_extents().length(),
            start,
            end,
        ),
        |_, ti, _, tj, _| {
            // Without `stop_at_penetration` a triangle pair that already
            // intersects at `start` can only answer `start` (parry's rule
            // for a pair in contact), which rapier's CCD discards, and
            // which as the best time would hide a later first contact of
            // another pair. Skipped by the kernel's exact separating-axis
            // test instead of a nonlinear cast: a body resting on a mesh
            // has thousands of such pairs, and casting each took seconds a
            // step for a 1.2 M-triangle scan on an 18 k-triangle part.
            if !stop_at_penetration && triangles_intersect(ti, &to_1(tj)) {
                return None;
            }
            let (t1, t2) = (to_parry_triangle(ti), to_parry_triangle(tj));
            leaf_cast(
                dispatcher,
                m1,
                &t1,
                m2,
                &t2,
                start,
                end,
                stop_at_penetration,
            )
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
    let sphere = other.compute_local_bounding_sphere();
    let mut stats = TraversalStats::default();
    let found = with_cursor!(mesh, |c| find_best(
        c,
        end,
        &mut stats,
        |b: &Aabb| ball_toi(
            m_mesh,
            b.center().into(),
            b.half_extents().length(),
            m_other,
            sphere.center,
            sphere.radius,
            start,
            end,
        ),
        |_, tri, _| {
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
