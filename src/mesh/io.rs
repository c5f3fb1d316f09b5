//! Mesh file input and output: format detection by extension, the loaders
//! (OFF, PLY, OBJ, STL) and the writers (binary PLY, OBJ; [`PlyWriter`]
//! writes binary PLY batch by batch, for meshes not held in memory).
//!
//! Every reader is hand-written and streams from a [`BufRead`], so the same
//! code serves files ([`load`]) and memory ([`load_bytes`]). Readers check
//! what they read as they go (finite coordinates, face indices in range) so
//! that errors name the exact line (text) or byte offset (binary). They never
//! panic and never trust a count from a header for an allocation: capacities
//! are capped by what the remaining bytes could possibly hold. A count must
//! match the body both ways: a body short of it is truncated, and data
//! after the records it counts is refused (OFF, PLY, binary STL), never
//! dropped.

mod obj;
mod off;
mod ply;
mod stl;

pub use ply::PlyWriter;

use std::fmt;
use std::fs::File;
use std::io::{self, BufRead, BufReader, Read};
use std::path::{Path, PathBuf};

use super::{Mesh, MeshError, Place};

/// A mesh file format, chosen by file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Format {
    /// Object File Format (`.off`), ASCII.
    Off,
    /// Stanford polygon file (`.ply`): ASCII or binary of either endianness.
    Ply,
    /// Wavefront OBJ (`.obj`): positions and faces only.
    Obj,
    /// Stereolithography (`.stl`): ASCII or binary.
    Stl,
}

impl Format {
    /// The format named by `path`'s extension (case-insensitive).
    ///
    /// # Errors
    /// [`MeshError::UnknownExtension`] when the extension is missing or
    /// names no supported format.
    pub fn from_path(path: &Path) -> Result<Format, MeshError> {
        let ext = extension(path);
        Format::from_extension(&ext).ok_or_else(|| MeshError::UnknownExtension {
            path: path.to_path_buf(),
            ext,
        })
    }

    /// The format with extension `ext` (without the dot, case-insensitive).
    pub fn from_extension(ext: &str) -> Option<Format> {
        match ext.to_ascii_lowercase().as_str() {
            "off" => Some(Format::Off),
            "ply" => Some(Format::Ply),
            "obj" => Some(Format::Obj),
            "stl" => Some(Format::Stl),
            _ => None,
        }
    }

    /// The short lowercase name: `"off"`, `"ply"`, `"obj"` or `"stl"`.
    pub fn name(self) -> &'static str {
        match self {
            Format::Off => "off",
            Format::Ply => "ply",
            Format::Obj => "obj",
            Format::Stl => "stl",
        }
    }
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// How the data of a loaded file was encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Encoding {
    /// Text.
    Ascii,
    /// Binary, little-endian (binary STL is always little-endian).
    BinaryLittleEndian,
    /// Binary, big-endian.
    BinaryBigEndian,
}

/// The format of a loaded file together with its encoding, e.g.
/// "ply (binary little-endian)".
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct FormatDetail {
    /// The file format.
    pub format: Format,
    /// The encoding of the data.
    pub encoding: Encoding,
}

impl fmt::Display for FormatDetail {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let enc = match (self.format, self.encoding) {
            (_, Encoding::Ascii) => "ascii",
            (Format::Stl, Encoding::BinaryLittleEndian) => "binary",
            (_, Encoding::BinaryLittleEndian) => "binary little-endian",
            (_, Encoding::BinaryBigEndian) => "binary big-endian",
        };
        write!(f, "{} ({enc})", self.format.name())
    }
}

/// Loads the mesh file at `path`, choosing the format by extension.
///
/// Polygons are fan-triangulated, STL vertices are welded, degenerate
/// triangles are kept. The result passes [`Mesh::validate`], except
/// that coordinates are read as written: `validate` refuses those beyond
/// [`MAX_COORDINATE`](super::MAX_COORDINATE).
///
/// # Errors
/// Any [`MeshError`]: unknown extension, I/O failure, malformed or truncated
/// data, out-of-range indices, non-finite coordinates, no faces.
pub fn load(path: impl AsRef<Path>) -> Result<Mesh, MeshError> {
    load_with_detail(path).map(|(mesh, _)| mesh)
}

