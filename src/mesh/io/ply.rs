//! The PLY reader (ASCII, binary little- and big-endian) and the binary
//! little-endian PLY writer.
//!
//! The reader takes positions from the `x`, `y`, `z` properties of the
//! `vertex` element (any numeric type) and polygons from the `vertex_indices`
//! (or `vertex_index`) list of the `face` element (any integer count and
//! index types); polygons are fan-triangulated. Other elements and
//! properties are skipped. Errors name the line (ASCII) or the byte offset
//! of the record (binary).
//!
//! The elements' counts must match the body in both directions: a file
//! that ends before them is truncated, and one with data after the last
//! record they announce (a line with content, or any byte in a binary
//! file) is refused, naming the counts (a short count would otherwise drop
//! the records after it without a word, where binary STL refuses the same).

use std::io::{self, BufRead, Write};

use super::{
    Bytes, Encoding, Lines, Src, Tris, finite, parse_f32, parse_i64, parse_u64, show, tokens,
};
use crate::mesh::{Mesh, MeshError, Place};

/// A scalar property type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &[u8]) -> Option<Scalar> {
        Some(match name {
            b"char" | b"int8" => Scalar::I8,
            b"uchar" | b"uint8" => Scalar::U8,
            b"short" | b"int16" => Scalar::I16,
            b"ushort" | b"uint16" => Scalar::U16,
            b"int" | b"int32" => Scalar::I32,
            b"uint" | b"uint32" => Scalar::U32,
            b"float" | b"float32" => Scalar::F32,
            b"double" | b"float64" => Scalar::F64,
            _ => return None,
        })
    }

    #[inline]
    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }
}

/// A decoded binary value.
#[derive(Clone, Copy, Debug)]
enum Num {
    Int(i64),
    Float(f64),
}

impl Num {
    #[inline]
    fn as_f32(self) -> f32 {
        match self {
            Num::Int(i) => i as f32,
            Num::Float(f) => f as f32,
        }
    }
}

#[derive(Clone, Copy, Debug)]
enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

/// What the reader does with a property.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Role {
    Coord(usize),
    Indices,
    Skip,
}

#[derive(Debug)]
struct Property {
    name: Vec<u8>,
    kind: Kind,
    role: Role,
}

#[derive(Debug)]
struct Element {
    name: Vec<u8>,
    count: u64,
    props: Vec<Property>,
    line: usize,
}

/// Which element a reading pass is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Which {
    Vertex,
    Face,
    Other,
}

struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
}

