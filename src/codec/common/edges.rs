//! The edge-flags section every codec file ends with: the active-edge
//! flags of [`EdgeFlags`] (one byte a triangle in memory, bits 0–5),
//! computed once when a codec encodes ([`of_cursor`]) and stored, so that
//! opening a file reads them rather than recomputing them (two parallel
//! sorts of three entries a triangle: about a second per million
//! triangles, five to ten times a plain file's whole open).
//!
//! # The coding
//!
//! Flags are stored in the codec's id order (the ids its traversal
//! reports), each coded through a static dictionary
//! ([`static_dict`](super::static_dict), HCCMesh §5.2) chosen by the
//! *previous* triangle's flags: one dictionary per context, 64 contexts at
//! most. Neighbouring ids are mostly neighbouring triangles (a mesh's own
//! order, a tree's order), whose flags are alike: the two triangles of a
//! quad, a run along a flat region or a crease. Measured in bits a
//! triangle (order-0 entropy `H0`, order-1 entropy `H1`, this coding; 6
//! for the bits packed):
//!
//! | mesh | zero flags | H0 | H1 | stored |
//! |---|---|---|---|---|
//! | statue 200 k (generated) | 52 % | 2.29 | 1.40 | 1.83 (1.77 in hcc-ooc's tree order) |
//! | turbine 200 k (generated) | 90 % | 0.63 | 0.58 | 1.23 |
//! | bunny 75 k (scan) | 36 % | 3.39 | 3.16 | 3.49 (3.18 in tree order) |
//! | turbine 18 k (CAD) | 42 % | 2.45 | 0.85 | 1.52 (1.69 in tree order) |
//! | statue 2 M (generated) | | | | 1.12 |
//!
//! Against the order-0 dictionary (one context) this takes 0.2 to 1.2
//! bits a triangle off but on the generated turbine (the same), whose
//! flags are mostly zero: a dictionary code takes at least a bit a
//! symbol. On the 200 k statue the section adds 0.23 bytes a triangle to
//! every file: 6 % of hcc-ooc's, 1–2 % of racbvh's and hcc's. Decoding is
//! one table look-up a triangle (the dictionary decoder's): 20 ms for the
//! 2 M statue (100 M flags/s), where computing the flags took 2 s.
//!
//! # Layout
//!
//! All integers little-endian.
//!
//! | bytes | field |
//! |---|---|
//! | 0–7 | triangle count (u64; the file's) |
//! | 8–39 | edge counts: boundary, non-manifold, misoriented, flat (u64 each, at most 3 a triangle) |
//! | 40–47 | signed volume (f64, finite) |
//! | 48– | the coded flags, one bit stream, least-significant bit first |
//!
//! The bit stream: a 64-bit mask of the contexts that have a dictionary
//! (bit `c`: some triangle follows one whose flags are `c`; the first
//! triangle follows flags 0), those contexts' dictionaries in increasing
//! order as [`StaticDict::write`] writes them (6-bit symbols), then each
//! triangle's flags through its context's dictionary, the last byte
//! zero-padded. No triangles: the mask is 0 and nothing follows.
//!
//! # Validation
//!
//! [`decode`] (run when a file is opened) checks the count against the
//! file's triangle count, bounds it by the section's bits before
//! allocating (every flag takes at least one bit), reads every code with
//! checked reads, and rejects a context without a dictionary, a value with
//! bits 6–7 set, a stream that runs past its section, nonzero padding and
//! bytes after the stream: hostile bytes give a [`FormatError`], never a
//! panic. The section's checksum is the codec's section table's.

use std::ops::ControlFlow;

use glam::Vec3A;

use super::FormatError;
use super::bits::{BitReader, BitWriter};
use super::static_dict::{StaticDecoder, StaticDict};
use crate::contact::EdgeFlags;
use crate::contact::edges::{ALL_ACTIVE, OpenEdge};
use crate::cursor::{NodeCursor, TraversalStats};
use crate::geom::Aabb;

/// The section's name in errors and section tables.
pub const SECTION: &str = "edge flags";

/// Contexts: every value of a triangle's flags (6 bits).
const CONTEXTS: usize = 64;

/// Bits of a stored flag value.
const VALUE_BITS: u32 = 6;

/// Bytes before the coded flags.
const FIXED: usize = 48;

/// The flags of `c`'s triangles as `c` reports them (its ids, its vertex
/// precision), in one traversal of its tree: what every codec stores
/// when it encodes.
pub fn of_cursor<C: NodeCursor>(c: &C) -> EdgeFlags {
    EdgeFlags::from_visit(c.triangle_count(), |f| visit_all(c, f))
}

