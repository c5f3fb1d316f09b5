//! The Wavefront OBJ reader (positions and faces only) and writer.
//!
//! The reader keeps one global vertex list, as the format defines it, so
//! groups and objects (`g`, `o`) share vertices and unreferenced vertices
//! are kept. Faces `f` may use `v`, `v/vt`, `v//vn`, `v/vt/vn` corners and
//! negative (relative) indices; polygons are fan-triangulated. Texture
//! coordinates, normals, materials, lines, points and any unknown statements
//! are ignored. A line ending in `\` continues on the next line.

use std::io::{self, BufRead, Write};

use rayon::prelude::*;

use super::{
    Lines, Src, Tris, finite, parse_f32, parse_i64, show, tokens_before_comment, write_u64,
};
use crate::mesh::{Mesh, MeshError, Place};

/// A face corner that refers to a vertex not yet defined when it was read.
struct Forward {
    face: usize,
    index: u64,
    line: usize,
}

pub(super) fn read<R: BufRead>(
    reader: R,
    src: &Src,
    triangles: &mut Tris<'_>,
) -> Result<Vec<[f32; 3]>, MeshError> {
    let mut lines = Lines::new(reader);
    let mut vertices: Vec<[f32; 3]> = Vec::new();
    let mut polygon: Vec<u32> = Vec::new();
    let mut forward: Vec<Forward> = Vec::new();
    let mut joined: Vec<u8> = Vec::new();
    let mut face = 0usize;
    loop {
        if !lines.advance().map_err(|e| src.io(e))? {
            break;
        }
        // Gather continuation lines; errors name the first line.
        let line_no = lines.line();
        let place = Place::Line(line_no);
        let text: &[u8] = if lines.text().ends_with(b"\\") {
            joined.clear();
            loop {
                let t = lines.text();
                match t.strip_suffix(b"\\") {
                    Some(head) => {
                        joined.extend_from_slice(head);
                        joined.push(b' ');
                        if !lines.advance().map_err(|e| src.io(e))? {
                            break;
                        }
                    }
                    None => {
                        joined.extend_from_slice(t);
                        break;
                    }
                }
            }
            &joined
        } else {
            lines.text()
        };
        let mut toks = tokens_before_comment(text);
        match toks.next() {
            Some(b"v") => {
                let vertex = vertices.len();
                let mut v = [0f32; 3];
                for (k, c) in v.iter_mut().enumerate() {
                    let axis = ["x", "y", "z"][k];
                    let Some(t) = toks.next() else {
                        return Err(src.malformed(
                            place,
                            format!("vertex {vertex} has {k} coordinates, 3 are needed"),
                        ));
                    };
                    *c = parse_f32(t).ok_or_else(|| {
                        src.malformed(
                            place,
                            format!(
                                "vertex {vertex}: expected the {axis} coordinate, found {}",
                                show(t)
                            ),
                        )
                    })?;
                }
                if !finite(&v) {
                    return Err(src.non_finite(place, vertex));
                }
                if vertices.len() > u32::MAX as usize {
                    return Err(src.malformed(place, "more than 2^32 vertices"));
                }
                vertices.push(v);
            }
            Some(b"f") => {
                polygon.clear();
                for t in toks {
                    let head = t.split(|&b| b == b'/').next().unwrap_or_default();
                    let Some(i) = parse_i64(head) else {
                        return Err(src.malformed(
                            place,
                            format!("face {face}: expected a vertex index, found {}", show(t)),
                        ));
                    };
                    let n = vertices.len() as i64; // at most 2^32
                    let resolved = match i {
                        0 => {
                            return Err(src.malformed(
                                place,
                                format!("face {face}: vertex index 0 is invalid (OBJ indices start at 1)"),
                            ));
                        }
                        i if i < 0 => {
                            let r = n + i; // cannot overflow: 0 <= n <= 2^32
                            if i < -n {
                                return Err(src.malformed(
                                    place,
                                    format!(
                                        "face {face}: relative index {i} reaches before the first vertex \
                                         ({n} vertices are defined so far)"
                                    ),
                                ));
                            }
                            r as u64
                        }
                        i => {
                            let r = (i - 1) as u64;
                            if r >= n as u64 {
                                if r > u64::from(u32::MAX) {
                                    // Quote the index as the file writes it (1-based).
                                    return Err(src.out_of_range(
                                        place,
                                        face,
                                        i as u64,
                                        vertices.len(),
                                    ));
                                }
                                forward.push(Forward {
                                    face,
                                    index: r,
                                    line: line_no,
                                });
                            }
                            r
                        }
                    };
                    polygon.push(resolved as u32); // <= u32::MAX, checked above
                }
                if polygon.len() < 3 {
                    return Err(src.malformed(
                        place,
                        format!(
                            "face {face} has {} corners; a face needs at least 3",
                            polygon.len()
                        ),
                    ));
                }
                triangles.fan(&polygon);
                face += 1;
            }
            _ => {}
        }
    }
    let n = vertices.len();
    if let Some(bad) = forward.iter().find(|f| f.index >= n as u64) {
        // Quote the index as the file writes it (1-based).
        return Err(src.out_of_range(Place::Line(bad.line), bad.face, bad.index + 1, n));
    }
    Ok(vertices)
}

/// Writes `mesh` as OBJ: `v x y z` lines with shortest round-trip decimals,
/// then `f a b c` lines with 1-based indices. Lines are formatted in
/// parallel, a batch at a time, and written in order.
pub(super) fn write(mesh: &Mesh, out: &mut impl Write) -> io::Result<()> {
    writeln!(
        out,
        "# written by cbvh: {} vertices, {} triangles",
        mesh.vertices.len(),
        mesh.triangles.len()
    )?;
    write_parallel(&mesh.vertices, out, |buf, v| {
        // Display for f32 prints the shortest decimal that parses back to
        // the same value, so the round trip is exact.
        writeln!(buf, "v {} {} {}", v[0], v[1], v[2])
    })?;
    write_parallel(&mesh.triangles, out, |buf, t| {
        buf.push(b'f');
        for &i in t {
            buf.push(b' ');
            write_u64(buf, u64::from(i) + 1);
        }
        buf.push(b'\n');
        Ok(())
    })
}

/// Formats `items` with `line` on all cores, in batches so that memory stays
/// bounded, and writes the text in order.
fn write_parallel<T: Sync>(
    items: &[T],
    out: &mut impl Write,
    line: impl Fn(&mut Vec<u8>, &T) -> io::Result<()> + Sync,
) -> io::Result<()> {
    const PIECE: usize = 1 << 14;
    const BATCH: usize = PIECE * 64;
    for batch in items.chunks(BATCH) {
        let pieces = batch
            .par_chunks(PIECE)
            .map(|piece| {
                let mut buf = Vec::with_capacity(piece.len() * 32);
                for item in piece {
                    line(&mut buf, item)?;
                }
                Ok(buf)
            })
            .collect::<io::Result<Vec<Vec<u8>>>>()?;
        for piece in pieces {
            out.write_all(&piece)?;
        }
    }
    Ok(())
}