/// Like [`load`], and also reports the format and encoding found.
///
/// # Errors
/// As [`load`].
pub fn load_with_detail(path: impl AsRef<Path>) -> Result<(Mesh, FormatDetail), MeshError> {
    collect(|tris| read_file(path.as_ref(), tris))
}

/// Loads a mesh of the given `format` from memory; `name` names it in
/// error messages.
///
/// # Errors
/// As [`load`] (except I/O errors, which cannot happen).
pub fn load_bytes(bytes: &[u8], format: Format, name: &Path) -> Result<Mesh, MeshError> {
    load_bytes_with_detail(bytes, format, name).map(|(mesh, _)| mesh)
}

/// Like [`load_bytes`], and also reports the format and encoding found.
///
/// # Errors
/// As [`load_bytes`].
pub fn load_bytes_with_detail(
    bytes: &[u8],
    format: Format,
    name: &Path,
) -> Result<(Mesh, FormatDetail), MeshError> {
    collect(|tris| read_into(bytes, bytes.len() as u64, format, name, tris))
}

/// The mesh that `read` reads, its triangles collected ([`Tris::collect`]).
fn collect(read: impl FnOnce(&mut Tris<'_>) -> Parsed) -> Result<(Mesh, FormatDetail), MeshError> {
    let mut tris = Tris::collect();
    let (vertices, detail) = read(&mut tris)?;
    Ok((Mesh::new(vertices, tris.finish()?), detail))
}

/// Opens the mesh file at `path`: its format (by extension), the file
/// and its length.
fn open(path: &Path) -> Result<(Format, File, u64), MeshError> {
    let format = Format::from_path(path)?;
    let file = File::open(path).map_err(|e| io_error(path, e))?;
    let len = file.metadata().map_err(|e| io_error(path, e))?.len();
    Ok((format, file, len))
}

/// An I/O error on `path`.
fn io_error(path: &Path, source: io::Error) -> MeshError {
    crate::files::IoError::new(path, source).into()
}

/// Reads the mesh file at `path` (the format by its extension): its
/// vertices, its triangles into `tris` ([`load`] and [`stream`]).
fn read_file(path: &Path, tris: &mut Tris<'_>) -> Parsed {
    let (format, file, len) = open(path)?;
    read_into(
        BufReader::with_capacity(1 << 16, file),
        len,
        format,
        path,
        tris,
    )
}

/// What a reader gives: the file's vertices and the format found (its
/// triangles went to a [`Tris`]).
type Parsed = Result<(Vec<[f32; 3]>, FormatDetail), MeshError>;

/// Reads a mesh file's vertices, putting its triangles into `tris`.
fn read_into<R: BufRead>(
    reader: R,
    len: u64,
    format: Format,
    path: &Path,
    tris: &mut Tris<'_>,
) -> Parsed {
    let src = Src { path, len };
    let (vertices, encoding) = match format {
        Format::Off => (off::read(reader, &src, tris)?, Encoding::Ascii),
        Format::Ply => ply::read(reader, &src, tris)?,
        Format::Obj => (obj::read(reader, &src, tris)?, Encoding::Ascii),
        Format::Stl => stl::read(reader, &src, tris)?,
    };
    if tris.count() == 0 {
        return Err(src.no_faces());
    }
    Ok((vertices, FormatDetail { format, encoding }))
}

/// The vertex and triangle counts of the mesh file at `path`, read from
/// its header without reading the rest: exact for PLY and OFF (faces
/// counted as triangles; a polygon gives more), binary STL (vertices
/// estimated as half the triangles, as in a closed mesh); estimated from
/// the file's length for OBJ and ASCII STL. For choosing how to build a
/// model (in memory or out of core) before reading it.
///
/// # Errors
/// An unknown extension, or the file cannot be opened.
pub fn estimate_counts(path: impl AsRef<Path>) -> Result<(u64, u64), MeshError> {
    counts(path.as_ref()).map(|(c, _)| c)
}

/// The triangle count the header of the mesh file at `path` states, read
/// without reading the rest: PLY's and OFF's face count (a polygon gives
/// more triangles, so it is at least the count the file loads as) and
/// binary STL's; `None` for OBJ and ASCII STL, which state none (see
/// [`estimate_counts`] for a guess). For refusing, before any work, a
/// model some later step could not take.
///
/// # Errors
/// An unknown extension, or the file cannot be opened.
pub fn header_triangles(path: impl AsRef<Path>) -> Result<Option<u64>, MeshError> {
    counts(path.as_ref()).map(|((_, t), stated)| stated.then_some(t))
}

/// [`estimate_counts`], and whether the triangles' count is the header's
/// (PLY, OFF, binary STL) rather than a guess from the file's length.
fn counts(path: &Path) -> Result<((u64, u64), bool), MeshError> {
    let (format, mut file, len) = open(path)?;
    let mut head = Vec::new();
    std::io::Read::take(&mut file, 1 << 16)
        .read_to_end(&mut head)
        .map_err(|e| io_error(path, e))?;
    let text = String::from_utf8_lossy(&head);
    let mut words = text
        .lines()
        .map(|l| {
            l.split('#')
                .next()
                .unwrap_or("")
                .split_whitespace()
                .collect::<Vec<_>>()
        })
        .filter(|w| !w.is_empty());
    let num = |w: Option<&&str>| w.and_then(|x| x.parse::<u64>().ok());
    let guess = |bytes_a_triangle: u64| (len / bytes_a_triangle / 2, len / bytes_a_triangle);
    Ok(match format {
        Format::Ply => {
            let (mut nv, mut nf) = (None, None);
            for w in words {
                match w.as_slice() {
                    ["element", "vertex", n, ..] => nv = n.parse().ok(),
                    ["element", "face", n, ..] => nf = n.parse().ok(),
                    ["end_header", ..] => break,
                    _ => {}
                }
            }
            ((nv.unwrap_or(0), nf.unwrap_or(0)), nf.is_some())
        }
        Format::Off => {
            let first = words.next().unwrap_or_default();
            let counts = if first.first().is_some_and(|k| k.ends_with("OFF")) {
                if first.len() >= 3 {
                    first[1..].to_vec()
                } else {
                    words.next().unwrap_or_default()
                }
            } else {
                first
            };
            let faces = num(counts.get(1));
            (
                (num(counts.first()).unwrap_or(0), faces.unwrap_or(0)),
                faces.is_some(),
            )
        }
        Format::Stl => {
            let n = head.get(80..84).map_or(0, |b| {
                u64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            });
            if len == 84 + 50 * n {
                ((n / 2, n), true)
            } else {
                (guess(250), false)
            }
        }
        Format::Obj => (guess(40), false),
    })
}

/// What [`stream`] read: the vertices (all of them, in memory), the
/// number of triangles it handed out, and the format found.
#[derive(Debug)]
pub struct Streamed {
    /// Every vertex of the file.
    pub vertices: Vec<[f32; 3]>,
    /// Triangles handed to the callback.
    pub triangles: u64,
    /// The format and encoding found.
    pub detail: FormatDetail,
}

/// Reads the mesh file at `path` as [`load`] does, but hands its
/// triangles to `batches` as they are read, a batch of up to 65 536 at a
/// time in file order, instead of collecting them: the faces of a model
/// larger than memory never are all in memory (the vertices are, 12
/// bytes each; OBJ faces may name vertices defined after them, so the
/// indices of a batch are checked against the vertex count only when the
/// whole file has been read, before this returns). The out-of-core
/// builder reads its input this way.
///
/// # Errors
/// As [`load`], and the first error `batches` returns (the file is then
/// read to its end without calling it again).
pub fn stream(path: impl AsRef<Path>, batches: TriangleBatches<'_>) -> Result<Streamed, MeshError> {
    let mut tris = Tris::batches(batches);
    let (vertices, detail) = read_file(path.as_ref(), &mut tris)?;
    let triangles = tris.count();
    tris.finish()?;
    Ok(Streamed {
        vertices,
        triangles,
        detail,
    })
}

/// Writes `mesh` to `path`: binary little-endian PLY for `.ply`, OBJ for
/// `.obj` (extension case-insensitive), atomically ([`crate::files`]).
/// The mesh is written as it is, without validation.
///
/// # Errors
/// [`MeshError::UnsupportedWrite`] for any other extension,
/// [`MeshError::Io`] when the file cannot be created or written.
pub fn save(mesh: &Mesh, path: impl AsRef<Path>) -> Result<(), MeshError> {
    let path = path.as_ref();
    let ext = extension(path);
    let format = match Format::from_extension(&ext) {
        Some(f @ (Format::Ply | Format::Obj)) => f,
        _ => {
            return Err(MeshError::UnsupportedWrite {
                path: path.to_path_buf(),
                ext,
            });
        }
    };
    let io_err = |source| io_error(path, source);
    // Atomic: a reader never sees half a mesh, and one that has the old
    // file mapped keeps its pages.
    let mut out = crate::files::AtomicFile::create(path).map_err(io_err)?;
    match format {
        Format::Ply => ply::write(mesh, &mut out),
        _ => obj::write(mesh, &mut out),
    }
    .map_err(io_err)?;
    out.commit().map_err(io_err)
}

/// The extension of `path` as a string (empty when there is none).
fn extension(path: &Path) -> String {
    path.extension()
        .map(|e| e.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// The source being read: its name for errors and its total length, used to
/// cap allocations announced by headers.
pub(super) struct Src<'a> {
    path: &'a Path,
    len: u64,
}

impl Src<'_> {
    fn path(&self) -> PathBuf {
        self.path.to_path_buf()
    }

    pub(super) fn io(&self, source: io::Error) -> MeshError {
        io_error(self.path, source)
    }

    pub(super) fn malformed(&self, place: Place, message: impl Into<String>) -> MeshError {
        MeshError::Malformed {
            path: self.path(),
            place,
            message: message.into(),
        }
    }

    pub(super) fn truncated(&self, place: Place, expected: impl Into<String>) -> MeshError {
        MeshError::Truncated {
            path: self.path(),
            place,
            expected: expected.into(),
        }
    }

    pub(super) fn out_of_range(
        &self,
        place: Place,
        face: usize,
        index: u64,
        vertices: usize,
    ) -> MeshError {
        MeshError::IndexOutOfRange {
            path: self.path(),
            place,
            face,
            index,
            vertices,
        }
    }

    pub(super) fn non_finite(&self, place: Place, vertex: usize) -> MeshError {
        MeshError::NonFinite {
            path: self.path(),
            place,
            vertex,
        }
    }

    pub(super) fn no_faces(&self) -> MeshError {
        MeshError::NoFaces { path: self.path() }
    }

    /// A capacity for `count` items of at least `min_bytes` bytes each when
    /// `consumed` bytes of the source are already read: never more than the
    /// rest of the source could hold, so a corrupt count cannot exhaust memory.
    pub(super) fn capacity(&self, count: u64, consumed: u64, min_bytes: u64) -> usize {
        let possible = self.len.saturating_sub(consumed) / min_bytes.max(1);
        usize::try_from(count.min(possible)).unwrap_or(0)
    }
}

/// Reads text line by line, counting lines (1-based) and bytes.
pub(super) struct Lines<R> {
    reader: R,
    buf: Vec<u8>,
    line: usize,
    offset: u64,
    newline: bool,
}

impl<R: BufRead> Lines<R> {
    pub(super) fn new(reader: R) -> Self {
        Self {
            reader,
            buf: Vec::new(),
            line: 0,
            offset: 0,
            newline: true,
        }
    }

    /// Reads the next line; `Ok(false)` at the end of the input.
    pub(super) fn advance(&mut self) -> io::Result<bool> {
        self.buf.clear();
        let n = loop {
            match self.reader.read_until(b'\n', &mut self.buf) {
                Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                r => break r?,
            }
        };
        if n == 0 {
            return Ok(false);
        }
        self.offset += n as u64;
        self.line += 1;
        self.newline = self.buf.last() == Some(&b'\n');
        if self.newline {
            self.buf.pop();
        }
        if self.buf.last() == Some(&b'\r') {
            self.buf.pop();
        }
        Ok(true)
    }

    /// The current line without its line ending.
    pub(super) fn text(&self) -> &[u8] {
        &self.buf
    }

    /// The 1-based number of the current line.
    pub(super) fn line(&self) -> usize {
        self.line
    }

    /// The place of the current line.
    pub(super) fn place(&self) -> Place {
        Place::Line(self.line)
    }

    /// Bytes consumed so far.
    pub(super) fn offset(&self) -> u64 {
        self.offset
    }

    /// Whether the current line is the unterminated last line of the input
    /// (a file cut off in the middle of a line).
    pub(super) fn cut_off(&self) -> bool {
        !self.newline
    }

    /// Where data ran out after the last line was read: that line when it
    /// was cut off, otherwise the line after it.
    pub(super) fn eof_place(&self) -> Place {
        if self.newline {
            Place::Line(self.line + 1)
        } else {
            Place::Line(self.line)
        }
    }

    /// The reader positioned after the current line, and the bytes consumed.
    pub(super) fn into_inner(self) -> (R, u64) {
        (self.reader, self.offset)
    }
}

/// Reads binary data, counting bytes.
pub(super) struct Bytes<R> {
    reader: R,
    offset: u64,
}

impl<R: BufRead> Bytes<R> {
    pub(super) fn new(reader: R, offset: u64) -> Self {
        Self { reader, offset }
    }

    /// Bytes consumed so far.
    pub(super) fn offset(&self) -> u64 {
        self.offset
    }

    /// Reads the next `n` bytes and passes them to `f`: straight from the
    /// reader's buffer when they are all there, otherwise through `scratch`.
    /// `Ok(None)` when the input ends first.
    #[inline]
    pub(super) fn record<T>(
        &mut self,
        n: usize,
        scratch: &mut Vec<u8>,
        f: impl FnOnce(&[u8]) -> T,
    ) -> io::Result<Option<T>> {
        let available = loop {
            match self.reader.fill_buf() {
                Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                r => break r?,
            }
        };
        if let Some(bytes) = available.get(..n) {
            let value = f(bytes);
            self.reader.consume(n);
            self.offset += n as u64;
            return Ok(Some(value));
        }
        scratch.clear();
        scratch.resize(n, 0);
        if !self.fill(scratch)? {
            return Ok(None);
        }
        Ok(Some(f(scratch)))
    }

    /// Fills `out`; returns `Ok(false)` when the input ends first.
    pub(super) fn fill(&mut self, out: &mut [u8]) -> io::Result<bool> {
        let mut done = 0;
        while done < out.len() {
            let available = match self.reader.fill_buf() {
                Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                r => r?,
            };
            if available.is_empty() {
                return Ok(false);
            }
            let n = available.len().min(out.len() - done);
            out[done..done + n].copy_from_slice(&available[..n]);
            self.reader.consume(n);
            self.offset += n as u64;
            done += n;
        }
        Ok(true)
    }
}

/// The whitespace-separated tokens of a line (see [`tokens`] and
/// [`tokens_before_comment`]).
pub(super) struct Tokens<'a> {
    rest: &'a [u8],
    /// Whether `#` ends a token and starts a comment up to the line's end.
    comments: bool,
}

