//! The plain codec's [`Codec`] contract, delegating to [`PlainBvh`]'s own
//! methods.

use crate::codec::common::container::Frame;

use super::{PlainBvh, PlainError, file};
use crate::build::CanonicalBvh;
use crate::codec::common::MassProps;
use crate::codec::{Codec, CodecKind, OpenOptions};
use crate::contact::EdgeFlags;
use crate::mesh::Mesh;

impl Codec for PlainBvh {
    const KIND: CodecKind = CodecKind::Plain;
    const MAGIC: [u8; 8] = file::MAGIC;
    const FRAME: Frame = file::FRAME;
    /// The plain codec has nothing to choose: no settings of its own, and
    /// `f32` vertices whatever `vertex_bits` says.
    type Options = ();
    type Error = PlainError;

    fn encode(bvh: &CanonicalBvh, mesh: &Mesh, _: &()) -> Result<Self, PlainError> {
        PlainBvh::encode(bvh, mesh)
    }

    fn triangle_vertices(&self, id: u32) -> [u32; 3] {
        self.triangles()[id as usize]
    }

    fn decoded_mesh(&self) -> Mesh {
        Mesh::new(self.vertices().to_vec(), self.triangles().to_vec())
    }

    fn mass(&self) -> MassProps {
        PlainBvh::mass(self)
    }

    fn edge_flags(&self) -> &EdgeFlags {
        PlainBvh::edge_flags(self)
    }

    fn verify(&self) -> Result<(), PlainError> {
        PlainBvh::verify(self)
    }

    fn to_bytes(&self) -> Vec<u8> {
        PlainBvh::to_bytes(self)
    }

    /// Copies the bytes (the options do not apply).
    fn from_bytes(bytes: &[u8], _: &OpenOptions) -> Result<Self, PlainError> {
        PlainBvh::from_bytes(bytes)
    }

    fn header_fields(&self) -> Vec<(&'static str, String)> {
        vec![
            ("nodes", self.nodes().len().to_string()),
            ("vertices", self.vertices().len().to_string()),
        ]
    }

    #[cfg(feature = "serde")]
    fn build_fields(&self) -> Vec<(&'static str, serde_json::Value)> {
        vec![
            ("nodes", self.nodes().len().into()),
            ("height", self.height().into()),
        ]
    }
}