fn read_header<R: BufRead>(lines: &mut Lines<R>, src: &Src) -> Result<Header, MeshError> {
    let io = |e| src.io(e);
    if !lines.advance().map_err(io)? {
        return Err(src.truncated(lines.eof_place(), "the PLY header"));
    }
    if lines.text().trim_ascii_end() != b"ply" {
        return Err(src.malformed(
            lines.place(),
            format!(
                "not a PLY file: expected \"ply\" on the first line, found {}",
                show(lines.text())
            ),
        ));
    }
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        if !lines.advance().map_err(io)? {
            return Err(src.truncated(
                lines.eof_place(),
                "the rest of the PLY header up to end_header",
            ));
        }
        if lines.cut_off() {
            return Err(src.truncated(
                lines.place(),
                "the rest of the PLY header up to end_header (the file ends inside a header line)",
            ));
        }
        let place = lines.place();
        let mut toks = tokens(lines.text());
        let Some(keyword) = toks.next() else { continue };
        let mut next = |what: &str| {
            toks.next()
                .ok_or_else(|| src.malformed(place, format!("header line ends before the {what}")))
        };
        match keyword {
            b"format" => {
                encoding = Some(match next("format name")? {
                    b"ascii" => Encoding::Ascii,
                    b"binary_little_endian" => Encoding::BinaryLittleEndian,
                    b"binary_big_endian" => Encoding::BinaryBigEndian,
                    other => {
                        return Err(src.malformed(
                            place,
                            format!(
                                "unknown PLY format {}; expected ascii, binary_little_endian or binary_big_endian",
                                show(other)
                            ),
                        ));
                    }
                });
            }
            b"comment" | b"obj_info" => {}
            b"element" => {
                let name = next("element name")?.to_vec();
                let count = next("element count")?;
                let count = parse_u64(count).ok_or_else(|| {
                    src.malformed(
                        place,
                        format!("expected the element count, found {}", show(count)),
                    )
                })?;
                elements.push(Element {
                    name,
                    count,
                    props: Vec::new(),
                    line: lines.line(),
                });
            }
            b"property" => {
                let Some(element) = elements.last_mut() else {
                    return Err(src.malformed(place, "property before any element"));
                };
                let type_of = |t: &[u8]| {
                    Scalar::parse(t).ok_or_else(|| {
                        src.malformed(place, format!("unknown property type {}", show(t)))
                    })
                };
                let first = next("property type")?;
                let kind = if first == b"list" {
                    let count = type_of(next("list count type")?)?;
                    let item = type_of(next("list item type")?)?;
                    if !count.is_integer() {
                        return Err(
                            src.malformed(place, "a list count type must be an integer type")
                        );
                    }
                    Kind::List { count, item }
                } else {
                    Kind::Scalar(type_of(first)?)
                };
                let name = next("property name")?.to_vec();
                element.props.push(Property {
                    name,
                    kind,
                    role: Role::Skip,
                });
            }
            b"end_header" => break,
            other => {
                // Real exporters write free text in the header (a Blender
                // export had a line starting "Created by"); assimp and other
                // readers skip such lines, so skip it too, but say so.
                log::warn!(
                    "{}: {place}: skipping PLY header line with unknown keyword {}",
                    src.path.display(),
                    show(other)
                );
            }
        }
    }
    let encoding = encoding
        .ok_or_else(|| src.malformed(lines.place(), "the PLY header has no format line"))?;
    Ok(Header { encoding, elements })
}

/// Assigns roles to the properties of the vertex and face elements and
/// returns the index of each element.
fn assign_roles(elements: &mut [Element], src: &Src) -> Result<(usize, usize), MeshError> {
    let Some(fi) = elements.iter().position(|e| e.name == b"face") else {
        return Err(src.no_faces());
    };
    let Some(vi) = elements.iter().position(|e| e.name == b"vertex") else {
        return Err(src.malformed(Place::Unknown, "the PLY header has no vertex element"));
    };
    let vertex = &mut elements[vi];
    for (k, axis) in [&b"x"[..], b"y", b"z"].into_iter().enumerate() {
        let place = Place::Line(vertex.line);
        let Some(p) = vertex.props.iter_mut().find(|p| p.name == axis) else {
            return Err(src.malformed(
                place,
                format!("the vertex element has no property {}", show(axis)),
            ));
        };
        if !matches!(p.kind, Kind::Scalar(_)) {
            return Err(src.malformed(place, format!("vertex property {} is a list", show(axis))));
        }
        p.role = Role::Coord(k);
    }
    let face = &mut elements[fi];
    let place = Place::Line(face.line);
    let Some(p) = face
        .props
        .iter_mut()
        .find(|p| p.name == b"vertex_indices" || p.name == b"vertex_index")
    else {
        return Err(src.malformed(
            place,
            "the face element has no list property vertex_indices (or vertex_index)",
        ));
    };
    match p.kind {
        Kind::List { item, .. } if item.is_integer() => p.role = Role::Indices,
        _ => {
            return Err(src.malformed(
                place,
                format!("face property {} must be a list of integers", show(&p.name)),
            ));
        }
    }
    Ok((vi, fi))
}

