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
//!   with nothing left sideways is dropped (a back face). parry's
//!   `TrianglePseudoNormals` does the same with pseudo-normals, which need
//!   the neighbours' normals; the flags say as much in one byte.
//! - [`PairRule`]: two cbvh triangles (the per-pair mode): the normal is
//!   the oriented axis of [`crate::contact::orient`], the same rule the
//!   patch mode uses, and parry computes the contact points along it.

use glam::Vec3A;
use parry3d::math::{Pose as PPose, Vector};
use parry3d::query::details::NormalConstraints;

use crate::contact::Facing;
use crate::contact::edges::side_bits;
use crate::contact::orient::{PairFacing, oriented_axis};
use crate::geom::Triangle;

/// One triangle's normal cone from its facing and active edges. See the
/// module docs.
#[derive(Clone, Copy, Debug)]
pub struct EdgeCone {
    out: Vec3A,
    /// Outward in-plane normals of the edges.
    m: [Vec3A; 3],
    active: u8,
}

impl EdgeCone {
    /// The cone of triangle `t` with edge flags `flags`, facing `facing`;
    /// `None` for a triangle without area.
    pub fn new(t: &Triangle, flags: u8, facing: Facing) -> Option<Self> {
        let raw = (t[1] - t[0]).cross(t[2] - t[0]).try_normalize()?;
        let sign = facing.sign(t, raw);
        let m = [0, 1, 2].map(|k| (t[(k + 1) % 3] - t[k]).cross(raw).normalize_or_zero());
        Some(Self {
            out: raw * sign,
            m,
            active: side_bits(flags, sign > 0.0),
        })
    }

    /// Projects the unit direction `dir` (out of the triangle) into the
    /// cone; `false` when it points into the back face.
    pub fn project(&self, dir: Vec3A) -> Option<Vec3A> {
        let d = dir.dot(self.out);
        let u = dir - self.out * d;
        let mut act = [Vec3A::ZERO; 3];
        let mut len = 0;
        for k in 0..3 {
            if self.active & (1 << k) != 0 {
                act[len] = self.m[k];
                len += 1;
            }
        }
        let side = match len {
            0 => Vec3A::ZERO,
            1 => act[0] * u.dot(act[0]).max(0.0),
            2 => {
                // u = x m0 + y m1 in the plane: inside when both are >= 0.
                let (m0, m1) = (act[0], act[1]);
                let (a, b, c) = (m0.dot(m0), m0.dot(m1), m1.dot(m1));
                let (p, q) = (u.dot(m0), u.dot(m1));
                let det = a * c - b * b;
                let inside = det.abs() > 1e-12 && {
                    let x = (p * c - q * b) / det;
                    let y = (q * a - p * b) / det;
                    x >= 0.0 && y >= 0.0
                };
                if inside {
                    u
                } else if p >= q {
                    m0 * p.max(0.0)
                } else {
                    m1 * q.max(0.0)
                }
            }
            _ => u,
        };
        if d < 0.0 && side.length_squared() <= 1e-12 {
            return None;
        }
        let n = self.out * d.max(0.0) + side;
        Some(n.try_normalize().unwrap_or(self.out))
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
#[derive(Clone, Copy, Debug)]
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
    /// [`oriented_axis`]).
    pub prediction: f32,
}

impl PairRule {
    fn normal(&self) -> Option<Vec3A> {
        oriented_axis(
            &self.a,
            self.fa,
            &self.b,
            self.fb,
            &self.facing,
            self.prediction,
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
