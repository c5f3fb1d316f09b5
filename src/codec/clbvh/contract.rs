//! CLBVH's [`Codec`] contract, twice: [`ClBvh`] (registry name `clbvh`,
//! fast leaves) and [`ClBvhCompact`] (`clbvh-compact`), both delegating to
//! [`ClBvh`]'s own methods. The registry names each type once, so the
//! compact variant is a type of its own.

use crate::codec::common::container::Frame;

use super::{ClBvh, ClBvhCompact, ClError, ClOptions, CompactOptions, LeafKind, file};
use crate::build::CanonicalBvh;
use crate::codec::common::{FormatError, MassProps};
use crate::codec::{Codec, CodecKind, OpenOptions};
use crate::contact::EdgeFlags;
use crate::mesh::Mesh;

fn wrong_kind(want: LeafKind) -> ClError {
    FormatError::header("magic", format!("not a CLBVH file with {want:?} leaves")).into()
}

fn header_fields(c: &ClBvh) -> Vec<(&'static str, String)> {
    vec![
        ("leaf size", c.options().leaf_size.to_string()),
        ("inner nodes", c.inner_nodes().len().to_string()),
        ("multi-leaf nodes", c.multi_leaf_count().to_string()),
        ("vertices", c.vertices().len().to_string()),
    ]
}

#[cfg(feature = "serde")]
fn build_fields(c: &ClBvh) -> Vec<(&'static str, serde_json::Value)> {
    vec![
        ("leaf_size", c.options().leaf_size.into()),
        ("inner_nodes", c.inner_nodes().len().into()),
        ("multi_leaf_nodes", c.multi_leaf_count().into()),
    ]
}

impl Codec for ClBvh {
    const KIND: CodecKind = CodecKind::Clbvh;
    const MAGIC: [u8; 8] = file::MAGIC;
    const FRAME: Frame = file::FRAME;
    /// `leaves` must be [`LeafKind::Fast`] (the compact variant is
    /// [`ClBvhCompact`]).
    type Options = ClOptions;
    type Error = ClError;

    fn encode(bvh: &CanonicalBvh, mesh: &Mesh, options: &ClOptions) -> Result<Self, ClError> {
        ClBvh::encode(
            bvh,
            mesh,
            &ClOptions {
                leaves: LeafKind::Fast,
                ..*options
            },
        )
    }

    fn triangle_vertices(&self, id: u32) -> [u32; 3] {
        self.vertex_indices(id)
    }

    fn decoded_mesh(&self) -> Mesh {
        ClBvh::decoded_mesh(self)
    }

    fn mass(&self) -> MassProps {
        ClBvh::mass(self)
    }

    fn edge_flags(&self) -> &EdgeFlags {
        ClBvh::edge_flags(self)
    }

    fn verify(&self) -> Result<(), ClError> {
        ClBvh::verify(self)
    }

    fn to_bytes(&self) -> Vec<u8> {
        ClBvh::to_bytes(self)
    }

    fn from_bytes(bytes: &[u8], _: &OpenOptions) -> Result<Self, ClError> {
        let t = ClBvh::from_bytes(bytes)?;
        if t.options().leaves != LeafKind::Fast {
            return Err(wrong_kind(LeafKind::Fast));
        }
        Ok(t)
    }

    fn header_fields(&self) -> Vec<(&'static str, String)> {
        header_fields(self)
    }

    #[cfg(feature = "serde")]
    fn build_fields(&self) -> Vec<(&'static str, serde_json::Value)> {
        build_fields(self)
    }
}

impl Codec for ClBvhCompact {
    const KIND: CodecKind = CodecKind::ClbvhCompact;
    const MAGIC: [u8; 8] = file::MAGIC_COMPACT;
    const FRAME: Frame = file::FRAME;
    type Options = CompactOptions;
    type Error = ClError;

    fn encode(bvh: &CanonicalBvh, mesh: &Mesh, o: &CompactOptions) -> Result<Self, ClError> {
        ClBvhCompact::encode(bvh, mesh, o)
    }

    fn triangle_vertices(&self, id: u32) -> [u32; 3] {
        self.0.vertex_indices(id)
    }

    fn decoded_mesh(&self) -> Mesh {
        self.0.decoded_mesh()
    }

    fn mass(&self) -> MassProps {
        self.0.mass()
    }

    fn edge_flags(&self) -> &EdgeFlags {
        self.0.edge_flags()
    }

    fn verify(&self) -> Result<(), ClError> {
        self.0.verify()
    }

    fn to_bytes(&self) -> Vec<u8> {
        self.0.to_bytes()
    }

    fn from_bytes(bytes: &[u8], _: &OpenOptions) -> Result<Self, ClError> {
        let t = ClBvh::from_bytes(bytes)?;
        if t.options().leaves != LeafKind::Compact {
            return Err(wrong_kind(LeafKind::Compact));
        }
        Ok(ClBvhCompact(t))
    }

    fn header_fields(&self) -> Vec<(&'static str, String)> {
        header_fields(&self.0)
    }

    #[cfg(feature = "serde")]
    fn build_fields(&self) -> Vec<(&'static str, serde_json::Value)> {
        build_fields(&self.0)
    }
}
