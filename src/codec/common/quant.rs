//! Conservative quantization of boxes: a [`Grid`] of `2^bits − 1` steps
//! per axis over a box, and the [`QBox`] a box quantizes to, its min
//! rounded down and its max rounded up, so that the decoded box always
//! contains the original.
//!
//! RACBVH quantizes every box on one grid over the root box (16 bits by
//! default); a codec that stores child boxes relative to their parent's
//! float box (CLBVH's 8-bit child boxes) makes a grid over the parent box
//! with `Grid::new(&parent, 8)` and quantizes each child on it.

use glam::{UVec3, Vec3A};

use crate::geom::Aabb;

/// A fixed-rate quantization grid over a box: `2^bits − 1` steps per
/// axis. `dequantize(q) = origin + q · step`, evaluated in `f32` the same
/// way by the encoder and the decoder, so the encoder can check that every
/// decoded box contains its subtree.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    /// The grid box's minimum.
    pub origin: Vec3A,
    /// The size of one quantum per axis (0 for a flat axis).
    pub step: Vec3A,
    /// The largest quantized value, `2^bits − 1`.
    pub max_q: u32,
}

impl Grid {
    /// The grid over `root` with `bits` bits per coordinate.
    /// `root` must be finite and non-empty.
    pub fn new(root: &Aabb, bits: u32) -> Self {
        let max_q = ((1u64 << bits) - 1) as u32;
        let n = max_q as f32;
        let mut step = [0f32; 3];
        for (a, s) in step.iter_mut().enumerate() {
            let (lo, hi) = (root.min[a], root.max[a]);
            if hi > lo {
                let mut st = (hi - lo) / n;
                // Grow the step until the last grid point reaches `hi`.
                while lo + n * st < hi {
                    st = f32::from_bits(st.to_bits() + 1);
                }
                *s = st;
            }
        }
        Self {
            origin: root.min,
            step: Vec3A::from(step),
            max_q,
        }
    }

    #[inline]
    fn deq(&self, a: usize, q: u32) -> f32 {
        self.origin[a] + q as f32 * self.step[a]
    }

    /// The largest `q` whose grid point is at or below `v` (0 if none).
    fn floor(&self, a: usize, v: f32) -> u32 {
        if self.step[a] == 0.0 {
            return 0;
        }
        let guess = ((v - self.origin[a]) / self.step[a]).floor();
        let mut q = guess.clamp(0.0, self.max_q as f32) as u32;
        while q > 0 && self.deq(a, q) > v {
            q -= 1;
        }
        while q < self.max_q && self.deq(a, q + 1) <= v {
            q += 1;
        }
        q
    }

    /// The smallest `q` whose grid point is at or above `v` (`max_q` if none).
    fn ceil(&self, a: usize, v: f32) -> u32 {
        if self.step[a] == 0.0 {
            return 0;
        }
        let guess = ((v - self.origin[a]) / self.step[a]).ceil();
        let mut q = guess.clamp(0.0, self.max_q as f32) as u32;
        while q < self.max_q && self.deq(a, q) < v {
            q += 1;
        }
        while q > 0 && self.deq(a, q - 1) >= v {
            q -= 1;
        }
        q
    }

    /// Conservative quantization: min rounds down, max rounds up.
    pub fn quantize(&self, b: &Aabb) -> QBox {
        let mut q = QBox::default();
        for a in 0..3 {
            q.min[a] = self.floor(a, b.min[a]);
            q.max[a] = self.ceil(a, b.max[a]).max(q.min[a]);
        }
        q
    }

    /// The `f32` box of a quantized box.
    #[inline]
    pub fn dequantize(&self, q: &QBox) -> Aabb {
        Aabb::new(
            self.origin + q.min.as_vec3a() * self.step,
            self.origin + q.max.as_vec3a() * self.step,
        )
    }
}

/// A quantized box.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct QBox {
    /// Minimum corner.
    pub min: UVec3,
    /// Maximum corner.
    pub max: UVec3,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantization_is_conservative_and_tight() {
        let root = Aabb::from_arrays([-3.0, 1e9, 0.0], [7.5, 1e9 + 4096.0, 0.0]);
        for bits in [8, 16, 24] {
            let g = Grid::new(&root, bits);
            let full = g.quantize(&root);
            assert!(g.dequantize(&full).contains(&root));
            for k in 0..200 {
                let t = k as f32 / 200.0;
                let b = Aabb::new(
                    root.min + (root.max - root.min) * t * 0.5,
                    root.min + (root.max - root.min) * (0.5 + t * 0.4),
                );
                let q = g.quantize(&b);
                assert!(g.dequantize(&q).contains(&b), "{bits} {b:?}");
                for a in 0..3 {
                    if g.step[a] > 0.0 && q.max[a] > q.min[a] + 2 {
                        assert!(g.deq(a, q.min[a] + 1) > b.min[a]);
                        assert!(g.deq(a, q.max[a] - 1) < b.max[a]);
                    }
                }
            }
        }
    }
}