pub(super) fn read<R: BufRead>(
    reader: R,
    src: &Src,
    tris: &mut Tris<'_>,
) -> Result<(Vec<[f32; 3]>, Encoding), MeshError> {
    let mut lines = Lines::new(reader);
    let Header {
        encoding,
        mut elements,
    } = read_header(&mut lines, src)?;
    let (vi, fi) = assign_roles(&mut elements, src)?;
    let nv = elements[vi].count;
    if nv > u64::from(u32::MAX) + 1 {
        return Err(src.malformed(
            Place::Line(elements[vi].line),
            format!("{nv} vertices is more than the 2^32 that 32-bit indices can address"),
        ));
    }
    let mut sink = Sink {
        vertices: Vec::new(),
        triangles: tris,
        polygon: Vec::new(),
        nv,
    };
    match encoding {
        Encoding::Ascii => {
            for (i, element) in elements.iter().enumerate() {
                let which = which(i, vi, fi);
                reserve(&mut sink, which, element, lines.offset(), src, 6, 8);
                read_ascii_element(&mut lines, element, which, &mut sink, src)?;
            }
            while lines.advance().map_err(|e| src.io(e))? {
                if tokens(lines.text()).next().is_some() {
                    return Err(data_after_elements(lines.place(), &elements, src));
                }
            }
        }
        Encoding::BinaryLittleEndian | Encoding::BinaryBigEndian => {
            let big = encoding == Encoding::BinaryBigEndian;
            let (reader, offset) = lines.into_inner();
            let mut bytes = Bytes::new(reader, offset);
            for (i, element) in elements.iter().enumerate() {
                let which = which(i, vi, fi);
                reserve(&mut sink, which, element, bytes.offset(), src, 3, 4);
                read_binary_element(&mut bytes, element, which, big, &mut sink, src)?;
            }
            let end = bytes.offset();
            if bytes.fill(&mut [0u8]).map_err(|e| src.io(e))? {
                return Err(data_after_elements(Place::Byte(end), &elements, src));
            }
        }
    }
    Ok((sink.vertices, encoding))
}

/// The error for data at `place`, after the last record the header's
/// `elements` announce: a count is short.
fn data_after_elements(place: Place, elements: &[Element], src: &Src) -> MeshError {
    let counts: Vec<String> = elements
        .iter()
        .map(|e| format!("{} {} on line {}", element_name(e), e.count, e.line))
        .collect();
    src.malformed(
        place,
        format!(
            "the file goes on after the records the header announces (element {}): a count is \
             short, and what follows would be lost; correct the counts",
            counts.join(", element ")
        ),
    )
}

fn which(i: usize, vi: usize, fi: usize) -> Which {
    if i == vi {
        Which::Vertex
    } else if i == fi {
        Which::Face
    } else {
        Which::Other
    }
}

/// Reserves room for the vertices or faces of `element`, capped by what the
/// rest of the source could hold (`vmin`/`fmin` bytes per record at least).
fn reserve(
    sink: &mut Sink<'_, '_>,
    which: Which,
    e: &Element,
    at: u64,
    src: &Src,
    vmin: u64,
    fmin: u64,
) {
    match which {
        Which::Vertex => sink.vertices.reserve(src.capacity(e.count, at, vmin)),
        Which::Face => sink.triangles.reserve(src.capacity(e.count, at, fmin)),
        Which::Other => {}
    }
}

/// Where records go.
struct Sink<'t, 'a> {
    vertices: Vec<[f32; 3]>,
    triangles: &'t mut Tris<'a>,
    polygon: Vec<u32>,
    nv: u64,
}

impl Sink<'_, '_> {
    #[inline]
    fn push_vertex(&mut self, v: [f32; 3], place: Place, src: &Src) -> Result<(), MeshError> {
        if !finite(&v) {
            return Err(src.non_finite(place, self.vertices.len()));
        }
        self.vertices.push(v);
        Ok(())
    }