impl<'a> Iterator for Tokens<'a> {
    type Item = &'a [u8];

    #[inline]
    fn next(&mut self) -> Option<&'a [u8]> {
        let comments = self.comments;
        let start = self.rest.iter().position(|b| !b.is_ascii_whitespace())?;
        let (_, rest) = self.rest.split_at(start);
        if comments && rest.first() == Some(&b'#') {
            self.rest = &[];
            return None;
        }
        let end = rest
            .iter()
            .position(|&b| b.is_ascii_whitespace() || (comments && b == b'#'))
            .unwrap_or(rest.len());
        let (token, tail) = rest.split_at(end);
        self.rest = tail;
        Some(token)
    }
}

/// The whitespace-separated tokens of a line.
pub(super) fn tokens(line: &[u8]) -> Tokens<'_> {
    Tokens {
        rest: line,
        comments: false,
    }
}

/// The whitespace-separated tokens of a line up to a `#` comment.
pub(super) fn tokens_before_comment(line: &[u8]) -> Tokens<'_> {
    Tokens {
        rest: line,
        comments: true,
    }
}

/// Parses a decimal number (also `inf`/`nan`, which the callers reject as
/// non-finite with a precise message).
#[inline]
pub(super) fn parse_f32(token: &[u8]) -> Option<f32> {
    std::str::from_utf8(token).ok()?.parse().ok()
}

