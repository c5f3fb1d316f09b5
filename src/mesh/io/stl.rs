//! The STL reader (ASCII and binary) with vertex welding.
//!
//! A file is binary when its size is exactly `84 + 50 * count` for the
//! count stored at byte 80, otherwise ASCII when it starts with `solid` and
//! its first bytes are text, otherwise binary (many binary files also start
//! with `solid`, so the keyword alone decides nothing). Corners with bitwise
//! equal positions (`-0.0` counted as `0.0`) become one vertex, so the mesh
//! is indexed. ASCII loops with more than three vertices are
//! fan-triangulated. Normals and attribute bytes are ignored. A binary
//! file with data after the triangles its header counts is an error (the
//! count is short, and the triangles after it would be lost).

use std::collections::hash_map::Entry;
use std::io::{BufRead, Read};

use super::{Bytes, Encoding, Lines, Src, Tris, finite, parse_f32, show, tokens};
use crate::hash::FastMap;
use crate::mesh::{MeshError, Place};

/// How many leading bytes decide between ASCII and binary.
const PROBE: u64 = 512;

pub(super) fn read<R: BufRead>(
    mut reader: R,
    src: &Src,
    triangles: &mut Tris<'_>,
) -> Result<(Vec<[f32; 3]>, Encoding), MeshError> {
    let mut head = Vec::with_capacity(PROBE as usize);
    (&mut reader)
        .take(PROBE)
        .read_to_end(&mut head)
        .map_err(|e| src.io(e))?;
    let exact_binary = match head.get(80..84) {
        Some(&[a, b, c, d]) => 84 + 50 * u64::from(u32::from_le_bytes([a, b, c, d])) == src.len,
        _ => false,
    };
    let starts_solid = head
        .trim_ascii_start()
        .get(..5)
        .is_some_and(|k| k.eq_ignore_ascii_case(b"solid"));
    let text = head.iter().all(|&b| b >= 0x20 || b.is_ascii_whitespace());
    let rest = (&head[..]).chain(reader);
    if starts_solid && text && !exact_binary {
        Ok((read_ascii(rest, src, triangles)?, Encoding::Ascii))
    } else {
        Ok((
            read_binary(rest, src, triangles)?,
            Encoding::BinaryLittleEndian,
        ))
    }
}

/// Merges corners with bitwise equal positions into indexed vertices.
#[derive(Default)]
struct Welder {
    map: FastMap<u128, u32>,
    vertices: Vec<[f32; 3]>,
}

impl Welder {
    fn index(&mut self, v: [f32; 3], place: Place, src: &Src) -> Result<u32, MeshError> {
        if !finite(&v) {
            return Err(src.non_finite(place, self.vertices.len()));
        }
        // -0.0 == 0.0, so both get the bits of +0.0.
        let [x, y, z] = v.map(|c| {
            if c == 0.0 {
                0u128
            } else {
                u128::from(c.to_bits())
            }
        });
        match self.map.entry(x | (y << 32) | (z << 64)) {
            Entry::Occupied(e) => Ok(*e.get()),
            Entry::Vacant(e) => {
                let i = u32::try_from(self.vertices.len())
                    .map_err(|_| src.malformed(place, "more than 2^32 distinct vertices"))?;
                e.insert(i);
                self.vertices.push(v);
                Ok(i)
            }
        }
    }
}

