//! The frame every cbvh codec file shares: a fixed-size header that starts
//! with the codec's magic and ends with a section table and the header's
//! checksum, then the sections. Every codec declares where its table lies
//! and what its sections are called in a [`Frame`], writes its files with
//! [`Frame::write`] and reads them with [`version`],
//! [`Frame::check_header`], then [`Frame::sections`] (the table: sections
//! back to back, lengths, checksums). What the header holds
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

/// Where a codec file's frame lies: the section table's offset and the
/// sections' names, in table order. Each codec declares its own
/// ([`Codec::FRAME`](crate::codec::Codec::FRAME)) and reads and writes its
/// files through it; tools that inspect files (or, like the mutation
/// tests, forge them) read the table through it without knowing the codec.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Frame {
    /// The byte at which the section table starts (the header's fields
    /// end there).
    pub table: usize,
    /// The sections' names (used in errors), one table entry each.
    pub sections: &'static [&'static str],
}

impl Frame {
    /// The header's length: its fields, the section table and the
    /// header's checksum.
    pub const fn header_len(&self) -> usize {
        self.table + ENTRY * self.sections.len() + 8
    }

    /// Completes a file whose header, up to the section table, is in `out`:
    /// appends the section table (the sections stored back to back right
    /// after the header), the header's checksum, then the sections.
    ///
    /// # Panics
    /// If `out` does not end where the table starts, or `sections` is not
    /// one slice a name (a codec's own bug, not its input's).
    pub fn write(&self, out: &mut Vec<u8>, sections: &[&[u8]]) {
        let entries: Vec<(u64, u64)> = sections
            .iter()
            .map(|s| (s.len() as u64, xxh3_64(s)))
            .collect();
        self.write_table(out, &entries);
        for s in sections {
            out.extend_from_slice(s);
        }
    }

    /// Completes the header whose fields are in `out` with the table of
    /// sections of the given `(length, checksum)` (xxh3-64), stored back
    /// to back after the header, and the header's checksum; the caller
    /// writes the sections after it (a writer that streams a section too
    /// large to hold, hashing it as it goes).
    ///
    /// # Panics
    /// As [`write`](Self::write).
    pub fn write_table(&self, out: &mut Vec<u8>, sections: &[(u64, u64)]) {
        assert_eq!(out.len(), self.table, "the header fields end at the table");
        assert_eq!(sections.len(), self.sections.len(), "one section a name");
        let mut at = self.header_len() as u64;
        for &(len, hash) in sections {
            out.extend_from_slice(&at.to_le_bytes());
            out.extend_from_slice(&len.to_le_bytes());
            out.extend_from_slice(&hash.to_le_bytes());
            at += len;
        }
        let h = xxh3_64(out);
        out.extend_from_slice(&h.to_le_bytes());
    }

