//! cbvh's active edges and facing as parry normal constraints, for the
//! paths where parry's own convex-convex code computes the contact: a cbvh
//! triangle against a convex shape, and the per-triangle-pair mode.
//!
//! - [`EdgeCone`]: one triangle's normal cone. A normal out of the
//!   triangle keeps its component along the face normal (the side the
//!   triangle faces) and only the part of its sideways component that
//!   leans over an *active* edge (the cone spanned by the face normal and
//!   the outward in-plane normals of its active edges); a triangle with no
//!   active edge gives its face normal. A normal into the triangle's back
//!   with nothing left sideways is dropped (a back face). A lean over an
//!   edge shared with one neighbour (a sharp edge active from this side
//!   only, or one within the flat angle) goes no further than the
//!   neighbour's face normal, where the edge's normal cone ends: a box
//!   reaching a ridge over its flat half meets the crease along its own
//!   bottom's normal, not along the down triangle's in-plane edge normal
//!   (which kicks it up), and the lean over a nearly flat convex crease
//!   is the few degrees the surface turns there. The flags do not hold the
//!   neighbour: a projection that leans over such an edge records it
//!   ([`EdgeCone::wanted`]), and the caller looks the neighbour up
//!   ([`neighbour_apex`]) and computes the contact again, so contacts inside a
//!   face pay nothing. parry's `TrianglePseudoNormals` does much the same
//!   with pseudo-normals stored per triangle.
//! - [`PairRule`]: two cbvh triangles (the per-pair mode): the normal is
//!   the oriented axis of [`crate::contact::orient`], the same rule the
//!   patch mode uses, and parry computes the contact points along it.

use std::cell::Cell;
use std::ops::ControlFlow;
use std::sync::Arc;

use glam::Vec3A;
use parry3d::math::{Pose as PPose, Vector};
use parry3d::query::details::NormalConstraints;

use super::shape::CbvhShape;
use crate::contact::Facing;
use crate::contact::edges::side_bits;
use crate::contact::orient::{Neighbours, PairFacing, SideCache, bend_toward, oriented_axis_near};
use crate::cursor::TraversalStats;
use crate::geom::{Aabb, Pose, Triangle};
use crate::query::overlap;

/// How far a normal may lean over one edge of an [`EdgeCone`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lean {
    /// Not known yet: the edge is shared with one neighbour, whose face
    /// normal bounds the lean ([`EdgeCone::wanted`]).
    Unknown,
    /// No neighbour found: an active edge takes any lean out of the face
    /// (up to 90°), an inactive one none.
    Free,
    /// Up to the neighbour's face normal: `out · c + m · s` (the cosine
    /// and sine of the bend; `s ≤ 0` when the edge is concave from this
    /// side, which takes no lean).
    UpTo(f32, f32),
}

/// One triangle's normal cone from its facing and active edges. See the
/// module docs.
#[derive(Clone, Debug)]
pub struct EdgeCone {
    out: Vec3A,
    /// Outward in-plane normals of the edges.
    m: [Vec3A; 3],
    active: u8,
    /// Edges shared with one neighbour whose face normal bounds a lean
    /// over them: active from this side only (a sharp convex edge), or
    /// from neither side (within the flat angle, flat or nearly).
    shared: u8,
    lean: [Lean; 3],
    /// Shared edges a projection leaned over while their [`Lean`] was
    /// unknown.
    wanted: Cell<u8>,
}

impl EdgeCone {
    /// The cone of triangle `t` with edge flags `flags`, facing `facing`;
    /// `None` for a triangle without area.
    pub fn new(t: &Triangle, flags: u8, facing: Facing) -> Option<Self> {
        let raw = (t[1] - t[0]).cross(t[2] - t[0]).try_normalize()?;
        let sign = facing.sign(t, raw);
        let m = [0, 1, 2].map(|k| (t[(k + 1) % 3] - t[k]).cross(raw).normalize_or_zero());
        let active = side_bits(flags, sign > 0.0);
        let other = side_bits(flags, sign <= 0.0);
        Some(Self {
            out: raw * sign,
            m,
            active,
            shared: (active & !other) | (!active & !other & 0b111),
            lean: [Lean::Unknown; 3],
            wanted: Cell::new(0),
        })
    }

