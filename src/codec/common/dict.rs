//! The dictionary coder of RACBVH (§4.4), behind the [`SymbolEncoder`] /
//! [`SymbolDecoder`] traits.
//!
//! # The dictionary coder
//!
//! Each compression context owns a dictionary that starts *empty* (it holds
//! only an escape entry), gains a symbol the first time the symbol is met,
//! and never gains combination entries: the paper's variant for residual and
//! delta contexts (RACBVH uses it for every context; its module docs say
//! why). A symbol is sent as its current *rank* in the dictionary; a new
//! symbol is sent as the escape's rank followed by the symbol in `raw_bits`
//! bits. After every use the entry moves one place towards the front (the
//! transpose heuristic), so frequent symbols get small ranks. Ranks are
//! written with an Exp-Golomb code whose parameter `k` (0..=[`MAX_K`]) the
//! encoder chooses per context (RACBVH: per context and cluster, stored in
//! the cluster header), so a context with a flat distribution does not pay
//! the γ-code's price for it.
//!
//! The coder sits behind [`SymbolEncoder`] / [`SymbolDecoder`] so that a
//! range coder can be put in its place.

use super::FormatError;
use super::bits::{BitReader, golomb_at};

/// Largest Exp-Golomb parameter the encoder may choose.
pub const MAX_K: u32 = 3;

/// One step of an encoder: what a context decided for a symbol.
#[derive(Clone, Copy, Debug)]
pub struct Step {
    /// The rank sent.
    pub rank: u32,
    /// The raw symbol sent after an escape.
    pub raw: Option<u32>,
}

/// The encoding side of a per-context symbol coder.
pub trait SymbolEncoder {
    /// Codes `sym` and returns what must be written.
    fn encode(&mut self, sym: u32) -> Step;
}

/// The decoding side of a per-context symbol coder.
pub trait SymbolDecoder {
    /// Reads one symbol.
    fn decode(&mut self, r: &mut BitReader<'_>) -> Result<u32, FormatError>;
}

/// The dictionary for the encoder: symbols by rank and ranks by symbol.
pub struct DictEncoder {
    by_rank: Vec<u32>,
    rank_of: crate::hash::FastMap<u32, u32>,
    esc: u32,
}

impl DictEncoder {
    /// An empty dictionary (only the escape entry).
    pub fn new() -> Self {
        Self {
            by_rank: vec![0],
            rank_of: crate::hash::FastMap::default(),
            esc: 0,
        }
    }