/// [`of_cursor`] for one part of a larger mesh, with the part's open
/// edges ([`EdgeFlags::from_visit_open`]), which the out-of-core builder
/// pairs across parts.
pub fn of_cursor_open<C: NodeCursor>(c: &C) -> (EdgeFlags, Vec<OpenEdge>) {
    EdgeFlags::from_visit_open(c.triangle_count(), |f| visit_all(c, f))
}

/// The edge flags of a mesh built part by part (the out-of-core
/// builders' chunks): each part's flags, computed alone
/// ([`of_cursor_open`], [`EdgeFlags::from_visit_open`]), appended in order,
/// its open edges moved to the whole mesh's numbering and its edge counts
/// summed; [`ChunkedFlags::joined`] then pairs the open edges across parts.
pub struct ChunkedFlags {
    /// Every part's flags so far, one byte a triangle.
    flags: Vec<u8>,
    /// The parts' edge counts and signed volumes, summed.
    sum: EdgeFlags,
    /// The parts' open edges, in the whole mesh's numbering.
    open: Vec<OpenEdge>,
}

impl ChunkedFlags {
    /// No parts yet, with room for `triangles` flags.
    pub fn with_capacity(triangles: usize) -> Self {
        Self {
            flags: Vec::with_capacity(triangles),
            sum: EdgeFlags::default(),
            open: Vec::new(),
        }
    }

    /// Appends the next part's flags `f` and its open edges `open` (in the
    /// part's numbering); returns the part's first triangle in the whole
    /// mesh.
    pub fn push(&mut self, f: &EdgeFlags, open: Vec<OpenEdge>) -> u64 {
        let base = self.flags.len() as u64;
        self.open.extend(open.into_iter().map(|mut e| {
            e.corner += 3 * base;
            e
        }));
        self.flags.extend_from_slice(f.as_slice());
        let sum = &mut self.sum;
        sum.boundary_edges += f.boundary_edges;
        sum.non_manifold_edges += f.non_manifold_edges;
        sum.misoriented_edges += f.misoriented_edges;
        sum.flat_edges += f.flat_edges;
        sum.signed_volume += f.signed_volume;
        base
    }

    /// The whole mesh's flags, with the open edges paired across parts
    /// ([`EdgeFlags::joined`]), and how many edges were paired; `None` for
    /// a flag out of range.
    pub fn joined(self) -> Option<(EdgeFlags, u64)> {
        let Self {
            flags,
            sum,
            mut open,
        } = self;
        EdgeFlags::joined(flags, &sum, &mut open)
    }
}

/// Calls `f` with every triangle of `c` and its id.
fn visit_all<C: NodeCursor>(c: &C, f: &mut dyn FnMut(u32, &crate::geom::Triangle)) {
    let everything = Aabb::new(Vec3A::splat(f32::MIN), Vec3A::splat(f32::MAX));
    let mut stats = TraversalStats::default();
    crate::query::overlap(c, &everything, &mut stats, |id, t| {
        f(id, t);
        ControlFlow::Continue(())
    });
}

/// The section's bytes (see the module docs).
pub fn encode(e: &EdgeFlags) -> Vec<u8> {
    let flags = e.as_slice();
    let mut out = Vec::with_capacity(FIXED + 16 + flags.len() / 4);
    out.extend_from_slice(&(flags.len() as u64).to_le_bytes());
    for v in [
        e.boundary_edges,
        e.non_manifold_edges,
        e.misoriented_edges,
        e.flat_edges,
    ] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&e.signed_volume.to_bits().to_le_bytes());
    // Symbol counts by context.
    let mut counts = vec![[0u64; CONTEXTS]; CONTEXTS];
    let mut prev = 0usize;
    for &f in flags {
        debug_assert!(f & !ALL_ACTIVE == 0);
        counts[prev][usize::from(f)] += 1;
        prev = usize::from(f);
    }
    let mut mask = 0u64;
    let mut w = BitWriter::default();
    let mut encoders: Vec<_> = (0..CONTEXTS).map(|_| None).collect();
    let dicts: Vec<(usize, StaticDict)> = counts
        .iter()
        .enumerate()
        .filter(|(_, c)| c.iter().any(|&n| n > 0))
        .map(|(ctx, c)| {
            let c: Vec<(u32, u64)> = (0..CONTEXTS as u32)
                .zip(c.iter().copied())
                .filter(|&(_, n)| n > 0)
                .collect();
            (ctx, StaticDict::optimal(&c))
        })
        .collect();
    for (ctx, _) in &dicts {
        mask |= 1 << ctx;
    }
    w.put(mask & 0xffff_ffff, 32);
    w.put(mask >> 32, 32);
    for (ctx, d) in &dicts {
        d.write(&mut w);
        encoders[*ctx] = Some(d.encoder());
    }
    let mut prev = 0usize;
    for &f in flags {
        if let Some(enc) = encoders[prev].as_mut() {
            enc.put(&mut w, u32::from(f));
        }
        prev = usize::from(f);
    }
    out.extend_from_slice(&w.finish());
    out
}