    /// The shared edges (bit `k`: edge `k`) that a projection since
    /// [`set_lean`](Self::set_lean) leaned over without knowing how far it
    /// may: the caller looks their neighbours up ([`neighbour_apex`]), sets
    /// them, and projects again.
    pub fn wanted(&self) -> u8 {
        self.wanted.get()
    }

    /// Whether the triangle has an edge whose lean a neighbour bounds
    /// (so a projection may come to want it).
    pub fn has_shared(&self) -> bool {
        self.shared != 0
    }

    /// Sets the lean of every edge this cone of triangle `id` of `mesh`
    /// (`t`, in the mesh's frame) [`wanted`](Self::wanted), from the
    /// triangle sharing that edge: an overlap query with the edge's box,
    /// only for an edge a normal leaned over, so a contact inside a face
    /// pays nothing.
    pub fn complete(&mut self, mesh: &CbvhShape, id: u32, t: &Triangle) {
        let wanted = self.wanted();
        for k in (0..3).filter(|k| wanted & (1 << k) != 0) {
            let lean = neighbour_apex(mesh, id, t, k)
                .and_then(|w| bend_toward(t, k, self.out, self.m[k], w))
                .map_or(Lean::Free, |(c, s)| Lean::UpTo(c, s));
            self.set_lean(k, lean);
        }
    }

    /// Sets how far a normal may lean over edge `k`, and clears its
    /// [`wanted`](Self::wanted) bit.
    pub fn set_lean(&mut self, k: usize, lean: Lean) {
        self.lean[k] = lean;
        self.wanted.set(self.wanted.get() & !(1 << k));
    }

    /// The face's outward normal.
    pub fn out(&self) -> Vec3A {
        self.out
    }

    /// Edge `k`'s outward in-plane normal.
    pub fn edge_normal(&self, k: usize) -> Vec3A {
        self.m[k]
    }

    /// `(d, x)` (the components along the face normal and along edge
    /// `k`'s in-plane normal) turned back to the neighbour's face normal
    /// when they lean past it: the lean over a convex edge ends there.
    #[inline]
    fn bound(&self, k: usize, d: f32, x: f32) -> (f32, f32) {
        match self.lean[k] {
            Lean::UpTo(c, s) if x > 0.0 && x * c > d * s => {
                let r = (d * d + x * x).sqrt();
                if s <= 0.0 { (r, 0.0) } else { (r * c, r * s) }
            }
            _ => (d, x),
        }
    }

