//! The static dictionary coder of HCCMesh (§5.2), with the paper's optimal
//! dictionary size.
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
//! # Split values (not in the paper)
//!
//! A context whose values are large and spread (the vertex residuals of a
//! scanned model: 9–11 bits of entropy over thousands of distinct values)
//! fills a dictionary with values seen a few times each, or escapes most
//! of them: up to 5 bits a value over the entropy. So a value `v` of
//! `L` bits is coded as a *symbol* and *extra bits*, split at `m`: values
//! below `2^(m+1)` are their own symbol, no extra bits; a larger one is
//! the symbol `(L − m) · 2^m + (the m bits below v's leading one)`
//! followed by its `L − m − 1` low bits, raw. `m = 0` is the bucketed
//! coding of RACBVH's box residuals (the bit length through the
//! dictionary, the bits below the leading one raw); an `m` at least the
//! width of the largest value is the plain coding of the paper. The
//! encoder picks `m` per context with the dictionary (every `m` from 0 to
//! that width, exhaustively), so a context never costs more than its plain
//! coding, and the decoder's table holds each rank's value base and extra
//! bit count: a look-up and one read, whatever `m`.
//!
//! # Optimal dictionary size (§5.2)
//!
//! The paper picks `s` minimising `B(s) = p(s)·bits(index) + (1 − p(s))·C_o`
//! where `p(s)` is the share of the input the `s` most frequent symbols
//! cover. [`StaticDict::optimal`] minimises the same quantity with this
//! coder's real costs: every symbol's rank code, the escape's rank code
//! plus `C_o` for every symbol left out, the extra bits of split values
//! and the `s · C_o` bits of the stored dictionary itself, over every `s`
//! from 0 to the number of distinct symbols, every `k` in `0..=MAX_K` and
//! every split `m` (exhaustive with prefix sums, so `O(d log d)` per `k`
//! and `m`, rather than the paper's first local minimum: with a prefix
//! code `B(s)` need not be unimodal).
//!
//! # Layout
//!
//! A dictionary as stored (bit stream, least-significant bit first):
//! `k` (2 bits), `raw_bits` (6 bits, 0–32), the split `m` (6 bits, 0–32),
//! `s` (32 bits), the escape's rank (32 bits, at most `s`), then the `s`
//! symbols in rank order with the escape's rank skipped, `raw_bits` bits
//! each.

use super::FormatError;
use super::bits::{BitReader, BitWriter, golomb_at, golomb_len};
use super::dict::{MAX_K, SymbolDecoder};

/// A static dictionary: symbols by rank, the escape's rank and the split
/// of values into symbols and extra bits.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StaticDict {
    /// Exp-Golomb parameter of the ranks.
    pub k: u32,
    /// Bits of a symbol sent raw after an escape.
    pub raw_bits: u32,
    /// Values of more than `split + 1` bits are split into a symbol and
    /// extra bits (see the module docs).
    pub split: u32,
    /// The escape's rank (`0..=symbols.len()`).
    pub esc: u32,
    /// The dictionary's symbols in rank order, the escape's rank skipped.
    pub symbols: Vec<u32>,
}

/// Bits that hold `v` (at least 1).
fn width(v: u32) -> u32 {
    (32 - v.leading_zeros()).max(1)
}

/// The largest split stored (6 bits): every value is its own symbol.
const MAX_SPLIT: u32 = 32;

/// Value `v` split at `m`: its symbol, its extra bits and their count.
#[inline]
fn split_value(v: u32, m: u32) -> (u32, u32, u32) {
    let q = (32 - v.leading_zeros()).saturating_sub(m);
    if q <= 1 {
        return (v, 0, 0);
    }
    let n = q - 1;
    let top = (v >> n) & ((1 << m) - 1);
    ((q << m) | top, v & ((1 << n) - 1), n)
}

/// The base value (extra bits zero) and extra bit count of symbol `sym`
/// split at `m`, if its value has at most `max_len` bits.
fn join(sym: u32, m: u32, max_len: u32) -> Option<(u32, u32)> {
    let q = u64::from(sym) >> m;
    if q <= 1 {
        return (width(sym) <= max_len || sym == 0).then_some((sym, 0));
    }
    // Bits of the value: its leading one, m below it, q − 1 extra.
    if q + u64::from(m) > u64::from(max_len) {
        return None;
    }
    let n = q as u32 - 1;
    let top = (1u64 << m) | (u64::from(sym) & ((1u64 << m) - 1));
    Some(((top << n) as u32, n))
}

