//! The mesh stored beside the compressed tree, random-accessible by
//! triangle id in O(1).
//!
//! Vertices are quantized to `vertex_bits` per coordinate over the mesh's
//! bounding box (round to nearest), or kept as raw `f32` bits (lossless).
//! The x, y and z values and the triangles' vertex indices are stored as
//! four frame-of-reference arrays ([`ForArray`]): blocks of 128 values, each
//! block holding its minimum and the offsets from it in as many bits as the
//! block's largest offset needs. Consecutive triangles (and their vertices)
//! are usually close in the mesh's own order, so blocks are narrow, and any
//! value is one block-head read and one bit-field read away.
//!
//! This is *not* the paper's RACM (§4.5), which codes connectivity and
//! predicted positions cluster by cluster and needs a cache of decoded mesh
//! clusters; with the tree's leaves in layout order and the triangles in
//! mesh order, that cache would be hit in scattered order.
//!
//! # Layout of a [`ForArray`]
//! `len: u64`, `data_len: u64`, then per block of 128 values a 16-byte head
//! (`base: u32`, `width: u32`, bit offset in the data: `u64`), then
//! `data_len` bytes of offsets. All little-endian.

use glam::Vec3A;

use super::RacError;
use super::file::Store;
use crate::codec::common::FormatError;
use crate::codec::common::le::{u32_at, u64_at};
use crate::geom::Triangle;
use crate::mesh::Mesh;

/// Reads `bits` (≤ 32) bits at bit offset `at` of `data`; out-of-range
/// bytes read as zero.
#[inline]
fn get_bits(data: &[u8], at: u64, bits: u32) -> u32 {
    let byte = (at >> 3) as usize;
    let shift = (at & 7) as u32;
    let word = match data.get(byte..byte + 8) {
        Some(s) => u64::from_le_bytes([s[0], s[1], s[2], s[3], s[4], s[5], s[6], s[7]]),
        None => {
            let mut b = [0u8; 8];
            if let Some(s) = data.get(byte..) {
                let n = s.len().min(8);
                b[..n].copy_from_slice(&s[..n]);
            }
            u64::from_le_bytes(b)
        }
    };
    ((word >> shift) & ((1u64 << bits) - 1)) as u32
}

fn put_bits(data: &mut [u8], at: u64, bits: u32, v: u32) {
    for k in 0..u64::from(bits) {
        if (v >> k) & 1 == 1 {
            let p = at + k;
            data[(p >> 3) as usize] |= 1 << (p & 7);
        }
    }
}

/// Bits needed to store values `0..n` (at least 1).
pub fn bits_for(n: u64) -> u32 {
    (64 - n.saturating_sub(1).leading_zeros()).max(1)
}

/// Values per [`ForArray`] block.
const BLOCK: usize = 128;

/// A view of one frame-of-reference array inside a byte blob (see the
/// module docs for the layout).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ForArray {
    len: u64,
    heads: usize,
    data: usize,
    data_len: usize,
}

impl ForArray {
    const EMPTY: ForArray = ForArray {
        len: 0,
        heads: 0,
        data: 0,
        data_len: 0,
    };

    /// Appends the array of `values` to `out`.
    pub fn write(values: &[u32], out: &mut Vec<u8>) {
        let mut heads = Vec::new();
        let mut data = vec![0u8; 0];
        let mut bit = 0u64;
        for chunk in values.chunks(BLOCK) {
            let base = chunk.iter().copied().min().unwrap_or(0);
            let span = chunk.iter().map(|&v| v - base).max().unwrap_or(0);
            let width = 32 - span.leading_zeros();
            heads.extend_from_slice(&base.to_le_bytes());
            heads.extend_from_slice(&width.to_le_bytes());
            heads.extend_from_slice(&bit.to_le_bytes());
            data.resize(
                (bit + chunk.len() as u64 * u64::from(width)).div_ceil(8) as usize,
                0,
            );
            for &v in chunk {
                put_bits(&mut data, bit, width, v - base);
                bit += u64::from(width);
            }
        }
        out.extend_from_slice(&(values.len() as u64).to_le_bytes());
        out.extend_from_slice(&(data.len() as u64).to_le_bytes());
        out.extend_from_slice(&heads);
        out.extend_from_slice(&data);
    }

    /// Parses the array starting at `at` of `b`, checking every block head;
    /// returns it and the offset just past it.
    pub fn parse(b: &[u8], at: usize, section: &'static str) -> Result<(Self, usize), RacError> {
        let short = |need: u64| FormatError::Truncated {
            section,
            need,
            have: b.len() as u64,
        };
        let fixed = at.checked_add(16).ok_or(short(u64::MAX))?;
        if fixed > b.len() {
            return Err(short(fixed as u64).into());
        }
        let len = u64_at(b, at);
        let data_len = u64_at(b, at + 8);
        let blocks = len.div_ceil(BLOCK as u64);
        let end = blocks
            .checked_mul(16)
            .and_then(|h| h.checked_add(fixed as u64))
            .and_then(|d| d.checked_add(data_len).map(|e| (d, e)))
            .ok_or(short(u64::MAX))?;
        if end.1 > b.len() as u64 {
            return Err(short(end.1).into());
        }
        let arr = Self {
            len,
            heads: fixed,
            data: end.0 as usize,
            data_len: data_len as usize,
        };
        for k in 0..blocks as usize {
            let h = fixed + 16 * k;
            let (width, off) = (u32_at(b, h + 4), u64_at(b, h + 8));
            let count = (len - (k * BLOCK) as u64).min(BLOCK as u64);
            let stop = off.checked_add(count * u64::from(width));
            if width > 32 || stop.is_none_or(|x| x > data_len * 8) {
                return Err(RacError::Corrupt("a mesh block head is out of range"));
            }
        }
        Ok((arr, end.1 as usize))
    }