/// Parses a signed decimal integer (`[+-]digits`, as `str::parse`).
#[inline]
pub(super) fn parse_i64(token: &[u8]) -> Option<i64> {
    match token.split_first()? {
        (b'-', digits) => {
            let magnitude = parse_digits(digits)?;
            0i64.checked_sub_unsigned(magnitude)
        }
        (b'+', digits) => i64::try_from(parse_digits(digits)?).ok(),
        _ => i64::try_from(parse_digits(token)?).ok(),
    }
}

/// Parses an unsigned decimal integer (`[+]digits`, as `str::parse`).
#[inline]
pub(super) fn parse_u64(token: &[u8]) -> Option<u64> {
    parse_digits(token.strip_prefix(b"+").unwrap_or(token))
}

/// Parses a non-empty run of decimal digits.
#[inline]
fn parse_digits(digits: &[u8]) -> Option<u64> {
    if digits.is_empty() {
        return None;
    }
    let mut value = 0u64;
    for &d in digits {
        let d = d.wrapping_sub(b'0');
        if d > 9 {
            return None;
        }
        value = value.checked_mul(10)?.checked_add(u64::from(d))?;
    }
    Some(value)
}

/// A token quoted for an error message (lossy, at most 40 characters).
pub(super) fn show(token: &[u8]) -> String {
    let text = String::from_utf8_lossy(token);
    let mut shown: String = text.chars().take(40).collect();
    if text.chars().count() > 40 {
        shown.push_str("...");
    }
    format!("{shown:?}")
}