/// The plain dictionary (every value its own symbol) of optimal size for
/// symbol counts `sorted` (by decreasing count), with its cost in bits
/// (dictionary and symbols).
fn optimal_plain(sorted: &[(u32, u64)], split: u32) -> (StaticDict, u64) {
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
    let dict = StaticDict {
        k: best_k,
        raw_bits,
        split,
        esc,
        symbols: sorted[..best_s].iter().map(|c| c.0).collect(),
    };
    (dict, best)
}

impl StaticDict {
    /// The dictionary of optimal size and split (§5.2, see the module
    /// docs) for a context whose input holds value `v` `count` times, for
    /// every `(v, count)` of `counts` (values distinct, counts nonzero).
    pub fn optimal(counts: &[(u32, u64)]) -> Self {
        let max = counts.iter().map(|c| c.0).max().unwrap_or(0);
        let mut best: Option<(Self, u64)> = None;
        for m in 0..=width(max) {
            let mut syms: crate::hash::FastMap<u32, u64> = Default::default();
            let mut extra = 0u64;
            for &(v, n) in counts {
                let (sym, _, bits) = split_value(v, m);
                *syms.entry(sym).or_insert(0) += n;
                extra += u64::from(bits) * n;
            }
            let mut sorted: Vec<(u32, u64)> = syms.into_iter().collect();
            sorted.sort_unstable_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
            let (dict, bits) = optimal_plain(&sorted, m);
            if best.as_ref().is_none_or(|b| bits + extra < b.1) {
                best = Some((dict, bits + extra));
            }
        }
        best.map_or_else(|| optimal_plain(&[], MAX_SPLIT).0, |b| b.0)
    }

    /// Appends the dictionary to `w` (see the module docs).
    pub fn write(&self, w: &mut BitWriter) {
        w.put(u64::from(self.k), 2);
        w.put(u64::from(self.raw_bits), 6);
        w.put(u64::from(self.split), 6);
        w.put(self.symbols.len() as u64, 32);
        w.put(u64::from(self.esc), 32);
        for &s in &self.symbols {
            w.put(u64::from(s), self.raw_bits);
        }
    }

