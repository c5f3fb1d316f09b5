//! Small geometry types shared by the builder, the codecs and the queries.
//!
//! Vectors are glam's (the same glam that parry3d uses through `glamx`), so
//! the parry integration converts nothing. [`Aabb`] uses `Vec3A` for SIMD.

use glam::{BVec3A, Mat3A, Vec3, Vec3A};

/// An axis-aligned bounding box. An *empty* box has `min > max`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Minimum corner.
    pub min: Vec3A,
    /// Maximum corner.
    pub max: Vec3A,
}

impl Default for Aabb {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Aabb {
    /// The empty box: the identity of [`Aabb::union`].
    pub const EMPTY: Aabb = Aabb {
        min: Vec3A::splat(f32::INFINITY),
        max: Vec3A::splat(f32::NEG_INFINITY),
    };

    /// A box from its corners.
    #[inline]
    pub fn new(min: Vec3A, max: Vec3A) -> Self {
        Self { min, max }
    }

    /// A box from `[f32; 3]` corners.
    #[inline]
    pub fn from_arrays(min: [f32; 3], max: [f32; 3]) -> Self {
        Self::new(Vec3A::from(min), Vec3A::from(max))
    }

    /// The tight box around a triangle.
    #[inline]
    pub fn of_triangle(t: &Triangle) -> Self {
        Self::new(t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]))
    }

    /// Whether the box contains no point.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    /// The smallest box containing both.
    #[inline]
    pub fn union(&self, o: &Aabb) -> Aabb {
        Aabb::new(self.min.min(o.min), self.max.max(o.max))
    }

    /// Grows the box to contain `p`.
    #[inline]
    pub fn grow(&mut self, p: Vec3A) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// The box grown by `margin` on every side.
    #[inline]
    pub fn loosened(&self, margin: f32) -> Aabb {
        Aabb::new(
            self.min - Vec3A::splat(margin),
            self.max + Vec3A::splat(margin),
        )
    }

    /// Centre point.
    #[inline]
    pub fn center(&self) -> Vec3A {
        (self.min + self.max) * 0.5
    }

    /// Half of the extents.
    #[inline]
    pub fn half_extents(&self) -> Vec3A {
        (self.max - self.min) * 0.5
    }

    /// Extents (`max - min`).
    #[inline]
    pub fn extent(&self) -> Vec3A {
        self.max - self.min
    }

    /// Half the surface area (the SAH only needs ratios); 0 for empty boxes.
    #[inline]
    pub fn half_area(&self) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        let d = self.extent();
        d.x * d.y + d.y * d.z + d.z * d.x
    }

    /// Whether the two boxes share at least one point (touching counts).
    #[inline]
    pub fn intersects(&self, o: &Aabb) -> bool {
        self.min.cmple(o.max).all() && o.min.cmple(self.max).all()
    }

    /// Whether `o` lies inside this box (boundary included).
    #[inline]
    pub fn contains(&self, o: &Aabb) -> bool {
        self.min.cmple(o.min).all() && o.max.cmple(self.max).all()
    }

    /// Whether the point lies inside the box (boundary included).
    #[inline]
    pub fn contains_point(&self, p: Vec3A) -> bool {
        self.min.cmple(p).all() && p.cmple(self.max).all()
    }

    /// Squared distance from `p` to the box (0 inside).
    #[inline]
    pub fn distance_squared(&self, p: Vec3A) -> f32 {
        let d = (self.min - p).max(p - self.max).max(Vec3A::ZERO);
        d.length_squared()
    }

    /// The box of this box after the rigid transform `pose`: conservative
    /// (it contains every transformed point of the box, rounding included).
    #[inline]
    pub fn transformed(&self, pose: &Pose) -> Aabb {
        let c = pose.transform_point(self.center());
        let e = pose.abs_rotation() * self.half_extents();
        // Pad by a few ulps of the magnitudes involved, so that rounding in
        // this computation cannot leave a transformed point of the box
        // outside the result.
        let mag = c.abs().max_element()
            + e.max_element()
            + pose.translation.abs().max_element()
            + self.min.abs().max(self.max.abs()).max_element();
        let e = e + Vec3A::splat(mag * 8.0 * f32::EPSILON);
        Aabb::new(c - e, c + e)
    }

    /// The box scaled axis by axis by `s` (no component zero; a negative
    /// one mirrors, swapping that axis's bounds); an empty box stays empty.
    /// Exact: a product rounds the same way for a bound as for a point's
    /// coordinate, so the result contains the scaled points of the box.
    #[inline]
    pub fn scaled(&self, s: Vec3A) -> Aabb {
        if self.is_empty() {
            return *self;
        }
        let (p, q) = (self.min * s, self.max * s);
        Aabb::new(p.min(q), p.max(q))
    }

    /// The eight corners.
    pub fn corners(&self) -> [Vec3A; 8] {
        let (a, b) = (self.min, self.max);
        [
            Vec3A::new(a.x, a.y, a.z),
            Vec3A::new(b.x, a.y, a.z),
            Vec3A::new(a.x, b.y, a.z),
            Vec3A::new(b.x, b.y, a.z),
            Vec3A::new(a.x, a.y, b.z),
            Vec3A::new(b.x, a.y, b.z),
            Vec3A::new(a.x, b.y, b.z),
            Vec3A::new(b.x, b.y, b.z),
        ]
    }
}

