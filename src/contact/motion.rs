//! The prediction distance of a body pair bounded by how far its points
//! moved since the last step, region by region.
//!
//! A contact within the prediction distance is speculative: the solver only
//! acts on it if the bodies would close the gap within the step. A pair of
//! triangles whose gap is larger than the distance their points can move in
//! one step is inert, and a resting body need not pay for all of them.
//! [`PatchOptions::motion_factor`](super::PatchOptions::motion_factor) bounds
//! the distance by `factor ×` the largest move since the last step (at least
//! a tenth of the full distance, never more than it).
//!
//! The largest move over the whole contact region is that of its farthest
//! corner, and a body that turns (a statue rocking on a rotor) moves its
//! far points much more than the ones near the contact. So the bound is
//! taken per node pair of the two-tree traversal, over the box of `B`'s
//! points in that subtree: [`MotionBound`] is a
//! [`crate::query::Prediction`].
//!
//! # The bound over a box
//!
//! Let `Q` map the current position of a point of `B` (in `A`'s frame) to
//! its position at the last step: `Q = last ∘ now⁻¹`, a rigid motion
//! `y ↦ R y + t`. The move of a point `y` is `d(y) = y − Q y = (I − R) y −
//! t`, affine in `y`. Over a box with centre `c` and half extents `h`,
//! `|d(y)| ≤ |d(c)| + ‖I − R‖ |h|`, with the Frobenius norm of `I − R` (above
//! its spectral norm `2 sin(θ / 2)`, and computed element by element, so a
//! tiny rotation is not lost to rounding the way `3 − trace R` would lose
//! it).

use glam::Vec3A;

use crate::geom::{Aabb, Pose};
use crate::query::Prediction;

/// A prediction distance bounded by the motion of `B`'s points since the
/// last step, per region (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotionBound {
    /// The distance for the whole pair: the largest any region gets.
    pub prediction: f32,
    motion: Option<Motion>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct Motion {
    /// Current position in `A`'s frame → last step's.
    back: Pose,
    /// Frobenius norm of `I − R`.
    turn: f32,
    factor: f32,
    floor: f32,
}

impl MotionBound {
    /// The same distance everywhere.
    pub fn constant(prediction: f32) -> Self {
        Self {
            prediction: prediction.max(0.0),
            motion: None,
        }
    }

    /// The bound for `B` placed by `now` in `A`'s frame, placed by `last`
    /// at the last step: per region `factor ×` the largest move, at least
    /// `floor`, at most `prediction`.
    pub fn new(prediction: f32, now: &Pose, last: &Pose, factor: f32, floor: f32) -> Self {
        let back = last.mul(&now.inverse());
        let r = back.rotation;
        let d = [
            Vec3A::X - r.x_axis,
            Vec3A::Y - r.y_axis,
            Vec3A::Z - r.z_axis,
        ];
        let turn = d.iter().map(|c| c.length_squared()).sum::<f32>().sqrt();
        let prediction = prediction.max(0.0);
        Self {
            prediction,
            motion: Some(Motion {
                back,
                turn,
                factor: factor.max(0.0),
                floor: floor.clamp(0.0, prediction),
            }),
        }
    }

    /// The largest move of a point of `B` inside `b_box` (in `A`'s frame)
    /// since the last step; 0 without motion.
    pub fn largest_move(&self, b_box: &Aabb) -> f32 {
        match &self.motion {
            None => 0.0,
            Some(m) => {
                let c = b_box.center();
                (c - m.back.transform_point(c)).length() + m.turn * b_box.half_extents().length()
            }
        }
    }
}

impl Prediction for MotionBound {
    #[inline]
    fn at_most(&self) -> f32 {
        self.prediction
    }

    #[inline]
    fn within(&self, b_box: &Aabb) -> f32 {
        match &self.motion {
            None => self.prediction,
            Some(m) => (m.factor * self.largest_move(b_box))
                .max(m.floor)
                .min(self.prediction),
        }
    }

    #[inline]
    fn floor(&self) -> f32 {
        match &self.motion {
            None => self.prediction,
            Some(m) => m.floor,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Quat, Vec3};

    /// The bound holds for every point of a box, for turns and shifts of
    /// several sizes: the exact move of random points never exceeds it.
    #[test]
    fn the_bound_covers_every_point_of_the_box() {
        let mut seed = 7u64;
        let mut rnd = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 40) as f32 / (1u64 << 24) as f32 - 0.5
        };
        for k in 0..200 {
            let angle = [0.0, 1e-6, 1e-4, 1e-2, 0.5][k % 5];
            let axis = Vec3::new(rnd(), rnd(), rnd()).normalize_or(Vec3::X);
            let now = Pose::from_rotation_translation(
                Quat::from_axis_angle(axis, rnd() * 6.0),
                Vec3::new(rnd(), rnd(), rnd()) * 10.0,
            );
            let step = Pose::from_rotation_translation(
                Quat::from_axis_angle(axis, angle),
                Vec3::new(rnd(), rnd(), rnd()) * [0.0, 1e-4, 1e-2, 1.0][k % 4],
            );
            let last = step.mul(&now);
            let bound = MotionBound::new(1.0, &now, &last, 1.0, 0.0);
            let lo = Vec3A::new(rnd(), rnd(), rnd()) * 20.0;
            let b = Aabb::new(
                lo,
                lo + Vec3A::new(rnd() + 0.5, rnd() + 0.5, rnd() + 0.5) * 3.0,
            );
            let limit = bound.largest_move(&b);
            for _ in 0..50 {
                let t = Vec3A::new(rnd() + 0.5, rnd() + 0.5, rnd() + 0.5);
                let y = b.min + (b.max - b.min) * t;
                // `y` is where a point of B is now; where was it?
                let x = now.inverse().transform_point(y);
                let moved = (last.transform_point(x) - y).length();
                assert!(
                    moved <= limit * (1.0 + 1e-4) + 1e-5,
                    "a point moved {moved}, above the bound {limit} (angle {angle})"
                );
            }
        }
    }

    /// A still body gets the floor, a fast one the full distance, and a
    /// turn moves a far box more than a near one.
    #[test]
    fn the_distance_follows_the_motion() {
        let now = Pose::IDENTITY;
        let near = Aabb::new(Vec3A::splat(-0.01), Vec3A::splat(0.01));
        let far = Aabb::new(Vec3A::new(4.99, -0.01, -0.01), Vec3A::new(5.01, 0.01, 0.01));
        let still = MotionBound::new(0.02, &now, &now, 2.0, 0.002);
        assert_eq!(still.within(&near), 0.002);
        let fast = Pose::from_rotation_translation(Quat::IDENTITY, Vec3::new(0.0, 0.5, 0.0));
        assert_eq!(
            MotionBound::new(0.02, &now, &fast, 2.0, 0.002).within(&near),
            0.02
        );
        // Turning 1 mrad about the origin: the near box moves about 17 µm,
        // the box 5 away about 5 mm.
        let turn = Pose::from_rotation_translation(Quat::from_rotation_z(1e-3), Vec3::ZERO);
        let m = MotionBound::new(0.02, &now, &turn, 2.0, 0.002);
        assert_eq!(m.within(&near), 0.002);
        let f = m.within(&far);
        assert!(f > 0.009 && f < 0.0111, "far box: {f}");
        assert_eq!(MotionBound::constant(0.02).within(&far), 0.02);
        // `floor` is the least `within` gives: the traversal keeps a
        // prediction at the floor without computing the bound.
        assert_eq!(m.floor(), m.within(&near));
        assert!(m.floor() < f);
        assert_eq!(MotionBound::constant(0.02).floor(), 0.02);
    }
}