    #[inline]
    fn push_index(
        &mut self,
        index: i64,
        face: u64,
        place: Place,
        src: &Src,
    ) -> Result<(), MeshError> {
        if index < 0 {
            return Err(src.malformed(
                place,
                format!("face {face} has a negative vertex index {index}"),
            ));
        }
        let index = index as u64;
        if index >= self.nv {
            // Both fit: faces are counted as read, nv <= 2^32 was checked.
            return Err(src.out_of_range(place, face as usize, index, self.nv as usize));
        }
        self.polygon.push(index as u32);
        Ok(())
    }

    fn end_face(&mut self, face: u64, place: Place, src: &Src) -> Result<(), MeshError> {
        if self.polygon.len() < 3 {
            return Err(src.malformed(
                place,
                format!(
                    "face {face} has {} corners; a face needs at least 3",
                    self.polygon.len()
                ),
            ));
        }
        self.triangles.fan(&self.polygon);
        self.polygon.clear();
        Ok(())
    }
}

fn element_name(e: &Element) -> String {
    String::from_utf8_lossy(&e.name).into_owned()
}

fn read_ascii_element<R: BufRead>(
    lines: &mut Lines<R>,
    element: &Element,
    which: Which,
    sink: &mut Sink<'_, '_>,
    src: &Src,
) -> Result<(), MeshError> {
    let name = element_name(element);
    for record in 0..element.count {
        loop {
            if !lines.advance().map_err(|e| src.io(e))? {
                return Err(src.truncated(
                    lines.eof_place(),
                    format!("{name} {record} of {} (0-based)", element.count),
                ));
            }
            if tokens(lines.text()).next().is_some() {
                break;
            }
        }
        let place = lines.place();
        let cut_off = lines.cut_off();
        let mut toks = tokens(lines.text());
        let mut next = |what: &dyn Fn() -> String| {
            toks.next().ok_or_else(|| {
                let what = format!("{} of {name} {record}", what());
                if cut_off {
                    src.truncated(place, what)
                } else {
                    src.malformed(place, format!("the line ends before the {what}"))
                }
            })
        };
        let bad = |what: &str, t: &[u8]| {
            src.malformed(
                place,
                format!("{name} {record}: expected {what}, found {}", show(t)),
            )
        };
        let mut v = [0f32; 3];
        for p in &element.props {
            let pname = String::from_utf8_lossy(&p.name);
            match p.kind {
                Kind::Scalar(_) => {
                    let t = next(&|| format!("property {pname:?}"))?;
                    let value = parse_f32(t).ok_or_else(|| bad("a number", t))?;
                    if let Role::Coord(k) = p.role {
                        v[k] = value;
                    }
                }
                Kind::List { .. } => {
                    let t = next(&|| format!("length of list {pname:?}"))?;
                    let n = parse_u64(t).ok_or_else(|| bad("a list length", t))?;
                    for item in 0..n {
                        let t = next(&|| format!("item {item} of list {pname:?}"))?;
                        if p.role == Role::Indices {
                            let index = parse_i64(t).ok_or_else(|| bad("a vertex index", t))?;
                            sink.push_index(index, record, place, src)?;
                        } else if parse_f32(t).is_none() {
                            return Err(bad("a number", t));
                        }
                    }
                }
            }
        }
        if let Some(t) = toks.next() {
            return Err(src.malformed(
                place,
                format!(
                    "{name} {record}: unexpected extra value {} after the {} declared properties",
                    show(t),
                    element.props.len()
                ),
            ));
        }
        match which {
            Which::Vertex => sink.push_vertex(v, place, src)?,
            Which::Face => sink.end_face(record, place, src)?,
            Which::Other => {}
        }
    }
    Ok(())
}

/// The `N` bytes at `at` of `record` (zeros past its end, which callers
/// never ask for).
#[inline(always)]
fn bytes_at<const N: usize>(record: &[u8], at: usize) -> [u8; N] {
    record
        .get(at..at + N)
        .and_then(|b| b.try_into().ok())
        .unwrap_or([0; N])
}

