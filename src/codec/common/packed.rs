//! Packed arrays of `u32`: [`ForArray`], frame-of-reference blocks of 128
//! values, each block holding its minimum and the offsets from it in as
//! many bits as the block's largest offset needs, so that any value is one
//! block-head read and one bit-field read away; [`ForVec`], the same array
//! parsed into memory (typed block heads, padded data) for in-core hot
//! paths; and [`bits_for`].
//!
//! # Layout of a [`ForArray`]
//! `len: u64`, `data_len: u64`, then per block of 128 values a 16-byte head
//! (`base: u32`, `width: u32`, bit offset in the data: `u64`), then
//! `data_len` bytes of offsets. All little-endian.

use super::FormatError;
use super::le::{u32_at, u64_at, u64_at_padded};

/// Reads `bits` (≤ 32) bits at bit offset `at` of `data`; out-of-range
/// bytes read as zero.
#[inline]
fn get_bits(data: &[u8], at: u64, bits: u32) -> u32 {
    let byte = (at >> 3) as usize;
    let shift = (at & 7) as u32;
    let word = u64_at_padded(data, byte);
    ((word >> shift) & ((1u64 << bits) - 1)) as u32
}

fn put_bits(data: &mut [u8], at: u64, bits: u32, v: u32) {
    for k in 0..u64::from(bits) {
        if (v >> k) & 1 == 1 {
            let p = at + k;
            data[(p >> 3) as usize] |= 1 << (p & 7);
        }
    }
}

/// Bits needed to store values `0..n` (at least 1).
pub fn bits_for(n: u64) -> u32 {
    (64 - n.saturating_sub(1).leading_zeros()).max(1)
}

/// Values per [`ForArray`] block.
const BLOCK: usize = 128;

/// A view of one frame-of-reference array inside a byte blob (see the
/// module docs for the layout).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ForArray {
    len: u64,
    heads: usize,
    data: usize,
    data_len: usize,
}

impl ForArray {
    /// The array of no values.
    pub const EMPTY: ForArray = ForArray {
        len: 0,
        heads: 0,
        data: 0,
        data_len: 0,
    };

    /// Appends the array of `values` to `out`.
    pub fn write(values: &[u32], out: &mut Vec<u8>) {
        let mut heads = Vec::new();
        let mut data = vec![0u8; 0];
        let mut bit = 0u64;
        for chunk in values.chunks(BLOCK) {
            let base = chunk.iter().copied().min().unwrap_or(0);
            let span = chunk.iter().map(|&v| v - base).max().unwrap_or(0);
            let width = 32 - span.leading_zeros();
            heads.extend_from_slice(&base.to_le_bytes());
            heads.extend_from_slice(&width.to_le_bytes());
            heads.extend_from_slice(&bit.to_le_bytes());
            data.resize(
                (bit + chunk.len() as u64 * u64::from(width)).div_ceil(8) as usize,
                0,
            );
            for &v in chunk {
                put_bits(&mut data, bit, width, v - base);
                bit += u64::from(width);
            }
        }
        out.extend_from_slice(&(values.len() as u64).to_le_bytes());
        out.extend_from_slice(&(data.len() as u64).to_le_bytes());
        out.extend_from_slice(&heads);
        out.extend_from_slice(&data);
    }

    /// Parses the array starting at `at` of `b`, checking every block head;
    /// returns it and the offset just past it.
    pub fn parse(b: &[u8], at: usize, section: &'static str) -> Result<(Self, usize), FormatError> {
        let short = |need: u64| FormatError::Truncated {
            section,
            need,
            have: b.len() as u64,
        };
        let fixed = at.checked_add(16).ok_or(short(u64::MAX))?;
        if fixed > b.len() {
            return Err(short(fixed as u64));
        }
        let len = u64_at(b, at);
        let data_len = u64_at(b, at + 8);
        let blocks = len.div_ceil(BLOCK as u64);
        let end = blocks
            .checked_mul(16)
            .and_then(|h| h.checked_add(fixed as u64))
            .and_then(|d| d.checked_add(data_len).map(|e| (d, e)))
            .ok_or(short(u64::MAX))?;
        if end.1 > b.len() as u64 {
            return Err(short(end.1));
        }
        let arr = Self {
            len,
            heads: fixed,
            data: end.0 as usize,
            data_len: data_len as usize,
        };
        for k in 0..blocks as usize {
            let h = fixed + 16 * k;
            let (width, off) = (u32_at(b, h + 4), u64_at(b, h + 8));
            let count = (len - (k * BLOCK) as u64).min(BLOCK as u64);
            if width > 32 {
                return Err(FormatError::OutOfRange {
                    section,
                    what: "a packed block's bit width",
                    value: u64::from(width),
                    limit: 32,
                });
            }
            let stop = off.checked_add(count * u64::from(width));
            if stop.is_none_or(|x| x > data_len * 8) {
                return Err(FormatError::OutOfRange {
                    section,
                    what: "a packed block's last bit",
                    value: stop.unwrap_or(u64::MAX),
                    limit: data_len * 8,
                });
            }
        }
        Ok((arr, end.1 as usize))
    }