fn corrupt(what: &'static str) -> FormatError {
    FormatError::Corrupt { what }
}

/// Reads the section `b` of a file of `triangles` triangles (see the
/// module docs for what is checked).
pub fn decode(b: &[u8], triangles: u64) -> Result<EdgeFlags, FormatError> {
    if b.len() < FIXED + 8 {
        return Err(FormatError::Truncated {
            section: SECTION,
            need: (FIXED + 8) as u64,
            have: b.len() as u64,
        });
    }
    let u64_at = |at: usize| super::le::u64_at(b, at);
    let count = u64_at(0);
    if count != triangles {
        return Err(FormatError::header(
            SECTION,
            format!("flags for {count} triangles in a file of {triangles}"),
        ));
    }
    let stream = &b[FIXED..];
    // Every flag takes at least one bit: a count the stream cannot hold
    // is refused before anything is allocated for it.
    if count > (stream.len() as u64 - 8) * 8 {
        return Err(FormatError::Truncated {
            section: SECTION,
            need: FIXED as u64 + 8 + count.div_ceil(8),
            have: b.len() as u64,
        });
    }
    let edges = [u64_at(8), u64_at(16), u64_at(24), u64_at(32)];
    let limit = 3 * count;
    if let Some(&e) = edges.iter().find(|&&e| e > limit) {
        return Err(FormatError::OutOfRange {
            section: SECTION,
            what: "an edge count",
            value: e,
            limit,
        });
    }
    let signed_volume = f64::from_bits(u64_at(40));
    if !signed_volume.is_finite() {
        return Err(corrupt("the stored signed volume is not finite"));
    }
    let mut r = BitReader::new(stream);
    let mask = r.get(32) | r.get(32) << 32;
    let mut decoders: Vec<Option<StaticDecoder>> = vec![None; CONTEXTS];
    for (ctx, slot) in decoders.iter_mut().enumerate() {
        if mask >> ctx & 1 != 0 {
            let d = StaticDict::read(&mut r, CONTEXTS, VALUE_BITS)?;
            if r.overran() {
                return Err(corrupt(
                    "the edge flags' dictionaries run past their section",
                ));
            }
            *slot = Some(d.decoder(VALUE_BITS));
        }
    }
    let mut flags = vec![0u8; count as usize];
    let mut prev = 0usize;
    for f in flags.iter_mut() {
        let d = decoders[prev]
            .as_ref()
            .ok_or_else(|| corrupt("a triangle's flags follow flags that have no dictionary"))?;
        let v = d.get(&mut r)?;
        if v > u32::from(ALL_ACTIVE) {
            return Err(FormatError::OutOfRange {
                section: SECTION,
                what: "a triangle's flags",
                value: u64::from(v),
                limit: u64::from(ALL_ACTIVE),
            });
        }
        *f = v as u8;
        prev = v as usize;
    }
    if r.overran() {
        return Err(FormatError::Truncated {
            section: SECTION,
            need: b.len() as u64 + 1,
            have: b.len() as u64,
        });
    }
    // The rest of the last byte is zero padding, and nothing follows.
    let read = r.bits_read();
    let pad = (read.next_multiple_of(8) - read) as u32;
    if r.get(pad) != 0 || read.div_ceil(8) != stream.len() as u64 {
        return Err(corrupt("bits follow the edge flags"));
    }
    let mut e = EdgeFlags::from_flags(flags).ok_or_else(|| corrupt("a flag has bits 6-7 set"))?;
    [
        e.boundary_edges,
        e.non_manifold_edges,
        e.misoriented_edges,
        e.flat_edges,
    ] = edges;
    e.signed_volume = signed_volume;
    Ok(e)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flags(v: &[u8]) -> EdgeFlags {
        let mut e = EdgeFlags::from_flags(v.to_vec()).unwrap();
        e.boundary_edges = 3 * v.len() as u64;
        e.flat_edges = v.len() as u64 / 2;
        e.signed_volume = -0.25;
        e
    }

    /// Runs of alike flags, a crease, a few odd ones, every value once.
    fn sample(n: usize) -> Vec<u8> {
        let mut x = 7u64;
        (0..n)
            .map(|i| {
                x = x.wrapping_mul(6364136223846793005).wrapping_add(1);
                match i % 97 {
                    0..=40 => 0,
                    41..=60 => 0b000_010,
                    61..=63 => (x >> 58) as u8,
                    _ => [0b000_001, 0b010_000, 0b100_100][(x >> 40) as usize % 3],
                }
            })
            .chain(0..64)
            .collect()
    }

    #[test]
    fn flags_read_back_as_written() {
        for v in [vec![], vec![0], vec![0b111_111], sample(5000)] {
            let e = flags(&v);
            let b = encode(&e);
            assert_eq!(decode(&b, v.len() as u64).unwrap(), e, "{} flags", v.len());
        }
    }

    #[test]
    fn mostly_alike_flags_take_about_two_bits_or_less() {
        let v = sample(100_000);
        let b = encode(&flags(&v));
        assert!(b.len() * 8 < v.len() * 2, "{} bytes", b.len());
    }

    #[test]
    fn a_count_other_than_the_files_is_an_error() {
        let v = sample(300);
        let n = v.len() as u64;
        let b = encode(&flags(&v));
        let e = decode(&b, n - 1).unwrap_err();
        assert!(
            e.to_string()
                .contains(&format!("flags for {n} triangles in a file of {}", n - 1)),
            "{e}"
        );
        // A forged count that matches a forged file: more flags than the
        // stream holds bits, refused before allocating.
        let mut f = b.clone();
        f[..8].copy_from_slice(&u64::MAX.to_le_bytes());
        assert!(matches!(
            decode(&f, u64::MAX),
            Err(FormatError::Truncated { .. })
        ));
        // One more than written: the stream runs out.
        f[..8].copy_from_slice(&(n + 1).to_le_bytes());
        assert!(decode(&f, n + 1).is_err());
    }

    #[test]
    fn a_value_with_bits_6_or_7_is_an_error() {
        // A dictionary of 8-bit symbols (0xC0) for context 0.
        let mut w = BitWriter::default();
        w.put(1, 32);
        w.put(0, 32);
        StaticDict {
            k: 0,
            raw_bits: 8,
            split: 32,
            esc: 1,
            symbols: vec![0xC0],
        }
        .write(&mut w);
        w.put(1, 1);
        let mut b = encode(&flags(&[0]))[..FIXED].to_vec();
        b.extend_from_slice(&w.finish());
        let e = decode(&b, 1).unwrap_err();
        assert!(e.to_string().contains("raw symbol width"), "{e}");
        assert!(EdgeFlags::from_flags(vec![0, 0x40]).is_none());
    }

    #[test]
    fn damaged_sections_are_errors_never_panics() {
        let v = sample(2000);
        let b = encode(&flags(&v));
        for cut in 0..b.len() {
            assert!(decode(&b[..cut], v.len() as u64).is_err(), "cut at {cut}");
        }
        let mut longer = b.clone();
        longer.push(0);
        assert!(decode(&longer, v.len() as u64).is_err());
        let mut x = 3u64;
        let mut changed = 0;
        for _ in 0..3000 {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1);
            let mut f = b.clone();
            let at = (x >> 33) as usize % f.len();
            f[at] ^= 1 << ((x >> 20) % 8);
            if let Ok(e) = decode(&f, v.len() as u64) {
                assert_eq!(e.len(), v.len());
                assert!(e.as_slice().iter().all(|&f| f & !ALL_ACTIVE == 0));
                changed += usize::from(e != flags(&v));
            }
        }
        // The section has no checksum of its own (the file's table has).
        assert!(changed > 0);
    }

    #[test]
    fn counters_out_of_range_are_errors() {
        let b = encode(&flags(&[1, 2, 3]));
        let mut f = b.clone();
        f[8..16].copy_from_slice(&10u64.to_le_bytes());
        assert!(decode(&b, 3).is_ok());
        assert!(matches!(decode(&f, 3), Err(FormatError::OutOfRange { .. })));
        let mut f = b;
        f[40..48].copy_from_slice(&f64::NAN.to_bits().to_le_bytes());
        assert!(decode(&f, 3).is_err());
    }
}
