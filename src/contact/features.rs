//! Closest features and clipping for the triangle-pair kernel: the closest
//! points of two segments and of two triangles (exact distances of
//! separated pairs), and a triangle clipped to another's prism (the support
//! polygon of a face contact).

use glam::Vec3A;

use crate::geom::{Triangle, closest_point_on_triangle};

/// Clips triangle `t` to the prism over triangle `f` with unit normal `n`
/// (Sutherland–Hodgman): at most six corners.
pub(crate) fn clip_to_prism(t: &Triangle, f: &Triangle, n: Vec3A) -> Poly {
    let mut poly = Poly::from(t);
    for k in 0..3 {
        let (p, q) = (f[k], f[(k + 1) % 3]);
        let inward = n.cross(q - p);
        poly = poly.clip(p, inward);
        if poly.len == 0 {
            break;
        }
    }
    poly
}

/// A convex polygon of at most six corners (a triangle clipped by three
/// planes), on the stack.
#[derive(Clone, Copy)]
pub(crate) struct Poly {
    v: [Vec3A; 9],
    len: usize,
}

impl Poly {
    fn from(t: &Triangle) -> Self {
        let mut v = [Vec3A::ZERO; 9];
        v[..3].copy_from_slice(t);
        Self { v, len: 3 }
    }

    pub(crate) fn iter(&self) -> impl Iterator<Item = &Vec3A> {
        self.v[..self.len].iter()
    }

    /// Keeps the part where `inward · (x − p) ≥ 0`.
    fn clip(&self, p: Vec3A, inward: Vec3A) -> Poly {
        let mut out = Poly {
            v: [Vec3A::ZERO; 9],
            len: 0,
        };
        // A tolerance relative to the plane's scale keeps corners lying on
        // the plane (shared edges) on both sides.
        let eps = 1e-6 * inward.length() * (self.v[0] - p).length().max(1.0);
        for k in 0..self.len {
            let x = self.v[k];
            let y = self.v[(k + 1) % self.len];
            let dx = inward.dot(x - p);
            let dy = inward.dot(y - p);
            let x_in = dx >= -eps;
            let y_in = dy >= -eps;
            if x_in && out.len < 9 {
                out.v[out.len] = x;
                out.len += 1;
            }
            if x_in != y_in && out.len < 9 {
                let t = dx / (dx - dy);
                if t.is_finite() {
                    out.v[out.len] = x + (y - x) * t.clamp(0.0, 1.0);
                    out.len += 1;
                }
            }
        }
        out
    }
}

/// The closest points of segments `p0 q0` and `p1 q1` (Ericson §5.1.9).
pub fn closest_on_segments(p0: Vec3A, q0: Vec3A, p1: Vec3A, q1: Vec3A) -> (Vec3A, Vec3A) {
    let d1 = q0 - p0;
    let d2 = q1 - p1;
    let r = p0 - p1;
    let a = d1.dot(d1);
    let e = d2.dot(d2);
    let f = d2.dot(r);
    const EPS: f32 = 1e-30;
    let (s, t);
    if a <= EPS && e <= EPS {
        return (p0, p1);
    }
    if a <= EPS {
        s = 0.0;
        t = (f / e).clamp(0.0, 1.0);
    } else {
        let c = d1.dot(r);
        if e <= EPS {
            t = 0.0;
            s = (-c / a).clamp(0.0, 1.0);
        } else {
            let b = d1.dot(d2);
            let denom = a * e - b * b;
            let mut s0 = if denom > 0.0 {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t0 = (b * s0 + f) / e;
            if t0 < 0.0 {
                t0 = 0.0;
                s0 = (-c / a).clamp(0.0, 1.0);
            } else if t0 > 1.0 {
                t0 = 1.0;
                s0 = ((b - c) / a).clamp(0.0, 1.0);
            }
            s = s0;
            t = t0;
        }
    }
    (p0 + d1 * s, p1 + d2 * t)
}

/// The closest points of two triangles that do not intersect, and their
/// distance: the best of the six corner–triangle and nine edge–edge pairs.
pub fn closest_points(a: &Triangle, b: &Triangle) -> (Vec3A, Vec3A, f32) {
    let mut best = (a[0], b[0], f32::INFINITY);
    let mut consider = |p: Vec3A, q: Vec3A| {
        let d2 = (q - p).length_squared();
        if d2 < best.2 {
            best = (p, q, d2);
        }
    };
    for v in a {
        consider(*v, closest_point_on_triangle(*v, b).0);
    }
    for v in b {
        consider(closest_point_on_triangle(*v, a).0, *v);
    }
    for ia in 0..3 {
        for ib in 0..3 {
            let (p, q) = closest_on_segments(a[ia], a[(ia + 1) % 3], b[ib], b[(ib + 1) % 3]);
            consider(p, q);
        }
    }
    (best.0, best.1, best.2.sqrt())
}
