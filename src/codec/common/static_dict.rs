//! The static dictionary coder of HCCMesh (§5.2), with the paper's optimal
//! dictionary size, behind the same [`SymbolEncoder`] / [`SymbolDecoder`]
//! traits as RACBVH's adaptive coder ([`dict`](super::dict)).
//!
//! # The coder
//!
//! A context's dictionary holds the `s` symbols that occur most often in
//! the whole input of that context, by decreasing count, and one *escape*
//! entry placed among them by its own count (the symbols left out). A
//! symbol in the dictionary is sent as its rank; any other as the escape's
//! rank followed by the symbol in `raw_bits` bits (the paper's `C_o`). The
//! dictionary never changes while coding, so a decoder reads a rank and
//! looks it up: no per-symbol bookkeeping, the fastest decode of the
//! coders here (the paper chose its coder for decode speed, §5.1).
//!
//! Ranks are written with an Exp-Golomb code of parameter `k` (the code
//! [`dict`](super::dict) uses), not with the paper's fixed `⌈log₂ s⌉` bits:
//! the ranks are sorted by frequency, so a prefix code over them gains
//! where the distribution is skewed (parallelogram residuals, corner
//! cache ranks) and loses little where it is flat.
//!
//! # Optimal dictionary size (§5.2)
//!
//! The paper picks `s` minimising `B(s) = p(s)·bits(index) + (1 − p(s))·C_o`
//! where `p(s)` is the share of the input the `s` most frequent symbols
//! cover. [`StaticDict::optimal`] minimises the same quantity with this
//! coder's real costs: every symbol's rank code, the escape's rank code
//! plus `C_o` for every symbol left out, and the `s · C_o` bits of the
//! stored dictionary itself, over every `s` from 0 to the number of
//! distinct symbols and every `k` in `0..=MAX_K` (exhaustive with prefix
//! sums, so `O(d log d)` per `k`, rather than the paper's first local
//! minimum: with a prefix code `B(s)` need not be unimodal).
//!
//! # Layout
//!
//! A dictionary as stored (bit stream, least-significant bit first):
//! `k` (2 bits), `raw_bits` (6 bits, 0–32), `s` (32 bits), the escape's
//! rank (32 bits, at most `s`), then the `s` symbols in rank order with
//! the escape's rank skipped, `raw_bits` bits each.

use super::FormatError;
use super::bits::{BitReader, BitWriter, golomb_len};
use super::dict::{MAX_K, Step, SymbolDecoder, SymbolEncoder};

/// A static dictionary: symbols by rank and the escape's rank.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StaticDict {
    /// Exp-Golomb parameter of the ranks.
    pub k: u32,
    /// Bits of a symbol sent raw after an escape.
    pub raw_bits: u32,
    /// The escape's rank (`0..=symbols.len()`).
    pub esc: u32,
    /// The dictionary's symbols in rank order, the escape's rank skipped.
    pub symbols: Vec<u32>,
}

/// Bits that hold `v` (at least 1).
fn width(v: u32) -> u32 {
    (32 - v.leading_zeros()).max(1)
}

impl StaticDict {
    /// The dictionary of optimal size (§5.2, see the module docs) for a
    /// context whose input holds symbol `sym` `count` times, for every
    /// `(sym, count)` of `counts` (symbols distinct, counts nonzero).
    pub fn optimal(counts: &[(u32, u64)]) -> Self {
        let mut sorted = counts.to_vec();
        sorted.sort_unstable_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
        let raw_bits = width(sorted.iter().map(|c| c.0).max().unwrap_or(0));
        let c_o = u64::from(raw_bits);
        let d = sorted.len();
        let total: u64 = sorted.iter().map(|c| c.1).sum();
        // Prefix counts: covered[s] = occurrences of the s most frequent.
        let mut covered = vec![0u64; d + 1];
        for (i, c) in sorted.iter().enumerate() {
            covered[i + 1] = covered[i] + c.1;
        }
        let (mut best, mut best_k, mut best_s) = (u64::MAX, 0, 0);
        let mut at = vec![0u64; d + 1];
        let mut after = vec![0u64; d + 1];
        for k in 0..=MAX_K {
            // at[i]: the first i symbols at ranks 0..i; after[i]: at ranks
            // 1..=i (one place down, behind the escape).
            for (i, c) in sorted.iter().enumerate() {
                at[i + 1] = at[i] + c.1 * golomb_len(i as u32, k);
                after[i + 1] = after[i] + c.1 * golomb_len(i as u32 + 1, k);
            }
            for s in 0..=d {
                let esc_count = total - covered[s];
                // The escape sits behind the symbols at least as frequent.
                let pos = sorted[..s].partition_point(|c| c.1 >= esc_count);
                let bits = at[pos]
                    + esc_count * (golomb_len(pos as u32, k) + c_o)
                    + (after[s] - after[pos])
                    + s as u64 * c_o;
                if bits < best {
                    (best, best_k, best_s) = (bits, k, s);
                }
            }
        }
        let esc_count = total - covered[best_s];
        let esc = sorted[..best_s].partition_point(|c| c.1 >= esc_count) as u32;
        Self {
            k: best_k,
            raw_bits,
            esc,
            symbols: sorted[..best_s].iter().map(|c| c.0).collect(),
        }
    }