/// Decodes the value of type `s` at byte `at` of `record`.
#[inline(always)]
fn num_at(s: Scalar, record: &[u8], at: usize, big: bool) -> Num {
    macro_rules! get {
        ($t:ty) => {{
            let b = bytes_at(record, at);
            if big {
                <$t>::from_be_bytes(b)
            } else {
                <$t>::from_le_bytes(b)
            }
        }};
    }
    match s {
        Scalar::I8 => Num::Int(i64::from(get!(i8))),
        Scalar::U8 => Num::Int(i64::from(get!(u8))),
        Scalar::I16 => Num::Int(i64::from(get!(i16))),
        Scalar::U16 => Num::Int(i64::from(get!(u16))),
        Scalar::I32 => Num::Int(i64::from(get!(i32))),
        Scalar::U32 => Num::Int(i64::from(get!(u32))),
        Scalar::F32 => Num::Float(f64::from(get!(f32))),
        Scalar::F64 => Num::Float(get!(f64)),
    }
}

/// List items read per call.
const CHUNK_ITEMS: u64 = 256;

fn read_binary_element<R: BufRead>(
    bytes: &mut Bytes<R>,
    element: &Element,
    which: Which,
    big: bool,
    sink: &mut Sink<'_, '_>,
    src: &Src,
) -> Result<(), MeshError> {
    let name = element_name(element);
    let mut scratch = Vec::new();
    let truncated = |bytes: &Bytes<R>, record: u64, start: u64| {
        src.truncated(
            Place::Byte(bytes.offset()),
            format!(
                "the rest of {name} {record} of {} (record starting at byte {start})",
                element.count
            ),
        )
    };
    let io = |e| src.io(e);

    // Records of scalars only have a fixed size: read each in one go.
    let fixed: Option<usize> = element
        .props
        .iter()
        .map(|p| match p.kind {
            Kind::Scalar(s) => Some(s.size()),
            Kind::List { .. } => None,
        })
        .sum();
    if let Some(stride) = fixed {
        if stride == 0 {
            return Ok(()); // no properties: the records take no bytes
        }
        let mut coords = [(0usize, Scalar::F32); 3];
        let mut at = 0;
        for p in &element.props {
            if let Kind::Scalar(s) = p.kind {
                if let Role::Coord(k) = p.role {
                    coords[k] = (at, s);
                }
                at += s.size();
            }
        }
        for record in 0..element.count {
            let start = bytes.offset();
            let v = bytes
                .record(stride, &mut scratch, |r| {
                    coords.map(|(at, s)| num_at(s, r, at, big).as_f32())
                })
                .map_err(io)?
                .ok_or_else(|| truncated(bytes, record, start))?;
            if which == Which::Vertex {
                sink.push_vertex(v, Place::Byte(start), src)?;
            }
        }
        return Ok(());
    }

    for record in 0..element.count {
        let start = bytes.offset();
        let place = Place::Byte(start);
        let mut v = [0f32; 3];
        for p in &element.props {
            match p.kind {
                Kind::Scalar(s) => {
                    let value = bytes
                        .record(s.size(), &mut scratch, |r| num_at(s, r, 0, big))
                        .map_err(io)?
                        .ok_or_else(|| truncated(bytes, record, start))?;
                    if let Role::Coord(k) = p.role {
                        v[k] = value.as_f32();
                    }
                }
                Kind::List { count, item } => {
                    let n = bytes
                        .record(count.size(), &mut scratch, |r| num_at(count, r, 0, big))
                        .map_err(io)?
                        .ok_or_else(|| truncated(bytes, record, start))?;
                    let n = match n {
                        Num::Int(n) if n >= 0 => n as u64,
                        n => {
                            return Err(src.malformed(
                                place,
                                format!("{name} {record}: invalid list length {n:?}"),
                            ));
                        }
                    };
                    let size = item.size();
                    let mut left = n;
                    while left > 0 {
                        let chunk = left.min(CHUNK_ITEMS);
                        left -= chunk;
                        bytes
                            .record(chunk as usize * size, &mut scratch, |r| {
                                if p.role != Role::Indices {
                                    return Ok::<(), MeshError>(());
                                }
                                for c in r.chunks_exact(size) {
                                    if let Num::Int(index) = num_at(item, c, 0, big) {
                                        sink.push_index(index, record, place, src)?;
                                    }
                                }
                                Ok(())
                            })
                            .map_err(io)?
                            .ok_or_else(|| truncated(bytes, record, start))??;
                    }
                }
            }
        }
        match which {
            Which::Vertex => sink.push_vertex(v, place, src)?,
            Which::Face => sink.end_face(record, place, src)?,
            Which::Other => {}
        }
    }
    Ok(())
}