/// Whether all three coordinates are finite.
pub(super) fn finite(v: &[f32; 3]) -> bool {
    v.iter().all(|c| c.is_finite())
}

/// Triangles handed to a batch callback as they are read.
pub type TriangleBatches<'a> = &'a mut dyn FnMut(&[[u32; 3]]) -> Result<(), MeshError>;

/// Where a reader puts its triangles: a vector it returns ([`load`]), or
/// batches of 65 536 handed to a callback as they are read
/// ([`stream`]), so that the faces of a model larger than memory never
/// are all in memory at once.
pub(super) struct Tris<'a> {
    buf: Vec<[u32; 3]>,
    count: u64,
    batches: Option<TriangleBatches<'a>>,
    /// The callback's first error: later batches are dropped, and the
    /// reader's result is this error.
    failed: Option<MeshError>,
}

impl<'a> Tris<'a> {
    /// Triangles a batch.
    const BATCH: usize = 1 << 16;

    /// Collects every triangle.
    pub(super) fn collect() -> Self {
        Self {
            buf: Vec::new(),
            count: 0,
            batches: None,
            failed: None,
        }
    }

    /// Hands the triangles to `batches`.
    pub(super) fn batches(batches: TriangleBatches<'a>) -> Self {
        Self {
            buf: Vec::with_capacity(Self::BATCH),
            count: 0,
            batches: Some(batches),
            failed: None,
        }
    }