    /// Value `i` (`i < len`), read from the blob the array was parsed from.
    #[inline]
    pub fn get(&self, b: &[u8], i: u64) -> u32 {
        let h = self.heads + 16 * (i as usize / BLOCK);
        let (base, width, off) = (u32_at(b, h), u32_at(b, h + 4), u64_at(b, h + 8));
        let data = &b[self.data..self.data + self.data_len];
        base.wrapping_add(get_bits(
            data,
            off + (i % BLOCK as u64) * u64::from(width),
            width,
        ))
    }

    /// Number of values.
    pub fn len(&self) -> u64 {
        self.len
    }

    /// Whether the array has no values.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

/// A [`ForArray`] written as its values come, for arrays too large to
/// hold: the offsets go to a writer as each block fills (LSB first, as
/// [`ForArray::write`] packs them), the block heads (16 bytes per 128
/// values) stay in memory until [`finish`](Self::finish). The array is
/// then the 16 bytes of [`ForPieces::prefix`], the heads, and what the
/// writer got: byte for byte what [`ForArray::write`] writes for the same
/// values.
#[derive(Debug)]
pub struct ForWriter<W: std::io::Write> {
    block: Vec<u32>,
    heads: Vec<u8>,
    out: W,
    /// Bytes not yet given to `out`.
    buf: Vec<u8>,
    /// Bits not yet in `buf` (fewer than 8 between blocks).
    acc: u64,
    acc_bits: u32,
    bit: u64,
    len: u64,
}

/// A finished [`ForWriter`]'s array: the prefix and heads in memory, the
/// offsets in the writer.
#[derive(Debug)]
pub struct ForPieces<W> {
    /// `len` and `data_len`, as the layout starts.
    pub prefix: [u8; 16],
    /// The block heads.
    pub heads: Vec<u8>,
    /// The writer, holding `data_len` bytes of offsets.
    pub out: W,
}

impl<W: std::io::Write> ForWriter<W> {
    /// An empty array whose offsets go to `out`.
    pub fn new(out: W) -> Self {
        Self {
            block: Vec::with_capacity(BLOCK),
            heads: Vec::new(),
            out,
            buf: Vec::with_capacity(1 << 16),
            acc: 0,
            acc_bits: 0,
            bit: 0,
            len: 0,
        }
    }

    /// Appends `v`.
    pub fn push(&mut self, v: u32) -> std::io::Result<()> {
        self.block.push(v);
        self.len += 1;
        if self.block.len() == BLOCK {
            self.flush_block()?;
        }
        Ok(())
    }

    fn flush_block(&mut self) -> std::io::Result<()> {
        if self.block.is_empty() {
            return Ok(());
        }
        let base = self.block.iter().copied().min().unwrap_or(0);
        let span = self.block.iter().map(|&v| v - base).max().unwrap_or(0);
        let width = 32 - span.leading_zeros();
        self.heads.extend_from_slice(&base.to_le_bytes());
        self.heads.extend_from_slice(&width.to_le_bytes());
        self.heads.extend_from_slice(&self.bit.to_le_bytes());
        for &v in &self.block {
            self.acc |= u64::from(v - base) << self.acc_bits;
            self.acc_bits += width;
            while self.acc_bits >= 8 {
                self.buf.push(self.acc as u8);
                self.acc >>= 8;
                self.acc_bits -= 8;
            }
        }
        self.bit += self.block.len() as u64 * u64::from(width);
        self.block.clear();
        if self.buf.len() >= 1 << 16 {
            self.out.write_all(&self.buf)?;
            self.buf.clear();
        }
        Ok(())
    }

    /// Writes the last block and the last partial byte (zero-padded).
    pub fn finish(mut self) -> std::io::Result<ForPieces<W>> {
        self.flush_block()?;
        if self.acc_bits > 0 {
            self.buf.push(self.acc as u8);
        }
        self.out.write_all(&self.buf)?;
        self.out.flush()?;
        let mut prefix = [0u8; 16];
        prefix[..8].copy_from_slice(&self.len.to_le_bytes());
        prefix[8..].copy_from_slice(&self.bit.div_ceil(8).to_le_bytes());
        Ok(ForPieces {
            prefix,
            heads: self.heads,
            out: self.out,
        })
    }
}

/// One [`ForVec`] block head.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Head {
    base: u32,
    width: u32,
    bit: u64,
}

/// A [`ForArray`] in memory, in the same layout on disk: the block heads
/// as a typed array (small enough to stay in cache: 16 bytes per 128
/// values) and the offsets followed by eight zero bytes, so that a read is
/// one head and one unaligned 64-bit load, without branches.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ForVec {
    len: u64,
    heads: Vec<Head>,
    /// The offsets, then 8 bytes of padding.
    data: Vec<u8>,
}

impl ForVec {
    /// The array of `values`.
    pub fn new(values: &[u32]) -> Self {
        let mut blob = Vec::new();
        ForArray::write(values, &mut blob);
        Self::parse(&blob, 0, "packed array")
            .expect("a fresh array parses")
            .0
    }

