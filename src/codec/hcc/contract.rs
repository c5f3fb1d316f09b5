//! The i-HCCMesh's [`Codec`] contract, delegating to [`HccBvh`]'s own
//! methods.

use crate::codec::common::container::Frame;

use super::{HccBvh, HccError, HccOptions, file};
use crate::build::CanonicalBvh;
use crate::codec::common::MassProps;
use crate::codec::{Codec, CodecKind, OpenOptions};
use crate::contact::EdgeFlags;
use crate::mesh::Mesh;
// The build figures' byte and triangle counts.
#[cfg(feature = "serde")]
use crate::{codec::ByteSize, cursor::NodeCursor};

impl Codec for HccBvh {
    const KIND: CodecKind = CodecKind::Hcc;
    const MAGIC: [u8; 8] = file::MAGIC;
    const FRAME: Frame = file::FRAME;
    /// Vertex format, vertex ids and triangle ids; the canonical tree's leaf size picks
    /// one triangle a leaf (the paper's form) or multi-triangle leaves.
    type Options = HccOptions;
    type Error = HccError;

    fn encode(bvh: &CanonicalBvh, mesh: &Mesh, options: &HccOptions) -> Result<Self, HccError> {
        HccBvh::encode_with(bvh, mesh, options)
    }

    fn triangle_vertices(&self, id: u32) -> [u32; 3] {
        self.triangle_vertex_indices(id)
    }

    /// The stored mesh, triangles in input order (the input mesh itself
    /// with `f32` vertices and both id maps kept), or in storage order
    /// without triangle ids.
    fn decoded_mesh(&self) -> Mesh {
        HccBvh::decoded_mesh(self)
    }

    fn mass(&self) -> MassProps {
        HccBvh::mass(self)
    }

    fn edge_flags(&self) -> &EdgeFlags {
        HccBvh::edge_flags(self)
    }

    fn verify(&self) -> Result<(), HccError> {
        HccBvh::verify(self)
    }

    fn to_bytes(&self) -> Vec<u8> {
        HccBvh::to_bytes(self)
    }

    /// Copies the bytes (the options do not apply).
    fn from_bytes(bytes: &[u8], _: &OpenOptions) -> Result<Self, HccError> {
        HccBvh::from_bytes(bytes)
    }

    fn header_fields(&self) -> Vec<(&'static str, String)> {
        let vertices = match self.vertex_bits() {
            None => "f32 (lossless)".to_string(),
            Some(b) => {
                let [x, y, z] = self.vertex_error();
                format!("{b}-bit grid over the mesh, error at most ({x:e}, {y:e}, {z:e})")
            }
        };
        vec![
            ("low-level trees", self.tree_count().to_string()),
            ("multi-triangle leaves", self.is_multi().to_string()),
            ("vertices", vertices),
            ("stored vertices", self.stats().tree_vertices.to_string()),
            (
                "input mesh",
                format!(
                    "{} vertices, {} of them used",
                    self.mesh_vertices,
                    self.stats().mesh_vertices
                ),
            ),
            ("vertex ids", self.has_vertex_ids().to_string()),
            (
                "triangle ids",
                if self.has_triangle_ids() {
                    "input's".to_string()
                } else {
                    "tree order".to_string()
                },
            ),
        ]
    }

    #[cfg(feature = "serde")]
    fn build_fields(&self) -> Vec<(&'static str, serde_json::Value)> {
        let st = self.stats();
        let n = self.triangle_count().max(1) as f64;
        let parts: serde_json::Map<String, serde_json::Value> = self
            .bytes_by_part()
            .into_iter()
            .map(|(p, b)| (p.to_string(), (b as f64 / n).into()))
            .collect();
        vec![
            ("low_level_trees", st.trees.into()),
            ("multi_triangle_leaves", self.is_multi().into()),
            ("vertex_bits", self.vertex_bits().into()),
            ("vertex_error", self.vertex_error().to_vec().into()),
            ("vertex_ids", self.has_vertex_ids().into()),
            ("triangle_ids", self.has_triangle_ids().into()),
            ("duplicated_vertices", st.duplicated_fraction().into()),
            ("loose_extents", st.loose_extents.into()),
            ("bytes_per_triangle_by_part", parts.into()),
        ]
    }
}