    /// Value `i` (`i < len`), read from the blob the array was parsed from.
    #[inline]
    pub fn get(&self, b: &[u8], i: u64) -> u32 {
        let h = self.heads + 16 * (i as usize / BLOCK);
        let (base, width, off) = (u32_at(b, h), u32_at(b, h + 4), u64_at(b, h + 8));
        let data = &b[self.data..self.data + self.data_len];
        base.wrapping_add(get_bits(
            data,
            off + (i % BLOCK as u64) * u64::from(width),
            width,
        ))
    }

    /// Number of values.
    pub fn len(&self) -> u64 {
        self.len
    }

    /// Whether the array has no values.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

/// The stored mesh.
#[derive(Clone, Debug)]
pub struct PackedMesh {
    /// Bits per vertex coordinate (32 = raw `f32`).
    pub(super) vertex_bits: u32,
    /// Whether coordinates are raw `f32` bits.
    pub(super) lossless: bool,
    /// Quantization origin (unused when lossless).
    pub(super) origin: [f32; 3],
    /// Quantization step per axis (unused when lossless).
    pub(super) step: [f32; 3],
    pub(super) vertex_count: u32,
    pub(super) triangle_count: u32,
    /// Bits per vertex index (recorded in the header, checked on reading).
    pub(super) index_bits: u32,
    /// The x, y, z arrays, back to back.
    pub(super) vertices: Store,
    /// The vertex-index array (three per triangle).
    pub(super) triangles: Store,
    axes: [ForArray; 3],
    indices: ForArray,
}

/// The scalar fields of a [`PackedMesh`], as the container header holds them.
pub struct MeshParams {
    /// Bits per vertex coordinate (32 = raw `f32`).
    pub vertex_bits: u32,
    /// Whether coordinates are raw `f32` bits.
    pub lossless: bool,
    /// Quantization origin.
    pub origin: [f32; 3],
    /// Quantization step.
    pub step: [f32; 3],
    /// Number of vertices.
    pub vertex_count: u32,
    /// Number of triangles.
    pub triangle_count: u32,
    /// Bits per vertex index.
    pub index_bits: u32,
}

impl PackedMesh {
    /// Packs `mesh` with `vertex_bits` bits per coordinate (`None`: lossless).
    pub fn encode(mesh: &Mesh, vertex_bits: Option<u32>) -> Result<Self, RacError> {
        let vc = u32::try_from(mesh.vertices.len())
            .map_err(|_| RacError::InvalidMesh("more than 2^32 vertices".into()))?;
        let tc = u32::try_from(mesh.triangles.len())
            .map_err(|_| RacError::InvalidMesh("more than 2^32 triangles".into()))?;
        let (lossless, vbits) = match vertex_bits {
            None => (true, 32),
            Some(b) => (false, b),
        };
        let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        for v in &mesh.vertices {
            for a in 0..3 {
                if !v[a].is_finite() || v[a].abs() > crate::mesh::MAX_COORDINATE {
                    return Err(RacError::InvalidMesh(format!(
                        "vertex coordinate {} is not finite or beyond ±{:e}, the supported range",
                        v[a],
                        crate::mesh::MAX_COORDINATE
                    )));
                }
                lo[a] = lo[a].min(v[a]);
                hi[a] = hi[a].max(v[a]);
            }
        }
        let maxq = ((1u64 << vbits.min(31)) - 1) as f32;
        let mut step = [0f32; 3];
        let mut origin = [0f32; 3];
        if !mesh.vertices.is_empty() {
            origin = lo;
            for a in 0..3 {
                let e = hi[a] - lo[a];
                if !e.is_finite() {
                    return Err(RacError::InvalidMesh(
                        "the mesh's extent overflows f32".into(),
                    ));
                }
                step[a] = if e > 0.0 { e / maxq } else { 0.0 };
            }
        }
        let mut axes = [Vec::new(), Vec::new(), Vec::new()];
        for v in &mesh.vertices {
            for a in 0..3 {
                axes[a].push(if lossless {
                    v[a].to_bits()
                } else if step[a] == 0.0 {
                    0
                } else {
                    ((v[a] - origin[a]) / step[a]).round().clamp(0.0, maxq) as u32
                });
            }
        }
        let mut vdata = Vec::new();
        for axis in &axes {
            ForArray::write(axis, &mut vdata);
        }
        let mut flat = Vec::with_capacity(mesh.triangles.len() * 3);
        for (t, tri) in mesh.triangles.iter().enumerate() {
            for &i in tri {
                if i >= vc {
                    return Err(RacError::InvalidMesh(format!(
                        "triangle {t} refers to missing vertex {i}"
                    )));
                }
                flat.push(i);
            }
        }
        let mut tdata = Vec::new();
        ForArray::write(&flat, &mut tdata);
        let params = MeshParams {
            vertex_bits: vbits,
            lossless,
            origin,
            step,
            vertex_count: vc,
            triangle_count: tc,
            index_bits: bits_for(u64::from(vc)),
        };
        Self::from_parts(params, Store::Owned(vdata), Store::Owned(tdata))
    }