/// A triangle as its three corners.
pub type Triangle = [Vec3A; 3];

/// Converts `[f32; 3]` corners into a [`Triangle`].
#[inline]
pub fn triangle_from_arrays(v: [[f32; 3]; 3]) -> Triangle {
    [Vec3A::from(v[0]), Vec3A::from(v[1]), Vec3A::from(v[2])]
}

/// A rigid transform: rotation then translation, `p ↦ R p + t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Rotation matrix (orthonormal).
    pub rotation: Mat3A,
    /// Translation.
    pub translation: Vec3A,
}

impl Default for Pose {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Pose {
    /// The identity transform.
    pub const IDENTITY: Pose = Pose {
        rotation: Mat3A::IDENTITY,
        translation: Vec3A::ZERO,
    };

    /// A pose from a unit quaternion and a translation.
    pub fn from_rotation_translation(rotation: glam::Quat, translation: Vec3) -> Self {
        Self {
            rotation: Mat3A::from_quat(rotation),
            translation: translation.into(),
        }
    }

    /// Transforms a point.
    #[inline]
    pub fn transform_point(&self, p: Vec3A) -> Vec3A {
        self.rotation * p + self.translation
    }

    /// Rotates a vector (no translation).
    #[inline]
    pub fn transform_vector(&self, v: Vec3A) -> Vec3A {
        self.rotation * v
    }

    /// The inverse transform.
    pub fn inverse(&self) -> Pose {
        let rt = self.rotation.transpose();
        Pose {
            rotation: rt,
            translation: -(rt * self.translation),
        }
    }

    /// `self ∘ other`: first `other`, then `self`.
    pub fn mul(&self, other: &Pose) -> Pose {
        Pose {
            rotation: self.rotation * other.rotation,
            translation: self.transform_point(other.translation),
        }
    }

    /// The element-wise absolute value of the rotation matrix, used to
    /// bound a rotated box.
    #[inline]
    pub fn abs_rotation(&self) -> Mat3A {
        Mat3A::from_cols(
            self.rotation.x_axis.abs(),
            self.rotation.y_axis.abs(),
            self.rotation.z_axis.abs(),
        )
    }
}

/// A ray `origin + t · dir`, with the reciprocal direction precomputed for
/// slab tests and the shear of the watertight triangle test.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    /// Origin.
    pub origin: Vec3A,
    /// Direction (need not be normalised; `t` is measured in its units).
    pub dir: Vec3A,
    /// `1 / dir`, component-wise (infinite where a component is 0).
    pub inv_dir: Vec3A,
    /// Where `inv_dir` is negative (`-0.0` directions included): on those
    /// axes a box's maximum is the plane the ray enters by.
    neg: BVec3A,
    /// Axis permutation of the watertight test: `kz` is the direction's
    /// dominant axis.
    k: [usize; 3],
    /// Shear constants `(dir[kx] / dir[kz], dir[ky] / dir[kz], 1 / dir[kz])`.
    shear: [f32; 3],
}

impl Ray {
    /// A ray from an origin and a direction.
    #[inline]
    pub fn new(origin: Vec3A, dir: Vec3A) -> Self {
        let a = dir.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if dir[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let shear = [dir[kx] / dir[kz], dir[ky] / dir[kz], 1.0 / dir[kz]];
        Self {
            origin,
            dir,
            inv_dir: dir.recip(),
            neg: dir.recip().cmplt(Vec3A::ZERO),
            k: [kx, ky, kz],
            shear,
        }
    }

    /// The watertight triangle test's axis permutation `[kx, ky, kz]` and
    /// shear constants (for codecs that run [`ray_triangle`]'s operations
    /// on several triangles at once).
    #[inline]
    pub(crate) fn shear_frame(&self) -> ([usize; 3], [f32; 3]) {
        (self.k, self.shear)
    }

    /// The point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3A {
        self.origin + self.dir * t
    }

