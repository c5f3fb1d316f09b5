//! The mesh stored beside the compressed tree, random-accessible by
//! triangle id in O(1).
//!
//! Vertices are quantized to `vertex_bits` per coordinate over the mesh's
//! bounding box (round to nearest), or kept as raw `f32` bits (lossless).
//! The x, y and z values and the triangles' vertex indices are stored as
//! four frame-of-reference arrays ([`ForArray`], laid out as its module
//! [`packed`](crate::codec::common::packed) says): blocks of 128 values,
//! each block holding its minimum and the offsets from it in as many bits
//! as the block's largest offset needs. Consecutive triangles (and their
//! vertices) are usually close in the mesh's own order, so blocks are
//! narrow, and any value is one block-head read and one bit-field read
//! away.
//!
//! This is *not* the paper's RACM (§4.5), which codes connectivity and
//! predicted positions cluster by cluster and needs a cache of decoded mesh
//! clusters; with the tree's leaves in layout order and the triangles in
//! mesh order, that cache would be hit in scattered order.

use glam::Vec3A;

use super::RacError;
use crate::codec::common::Store;
use crate::codec::common::packed::{ForArray, bits_for};
use crate::geom::Triangle;
use crate::mesh::Mesh;

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

/// A vertex as stored, `q`, decoded: the one formula the reader and the
/// encoders (which box the triangles as the reader will see them) share.
#[inline]
fn decode_vertex(lossless: bool, origin: [f32; 3], step: [f32; 3], q: [u32; 3]) -> Vec3A {
    if lossless {
        Vec3A::from(q.map(f32::from_bits))
    } else {
        Vec3A::from(origin) + Vec3A::new(q[0] as f32, q[1] as f32, q[2] as f32) * Vec3A::from(step)
    }
}

/// How a mesh's vertices are stored: quantized over the box of all of
/// them (round to nearest), or as raw `f32` bits. [`PackedMesh::encode`]
/// stores a mesh through it, and the out-of-core encoder its model's
/// vertices, whose chunks it boxes with [`stored`](Self::stored).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct VertexCoder {
    lossless: bool,
    bits: u32,
    origin: [f32; 3],
    step: [f32; 3],
    maxq: f32,
}

impl VertexCoder {
    /// The coder for `vertices` with `vertex_bits` bits (`None`: lossless).
    ///
    /// # Errors
    /// A coordinate not finite or beyond [`crate::mesh::MAX_COORDINATE`],
    /// an extent that overflows `f32`.
    pub(super) fn of(vertices: &[[f32; 3]], vertex_bits: Option<u32>) -> Result<Self, RacError> {
        let (lossless, bits) = match vertex_bits {
            None => (true, 32),
            Some(b) => (false, b),
        };
        let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        for v in vertices {
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
        let maxq = ((1u64 << bits.min(31)) - 1) as f32;
        let mut step = [0f32; 3];
        let mut origin = [0f32; 3];
        if !vertices.is_empty() {
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
        Ok(Self {
            lossless,
            bits,
            origin,
            step,
            maxq,
        })
    }

    /// Vertex `v` as stored.
    #[inline]
    pub(super) fn quantize(&self, v: [f32; 3]) -> [u32; 3] {
        std::array::from_fn(|a| {
            if self.lossless {
                v[a].to_bits()
            } else if self.step[a] == 0.0 {
                0
            } else {
                ((v[a] - self.origin[a]) / self.step[a])
                    .round()
                    .clamp(0.0, self.maxq) as u32
            }
        })
    }

    /// Vertex `v` as the reader decodes it.
    #[inline]
    pub(super) fn stored(&self, v: [f32; 3]) -> Vec3A {
        decode_vertex(self.lossless, self.origin, self.step, self.quantize(v))
    }

    /// The header's fields for `vertices` vertices and `triangles`
    /// triangles stored through this coder.
    pub(super) fn params(&self, vertices: u32, triangles: u32) -> MeshParams {
        MeshParams {
            vertex_bits: self.bits,
            lossless: self.lossless,
            origin: self.origin,
            step: self.step,
            vertex_count: vertices,
            triangle_count: triangles,
            index_bits: bits_for(u64::from(vertices)),
        }
    }
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
        let coder = VertexCoder::of(&mesh.vertices, vertex_bits)?;
        let mut axes = [Vec::new(), Vec::new(), Vec::new()];
        for v in &mesh.vertices {
            let q = coder.quantize(*v);
            for a in 0..3 {
                axes[a].push(q[a]);
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
        let params = coder.params(vc, tc);
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
        decode_vertex(self.lossless, self.origin, self.step, q)
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

    /// The header's fields.
    pub(super) fn params(&self) -> MeshParams {
        MeshParams {
            vertex_bits: self.vertex_bits,
            lossless: self.lossless,
            origin: self.origin,
            step: self.step,
            vertex_count: self.vertex_count,
            triangle_count: self.triangle_count,
            index_bits: self.index_bits,
        }
    }

    /// Stored bytes (the two sections and the header fields).
    pub fn bytes(&self) -> usize {
        self.vertices.len() + self.triangles.len() + 48
    }
}