    /// Reserves room for `n` more triangles when collecting.
    pub(super) fn reserve(&mut self, n: usize) {
        if self.batches.is_none() {
            self.buf.reserve(n);
        }
    }

    /// Triangles so far.
    pub(super) fn count(&self) -> u64 {
        self.count
    }

    #[inline]
    pub(super) fn push(&mut self, t: [u32; 3]) {
        self.buf.push(t);
        self.count += 1;
        if self.batches.is_some() && self.buf.len() >= Self::BATCH {
            self.flush();
        }
    }

    /// Fan-triangulates `polygon`: `(0 1 2) (0 2 3) …`.
    pub(super) fn fan(&mut self, polygon: &[u32]) {
        if let Some((&first, rest)) = polygon.split_first() {
            for pair in rest.windows(2) {
                self.push([first, pair[0], pair[1]]);
            }
        }
    }

    fn flush(&mut self) {
        if let Some(f) = self.batches.as_mut() {
            if self.failed.is_none()
                && let Err(e) = f(&self.buf)
            {
                self.failed = Some(e);
            }
            self.buf.clear();
        }
    }

    /// The collected triangles (none when streaming), or the batch
    /// callback's first error.
    pub(super) fn finish(mut self) -> Result<Vec<[u32; 3]>, MeshError> {
        self.flush();
        match self.failed {
            Some(e) => Err(e),
            None => Ok(self.buf),
        }
    }
}