    /// A mesh from its header fields and its two sections, checking the
    /// arrays' block heads and lengths (O(blocks)).
    pub fn from_parts(p: MeshParams, vertices: Store, triangles: Store) -> Result<Self, RacError> {
        let mut at = 0;
        let mut axes = [ForArray::EMPTY; 3];
        for axis in &mut axes {
            let (arr, next) = ForArray::parse(&vertices, at, "vertices")?;
            if arr.len() != u64::from(p.vertex_count) {
                return Err(RacError::Corrupt("a vertex array has the wrong length"));
            }
            *axis = arr;
            at = next;
        }
        let (indices, _) = ForArray::parse(&triangles, 0, "triangles")?;
        if indices.len() != 3 * u64::from(p.triangle_count) {
            return Err(RacError::Corrupt(
                "the vertex-index array has the wrong length",
            ));
        }
        Ok(Self {
            vertex_bits: p.vertex_bits,
            lossless: p.lossless,
            origin: p.origin,
            step: p.step,
            vertex_count: p.vertex_count,
            triangle_count: p.triangle_count,
            index_bits: p.index_bits,
            vertices,
            triangles,
            axes,
            indices,
        })
    }

    /// Vertex `i`, decoded.
    #[inline]
    pub fn vertex(&self, i: u32) -> Vec3A {
        let q = self.axes.map(|a| a.get(&self.vertices, u64::from(i)));
        if self.lossless {
            Vec3A::from(q.map(f32::from_bits))
        } else {
            Vec3A::from(self.origin)
                + Vec3A::new(q[0] as f32, q[1] as f32, q[2] as f32) * Vec3A::from(self.step)
        }
    }

    /// The vertex indices of triangle `t`.
    #[inline]
    pub fn indices(&self, t: u32) -> [u32; 3] {
        let at = 3 * u64::from(t);
        [0, 1, 2].map(|c| self.indices.get(&self.triangles, at + c))
    }

    /// The corners of triangle `t`.
    ///
    /// # Panics
    /// If a vertex index is out of range (corrupted bytes that
    /// [`check`](Self::check) would have reported).
    #[inline]
    pub fn triangle(&self, t: u32) -> Triangle {
        let idx = self.indices(t);
        assert!(
            idx.iter().all(|&i| i < self.vertex_count),
            "racbvh: triangle {t} of the stored mesh refers to a missing vertex (corrupted data; run verify())"
        );
        idx.map(|i| self.vertex(i))
    }

    /// Checks every vertex index.
    pub fn check(&self) -> Result<(), RacError> {
        for t in 0..self.triangle_count {
            if self.indices(t).iter().any(|&i| i >= self.vertex_count) {
                return Err(RacError::Corrupt(
                    "a stored triangle refers to a missing vertex",
                ));
            }
        }
        Ok(())
    }

    /// The mesh as stored (quantized vertices decoded).
    pub fn decoded(&self) -> Mesh {
        Mesh::new(
            (0..self.vertex_count)
                .map(|i| self.vertex(i).to_array())
                .collect(),
            (0..self.triangle_count).map(|t| self.indices(t)).collect(),
        )
    }

    /// Stored bytes (the two sections and the header fields).
    pub fn bytes(&self) -> usize {
        self.vertices.len() + self.triangles.len() + 48
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_of_reference_arrays_round_trip_and_reject_bad_heads() {
        let values: Vec<u32> = (0..1000u32)
            .map(|i| match i % 7 {
                0 => u32::MAX,
                1 => 0,
                _ => 5000 + i * 3,
            })
            .chain(std::iter::repeat_n(42, 300))
            .collect();
        let mut blob = vec![9u8; 5];
        ForArray::write(&values, &mut blob);
        ForArray::write(&[], &mut blob);
        let (arr, next) = ForArray::parse(&blob, 5, "test").unwrap();
        assert_eq!(arr.len(), values.len() as u64);
        for (i, &v) in values.iter().enumerate() {
            assert_eq!(arr.get(&blob, i as u64), v);
        }
        let (empty, end) = ForArray::parse(&blob, next, "test").unwrap();
        assert!(empty.is_empty());
        assert_eq!(end, blob.len());
        // A width above 32 or a truncated blob is an error, not a panic.
        let mut bad = blob.clone();
        bad[5 + 16 + 4] = 33;
        assert!(ForArray::parse(&bad, 5, "test").is_err());
        assert!(ForArray::parse(&blob[..next - 1], 5, "test").is_err());
    }
}