    /// Appends the dictionary to `w` (see the module docs).
    pub fn write(&self, w: &mut BitWriter) {
        w.put(u64::from(self.k), 2);
        w.put(u64::from(self.raw_bits), 6);
        w.put(self.symbols.len() as u64, 32);
        w.put(u64::from(self.esc), 32);
        for &s in &self.symbols {
            w.put(u64::from(s), self.raw_bits);
        }
    }

    /// Reads a dictionary written by [`write`](Self::write) of at most
    /// `max_symbols` symbols, each below `2^max_raw_bits`.
    pub fn read(
        r: &mut BitReader<'_>,
        max_symbols: usize,
        max_raw_bits: u32,
    ) -> Result<Self, FormatError> {
        let k = r.get(2) as u32;
        let raw_bits = r.get(6) as u32;
        let s = r.get(32);
        let esc = r.get(32);
        let corrupt = |what| Err(FormatError::Corrupt { what });
        if k > MAX_K {
            return corrupt("a dictionary's Exp-Golomb parameter is out of range");
        }
        if raw_bits > max_raw_bits {
            return corrupt("a dictionary's raw symbol width is out of range");
        }
        // Distinct symbols of `raw_bits` bits: at most 2^raw_bits of them.
        if s > max_symbols as u64 || s > 1u64 << raw_bits || r.overran() {
            return corrupt("a dictionary holds more symbols than its context has");
        }
        if esc > s {
            return corrupt("a dictionary's escape rank is out of range");
        }
        let mut symbols = Vec::with_capacity((s as usize).min(1 << 12));
        for _ in 0..s {
            symbols.push(r.get(raw_bits) as u32);
            if r.overran() {
                return corrupt("a dictionary runs past its section");
            }
        }
        Ok(Self {
            k,
            raw_bits,
            esc: esc as u32,
            symbols,
        })
    }

    /// The encoder of this dictionary.
    pub fn encoder(&self) -> StaticEncoder {
        let mut rank_of = crate::hash::FastMap::default();
        for (i, &s) in self.symbols.iter().enumerate() {
            let r = i as u32 + u32::from(i as u32 >= self.esc);
            rank_of.insert(s, r);
        }
        StaticEncoder {
            rank_of,
            esc: self.esc,
            k: self.k,
            raw_bits: self.raw_bits,
        }
    }

    /// The decoder of this dictionary.
    pub fn decoder(&self) -> StaticDecoder {
        let mut table = self.symbols.clone();
        table.insert(self.esc as usize, 0);
        StaticDecoder {
            table,
            esc: self.esc,
            k: self.k,
            raw_bits: self.raw_bits,
        }
    }
}

/// Codes symbols with a [`StaticDict`].
pub struct StaticEncoder {
    rank_of: crate::hash::FastMap<u32, u32>,
    esc: u32,
    k: u32,
    raw_bits: u32,
}

impl StaticEncoder {
    /// Codes `sym` into `w`.
    pub fn put(&mut self, w: &mut BitWriter, sym: u32) {
        let st = self.encode(sym);
        w.put_golomb(st.rank, self.k);
        if let Some(raw) = st.raw {
            w.put(u64::from(raw), self.raw_bits);
        }
    }
}

impl SymbolEncoder for StaticEncoder {
    fn encode(&mut self, sym: u32) -> Step {
        match self.rank_of.get(&sym) {
            Some(&rank) => Step { rank, raw: None },
            None => {
                debug_assert!(self.raw_bits >= 32 || sym >> self.raw_bits == 0);
                Step {
                    rank: self.esc,
                    raw: Some(sym),
                }
            }
        }
    }
}

/// Decodes symbols with a [`StaticDict`]: a rank and a table look-up.
#[derive(Clone, Debug)]
pub struct StaticDecoder {
    /// Symbols by rank (the escape's slot unused).
    table: Vec<u32>,
    esc: u32,
    k: u32,
    raw_bits: u32,
}