    /// Projects the unit direction `dir` (out of the triangle) into the
    /// cone; `None` when it points into the back face.
    pub fn project(&self, dir: Vec3A) -> Option<Vec3A> {
        let d = dir.dot(self.out);
        let u = dir - self.out * d;
        // The edges a normal may lean over: the active ones, and the
        // shared inactive ones whose neighbour bends away (convex).
        let mut act = [(0usize, Vec3A::ZERO); 3];
        let mut len = 0;
        let mut wanted = 0u8;
        for k in 0..3 {
            let bit = 1 << k;
            let over = u.dot(self.m[k]) > 1e-6;
            let lean = if self.active & bit != 0 {
                true
            } else if self.shared & bit != 0 {
                matches!(self.lean[k], Lean::UpTo(_, s) if s > 0.0)
            } else {
                false
            };
            if over && self.shared & bit != 0 && self.lean[k] == Lean::Unknown {
                wanted |= bit;
            }
            if lean {
                act[len] = (k, self.m[k]);
                len += 1;
            }
        }
        if wanted != 0 {
            self.wanted.set(self.wanted.get() | wanted);
        }
        let within = |k: usize, x: f32| self.bound(k, d, x) == (d, x);
        // Lean over one edge: its component, bounded by the neighbour.
        let one = |(k, m): (usize, Vec3A)| {
            let (dd, x) = self.bound(k, d, u.dot(m).max(0.0));
            (dd, m * x)
        };
        let (d2, side) = match len {
            0 => (d, Vec3A::ZERO),
            1 => one(act[0]),
            2 => {
                // u = x m0 + y m1 in the plane: inside when both are >= 0.
                let ((k0, m0), (k1, m1)) = (act[0], act[1]);
                let (a, b, c) = (m0.dot(m0), m0.dot(m1), m1.dot(m1));
                let (p, q) = (u.dot(m0), u.dot(m1));
                let det = a * c - b * b;
                let inside = det.abs() > 1e-12 && {
                    let x = (p * c - q * b) / det;
                    let y = (q * a - p * b) / det;
                    x >= 0.0 && y >= 0.0 && within(k0, x) && within(k1, y)
                };
                if inside {
                    (d, u)
                } else if p >= q {
                    one(act[0])
                } else {
                    one(act[1])
                }
            }
            _ => {
                if (0..3).all(|k| within(k, u.dot(self.m[k]).max(0.0))) {
                    (d, u)
                } else {
                    let k = (0..3)
                        .max_by(|&i, &j| u.dot(self.m[i]).total_cmp(&u.dot(self.m[j])))
                        .expect("three edges");
                    one(act[k])
                }
            }
        };
        if d2 < 0.0 && side.length_squared() <= 1e-12 {
            return None;
        }
        let n = self.out * d2.max(0.0) + side;
        let n = n.try_normalize().unwrap_or(self.out);
        // A direction the cone keeps comes back as it was, to the bit:
        // parry takes any change as a correction and casts a ray for the
        // contact point, which misses a triangle whose edge the contact
        // lies on (a ball just off a ridge's crease, on a codec that
        // quantizes the crease a few micrometres off the ball's foot).
        if (n - dir).length_squared() <= 1e-12 {
            return Some(dir);
        }
        Some(n)
    }
}

/// The corner, off the edge, of the triangle of `mesh` other than `id`
/// that shares edge `k` (corner `k` to `k + 1`) of triangle `t` (in the
/// mesh's frame): an overlap query with the edge's box, its corners matched
/// within a hundred-thousandth of the edge's length.
pub fn neighbour_apex(mesh: &CbvhShape, id: u32, t: &Triangle, k: usize) -> Option<Vec3A> {
    let (a, b) = (t[k], t[(k + 1) % 3]);
    let tol = 1e-5 * (b - a).length() + 1e-7 * a.abs().max(b.abs()).max_element();
    let mut edge = Aabb::EMPTY;
    edge.grow(a);
    edge.grow(b);
    let query = edge.loosened(tol);
    let near = |p: Vec3A, q: Vec3A| (p - q).length_squared() <= tol * tol;
    let mut found = None;
    let mut stats = TraversalStats::default();
    with_cursor!(mesh, |c| {
        overlap(c, &query, &mut stats, |j, other| {
            if j == id {
                return ControlFlow::Continue(());
            }
            let ia = (0..3).find(|&i| near(other[i], a));
            let ib = (0..3).find(|&i| near(other[i], b));
            match (ia, ib) {
                (Some(ia), Some(ib)) if ia != ib => {
                    found = Some(other[3 - ia - ib]);
                    ControlFlow::Break(())
                }
                _ => ControlFlow::Continue(()),
            }
        });
    });
    found
}

/// [`Neighbours`] of a pair of cbvh shapes (or of side A alone): side B
/// placed in A's frame by a pose.
#[derive(Clone)]
pub struct MeshNeighbours {
    /// Side A.
    pub a: CbvhShape,
    /// Side B and its pose in A's frame.
    pub b: Option<(CbvhShape, Pose)>,
}

impl Neighbours for MeshNeighbours {
    fn apex(&self, b: bool, id: u32, t: &Triangle, k: usize) -> Option<Vec3A> {
        if !b {
            return neighbour_apex(&self.a, id, t, k);
        }
        let (mesh, pose) = self.b.as_ref()?;
        let inv = pose.inverse();
        let local = t.map(|v| inv.transform_point(v));
        neighbour_apex(mesh, id, &local, k).map(|w| pose.transform_point(w))
    }
}