/// Writes `mesh` as binary little-endian PLY (see [`PlyWriter`]).
pub(super) fn write(mesh: &Mesh, out: &mut impl Write) -> io::Result<()> {
    let mut ply = PlyWriter::new(out, mesh.vertices.len() as u64, mesh.triangles.len() as u64)?;
    ply.write_vertices(&mesh.vertices)?;
    ply.write_triangles(&mesh.triangles)?;
    ply.finish().map(drop)
}

/// A binary little-endian PLY file written as it is produced, for meshes
/// too large to hold in memory: the header with the vertex and face counts
/// given up front, then the vertices in batches, then the triangles in
/// batches. Vertices are `float x y z`, faces a `uchar` count (3) and
/// `uint` indices; [`save`](super::save) writes the same bytes for a mesh
/// in memory.
///
/// The writer keeps the file consistent with its header: a batch that
/// would write more vertices or triangles than announced, or triangles
/// before every vertex, is refused (an [`io::ErrorKind::InvalidInput`]
/// error, nothing written), and [`finish`](Self::finish) fails unless
/// exactly the announced counts were written. Indices are written as
/// given, without checking them against the vertex count.
///
/// ```
/// use cbvh::mesh::PlyWriter;
/// let mut ply = PlyWriter::new(Vec::new(), 3, 1)?;
/// ply.write_vertices(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])?;
/// ply.write_vertices(&[[0.0, 1.0, 0.0]])?;
/// ply.write_triangles(&[[0, 1, 2]])?;
/// let bytes = ply.finish()?;
/// assert!(bytes.starts_with(b"ply\n"));
/// # Ok::<(), std::io::Error>(())
/// ```
#[derive(Debug)]
pub struct PlyWriter<W: Write> {
    out: W,
    /// Vertices and faces announced by the header.
    vertices: u64,
    faces: u64,
    /// Vertices and faces written so far.
    vertices_written: u64,
    faces_written: u64,
    /// Encoding buffer, reused across batches.
    buf: Vec<u8>,
}

/// Bytes encoded before each write to the output.
const WRITE_CHUNK: usize = 1 << 16;

impl<W: Write> PlyWriter<W> {
    /// Writes the header of a mesh of `vertices` vertices and `faces`
    /// triangles to `out`.
    ///
    /// # Errors
    /// Any error of `out`.
    pub fn new(mut out: W, vertices: u64, faces: u64) -> io::Result<Self> {
        write!(
            out,
            "ply\nformat binary_little_endian 1.0\ncomment written by cbvh\n\
             element vertex {vertices}\nproperty float x\nproperty float y\nproperty float z\n\
             element face {faces}\nproperty list uchar uint vertex_indices\nend_header\n"
        )?;
        Ok(Self {
            out,
            vertices,
            faces,
            vertices_written: 0,
            faces_written: 0,
            buf: Vec::with_capacity(WRITE_CHUNK),
        })
    }