    /// Per axis, whether the ray enters a box by its maximum plane (its
    /// reciprocal direction is negative, `-0.0` directions included).
    #[inline]
    pub fn enters_by_max(&self) -> [bool; 3] {
        [self.neg.test(0), self.neg.test(1), self.neg.test(2)]
    }

    /// Slab test: the entry parameter if the ray meets `b` within
    /// `[0, t_max]`, else `None`.
    ///
    /// Each axis gives the distance to the plane the ray enters by (the
    /// box's minimum, or its maximum where the direction is negative) and
    /// to the one it leaves by; the entry is the largest of the first, the
    /// exit the smallest of the second. A zero direction component gives
    /// ±∞ for a plane off the origin, which rejects or does not constrain
    /// as it should, and NaN (`0 · ∞`) for a plane through the origin: the
    /// ray runs in the box's face, which does not constrain either, and the
    /// folds skip NaN. (Sorting the two distances with `min`/`max` instead,
    /// as many tracers do, turns a NaN near plane into `+∞` and misses rays
    /// that run in a box's face, which far from the origin, where
    /// coordinates are coarse, is common.)
    ///
    /// Conservative under rounding (Ize, "Robust BVH ray traversal", JCGT
    /// 2013): the exit distance is enlarged by [`SLAB_EXIT_SCALE`], so a box
    /// is never rejected for a point inside it that the triangle test hits,
    /// even when the box is the triangle's own tight box. Without it, two
    /// trees with the same triangles but different boxes (plain's exact
    /// ones, RACBVH's quantized ones) could disagree on grazing and tied
    /// hits.
    #[inline]
    pub fn intersect_aabb(&self, b: &Aabb, t_max: f32) -> Option<f32> {
        let near = Vec3A::select(self.neg, b.max, b.min);
        let far = Vec3A::select(self.neg, b.min, b.max);
        let tn = (near - self.origin) * self.inv_dir;
        let tf = (far - self.origin) * self.inv_dir;
        // `f32::max`/`min` return the other operand when one is NaN.
        let t_enter = tn.x.max(tn.y).max(tn.z).max(0.0);
        let t_exit = tf.x.min(tf.y).min(tf.z).min(t_max) * SLAB_EXIT_SCALE;
        if t_enter <= t_exit {
            Some(t_enter)
        } else {
            None
        }
    }
}

/// The factor [`Ray::intersect_aabb`] applies to the exit distance:
/// `1 + 2γ₃` of Ize's analysis (γ₃ = 3u / (1 − 3u), u = 2⁻²⁴), rounded up.
pub const SLAB_EXIT_SCALE: f32 = 1.0 + 4.0 * f32::EPSILON;

/// A ray–triangle hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriHit {
    /// Ray parameter of the hit.
    pub t: f32,
    /// Barycentric coordinate of the second corner.
    pub u: f32,
    /// Barycentric coordinate of the third corner.
    pub v: f32,
}

/// The closest intersection of a ray with a mesh: a [`TriHit`] with the
/// id of the triangle hit (what the ray queries of [`crate::query`]
/// return).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayHit {
    /// Ray parameter of the hit (distance if the direction is a unit vector).
    pub t: f32,
    /// Id of the triangle hit.
    pub triangle: u32,
    /// Barycentric coordinate of the triangle's second corner.
    pub u: f32,
    /// Barycentric coordinate of the triangle's third corner.
    pub v: f32,
}

