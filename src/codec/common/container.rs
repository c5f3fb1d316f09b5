//! The frame every cbvh codec file shares: a fixed-size header that starts
//! with the codec's magic and ends with a section table and the header's
//! checksum, then the sections. Every codec reads its frame with the
//! functions here: [`version`], [`check_header`], then [`sections`] (the
//! table: sections back to back, lengths, checksums). What the header holds
//! between the magic and the table, which sections there are and how they
//! are checked against each other is the codec's own (see its `file.rs`).
//!
//! # Layout
//! All integers little-endian; checksums are xxh3-64.
//!
//! | bytes | field |
//! |---|---|
//! | 0–7 | the codec's magic (starting with [`MAGIC_PREFIX`](super::MAGIC_PREFIX)) |
//! | 8 – table start | the codec's header fields |
//! | 24 per section | the section table: offset u64, length u64, checksum u64 |
//! | the header's last 8 | checksum of every header byte before it |
//!
//! The sections follow the header back to back, in table order. Every
//! codec's version field is bytes 8–11; it is read before the header is
//! checked ([`version`]), because another version's header may be of
//! another length (the edge-flags section, [`edges`](super::edges), added
//! a table entry to every codec's header, and a version to each): a file
//! of another version is reported as such, not as damaged.

use xxhash_rust::xxh3::xxh3_64;

use super::FormatError;
use super::le::u64_at;

/// Bytes of one section-table entry.
const ENTRY: usize = 24;

/// Completes a file whose header, up to the section table, is in `out`:
/// appends the section table (the sections stored back to back from
/// `header_len` on), the header's checksum, then the sections.
pub fn write_sections(out: &mut Vec<u8>, header_len: usize, sections: &[&[u8]]) {
    let mut at = header_len as u64;
    for s in sections {
        out.extend_from_slice(&at.to_le_bytes());
        out.extend_from_slice(&(s.len() as u64).to_le_bytes());
        out.extend_from_slice(&xxh3_64(s).to_le_bytes());
        at += s.len() as u64;
    }
    let h = xxh3_64(out);
    out.extend_from_slice(&h.to_le_bytes());
    debug_assert_eq!(out.len(), header_len);
    for s in sections {
        out.extend_from_slice(s);
    }
}

/// The version field (bytes 8–11) of `b` if it starts with `magic`, read
/// before anything else is checked (see the module docs).
pub fn version(b: &[u8], magic: &[u8; 8]) -> Option<u32> {
    if b.len() < 12 || b[..8] != *magic {
        return None;
    }
    Some(super::le::u32_at(b, 8))
}

/// Checks that `b` holds a whole header of `header_len` bytes that starts
/// with `magic` (of the format called `format` in errors) and whose
/// checksum matches.
pub fn check_header(
    b: &[u8],
    header_len: usize,
    magic: &[u8; 8],
    format: &'static str,
) -> Result<(), FormatError> {
    if b.len() < header_len {
        return Err(FormatError::Truncated {
            section: "header",
            need: header_len as u64,
            have: b.len() as u64,
        });
    }
    if b[..8] != *magic {
        return Err(FormatError::BadMagic { format });
    }
    if xxh3_64(&b[..header_len - 8]) != u64_at(b, header_len - 8) {
        return Err(FormatError::Checksum { section: "header" });
    }
    Ok(())
}

/// Checks the section table of `b`, whose header [`check_header`] has
/// passed, and returns each section's byte range, in table order. The
/// table starts at byte `table` and has one entry per name in `names`
/// (used in errors). Every section must:
///
/// - start where the one before it ends (the first right after the
///   header), the last one ending the file: no gap, no overlap, nothing
///   after;
/// - have a length `len_ok(k, len)` accepts (the codec's counts give most
///   lengths; `Err(why)` is reported as a header error of that section);
/// - match its checksum, unless `lazy(k)`: a section checked piece by
///   piece as it is read (RACBVH's clusters, o-HCCMesh's trees out of
///   core), or by `verify`.
///
/// Never panics and allocates only the ranges, whatever the table says.
pub fn sections(
    b: &[u8],
    table: usize,
    names: &[&'static str],
    len_ok: impl Fn(usize, u64) -> Result<(), String>,
    lazy: impl Fn(usize) -> bool,
) -> Result<Vec<std::ops::Range<usize>>, FormatError> {
    let header_len = table + ENTRY * names.len() + 8;
    let mut at = header_len as u64;
    let mut ranges = Vec::with_capacity(names.len());
    for (k, &name) in names.iter().enumerate() {
        let (off, len, hash) = section_entry(b, table, k);
        if off != at {
            return Err(FormatError::header(
                name,
                format!("the section starts at {off}, not right after the previous one ({at})"),
            ));
        }
        len_ok(k, len).map_err(|why| FormatError::header(name, why))?;
        let end = off.checked_add(len).filter(|&e| e <= b.len() as u64);
        let Some(end) = end else {
            return Err(FormatError::Truncated {
                section: name,
                need: off.saturating_add(len),
                have: b.len() as u64,
            });
        };
        let r = off as usize..end as usize;
        if !lazy(k) && xxh3_64(&b[r.clone()]) != hash {
            return Err(FormatError::Checksum { section: name });
        }
        ranges.push(r);
        at = end;
    }
    if at != b.len() as u64 {
        return Err(FormatError::header(
            "length",
            format!("{} bytes follow the last section", b.len() as u64 - at),
        ));
    }
    Ok(ranges)
}

/// Entry `k` of the section table that starts at byte `table` of a checked
/// header: the section's offset, length and checksum.
pub fn section_entry(b: &[u8], table: usize, k: usize) -> (u64, u64, u64) {
    let at = table + ENTRY * k;
    (u64_at(b, at), u64_at(b, at + 8), u64_at(b, at + 16))
}
