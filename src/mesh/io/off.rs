//! The OFF reader (Object File Format, ASCII).
//!
//! Accepted: an optional header keyword `OFF` (also `COFF`, `NOFF`, `CNOFF`,
//! `STOFF`, ...), which may carry the counts on the same line; `#` comments
//! and blank lines anywhere; a counts line `vertices faces [edges]`; one
//! vertex per line (columns after x y z, such as colours, are ignored); one
//! face per line, `n i0 ... i(n-1)` followed by optional colour values.
//! Polygons are fan-triangulated.
//!
//! The counts must match the body in both directions: a file that ends
//! before them is truncated, and one that goes on after the last face
//! they announce is refused, naming the counts' line (a short count would
//! otherwise drop the faces after it without a word, where binary STL
//! refuses the same).

use std::io::BufRead;

use super::{Lines, Src, Tris, finite, parse_f32, parse_u64, show, tokens_before_comment};
use crate::mesh::{MeshError, Place};

/// Reads the next line with content (comments stripped); `Ok(false)` at
/// the end of the input.
fn next_record<R: BufRead>(lines: &mut Lines<R>, src: &Src) -> Result<bool, MeshError> {
    loop {
        if !lines.advance().map_err(|e| src.io(e))? {
            return Ok(false);
        }
        if tokens_before_comment(lines.text()).next().is_some() {
            return Ok(true);
        }
    }
}

/// Interprets the first token of the file: `Ok(true)` for an OFF keyword,
/// `Ok(false)` when the file starts directly with the counts.
fn header_keyword(token: &[u8], place: Place, src: &Src) -> Result<bool, MeshError> {
    if parse_u64(token).is_some() {
        return Ok(false);
    }
    let Some(prefix) = token.strip_suffix(b"OFF") else {
        return Err(src.malformed(
            place,
            format!(
                "not an OFF file: expected the keyword OFF, found {}",
                show(token)
            ),
        ));
    };
    if prefix.contains(&b'4') || prefix.contains(&b'n') {
        return Err(src.malformed(
            place,
            format!(
                "{}: only 3-dimensional OFF files are supported",
                show(token)
            ),
        ));
    }
    if !prefix.iter().all(|b| b"STCN".contains(b)) {
        return Err(src.malformed(place, format!("unknown OFF variant {}", show(token))));
    }
    Ok(true)
}

/// Parses the counts `vertices faces [edges]` from `toks`.
fn counts<'a>(
    mut toks: impl Iterator<Item = &'a [u8]>,
    place: Place,
    src: &Src,
) -> Result<(u64, u64), MeshError> {
    let mut next = |what: &str| -> Result<u64, MeshError> {
        match toks.next() {
            Some(t) => parse_u64(t).ok_or_else(|| {
                src.malformed(
                    place,
                    format!(
                        "expected the {what} count (a non-negative integer), found {}",
                        show(t)
                    ),
                )
            }),
            None => Err(src.malformed(
                place,
                format!(
                    "expected the counts line \"vertices faces edges\", the {what} count is missing"
                ),
            )),
        }
    };
    let vertices = next("vertex")?;
    let faces = next("face")?;
    Ok((vertices, faces))
}