impl NormalConstraints for EdgeCone {
    fn project_local_normal_mut(&self, normal: &mut Vector) -> bool {
        match self.project(Vec3A::from(*normal)) {
            Some(n) => {
                *normal = n.into();
                true
            }
            None => false,
        }
    }
}

/// The oriented-axis rule for a pair of cbvh triangles, as the constraint
/// of parry's shape 1 (pass `None` for shape 2): the normal becomes the
/// pair's oriented axis, or the pair is dropped when there is none.
#[derive(Clone)]
pub struct PairRule {
    /// Triangle A, in shape 1's frame.
    pub a: Triangle,
    /// A's edge flags.
    pub fa: u8,
    /// Triangle B, in shape 1's frame.
    pub b: Triangle,
    /// B's edge flags.
    pub fb: u8,
    /// Both facings, in shape 1's frame.
    pub facing: PairFacing,
    /// The prediction distance (the depth slack of
    /// [`oriented_axis_near`]).
    pub prediction: f32,
    /// A's and B's triangle ids, for `neighbours`.
    pub ids: (u32, u32),
    /// Where the triangles sharing A's and B's edges are found (a lean
    /// over a shared edge ends at the neighbour's face normal); `None`: as
    /// far as the flags allow.
    pub neighbours: Option<Arc<dyn Neighbours>>,
}

impl PairRule {
    fn normal(&self) -> Option<Vec3A> {
        oriented_axis_near(
            (&self.a, self.ids.0, self.fa),
            (&self.b, self.ids.1, self.fb),
            &self.facing,
            self.prediction,
            None,
            &mut SideCache::new(),
            self.neighbours.as_deref(),
        )
        .map(|o| o.normal)
    }
}

impl NormalConstraints for PairRule {
    fn project_local_normal_mut(&self, normal: &mut Vector) -> bool {
        match self.normal() {
            Some(n) => {
                *normal = n.into();
                true
            }
            None => false,
        }
    }

    fn project_local_normal1(
        &self,
        pos12: &PPose,
        normal1: &mut Vector,
        normal2: &mut Vector,
    ) -> bool {
        if !self.project_local_normal_mut(normal1) {
            return false;
        }
        *normal2 = pos12.rotation.inverse() * -*normal1;
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::edges::ALL_ACTIVE;

    fn floor() -> Triangle {
        [[-1.0, 0.0, -1.0], [-1.0, 0.0, 1.0], [1.0, 0.0, 0.0]].map(Vec3A::from)
    }

    #[test]
    fn a_triangle_without_active_edges_gives_its_face_normal() {
        let c = EdgeCone::new(&floor(), 0, Facing::OneSided(1.0)).unwrap();
        let tilted = Vec3A::new(0.5, 1.0, 0.2).normalize();
        assert_eq!(c.project(tilted), Some(Vec3A::Y));
        assert_eq!(c.project(Vec3A::new(0.3, -1.0, 0.0).normalize()), None);
        // Two-sided, facing a point below: the face normal is -y.
        let below = Facing::TwoSided {
            toward: Vec3A::new(0.0, -3.0, 0.0),
        };
        let c = EdgeCone::new(&floor(), 0, below).unwrap();
        assert_eq!(
            c.project(Vec3A::new(0.1, -1.0, 0.0).normalize()),
            Some(Vec3A::NEG_Y)
        );
    }

    #[test]
    fn active_edges_keep_the_lean_over_them() {
        let c = EdgeCone::new(&floor(), ALL_ACTIVE, Facing::OneSided(1.0)).unwrap();
        let tilted = Vec3A::new(0.5, 1.0, 0.2).normalize();
        let p = c.project(tilted).unwrap();
        assert!((p - tilted).length() < 1e-6);
        // Only the edge at x = -1 (corner 0 -> 1) active: a lean toward +x
        // is removed, one toward -x kept.
        let c = EdgeCone::new(&floor(), 0b001, Facing::OneSided(1.0)).unwrap();
        assert!((c.project(tilted).unwrap() - Vec3A::Y).length() < 1e-6);
        let left = Vec3A::new(-0.5, 1.0, 0.0).normalize();
        assert!((c.project(left).unwrap() - left).length() < 1e-6);
    }
}