    /// Reads a dictionary written by [`write`](Self::write) of at most
    /// `max_symbols` symbols, each below `2^max_raw_bits`, as are the
    /// values they stand for.
    pub fn read(
        r: &mut BitReader<'_>,
        max_symbols: usize,
        max_raw_bits: u32,
    ) -> Result<Self, FormatError> {
        let k = r.get(2) as u32;
        let raw_bits = r.get(6) as u32;
        let split = r.get(6) as u32;
        let s = r.get(32);
        let esc = r.get(32);
        let corrupt = |what| Err(FormatError::Corrupt { what });
        if k > MAX_K {
            return corrupt("a dictionary's Exp-Golomb parameter is out of range");
        }
        if raw_bits > max_raw_bits {
            return corrupt("a dictionary's raw symbol width is out of range");
        }
        if split > MAX_SPLIT {
            return corrupt("a dictionary's split is out of range");
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
            let sym = r.get(raw_bits) as u32;
            if r.overran() {
                return corrupt("a dictionary runs past its section");
            }
            if join(sym, split, max_raw_bits).is_none() {
                return corrupt("a dictionary symbol stands for a value out of range");
            }
            symbols.push(sym);
        }
        Ok(Self {
            k,
            raw_bits,
            split,
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
            split: self.split,
        }
    }

    /// The decoder of this dictionary, whose values have at most
    /// `max_len` bits (a dictionary [`read`](Self::read) with the same
    /// bound; other symbols decode as 0).
    pub fn decoder(&self, max_len: u32) -> StaticDecoder {
        let mut table: Vec<Entry> = self
            .symbols
            .iter()
            .map(|&s| {
                let (base, extra) = join(s, self.split, max_len).unwrap_or((0, 0));
                Entry { base, extra }
            })
            .collect();
        table.insert(self.esc as usize, Entry { base: 0, extra: 0 });
        // Every code of at most FAST_BITS bits, under every value of the
        // bits that follow it (codes are read least-significant bit
        // first: 0^n 1, then the n + k low bits of rank + 2^k).
        let mut fast = Box::new([0u64; 1 << FAST_BITS]);
        for (rank, e) in table.iter().enumerate() {
            let x = rank as u64 + (1 << self.k);
            let n = 63 - x.leading_zeros() - self.k;
            let len = 2 * n + 1 + self.k;
            if rank as u32 == self.esc || len > FAST_BITS || len + e.extra > FAST_SPAN {
                continue;
            }
            let code = 1 << n | (x & ((1 << (n + self.k)) - 1)) << (n + 1);
            let entry = u64::from(e.base) << 32
                | u64::from(len + e.extra) << 16
                | u64::from(len) << 8
                | u64::from(e.extra);
            for fill in 0..1u64 << (FAST_BITS - len) {
                fast[(code | fill << len) as usize] = entry;
            }
        }
        StaticDecoder {
            whole: table.iter().all(|e| e.extra == 0),
            fast,
            table,
            esc: self.esc,
            k: self.k,
            raw_bits: self.raw_bits,
            split: self.split,
            max_len,
        }
    }
}

/// Bits of the stream [`StaticDecoder`] looks codes up by.
const FAST_BITS: u32 = 8;

/// The most bits a value read through [`StaticDecoder`]'s table takes,
/// code and extra bits: [`READS_PER_REFILL`] of them fit one refill.
const FAST_SPAN: u32 = 18;

/// Reads [`StaticDecoder::get_refilled`] may make after one
/// [`BitReader::refill`].
pub const READS_PER_REFILL: u32 = 3;

const _: () = assert!(READS_PER_REFILL * FAST_SPAN <= 56);

/// Codes values with a [`StaticDict`].
pub struct StaticEncoder {
    rank_of: crate::hash::FastMap<u32, u32>,
    esc: u32,
    k: u32,
    raw_bits: u32,
    split: u32,
}

impl StaticEncoder {
    /// Codes value `v` into `w`.
    pub fn put(&mut self, w: &mut BitWriter, v: u32) {
        let (sym, extra, n) = split_value(v, self.split);
        match self.rank_of.get(&sym) {
            Some(&rank) => w.put_golomb(rank, self.k),
            None => {
                debug_assert!(self.raw_bits >= 32 || sym >> self.raw_bits == 0);
                w.put_golomb(self.esc, self.k);
                w.put(u64::from(sym), self.raw_bits);
            }
        }
        w.put(u64::from(extra), n);
    }
}

/// A rank's value with its extra bits zero, and their count.
#[derive(Clone, Copy, Debug)]
struct Entry {
    base: u32,
    extra: u32,
}

/// Decodes values with a [`StaticDict`]: a rank, a table look-up and the
/// extra bits.
#[derive(Clone, Debug)]
pub struct StaticDecoder {
    /// Values by rank (the escape's slot unused).
    table: Vec<Entry>,
    /// By the next [`FAST_BITS`] bits of the stream, when they start a
    /// code of a rank other than the escape's whose code and extra bits
    /// take at most [`FAST_SPAN`] bits: its value's base (bits 32–63), the
    /// bits it takes (16–23), the code's length (bits 8–15, never 0) and
    /// the extra bits' count (bits 0–7); 0 otherwise (the code is read
    /// bit by bit). Fixed-size, so the masked index needs no bounds check.
    fast: Box<[u64; 1 << FAST_BITS]>,
    esc: u32,
    k: u32,
    raw_bits: u32,
    split: u32,
    max_len: u32,
    /// No rank stands for a split value: the extra bits are not read, so
    /// that where the next code starts does not wait for the table look-up
    /// (the corner and template contexts).
    whole: bool,
}

impl StaticDecoder {
    /// Reads one value.
    #[inline(always)]
    pub fn get(&self, r: &mut BitReader<'_>) -> Result<u32, FormatError> {
        r.refill();
        self.get_refilled(r)
    }

    /// Reads one value, one of at most [`READS_PER_REFILL`] since the
    /// last [`BitReader::refill`]: short codes (most of them: ranks are
    /// sorted by frequency) by one look-up in the bits already buffered,
    /// so that where the next code starts waits for this code's length
    /// only, not for a load from the stream; other codes refill before
    /// and after.
    #[inline(always)]
    pub fn get_refilled(&self, r: &mut BitReader<'_>) -> Result<u32, FormatError> {
        let w = r.buffered();
        let e = self.fast[(w & ((1 << FAST_BITS) - 1)) as usize];
        if e != 0 {
            let (span, len, extra) = (
                (e >> 16) as u8 as u32,
                (e >> 8) as u8 as u32,
                e as u8 as u32,
            );
            r.skip(span);
            return Ok((e >> 32) as u32 | ((w >> len) & ((1u64 << extra) - 1)) as u32);
        }
        // Refilled after, so that the reads left of this refill's find
        // their bits buffered.
        let v = self.get_long(r);
        r.refill();
        v
    }