fn read_binary<R: BufRead>(
    reader: R,
    src: &Src,
    triangles: &mut Tris<'_>,
) -> Result<Vec<[f32; 3]>, MeshError> {
    let mut bytes = Bytes::new(reader, 0);
    let mut header = [0u8; 84];
    if !bytes.fill(&mut header).map_err(|e| src.io(e))? {
        return Err(src.truncated(
            Place::Byte(bytes.offset()),
            "the 84-byte binary STL header (80 bytes of text and a 4-byte triangle count)",
        ));
    }
    let n = u32::from_le_bytes([header[80], header[81], header[82], header[83]]);
    let cap = src.capacity(u64::from(n), 84, 50);
    let mut welder = Welder::default();
    welder.map.reserve(cap / 2);
    welder.vertices.reserve(cap / 2);
    triangles.reserve(cap);
    let mut record = [0u8; 50];
    for t in 0..n {
        let start = bytes.offset();
        if !bytes.fill(&mut record).map_err(|e| src.io(e))? {
            return Err(src.truncated(
                Place::Byte(bytes.offset()),
                format!("triangle {t} of {n} (50 bytes from byte {start})"),
            ));
        }
        let f =
            |o: usize| f32::from_le_bytes([record[o], record[o + 1], record[o + 2], record[o + 3]]);
        let mut tri = [0u32; 3];
        for (k, corner) in tri.iter_mut().enumerate() {
            let o = 12 + 12 * k;
            let place = Place::Byte(start + o as u64);
            *corner = welder.index([f(o), f(o + 4), f(o + 8)], place, src)?;
        }
        triangles.push(tri);
    }
    // A count short of the data would drop the triangles after it.
    let end = bytes.offset();
    if bytes.fill(&mut [0u8]).map_err(|e| src.io(e))? {
        return Err(src.malformed(
            Place::Byte(end),
            format!(
                "the header counts {n} triangle(s), and data goes on after them (a binary \
                 STL is 84 + 50 × count = {end} bytes long)"
            ),
        ));
    }
    Ok(welder.vertices)
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum State {
    Outside,
    Solid,
    Facet,
    Loop,
    LoopDone,
}

impl State {
    fn expected(self) -> &'static str {
        match self {
            State::Outside => "\"solid\"",
            State::Solid => "\"facet\" or \"endsolid\"",
            State::Facet => "\"outer loop\"",
            State::Loop => "\"vertex x y z\" or \"endloop\"",
            State::LoopDone => "\"endfacet\"",
        }
    }
}

fn read_ascii<R: BufRead>(
    reader: R,
    src: &Src,
    triangles: &mut Tris<'_>,
) -> Result<Vec<[f32; 3]>, MeshError> {
    let mut lines = Lines::new(reader);
    let mut welder = Welder::default();
    let mut polygon: Vec<u32> = Vec::new();
    let mut state = State::Outside;
    let mut facet = 0usize;
    while lines.advance().map_err(|e| src.io(e))? {
        let place = lines.place();
        let mut toks = tokens(lines.text());
        let Some(keyword) = toks.next() else { continue };
        let is = |k: &[u8]| keyword.eq_ignore_ascii_case(k);
        let unexpected = || {
            src.malformed(
                place,
                format!("expected {}, found {}", state.expected(), show(keyword)),
            )
        };
        state = match state {
            State::Outside if is(b"solid") => State::Solid,
            State::Solid if is(b"facet") => State::Facet,
            State::Solid if is(b"endsolid") => State::Outside,
            State::Facet if is(b"outer") => {
                match toks.next() {
                    Some(t) if t.eq_ignore_ascii_case(b"loop") => {}
                    _ => return Err(src.malformed(place, "expected \"outer loop\"")),
                }
                polygon.clear();
                State::Loop
            }
            State::Loop if is(b"vertex") => {
                let mut v = [0f32; 3];
                for (k, c) in v.iter_mut().enumerate() {
                    let axis = ["x", "y", "z"][k];
                    let Some(t) = toks.next() else {
                        let what = format!("the {axis} coordinate of a vertex of facet {facet}");
                        return Err(if lines.cut_off() {
                            src.truncated(place, what)
                        } else {
                            src.malformed(place, format!("missing {what}"))
                        });
                    };
                    *c = parse_f32(t).ok_or_else(|| {
                        src.malformed(
                            place,
                            format!("expected the {axis} coordinate, found {}", show(t)),
                        )
                    })?;
                }
                if let Some(t) = toks.next() {
                    return Err(src.malformed(
                        place,
                        format!(
                            "unexpected {} after the three coordinates of a vertex",
                            show(t)
                        ),
                    ));
                }
                polygon.push(welder.index(v, place, src)?);
                State::Loop
            }
            State::Loop if is(b"endloop") => {
                if polygon.len() < 3 {
                    return Err(src.malformed(
                        place,
                        format!(
                            "facet {facet} has {} vertices; at least 3 are needed",
                            polygon.len()
                        ),
                    ));
                }
                triangles.fan(&polygon);
                State::LoopDone
            }
            State::LoopDone if is(b"endfacet") => {
                facet += 1;
                State::Solid
            }
            _ => return Err(unexpected()),
        };
    }
    if state != State::Outside {
        return Err(src.truncated(lines.eof_place(), state.expected()));
    }
    Ok(welder.vertices)
}