impl StaticDecoder {
    /// Reads one symbol.
    #[inline(always)]
    pub fn get(&self, r: &mut BitReader<'_>) -> Result<u32, FormatError> {
        let rank = r.get_golomb(self.k)?;
        if rank == self.esc {
            return Ok(r.get(self.raw_bits) as u32);
        }
        match self.table.get(rank as usize) {
            Some(&s) => Ok(s),
            None => Err(FormatError::Corrupt {
                what: "a dictionary rank is out of range",
            }),
        }
    }
}

impl SymbolDecoder for StaticDecoder {
    #[inline(always)]
    fn decode(&mut self, r: &mut BitReader<'_>) -> Result<u32, FormatError> {
        self.get(r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn counts(syms: &[u32]) -> Vec<(u32, u64)> {
        let mut m = std::collections::BTreeMap::new();
        for &s in syms {
            *m.entry(s).or_insert(0u64) += 1;
        }
        m.into_iter().collect()
    }

    fn round_trip(syms: &[u32]) -> (StaticDict, u64) {
        let dict = StaticDict::optimal(&counts(syms));
        let mut w = BitWriter::default();
        dict.write(&mut w);
        let mut enc = dict.encoder();
        for &s in syms {
            enc.put(&mut w, s);
        }
        let bits = w.bit_len();
        let bytes = w.finish();
        let mut r = BitReader::new(&bytes);
        let back = StaticDict::read(&mut r, syms.len(), 32).unwrap();
        assert_eq!(back, dict);
        let dec = back.decoder();
        for &s in syms {
            assert_eq!(dec.get(&mut r).unwrap(), s);
        }
        assert!(!r.overran());
        (dict, bits)
    }

    #[test]
    fn skewed_input_gets_a_small_dictionary_and_round_trips() {
        // Mostly a few symbols, with a long tail of singletons.
        let syms: Vec<u32> = (0..5000u32)
            .map(|i| if i % 10 == 9 { 1000 + i } else { i % 4 })
            .collect();
        let (dict, bits) = round_trip(&syms);
        assert_eq!(dict.symbols.len(), 4, "the singletons stay out");
        assert!(bits < 5000 * 6, "{bits} bits");
    }

    #[test]
    fn edge_inputs_round_trip() {
        round_trip(&[]);
        round_trip(&[7]);
        round_trip(&[u32::MAX, 0, u32::MAX]);
        let flat: Vec<u32> = (0..300).collect();
        let (dict, _) = round_trip(&flat);
        assert!(dict.symbols.is_empty(), "singletons are cheaper raw");
    }

    #[test]
    fn the_chosen_size_is_no_worse_than_its_neighbours() {
        let syms: Vec<u32> = (0..4000u32).map(|i| (i * i) % 97 % (1 + i % 23)).collect();
        let c = counts(&syms);
        let dict = StaticDict::optimal(&c);
        let cost = |d: &StaticDict| {
            let mut w = BitWriter::default();
            d.write(&mut w);
            let mut enc = d.encoder();
            for &s in &syms {
                enc.put(&mut w, s);
            }
            w.bit_len()
        };
        let best = cost(&dict);
        // Any other size (same k, escape placed by count) costs as much.
        let mut sorted = c.clone();
        sorted.sort_unstable_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
        for s in 0..=sorted.len() {
            let esc_count: u64 = sorted[s..].iter().map(|c| c.1).sum();
            let other = StaticDict {
                k: dict.k,
                raw_bits: dict.raw_bits,
                esc: sorted[..s].partition_point(|c| c.1 >= esc_count) as u32,
                symbols: sorted[..s].iter().map(|c| c.0).collect(),
            };
            assert!(cost(&other) >= best, "s = {s}");
        }
    }

    #[test]
    fn hostile_dictionaries_are_errors() {
        let mut w = BitWriter::default();
        w.put(0, 2);
        w.put(40, 6); // raw bits above 32
        w.put(0, 32);
        w.put(0, 32);
        let b = w.finish();
        assert!(StaticDict::read(&mut BitReader::new(&b), 10, 32).is_err());
        let mut w = BitWriter::default();
        w.put(0, 2);
        w.put(8, 6);
        w.put(1 << 30, 32); // more symbols than the stream holds
        w.put(0, 32);
        let b = w.finish();
        assert!(StaticDict::read(&mut BitReader::new(&b), usize::MAX, 32).is_err());
        // A rank past the table.
        let d = StaticDict {
            k: 0,
            raw_bits: 4,
            esc: 0,
            symbols: vec![3],
        };
        let mut w = BitWriter::default();
        w.put_golomb(5, 0);
        let b = w.finish();
        assert!(d.decoder().get(&mut BitReader::new(&b)).is_err());
    }
}