    /// Checks that `b` holds a whole header that starts with `magic` (of
    /// the format called `format` in errors) and whose checksum matches.
    pub fn check_header(
        &self,
        b: &[u8],
        magic: &[u8; 8],
        format: &'static str,
    ) -> Result<(), FormatError> {
        let header_len = self.header_len();
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

    /// Checks the section table of `b`, whose header
    /// [`check_header`](Self::check_header) has passed, and returns each
    /// section's byte range, in table order. Every section must:
    ///
    /// - start where the one before it ends (the first right after the
    ///   header), the last one ending the file: no gap, no overlap, nothing
    ///   after;
    /// - have a length `len_ok(k, len)` accepts (the codec's counts give
    ///   most lengths; `Err(why)` is reported as a header error of that
    ///   section);
    /// - match its checksum, unless `lazy(k)`: a section checked piece by
    ///   piece as it is read (RACBVH's clusters, o-HCCMesh's trees out of
    ///   core), or by `verify`.
    ///
    /// Never panics and allocates only the ranges, whatever the table says.
    pub fn sections(
        &self,
        b: &[u8],
        len_ok: impl Fn(usize, u64) -> Result<(), String>,
        lazy: impl Fn(usize) -> bool,
    ) -> Result<Vec<std::ops::Range<usize>>, FormatError> {
        Ok(self.sections_with_checksums(b, len_ok, lazy)?.0)
    }

    /// [`sections`](Self::sections) with each section's stored checksum, in
    /// table order, read in the same pass: for a reader that checks its
    /// lazy sections later, piece by piece or in `verify`.
    #[allow(clippy::type_complexity)]
    pub fn sections_with_checksums(
        &self,
        b: &[u8],
        len_ok: impl Fn(usize, u64) -> Result<(), String>,
        lazy: impl Fn(usize) -> bool,
    ) -> Result<(Vec<std::ops::Range<usize>>, Vec<u64>), FormatError> {
        let mut at = self.header_len() as u64;
        let mut ranges = Vec::with_capacity(self.sections.len());
        let mut checksums = Vec::with_capacity(self.sections.len());
        for (k, &name) in self.sections.iter().enumerate() {
            let (off, len, hash) = self.entry(b, k);
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
            checksums.push(hash);
            at = end;
        }
        if at != b.len() as u64 {
            return Err(FormatError::header(
                "length",
                format!("{} bytes follow the last section", b.len() as u64 - at),
            ));
        }
        Ok((ranges, checksums))
    }

    /// Entry `k` of the section table of a checked header: the section's
    /// offset, length and checksum.
    pub fn entry(&self, b: &[u8], k: usize) -> (u64, u64, u64) {
        let at = self.table + ENTRY * k;
        (u64_at(b, at), u64_at(b, at + 8), u64_at(b, at + 16))
    }

    /// Recomputes the checksum of every section the table places inside
    /// `b`, then the header's: for a tool that edits a file's bytes on
    /// purpose (the mutation tests forge files this way, to reach the
    /// checks behind the checksums). Checksums inside a section (RACBVH's
    /// per-cluster ones) are the codec's own and are left as they are.
    /// Entries that point outside `b`, and a `b` shorter than the header,
    /// are left alone: never panics.
    pub fn reseal(&self, b: &mut [u8]) {
        let header_len = self.header_len();
        if b.len() < header_len {
            return;
        }
        for k in 0..self.sections.len() {
            let (off, len, _) = self.entry(b, k);
            let range = usize::try_from(off).ok().and_then(|off| {
                let end = off.checked_add(usize::try_from(len).ok()?)?;
                (end <= b.len()).then_some(off..end)
            });
            if let Some(r) = range {
                let h = xxh3_64(&b[r]);
                let at = self.table + ENTRY * k + 16;
                b[at..at + 8].copy_from_slice(&h.to_le_bytes());
            }
        }
        let h = xxh3_64(&b[..header_len - 8]);
        b[header_len - 8..header_len].copy_from_slice(&h.to_le_bytes());
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

#[cfg(test)]
mod tests {
    use super::*;

    const FRAME: Frame = Frame {
        table: 16,
        sections: &["a", "b"],
    };

    fn file() -> Vec<u8> {
        let mut out = b"CBVHTST\0".to_vec();
        out.extend_from_slice(&[1, 0, 0, 0, 0, 0, 0, 0]);
        FRAME.write(&mut out, &[b"hello", b"world!"]);
        out
    }

    #[test]
    fn a_written_frame_reads_back() {
        let b = file();
        assert_eq!(b.len(), FRAME.header_len() + 11);
        FRAME.check_header(&b, b"CBVHTST\0", "test").unwrap();
        let r = FRAME.sections(&b, |_, _| Ok(()), |_| false).unwrap();
        assert_eq!(&b[r[0].clone()], b"hello");
        assert_eq!(&b[r[1].clone()], b"world!");
        let (r2, sums) = FRAME
            .sections_with_checksums(&b, |_, _| Ok(()), |_| false)
            .unwrap();
        assert_eq!(r2, r);
        assert_eq!(sums, [xxh3_64(b"hello"), xxh3_64(b"world!")]);
    }

    #[test]
    fn an_edited_file_fails_its_checksums_until_resealed() {
        let mut b = file();
        let end = b.len();
        b[end - 1] = b'?';
        assert!(matches!(
            FRAME.sections(&b, |_, _| Ok(()), |_| false),
            Err(FormatError::Checksum { section: "b" })
        ));
        // A table entry edited: the header's checksum fails.
        b[FRAME.table + 8] ^= 1;
        assert!(FRAME.check_header(&b, b"CBVHTST\0", "test").is_err());
        b[FRAME.table + 8] ^= 1;
        FRAME.reseal(&mut b);
        FRAME.check_header(&b, b"CBVHTST\0", "test").unwrap();
        let r = FRAME.sections(&b, |_, _| Ok(()), |_| false).unwrap();
        assert_eq!(&b[r[1].clone()], b"world?");
        // Resealing garbage never panics.
        for cut in 0..b.len() {
            let mut short = b[..cut].to_vec();
            FRAME.reseal(&mut short);
        }
    }
}