/// Watertight ray/triangle intersection (Woop, Benthin and Wald, JCGT
/// 2013), two-sided. Returns the hit if `t` lies in `[0, t_max]`.
///
/// Edges shared by two triangles are decided the same way for both, so a
/// ray never slips through the crack between neighbours (Möller–Trumbore
/// can miss both triangles of an edge through rounding).
#[inline]
pub fn ray_triangle(ray: &Ray, tri: &Triangle, t_max: f32) -> Option<TriHit> {
    let [kx, ky, kz] = ray.k;
    let [sx, sy, sz] = ray.shear;
    let a = tri[0] - ray.origin;
    let b = tri[1] - ray.origin;
    let c = tri[2] - ray.origin;
    let (ax, ay) = (a[kx] - sx * a[kz], a[ky] - sy * a[kz]);
    let (bx, by) = (b[kx] - sx * b[kz], b[ky] - sy * b[kz]);
    let (cx, cy) = (c[kx] - sx * c[kz], c[ky] - sy * c[kz]);
    let mut u = cx * by - cy * bx;
    let mut v = ax * cy - ay * cx;
    let mut w = bx * ay - by * ax;
    if u == 0.0 || v == 0.0 || w == 0.0 {
        // On an edge in single precision: decide it in double precision.
        let (ax, ay, bx, by, cx, cy) = (
            ax as f64, ay as f64, bx as f64, by as f64, cx as f64, cy as f64,
        );
        u = (cx * by - cy * bx) as f32;
        v = (ax * cy - ay * cx) as f32;
        w = (bx * ay - by * ax) as f32;
    }
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return None;
    }
    let det = u + v + w;
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let (az, bz, cz) = (sz * a[kz], sz * b[kz], sz * c[kz]);
    let t = (u * az + v * bz + w * cz) / det;
    if t >= 0.0 && t <= t_max {
        Some(TriHit {
            t,
            u: v / det,
            v: w / det,
        })
    } else {
        None
    }
}