    /// Parses the [`ForArray`] at `at` of `b` (checked as
    /// [`ForArray::parse`] does); returns it and the offset just past it.
    pub fn parse(b: &[u8], at: usize, section: &'static str) -> Result<(Self, usize), FormatError> {
        let (arr, end) = ForArray::parse(b, at, section)?;
        let blocks = arr.len.div_ceil(BLOCK as u64) as usize;
        let heads = (0..blocks)
            .map(|k| {
                let h = arr.heads + 16 * k;
                Head {
                    base: u32_at(b, h),
                    width: u32_at(b, h + 4),
                    bit: u64_at(b, h + 8),
                }
            })
            .collect();
        let mut data = b[arr.data..arr.data + arr.data_len].to_vec();
        data.extend_from_slice(&[0; 8]);
        Ok((
            Self {
                len: arr.len,
                heads,
                data,
            },
            end,
        ))
    }

    /// Appends the array in [`ForArray`]'s layout to `out`.
    pub fn write(&self, out: &mut Vec<u8>) {
        let data = &self.data[..self.data.len() - 8];
        out.extend_from_slice(&self.len.to_le_bytes());
        out.extend_from_slice(&(data.len() as u64).to_le_bytes());
        for h in &self.heads {
            out.extend_from_slice(&h.base.to_le_bytes());
            out.extend_from_slice(&h.width.to_le_bytes());
            out.extend_from_slice(&h.bit.to_le_bytes());
        }
        out.extend_from_slice(data);
    }

    /// Bytes of the array in [`ForArray`]'s layout.
    pub fn bytes(&self) -> usize {
        16 + 16 * self.heads.len() + self.data.len().saturating_sub(8)
    }

    /// Value `i` (`i < len`).
    #[inline(always)]
    pub fn get(&self, i: u64) -> u32 {
        let h = self.heads[(i / BLOCK as u64) as usize];
        let at = h.bit + (i % BLOCK as u64) * u64::from(h.width);
        let byte = (at >> 3) as usize;
        let w = u64::from_le_bytes(
            self.data[byte..byte + 8]
                .try_into()
                .expect("an 8-byte slice"),
        );
        h.base
            .wrapping_add(((w >> (at & 7)) & ((1u64 << h.width) - 1)) as u32)
    }

    /// Number of values.
    pub fn len(&self) -> u64 {
        self.len
    }

    /// Whether the array has no values.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_streaming_writer_writes_what_write_writes() {
        let mut x = 12345u64;
        for n in [0usize, 1, 127, 128, 129, 1000, 4097] {
            let values: Vec<u32> = (0..n)
                .map(|i| {
                    x = x
                        .wrapping_mul(6364136223846793005)
                        .wrapping_add(1442695040888963407);
                    // Blocks of many widths, up to 32 bits.
                    ((x >> 32) as u32) >> ((i / 128) % 32) as u32
                })
                .collect();
            let mut want = Vec::new();
            ForArray::write(&values, &mut want);
            let mut w = ForWriter::new(Vec::new());
            for &v in &values {
                w.push(v).unwrap();
            }
            let p = w.finish().unwrap();
            let mut got = p.prefix.to_vec();
            got.extend_from_slice(&p.heads);
            got.extend_from_slice(&p.out);
            assert_eq!(got, want, "{n} values");
        }
    }

    #[test]
    fn frame_of_reference_arrays_round_trip_and_reject_bad_heads() {
        let values: Vec<u32> = (0..1000u32)
            .map(|i| match i % 7 {
                0 => u32::MAX,
                1 => 0,
                _ => 5000 + i * 3,
            })
            .chain(std::iter::repeat_n(42, 300))
            .collect();
        let mut blob = vec![9u8; 5];
        ForArray::write(&values, &mut blob);
        ForArray::write(&[], &mut blob);
        let (arr, next) = ForArray::parse(&blob, 5, "test").unwrap();
        assert_eq!(arr.len(), values.len() as u64);
        for (i, &v) in values.iter().enumerate() {
            assert_eq!(arr.get(&blob, i as u64), v);
        }
        let (empty, end) = ForArray::parse(&blob, next, "test").unwrap();
        assert!(empty.is_empty());
        assert_eq!(end, blob.len());
        // The in-memory form reads the same and writes the same bytes.
        let (v, vnext) = ForVec::parse(&blob, 5, "test").unwrap();
        assert_eq!(vnext, next);
        for (i, &x) in values.iter().enumerate() {
            assert_eq!(v.get(i as u64), x);
        }
        let mut again = Vec::new();
        v.write(&mut again);
        assert_eq!(again, blob[5..next]);
        assert_eq!(v.bytes(), next - 5);
        assert_eq!(ForVec::new(&values), v);
        assert!(ForVec::new(&[]).is_empty());
        // A width above 32 or a truncated blob is an error, not a panic.
        let mut bad = blob.clone();
        bad[5 + 16 + 4] = 33;
        assert!(ForArray::parse(&bad, 5, "test").is_err());
        assert!(ForArray::parse(&blob[..next - 1], 5, "test").is_err());
    }
}