pub(super) fn read<R: BufRead>(
    reader: R,
    src: &Src,
    triangles: &mut Tris<'_>,
) -> Result<Vec<[f32; 3]>, MeshError> {
    let mut lines = Lines::new(reader);
    if !next_record(&mut lines, src)? {
        return Err(src.truncated(lines.eof_place(), "the OFF header"));
    }
    let place = lines.place();
    let header = lines.text();
    let mut toks = tokens_before_comment(header);
    let first = toks.next().unwrap_or_default();
    let ((nv, nf), counts_place) = if !header_keyword(first, place, src)? {
        (counts(tokens_before_comment(header), place, src)?, place)
    } else if let Some(t) = toks.next() {
        if t.eq_ignore_ascii_case(b"BINARY") {
            return Err(src.malformed(place, "binary OFF files are not supported"));
        }
        (counts(std::iter::once(t).chain(toks), place, src)?, place)
    } else {
        if !next_record(&mut lines, src)? {
            return Err(src.truncated(
                lines.eof_place(),
                "the counts line \"vertices faces edges\"",
            ));
        }
        let place = lines.place();
        (
            counts(tokens_before_comment(lines.text()), place, src)?,
            place,
        )
    };
    // What a face error adds while the first face is read: a line that is
    // no face there is most likely a vertex the vertex count left out.
    let first_face_hint = |face: u64| {
        if face == 0 {
            format!(
                " (the counts on {counts_place} announce {nv} vertices: if the file holds more, \
                 the count is short)"
            )
        } else {
            String::new()
        }
    };
    if nv > u64::from(u32::MAX) + 1 {
        return Err(src.malformed(
            lines.place(),
            format!("{nv} vertices is more than the 2^32 that 32-bit indices can address"),
        ));
    }
    let n_vertices = nv as usize; // fits: checked above against 2^32

    // "0 0 0\n" is the shortest vertex line, "3 0 0 0\n" the shortest face line.
    let mut vertices = Vec::with_capacity(src.capacity(nv, lines.offset(), 6));
    for vertex in 0..n_vertices {
        if !next_record(&mut lines, src)? {
            return Err(src.truncated(
                lines.eof_place(),
                format!("vertex {vertex} of {nv} (0-based)"),
            ));
        }
        let mut v = [0f32; 3];
        let mut toks = tokens_before_comment(lines.text());
        for (k, c) in v.iter_mut().enumerate() {
            let axis = ["x", "y", "z"][k];
            match toks.next() {
                Some(t) => {
                    *c = parse_f32(t).ok_or_else(|| {
                        src.malformed(
                            lines.place(),
                            format!(
                                "vertex {vertex}: expected the {axis} coordinate, found {}",
                                show(t)
                            ),
                        )
                    })?
                }
                None if lines.cut_off() => {
                    return Err(src.truncated(
                        lines.place(),
                        format!("the {axis} coordinate of vertex {vertex}"),
                    ));
                }
                None => {
                    return Err(src.malformed(
                        lines.place(),
                        format!("vertex {vertex} has {k} coordinates, 3 are needed"),
                    ));
                }
            }
        }
        if !finite(&v) {
            return Err(src.non_finite(lines.place(), vertex));
        }
        vertices.push(v);
    }

    triangles.reserve(src.capacity(nf, lines.offset(), 8));
    let mut polygon: Vec<u32> = Vec::new();
    let mut face = 0u64;
    while face < nf {
        let f = face as usize; // faces are counted as they are read, so this fits
        if !next_record(&mut lines, src)? {
            return Err(src.truncated(lines.eof_place(), format!("face {face} of {nf} (0-based)")));
        }
        let mut toks = tokens_before_comment(lines.text());
        let first = toks.next().unwrap_or_default();
        let n = parse_u64(first).ok_or_else(|| {
            src.malformed(
                lines.place(),
                format!(
                    "face {face}: expected the number of corners, found {}{}",
                    show(first),
                    first_face_hint(face)
                ),
            )
        })?;
        if n < 3 {
            return Err(src.malformed(
                lines.place(),
                format!(
                    "face {face} has {n} corners; a face needs at least 3{}",
                    first_face_hint(face)
                ),
            ));
        }
        polygon.clear();
        for corner in 0..n {
            let Some(t) = toks.next() else {
                let message = format!("corner {corner} of face {face} (which has {n} corners)");
                return Err(if lines.cut_off() {
                    src.truncated(lines.place(), message)
                } else {
                    src.malformed(lines.place(), format!("missing {message}"))
                });
            };
            let index = parse_u64(t).ok_or_else(|| {
                src.malformed(
                    lines.place(),
                    format!("face {face}: expected a vertex index, found {}", show(t)),
                )
            })?;
            if index >= nv {
                return Err(src.out_of_range(lines.place(), f, index, n_vertices));
            }
            polygon.push(index as u32); // < nv <= 2^32
        }
        triangles.fan(&polygon);
        face += 1;
    }
    // A face count short of the file's faces would drop the faces after
    // it (a vertex count short of the vertices shifts them into the faces,
    // which then either fail to parse or run past the face count).
    if next_record(&mut lines, src)? {
        return Err(src.malformed(
            lines.place(),
            format!(
                "the file goes on after the {nv} vertices and {nf} faces that the counts on \
                 {counts_place} announce: a count is short, and what follows would be lost; \
                 correct the counts"
            ),
        ));
    }
    Ok(vertices)
}
