//! Dequantizing all eight child boxes of a multi-leaf node at once.
//!
//! The scalar path and the AVX2 path compute `start + (q as f32) * step`
//! with a separate multiply and add (no fused multiply-add), so both give
//! the same bits; `tests` checks that on every byte value. The AVX2 path is
//! chosen at run time (`is_x86_feature_detected!`, which caches its answer).

use super::node::MultiLeafNode;

/// Eight boxes in structure-of-arrays form: min x, max x, min y, max y,
/// min z, max z, each over lanes 0–7 (the order of
/// [`InnerNode`](super::InnerNode)'s fields).
pub type SoaBoxes = [[f32; 8]; 6];

/// The quantized bounds of a node in [`SoaBoxes`] order.
#[inline]
fn planes(m: &MultiLeafNode) -> [&[u8; 8]; 6] {
    [&m.lo_x, &m.hi_x, &m.lo_y, &m.hi_y, &m.lo_z, &m.hi_z]
}

/// Dequantizes lanes 0–7 of `m` with plain scalar code.
#[inline]
pub fn dequantize_scalar(m: &MultiLeafNode, out: &mut SoaBoxes) {
    for (p, (q, o)) in planes(m).into_iter().zip(out.iter_mut()).enumerate() {
        let (s, st) = (m.start[p / 2], m.step[p / 2]);
        for k in 0..8 {
            o[k] = s + q[k] as f32 * st;
        }
    }
}

/// Dequantizes lanes 0–7 of `m` with AVX2.
///
/// # Safety
/// The processor must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn dequantize_avx2(m: &MultiLeafNode, out: &mut SoaBoxes) {
    use std::arch::x86_64::*;
    for (p, (q, o)) in planes(m).into_iter().zip(out.iter_mut()).enumerate() {
        let bytes = u64::from_le_bytes(*q);
        let v = _mm_cvtsi64_si128(bytes as i64);
        let f = _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(v));
        let r = _mm256_add_ps(
            _mm256_set1_ps(m.start[p / 2]),
            _mm256_mul_ps(f, _mm256_set1_ps(m.step[p / 2])),
        );
        // SAFETY: `o` is a `[f32; 8]`, 32 writable bytes; the store is
        // unaligned.
        unsafe { _mm256_storeu_ps(o.as_mut_ptr(), r) };
    }
}

/// Dequantizes lanes 0–7 of `m`, with AVX2 where the processor has it.
#[inline]
pub fn dequantize(m: &MultiLeafNode, out: &mut SoaBoxes) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: AVX2 was just detected.
        unsafe { dequantize_avx2(m, out) };
        return;
    }
    dequantize_scalar(m, out);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn simd_and_scalar_dequantize_to_the_same_bits() {
        let frames = [
            ([0.0f32, -1.0, 5.5], [0.01f32, 1e-7, 3.0]),
            ([1e7, -3e9, 0.0], [0.5, 12345.0, 0.0]),
            ([-1e-30, 1e30, 7.0], [1e-32, 1e27, 1.0 / 3.0]),
        ];
        for (start, step) in frames {
            for base in (0u32..256).step_by(8) {
                let q: [u8; 8] = std::array::from_fn(|k| (base as usize + k * 37 % 256) as u8);
                let m = MultiLeafNode {
                    start,
                    step,
                    lo_x: q,
                    hi_x: q.map(|v| 255 - v),
                    lo_y: q.map(|v| v.rotate_left(3)),
                    hi_y: q.map(|v| v ^ 0x5A),
                    lo_z: q.map(|v| v.wrapping_mul(7)),
                    hi_z: q.map(|v| v.wrapping_add(101)),
                };
                let mut a = [[0.0; 8]; 6];
                let mut b = [[1.0; 8]; 6];
                dequantize_scalar(&m, &mut a);
                dequantize(&m, &mut b);
                for (k, (lo, hi)) in a[0].iter().zip(&a[5]).enumerate() {
                    assert_eq!(m.child_box(k).min.x.to_bits(), lo.to_bits());
                    assert_eq!(m.child_box(k).max.z.to_bits(), hi.to_bits());
                }
                let bits = |s: &SoaBoxes| s.map(|p| p.map(f32::to_bits));
                assert_eq!(bits(&a), bits(&b));
            }
        }
    }
}
