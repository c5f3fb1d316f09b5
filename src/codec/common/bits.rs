//! Bit streams: [`BitWriter`] and [`BitReader`] (least-significant bit
//! first, with Exp-Golomb codes), and the zig-zag map of signed values.

use super::FormatError;
use super::le::u64_at_padded;

/// Writes bits least-significant first into bytes.
#[derive(Default)]
pub struct BitWriter {
    bytes: Vec<u8>,
    acc: u64,
    n: u32,
}

impl BitWriter {
    /// Appends the low `bits` bits of `v` (`bits` ≤ 56).
    #[inline]
    pub fn put(&mut self, v: u64, bits: u32) {
        debug_assert!(bits <= 56);
        if bits == 0 {
            return;
        }
        let v = v & ((1u64 << bits) - 1);
        self.acc |= v << self.n;
        self.n += bits;
        while self.n >= 8 {
            self.bytes.push(self.acc as u8);
            self.acc >>= 8;
            self.n -= 8;
        }
    }

    /// Appends `v` with the Exp-Golomb code of parameter `k`.
    #[inline]
    pub fn put_golomb(&mut self, v: u32, k: u32) {
        let x = u64::from(v) + (1u64 << k);
        let n = 63 - x.leading_zeros() - k; // prefix length
        self.put(0, n);
        self.put(1, 1);
        self.put(x, n + k);
    }

    /// Bits written so far.
    pub fn bit_len(&self) -> u64 {
        self.bytes.len() as u64 * 8 + u64::from(self.n)
    }

    /// The bytes, the last one zero-padded.
    pub fn finish(mut self) -> Vec<u8> {
        if self.n > 0 {
            self.bytes.push(self.acc as u8);
        }
        self.bytes
    }
}

/// Length in bits of the Exp-Golomb code of `v` with parameter `k`.
#[inline]
pub fn golomb_len(v: u32, k: u32) -> u64 {
    let x = u64::from(v) + (1u64 << k);
    let n = u64::from(63 - x.leading_zeros() - k);
    2 * n + 1 + u64::from(k)
}

/// Reads bits least-significant first. Reading past the end yields zero
/// bits; [`BitReader::overran`] tells whether that happened.
///
/// The next bits wait in a 64-bit buffer, topped up before every read
/// without a branch (F. Giesen's "bit extraction, variant 4"): eight bytes
/// are loaded where the buffer's valid bits end and OR-ed in above them
/// (bits already there are the same stream bits), and the whole bytes that
/// fit are counted in. A read then only shifts the buffer, so the position
/// of the next code depends on this code's length through one shift, not
/// through a load from the position as a plain bit pointer would.
pub struct BitReader<'a> {
    bytes: &'a [u8],
    /// The byte holding the stream bit just past the buffer's valid bits.
    byte: usize,
    /// Stream bits from the current position on: `count` valid ones, the
    /// bits above them zero or the stream's own.
    buf: u64,
    count: u32,
    limit: u64,
}

impl<'a> BitReader<'a> {
    /// A reader over `bytes`.
    pub fn new(bytes: &'a [u8]) -> Self {
        Self::with_limit(bytes, bytes.len())
    }

    /// A reader of the first `len` bytes of `bytes` (the rest may be read
    /// ahead but counts as running past the end).
    pub fn with_limit(bytes: &'a [u8], len: usize) -> Self {
        Self {
            bytes,
            byte: 0,
            buf: 0,
            count: 0,
            limit: len.min(bytes.len()) as u64 * 8,
        }
    }

    /// Tops the buffer up to at least 56 valid bits. Reads that follow
    /// without one ([`StaticDecoder::get_refilled`]) keep the load of the
    /// stream off the chain from one code's length to the next code.
    ///
    /// [`StaticDecoder::get_refilled`]: super::static_dict::StaticDecoder::get_refilled
    #[inline(always)]
    pub fn refill(&mut self) {
        self.buf |= u64_at_padded(self.bytes, self.byte) << self.count;
        self.byte += ((63 - self.count) >> 3) as usize;
        self.count |= 56;
    }

    /// The next 56 or more bits, without consuming them.
    #[inline(always)]
    pub(super) fn peek(&mut self) -> u64 {
        self.refill();
        self.buf
    }