    fn promote(&mut self, r: u32) {
        if r == 0 {
            return;
        }
        let (a, b) = (r as usize - 1, r as usize);
        self.by_rank.swap(a, b);
        // Fix the two moved entries' ranks (the escape has no symbol).
        if self.esc == r {
            self.esc = r - 1;
            let s = self.by_rank[b];
            self.rank_of.insert(s, r);
        } else if self.esc == r - 1 {
            self.esc = r;
            let s = self.by_rank[a];
            self.rank_of.insert(s, r - 1);
        } else {
            let (sa, sb) = (self.by_rank[a], self.by_rank[b]);
            self.rank_of.insert(sa, r - 1);
            self.rank_of.insert(sb, r);
        }
    }
}

impl Default for DictEncoder {
    fn default() -> Self {
        Self::new()
    }
}

impl SymbolEncoder for DictEncoder {
    fn encode(&mut self, sym: u32) -> Step {
        match self.rank_of.get(&sym) {
            Some(&r) => {
                self.promote(r);
                Step { rank: r, raw: None }
            }
            None => {
                let r = self.esc;
                let new = self.by_rank.len() as u32;
                self.by_rank.push(sym);
                self.rank_of.insert(sym, new);
                self.promote(r);
                Step {
                    rank: r,
                    raw: Some(sym),
                }
            }
        }
    }
}

/// The dictionary for the decoder, with the context's code parameters.
pub struct DictDecoder {
    by_rank: Vec<u32>,
    esc: u32,
    k: u32,
    raw_bits: u32,
}

impl DictDecoder {
    /// An empty dictionary whose ranks use Exp-Golomb parameter `k` and
    /// whose new symbols take `raw_bits` bits.
    pub fn new(k: u32, raw_bits: u32) -> Self {
        Self {
            by_rank: vec![0],
            esc: 0,
            k,
            raw_bits,
        }
    }
}

impl DictDecoder {
    #[cold]
    fn escape(&mut self, r: &mut BitReader<'_>) -> u32 {
        let s = r.get(self.raw_bits) as u32;
        self.by_rank.push(s);
        s
    }
}

impl DictDecoder {
    /// Reads a bit-length symbol and the bits below the leading one that
    /// follow it (a box residual or a far triangle delta): one look at the
    /// stream for both when they fit. Lengths above `max_len` are errors.
    #[inline(always)]
    pub fn decode_bucketed(
        &mut self,
        r: &mut BitReader<'_>,
        max_len: u32,
    ) -> Result<u32, FormatError> {
        let w = r.peek();
        let (rank, total) = golomb_at(w, self.k)?;
        if rank >= self.by_rank.len() as u32 {
            return Err(FormatError::Corrupt {
                what: "a dictionary rank is out of range",
            });
        }
        if rank == self.esc {
            r.skip(total);
            let b = self.escape(r);
            self.transpose(rank);
            if b > max_len {
                return Err(FormatError::Corrupt {
                    what: "a bit length is too large",
                });
            }
            return Ok(((1u32 << b) >> 1) | r.get(b.saturating_sub(1)) as u32);
        }
        let b = self.by_rank[rank as usize];
        self.transpose(rank);
        if b > max_len {
            return Err(FormatError::Corrupt {
                what: "a bit length is too large",
            });
        }
        let m = b.saturating_sub(1);
        let mant = if total + m <= 56 {
            r.skip(total + m);
            (w >> total) & ((1u64 << m) - 1)
        } else {
            r.skip(total);
            r.get(m)
        };
        Ok(((1u32 << b) >> 1) | mant as u32)
    }

    /// Moves the entry at `rank` one place to the front (a no-op for rank
    /// 0) without a branch on the rank. After an escape the new symbol was
    /// pushed at the end while the escape sat at `rank`; the escape's slot
    /// holds a stale value that is never read.
    #[inline(always)]
    fn transpose(&mut self, rank: u32) {
        let a = rank.saturating_sub(1);
        self.by_rank.swap(a as usize, rank as usize);
        let esc = self.esc;
        self.esc = if esc == rank {
            a
        } else if esc == a {
            rank
        } else {
            esc
        };
    }
}

impl SymbolDecoder for DictDecoder {
    #[inline(always)]
    fn decode(&mut self, r: &mut BitReader<'_>) -> Result<u32, FormatError> {
        let rank = r.get_golomb(self.k)?;
        if rank >= self.by_rank.len() as u32 {
            return Err(FormatError::Corrupt {
                what: "a dictionary rank is out of range",
            });
        }
        let sym = if rank == self.esc {
            self.escape(r)
        } else {
            self.by_rank[rank as usize]
        };
        self.transpose(rank);
        Ok(sym)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::codec::common::bits::BitWriter;

    #[test]
    fn dictionary_round_trip() {
        let syms: Vec<u32> = (0..2000u32)
            .map(|i| (i * 7919 % 13) ^ (i % 3))
            .chain([u32::MAX, 0, 5])
            .collect();
        for k in 0..=MAX_K {
            let mut enc = DictEncoder::new();
            let mut w = BitWriter::default();
            for &s in &syms {
                let st = enc.encode(s);
                w.put_golomb(st.rank, k);
                if let Some(raw) = st.raw {
                    w.put(u64::from(raw), 32);
                }
            }
            let bytes = w.finish();
            let mut r = BitReader::new(&bytes);
            let mut dec = DictDecoder::new(k, 32);
            for &s in &syms {
                assert_eq!(dec.decode(&mut r).unwrap(), s);
            }
            assert!(!r.overran());
        }
    }
}