    /// [`get`](Self::get) of a code the table does not hold.
    #[inline]
    fn get_long(&self, r: &mut BitReader<'_>) -> Result<u32, FormatError> {
        let w = r.peek();
        // The rank's Exp-Golomb code and the extra bits after it from one
        // look at the stream when they fit in it (as `get_golomb`).
        let (rank, total) = golomb_at(w, self.k)?;
        if rank == self.esc {
            r.skip(total);
            return self.escaped(r);
        }
        let Some(e) = self.table.get(rank as usize) else {
            return Err(FormatError::Corrupt {
                what: "a dictionary rank is out of range",
            });
        };
        if self.whole {
            r.skip(total);
            return Ok(e.base);
        }
        // `peek` gives at least 56 bits.
        if total + e.extra <= 56 {
            r.skip(total + e.extra);
            return Ok(e.base | ((w >> total) & ((1u64 << e.extra) - 1)) as u32);
        }
        r.skip(total);
        Ok(e.base | r.get(e.extra) as u32)
    }

    /// The value of a symbol sent raw after an escape.
    #[cold]
    fn escaped(&self, r: &mut BitReader<'_>) -> Result<u32, FormatError> {
        let sym = r.get(self.raw_bits) as u32;
        match join(sym, self.split, self.max_len) {
            Some((base, extra)) => Ok(base | r.get(extra) as u32),
            None => Err(FormatError::Corrupt {
                what: "an escaped symbol stands for a value out of range",
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
        let dec = back.decoder(32);
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
        let p = plain(&syms);
        assert_eq!(p.symbols.len(), 4, "the singletons stay out");
        let (_, bits) = round_trip(&syms);
        assert!(bits < 5000 * 6, "{bits} bits");
        assert!(bits <= cost(&p, &syms), "splitting never costs more");
    }

    /// The plain dictionary (no split) of optimal size for `syms`.
    fn plain(syms: &[u32]) -> StaticDict {
        let mut sorted = counts(syms);
        sorted.sort_unstable_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
        optimal_plain(&sorted, MAX_SPLIT).0
    }

    #[test]
    fn edge_inputs_round_trip() {
        round_trip(&[]);
        round_trip(&[7]);
        round_trip(&[u32::MAX, 0, u32::MAX]);
        let flat: Vec<u32> = (0..300).collect();
        let p = plain(&flat);
        assert!(p.symbols.is_empty(), "singletons are cheaper raw");
        let (_, bits) = round_trip(&flat);
        assert!(bits <= cost(&p, &flat), "splitting never costs more");
    }

    /// Bits of `d` and of `syms` coded with it.
    fn cost(d: &StaticDict, syms: &[u32]) -> u64 {
        let mut w = BitWriter::default();
        d.write(&mut w);
        let mut enc = d.encoder();
        for &s in syms {
            enc.put(&mut w, s);
        }
        w.bit_len()
    }

    #[test]
    fn the_chosen_size_is_no_worse_than_its_neighbours() {
        let syms: Vec<u32> = (0..4000u32).map(|i| (i * i) % 97 % (1 + i % 23)).collect();
        let c = counts(&syms);
        let mut sorted = c.clone();
        sorted.sort_unstable_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
        let (dict, bits) = optimal_plain(&sorted, MAX_SPLIT);
        let best = cost(&dict, &syms);
        // The cost the search minimised is the real one, less the fields
        // of the dictionary's head (k, widths, counts).
        assert_eq!(best, bits + 2 + 6 + 6 + 32 + 32);
        // Any other size (same k, escape placed by count) costs as much.
        for s in 0..=sorted.len() {
            let esc_count: u64 = sorted[s..].iter().map(|c| c.1).sum();
            let other = StaticDict {
                k: dict.k,
                raw_bits: dict.raw_bits,
                split: MAX_SPLIT,
                esc: sorted[..s].partition_point(|c| c.1 >= esc_count) as u32,
                symbols: sorted[..s].iter().map(|c| c.0).collect(),
            };
            assert!(cost(&other, &syms) >= best, "s = {s}");
        }
    }

    #[test]
    fn splitting_round_trips_every_value() {
        let mut x = 7u64;
        for m in 0..=MAX_SPLIT {
            for i in 0..2000u32 {
                x = x
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                // Values of every width.
                let v = ((x >> 32) as u32) >> (i % 33).min(31) >> u32::from(i % 33 == 32);
                let (sym, extra, n) = split_value(v, m);
                assert!(sym <= v, "a symbol is never above its value");
                let (base, bits) = join(sym, m, 32).unwrap();
                assert_eq!((bits, base | extra), (n, v), "v = {v}, m = {m}");
                if v > 0 {
                    assert_eq!(join(sym, m, width(v) - 1), None, "v = {v}, m = {m}");
                }
            }
        }
    }

    #[test]
    fn spread_values_are_split_and_cost_less_than_plain_coding() {
        // Residual-like values: mostly small, a wide tail, few repeats.
        let mut x = 3u64;
        let syms: Vec<u32> = (0..20000)
            .map(|_| {
                x = x
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((x >> 40) as u32) >> ((x >> 8) % 16)
            })
            .collect();
        let (dict, bits) = round_trip(&syms);
        assert!(dict.split < 8, "split at {}", dict.split);
        let plain = cost(&plain(&syms), &syms);
        assert!(bits * 10 < plain * 9, "{bits} bits split, {plain} plain");
        // And a skewed input of small values keeps them whole.
        let (dict, _) = round_trip(&(0..5000u32).map(|i| i % 7 % 3).collect::<Vec<_>>());
        assert_eq!(split_value(2, dict.split).2, 0);
    }

    /// Reads in groups after one refill give what reads one by one give,
    /// through short codes with extra bits, long codes and escapes, and
    /// never run short of buffered bits (`skip` checks that in debug
    /// builds).
    #[test]
    fn grouped_reads_after_one_refill_match_single_reads() {
        let mut x = 11u64;
        // Skewed and split values, a wide tail and rare singletons (sent
        // raw after the escape).
        let syms: Vec<u32> = (0..30000u32)
            .map(|i| {
                x = x
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let r = (x >> 33) as u32;
                match r % 8 {
                    0..=3 => r % 5,
                    4 | 5 => (r >> 8) % 300,
                    6 => (r >> 4) >> (r % 24),
                    _ => 1_000_000 + i,
                }
            })
            .collect();
        let dict = StaticDict::optimal(&counts(&syms));
        let mut w = BitWriter::default();
        let mut enc = dict.encoder();
        for &s in &syms {
            enc.put(&mut w, s);
        }
        let bytes = w.finish();
        let dec = dict.decoder(32);
        assert!(
            dec.fast.iter().any(|&e| e != 0 && e as u8 != 0),
            "short codes with extra bits"
        );
        let mut r = BitReader::new(&bytes);
        for group in syms.chunks(READS_PER_REFILL as usize) {
            r.refill();
            for (j, &s) in group.iter().enumerate() {
                assert_eq!(dec.get_refilled(&mut r).unwrap(), s);
                // The bits the rest of the group may take are buffered.
                let left = READS_PER_REFILL - 1 - j as u32;
                assert!(r.buffered_bits() >= left * FAST_SPAN);
            }
        }
        assert!(!r.overran());
    }

    #[test]
    fn hostile_dictionaries_are_errors() {
        let mut w = BitWriter::default();
        w.put(0, 2);
        w.put(40, 6); // raw bits above 32
        w.put(0, 6);
        w.put(0, 32);
        w.put(0, 32);
        let b = w.finish();
        assert!(StaticDict::read(&mut BitReader::new(&b), 10, 32).is_err());
        let mut w = BitWriter::default();
        w.put(0, 2);
        w.put(8, 6);
        w.put(0, 6);
        w.put(1 << 30, 32); // more symbols than the stream holds
        w.put(0, 32);
        let b = w.finish();
        assert!(StaticDict::read(&mut BitReader::new(&b), usize::MAX, 32).is_err());
        // A split above 32, and a symbol whose value is wider than allowed.
        for (split, sym) in [(33, 0), (2, 6 << 2)] {
            let mut w = BitWriter::default();
            w.put(0, 2);
            w.put(5, 6);
            w.put(split, 6);
            w.put(1, 32);
            w.put(0, 32);
            w.put(sym, 5);
            let b = w.finish();
            assert!(StaticDict::read(&mut BitReader::new(&b), 10, 7).is_err());
        }
        // A rank past the table.
        let d = StaticDict {
            k: 0,
            raw_bits: 4,
            split: MAX_SPLIT,
            esc: 0,
            symbols: vec![3],
        };
        let mut w = BitWriter::default();
        w.put_golomb(5, 0);
        let b = w.finish();
        assert!(d.decoder(32).get(&mut BitReader::new(&b)).is_err());
        // An escaped symbol whose value is wider than the decoder's bound.
        let d = StaticDict {
            k: 0,
            raw_bits: 8,
            split: 2,
            esc: 0,
            symbols: Vec::new(),
        };
        let mut w = BitWriter::default();
        w.put_golomb(0, 0);
        w.put(6 << 2, 8);
        w.put(0, 32);
        let b = w.finish();
        assert!(d.decoder(7).get(&mut BitReader::new(&b)).is_err());
        assert!(d.decoder(8).get(&mut BitReader::new(&b)).is_ok());
    }
}