    /// The buffered bits as they are (valid as far as the last
    /// [`refill`](Self::refill) less what was consumed since).
    #[inline(always)]
    pub(super) fn buffered(&self) -> u64 {
        self.buf
    }

    /// Valid bits in the buffer.
    #[cfg(test)]
    pub(super) fn buffered_bits(&self) -> u32 {
        self.count
    }

    /// Consumes `bits` bits already read with [`peek`](Self::peek) (at
    /// most 56).
    #[inline(always)]
    pub(super) fn skip(&mut self, bits: u32) {
        debug_assert!(bits <= self.count);
        self.buf >>= bits;
        self.count -= bits;
    }

    /// Consumes `bits` (≤ 56) bits.
    #[inline(always)]
    pub fn get(&mut self, bits: u32) -> u64 {
        let v = self.peek() & ((1u64 << bits) - 1);
        self.skip(bits);
        v
    }

    /// Consumes one Exp-Golomb code of parameter `k`.
    #[inline(always)]
    pub fn get_golomb(&mut self, k: u32) -> Result<u32, FormatError> {
        let (value, len) = golomb_at(self.peek(), k)?;
        self.skip(len);
        Ok(value)
    }

    /// Whether more bits were consumed than the stream holds.
    pub fn overran(&self) -> bool {
        self.bits_read() > self.limit
    }

    /// Bits consumed so far (past the end included).
    pub fn bits_read(&self) -> u64 {
        self.byte as u64 * 8 - u64::from(self.count)
    }
}

/// The Exp-Golomb code of parameter `k` at the start of `w` (bits from
/// `BitReader::peek`): its value and its length in bits, which the caller
/// skips (a dictionary decoder reads what follows the code from the same
/// `w` when it fits). Codes of values at or above 2^27 (at most 55 bits
/// for `k` ≤ 3, within the 56 bits a peek guarantees) are errors.
#[inline(always)]
pub fn golomb_at(w: u64, k: u32) -> Result<(u32, u32), FormatError> {
    let n = w.trailing_zeros();
    if n + k > 27 {
        return Err(FormatError::Corrupt {
            what: "an Exp-Golomb code is too long",
        });
    }
    let body = (w >> (n + 1)) & ((1u64 << (n + k)) - 1);
    let value = (((1u64 << (n + k)) | body) - (1u64 << k)) as u32;
    Ok((value, 2 * n + 1 + k))
}

/// Zig-zag map of a signed value.
#[inline]
pub fn zigzag(v: i64) -> u64 {
    ((v << 1) ^ (v >> 63)) as u64
}

/// Inverse of [`zigzag`].
#[inline]
pub fn unzigzag(v: u64) -> i64 {
    ((v >> 1) as i64) ^ -((v & 1) as i64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::codec::common::dict::MAX_K;

    /// Fields of every width read back as written, across refills, and
    /// reading runs past the end exactly one bit after the last byte.
    #[test]
    fn reads_match_the_writer_and_overrun_is_exact() {
        let mut w = BitWriter::default();
        let mut fields = Vec::new();
        let mut x = 5u64;
        for _ in 0..4000 {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let n = (x >> 58) as u32 % 57;
            let v = (x >> 3) & ((1u64 << n) - 1);
            w.put(v, n);
            fields.push((v, n));
        }
        let bits = w.bit_len();
        let b = w.finish();
        let mut r = BitReader::new(&b);
        for &(v, n) in &fields {
            assert_eq!(r.get(n), v, "a {n}-bit field");
        }
        r.get((b.len() as u64 * 8 - bits) as u32);
        assert!(!r.overran(), "the padding is the stream's");
        assert_eq!(r.get(1), 0);
        assert!(r.overran());
    }

    #[test]
    fn golomb_lengths_match_the_writer() {
        for k in 0..=MAX_K {
            for v in [0u32, 1, 2, 3, 7, 100, 65535, 1 << 20] {
                let mut w = BitWriter::default();
                w.put_golomb(v, k);
                assert_eq!(w.bit_len(), golomb_len(v, k));
                let b = w.finish();
                assert_eq!(BitReader::new(&b).get_golomb(k).unwrap(), v);
            }
        }
        for v in [-5i64, 0, 7, i64::from(i32::MIN)] {
            assert_eq!(unzigzag(zigzag(v)), v);
        }
    }
}
