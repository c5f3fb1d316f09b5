//! Seeded value noise: a smooth pseudo-random scalar field built from
//! hashed values on the integer lattice, blended with the quintic fade
//! curve (C² continuous). Cheap: eight hashes and seven lerps per sample.

use glam::Vec3;

use super::rng::hash3;

/// The quintic fade curve `6t⁵ − 15t⁴ + 10t³`.
#[inline]
pub(crate) fn fade(t: f32) -> f32 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

/// The lattice value at an integer point, uniform in `[-1, 1)`.
#[inline]
pub(crate) fn lattice(seed: u32, x: i32, y: i32, z: i32) -> f32 {
    (hash3(seed, x, y, z) >> 8) as f32 * (2.0 / 16_777_216.0) - 1.0
}

#[inline]
fn lerp(a: f32, b: f32, t: f32) -> f32 {
    a + (b - a) * t
}

/// Value noise at `p`: smooth, in `[-1, 1]`, unit feature size.
#[inline]
pub(crate) fn value_noise(seed: u32, p: Vec3) -> f32 {
    let f = p.floor();
    let (x, y, z) = (f.x as i32, f.y as i32, f.z as i32);
    let t = p - f;
    let (u, v, w) = (fade(t.x), fade(t.y), fade(t.z));
    let c = |dx: i32, dy: i32, dz: i32| lattice(seed, x + dx, y + dy, z + dz);
    let x00 = lerp(c(0, 0, 0), c(1, 0, 0), u);
    let x10 = lerp(c(0, 1, 0), c(1, 1, 0), u);
    let x01 = lerp(c(0, 0, 1), c(1, 0, 1), u);
    let x11 = lerp(c(0, 1, 1), c(1, 1, 1), u);
    lerp(lerp(x00, x10, v), lerp(x01, x11, v), w)
}

/// Fractal sum of value-noise octaves: octave `o` has frequency
/// `freq · lacunarity^o` and amplitude `amp · gain^o`.
#[derive(Clone, Debug)]
pub(crate) struct Fbm {
    /// Seed of the first octave (the others derive from it).
    pub seed: u32,
    /// Number of octaves (0 gives a zero field).
    pub octaves: u32,
    /// Frequency of the first octave (features per unit length).
    pub freq: f32,
    /// Amplitude of the first octave.
    pub amp: f32,
    /// Frequency ratio between octaves.
    pub lacunarity: f32,
    /// Amplitude ratio between octaves.
    pub gain: f32,
}

impl Fbm {
    /// The field at `p`.
    #[inline]
    pub(crate) fn sample(&self, p: Vec3) -> f32 {
        let mut sum = 0.0;
        let mut f = self.freq;
        let mut a = self.amp;
        for o in 0..self.octaves {
            // A per-octave shift keeps the lattices of the octaves apart.
            let shift = Vec3::new(0.37, 0.71, 0.13) * o as f32;
            sum += a * value_noise(
                self.seed.wrapping_add(o.wrapping_mul(0x9E37_79B9)),
                p * f + shift,
            );
            f *= self.lacunarity;
            a *= self.gain;
        }
        sum
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_is_bounded_smooth_and_seeded() {
        let mut prev = value_noise(3, Vec3::new(0.0, 0.0, 0.3));
        let mut differs = false;
        for i in 1..2000 {
            let p = Vec3::new(i as f32 * 0.01, i as f32 * 0.007, 0.3);
            let v = value_noise(3, p);
            assert!((-1.0..=1.0).contains(&v));
            assert!((v - prev).abs() < 0.1, "not smooth at {p}");
            differs |= v != value_noise(4, p);
            prev = v;
        }
        assert!(differs);
        // Lattice points carry the lattice value exactly.
        assert_eq!(
            value_noise(9, Vec3::new(2.0, -3.0, 5.0)),
            lattice(9, 2, -3, 5)
        );
    }
}
