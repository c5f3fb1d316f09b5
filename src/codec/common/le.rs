//! Little-endian readers of fixed-width values at a byte offset. The
//! callers check bounds first (the readers panic past the end), except
//! [`u64_at_padded`], which reads past the end as zero bytes.

/// The `u32` at byte `at` of `b`.
#[inline]
pub fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

/// The `u32`s of `b`, one every four bytes (a trailing partial word is
/// left out; the callers' sections are whole words).
#[inline]
pub fn words(b: &[u8]) -> impl ExactSizeIterator<Item = u32> + '_ {
    b.chunks_exact(4)
        .map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]))
}

/// The little-endian bytes of `it`'s words, in order.
pub fn word_bytes(it: impl Iterator<Item = u32>) -> Vec<u8> {
    it.flat_map(u32::to_le_bytes).collect()
}

/// The `u64` at byte `at` of `b`.
#[inline]
pub fn u64_at(b: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(std::array::from_fn(|k| b[at + k]))
}

/// The `f32` at byte `at` of `b`.
#[inline]
pub fn f32_at(b: &[u8], at: usize) -> f32 {
    f32::from_bits(u32_at(b, at))
}

/// Three `f32`s from byte `at` of `b`.
#[inline]
pub fn f32x3_at(b: &[u8], at: usize) -> [f32; 3] {
    [f32_at(b, at), f32_at(b, at + 4), f32_at(b, at + 8)]
}

/// The `u64` at byte `at` of `b`, bytes past the end read as zero (for bit
/// readers, which look eight bytes ahead).
#[inline(always)]
pub fn u64_at_padded(b: &[u8], at: usize) -> u64 {
    match b.get(at..at + 8) {
        Some(s) => u64::from_le_bytes([s[0], s[1], s[2], s[3], s[4], s[5], s[6], s[7]]),
        None => {
            let mut w = [0u8; 8];
            if let Some(s) = b.get(at..) {
                let n = s.len().min(8);
                w[..n].copy_from_slice(&s[..n]);
            }
            u64::from_le_bytes(w)
        }
    }
}