/// Writes `value` in decimal without going through `fmt`.
pub(super) fn write_u64(out: &mut Vec<u8>, mut value: u64) {
    let mut digits = [0u8; 20];
    let mut i = digits.len();
    loop {
        i -= 1;
        digits[i] = b'0' + (value % 10) as u8;
        value /= 10;
        if value == 0 {
            break;
        }
    }
    out.extend_from_slice(&digits[i..]);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn format_names_and_extensions() {
        assert_eq!(
            Format::from_path(Path::new("a/B.PlY")).unwrap(),
            Format::Ply
        );
        assert_eq!(Format::from_path(Path::new("x.off")).unwrap().name(), "off");
        assert!(matches!(
            Format::from_path(Path::new("x.txt")),
            Err(MeshError::UnknownExtension { .. })
        ));
        let d = FormatDetail {
            format: Format::Ply,
            encoding: Encoding::BinaryLittleEndian,
        };
        assert_eq!(d.to_string(), "ply (binary little-endian)");
    }

    #[test]
    fn tokens_stop_at_comments() {
        let line = b" v 1\t2 3#four # five";
        let all: Vec<&[u8]> = tokens(line).collect();
        assert_eq!(all, [&b"v"[..], b"1", b"2", b"3#four", b"#", b"five"]);
        let before: Vec<&[u8]> = tokens_before_comment(line).collect();
        assert_eq!(before, [&b"v"[..], b"1", b"2", b"3"]);
        assert_eq!(tokens_before_comment(b"  # x").count(), 0);
    }

    #[test]
    fn fan_triangulates() {
        let mut t = Tris::collect();
        t.fan(&[4, 5, 6, 7, 8]);
        assert_eq!(t.finish().unwrap(), vec![[4, 5, 6], [4, 6, 7], [4, 7, 8]]);
    }

    #[test]
    fn integer_parsing_matches_std() {
        for t in [
            "0",
            "7",
            "+7",
            "-7",
            "-0",
            "",
            "+",
            "-",
            "12a",
            " 1",
            "1.0",
            "9223372036854775807",
            "9223372036854775808",
            "-9223372036854775808",
            "-9223372036854775809",
            "18446744073709551615",
            "18446744073709551616",
        ] {
            assert_eq!(parse_i64(t.as_bytes()), t.parse::<i64>().ok(), "{t:?}");
            assert_eq!(parse_u64(t.as_bytes()), t.parse::<u64>().ok(), "{t:?}");
        }
    }

    #[test]
    fn decimal_writer() {
        for v in [0u64, 7, 10, 12345, u64::from(u32::MAX), u64::MAX] {
            let mut out = Vec::new();
            write_u64(&mut out, v);
            assert_eq!(out, v.to_string().as_bytes());
        }
    }

    #[test]
    fn capacity_is_capped_by_remaining_bytes() {
        let src = Src {
            path: Path::new("x"),
            len: 100,
        };
        assert_eq!(src.capacity(u64::MAX, 0, 10), 10);
        assert_eq!(src.capacity(3, 0, 10), 3);
        assert_eq!(src.capacity(5, 200, 10), 0);
    }

    #[test]
    fn lines_track_numbers_and_cut_off() {
        let mut l = Lines::new(&b"a\r\n\nlast"[..]);
        assert!(l.advance().unwrap());
        assert_eq!((l.text(), l.line()), (&b"a"[..], 1));
        assert!(l.advance().unwrap());
        assert_eq!(l.text(), b"");
        assert!(l.advance().unwrap());
        assert!(l.cut_off());
        assert_eq!(l.eof_place(), Place::Line(3));
        assert!(!l.advance().unwrap());
    }
}