    /// The vertex and face counts of the header.
    pub fn counts(&self) -> (u64, u64) {
        (self.vertices, self.faces)
    }

    /// The vertices and faces written so far.
    pub fn written(&self) -> (u64, u64) {
        (self.vertices_written, self.faces_written)
    }

    /// Writes the next vertices.
    ///
    /// # Errors
    /// [`io::ErrorKind::InvalidInput`] (and nothing written) when the batch
    /// would make more vertices than the header announces; any error of
    /// the output.
    pub fn write_vertices(&mut self, batch: &[[f32; 3]]) -> io::Result<()> {
        let n = batch.len() as u64;
        if self.vertices - self.vertices_written < n {
            return Err(invalid(format!(
                "PLY writer: {n} more vertices would make {} of the {} the header announces",
                self.vertices_written + n,
                self.vertices
            )));
        }
        encode(
            batch,
            &mut self.buf,
            &mut self.out,
            |v, rec: &mut [u8; 12]| {
                for (c, bytes) in v.iter().zip(rec.chunks_exact_mut(4)) {
                    bytes.copy_from_slice(&c.to_le_bytes());
                }
            },
        )?;
        self.vertices_written += n;
        Ok(())
    }

    /// Writes the next triangles; every vertex must have been written.
    ///
    /// # Errors
    /// [`io::ErrorKind::InvalidInput`] (and nothing written) when vertices
    /// are still missing, or when the batch would make more triangles than
    /// the header announces; any error of the output.
    pub fn write_triangles(&mut self, batch: &[[u32; 3]]) -> io::Result<()> {
        let n = batch.len() as u64;
        if self.vertices_written < self.vertices {
            return Err(invalid(format!(
                "PLY writer: triangles before the last vertex ({} of {} vertices written)",
                self.vertices_written, self.vertices
            )));
        }
        if self.faces - self.faces_written < n {
            return Err(invalid(format!(
                "PLY writer: {n} more triangles would make {} of the {} the header announces",
                self.faces_written + n,
                self.faces
            )));
        }
        encode(
            batch,
            &mut self.buf,
            &mut self.out,
            |t, rec: &mut [u8; 13]| {
                rec[0] = 3;
                for (i, bytes) in t.iter().zip(rec[1..].chunks_exact_mut(4)) {
                    bytes.copy_from_slice(&i.to_le_bytes());
                }
            },
        )?;
        self.faces_written += n;
        Ok(())
    }

    /// Checks that the header's counts were written, flushes the output
    /// and returns it.
    ///
    /// # Errors
    /// [`io::ErrorKind::InvalidInput`] when fewer vertices or triangles
    /// were written than the header announces; any error of the output.
    pub fn finish(mut self) -> io::Result<W> {
        if (self.vertices_written, self.faces_written) != (self.vertices, self.faces) {
            return Err(invalid(format!(
                "PLY writer: wrote {} vertices and {} triangles, but the header announces {} and {}",
                self.vertices_written, self.faces_written, self.vertices, self.faces
            )));
        }
        self.out.flush()?;
        Ok(self.out)
    }
}

fn invalid(message: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, message)
}

/// Encodes `items` as `N`-byte records with `f`, and writes them to `out`
/// in chunks of about [`WRITE_CHUNK`] bytes through `buf`.
fn encode<T, const N: usize>(
    items: &[T],
    buf: &mut Vec<u8>,
    out: &mut impl Write,
    f: impl Fn(&T, &mut [u8; N]),
) -> io::Result<()> {
    for chunk in items.chunks(WRITE_CHUNK / N) {
        buf.clear();
        buf.resize(chunk.len() * N, 0);
        for (item, rec) in chunk.iter().zip(buf.chunks_exact_mut(N)) {
            f(item, rec.try_into().expect("N-byte chunks"));
        }
        out.write_all(buf)?;
    }
    Ok(())
}