/// The point of triangle `t` closest to `p` (Ericson, *Real-Time Collision
/// Detection*, §5.1.5), with its barycentric coordinates of corners 1 and 2.
/// Degenerate triangles (segments, points) are handled as their edges.
pub fn closest_point_on_triangle(p: Vec3A, t: &Triangle) -> (Vec3A, f32, f32) {
    let r = ericson_closest(p, t);
    if r.0.is_finite() && r.1.is_finite() && r.2.is_finite() {
        return r;
    }
    // Degenerate: the closest point of the three edges.
    let seg = |a: Vec3A, b: Vec3A| {
        let d = b - a;
        let l2 = d.length_squared();
        let s = if l2 > 0.0 {
            ((p - a).dot(d) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (a + d * s, s)
    };
    let (q0, s0) = seg(t[0], t[1]);
    let (q1, s1) = seg(t[1], t[2]);
    let (q2, s2) = seg(t[2], t[0]);
    [(q0, s0, 0.0), (q1, 1.0 - s1, s1), (q2, 0.0, 1.0 - s2)]
        .into_iter()
        .min_by(|x, y| {
            (x.0 - p)
                .length_squared()
                .total_cmp(&(y.0 - p).length_squared())
        })
        .unwrap_or((t[0], 0.0, 0.0))
}

fn ericson_closest(p: Vec3A, t: &Triangle) -> (Vec3A, f32, f32) {
    let (a, b, c) = (t[0], t[1], t[2]);
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, 0.0, 0.0);
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (b, 1.0, 0.0);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (a + ab * v, v, 0.0);
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (c, 0.0, 1.0);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + ac * w, 0.0, w);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + (c - b) * w, 1.0 - w, w);
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    (a + ab * v + ac * w, v, w)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slab_test_handles_axis_parallel_rays() {
        let b = Aabb::from_arrays([0.0; 3], [1.0; 3]);
        let r = Ray::new(Vec3A::new(0.5, 0.5, -1.0), Vec3A::new(0.0, 0.0, 1.0));
        assert_eq!(r.intersect_aabb(&b, f32::INFINITY), Some(1.0));
        let miss = Ray::new(Vec3A::new(2.0, 0.5, -1.0), Vec3A::new(0.0, 0.0, 1.0));
        assert_eq!(miss.intersect_aabb(&b, f32::INFINITY), None);
        assert_eq!(r.intersect_aabb(&b, 0.5), None);
    }

    /// A ray running in a face of the box (a zero direction component and
    /// the origin on that face's plane) meets the box, whichever face and
    /// whichever sign of zero: the case that sorting the two plane
    /// distances with `min`/`max` gets wrong on the minimum face.
    #[test]
    fn slab_test_accepts_rays_in_a_face() {
        let b = Aabb::from_arrays([1.0, 2.0, 3.0], [2.0, 4.0, 6.0]);
        for axis in 0..3 {
            for on_max in [false, true] {
                for zero in [0.0f32, -0.0] {
                    for along in [1.0f32, -1.0] {
                        // Along the next axis, from outside the box.
                        let other = (axis + 1) % 3;
                        let mut origin = b.center();
                        origin[axis] = if on_max { b.max[axis] } else { b.min[axis] };
                        origin[other] = if along > 0.0 {
                            b.min[other] - 1.0
                        } else {
                            b.max[other] + 1.0
                        };
                        let mut dir = Vec3A::ZERO;
                        dir[axis] = zero;
                        dir[other] = along;
                        let r = Ray::new(origin, dir);
                        assert_eq!(r.intersect_aabb(&b, f32::INFINITY), Some(1.0), "{r:?}");
                        // Just off the face, outside: a miss.
                        let mut off = origin;
                        off[axis] += if on_max { 0.5 } else { -0.5 };
                        let r = Ray::new(off, dir);
                        assert_eq!(r.intersect_aabb(&b, f32::INFINITY), None, "{r:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn transformed_box_contains_transformed_corners() {
        let b = Aabb::from_arrays([-1.0, 0.0, 2.0], [3.0, 1.0, 2.5]);
        let pose = Pose::from_rotation_translation(
            glam::Quat::from_euler(glam::EulerRot::XYZ, 0.3, -1.1, 2.0),
            Vec3::new(1.0, -2.0, 0.5),
        );
        let tb = b.transformed(&pose).loosened(1e-5);
        for c in b.corners() {
            assert!(tb.contains_point(pose.transform_point(c)));
        }
        let back = pose.inverse().mul(&pose);
        assert!((back.transform_point(Vec3A::ONE) - Vec3A::ONE).length() < 1e-5);
    }

    #[test]
    fn closest_point_regions() {
        let t = [Vec3A::ZERO, Vec3A::X, Vec3A::Y];
        assert_eq!(
            closest_point_on_triangle(Vec3A::new(-1.0, -1.0, 0.0), &t).0,
            Vec3A::ZERO
        );
        let (p, _, _) = closest_point_on_triangle(Vec3A::new(0.25, 0.25, 3.0), &t);
        assert!((p - Vec3A::new(0.25, 0.25, 0.0)).length() < 1e-6);
        let (p, _, _) = closest_point_on_triangle(Vec3A::new(1.0, 1.0, 0.0), &t);
        assert!((p - Vec3A::new(0.5, 0.5, 0.0)).length() < 1e-6);
    }

    /// Regression: Möller–Trumbore let some rays slip between two triangles
    /// sharing an edge (found by comparing with obvhs and Embree).
    #[test]
    fn rays_through_shared_edges_never_slip_through() {
        // A quad split along its diagonal, tilted so the edge is not axis-aligned.
        let p = [
            Vec3A::new(0.1, 0.0, 0.3),
            Vec3A::new(1.3, 0.2, -0.1),
            Vec3A::new(1.1, 1.4, 0.5),
            Vec3A::new(-0.2, 1.1, 0.2),
        ];
        let t1 = [p[0], p[1], p[2]];
        let t2 = [p[0], p[2], p[3]];
        let mut misses = 0;
        for i in 0..=2000 {
            let f = i as f32 / 2000.0;
            let on_edge = p[0] + (p[2] - p[0]) * f;
            for d in [
                Vec3A::new(0.3, -0.2, -1.0),
                Vec3A::new(-0.7, 0.4, -1.3),
                Vec3A::new(0.01, 0.02, 1.0),
            ] {
                let r = Ray::new(on_edge - d * 3.7, d);
                let hit = ray_triangle(&r, &t1, f32::INFINITY).is_some()
                    || ray_triangle(&r, &t2, f32::INFINITY).is_some();
                misses += usize::from(!hit && f > 0.0 && f < 1.0);
            }
        }
        assert_eq!(misses, 0);
    }

    #[test]
    fn ray_hits_triangle_with_barycentrics() {
        let t = [Vec3A::ZERO, Vec3A::X, Vec3A::Y];
        let r = Ray::new(Vec3A::new(0.2, 0.3, 1.0), Vec3A::new(0.0, 0.0, -1.0));
        let h = ray_triangle(&r, &t, f32::INFINITY).unwrap();
        assert!((h.t - 1.0).abs() < 1e-6 && (h.u - 0.2).abs() < 1e-6 && (h.v - 0.3).abs() < 1e-6);
        assert!(ray_triangle(&r, &t, 0.5).is_none());
    }
}
