//! The `hcc-ooc` codec's [`Codec`] contract and its traversal: both
//! delegate to the decoded i-HCCMesh.

use std::path::Path;

use super::super::{HccBvh, HccNode};
use super::{HccOocBvh, OocError, OocOptions, file};
use crate::build::CanonicalBvh;
use crate::codec::common::MassProps;
use crate::codec::{ByteSize, Codec, CodecKind, OpenOptions};
use crate::cursor::{Children, NodeCursor};
use crate::geom::{Aabb, Triangle};
use crate::mesh::Mesh;

impl NodeCursor for HccOocBvh {
    type Node = HccNode;

    #[inline(always)]
    fn root(&self) -> (HccNode, Aabb) {
        self.hcc.root()
    }

    #[inline(always)]
    fn is_leaf(&self, node: &HccNode) -> bool {
        self.hcc.is_leaf(node)
    }

    #[inline]
    fn for_each_child(&self, node: &HccNode, f: impl FnMut(HccNode, Aabb)) {
        self.hcc.for_each_child(node, f)
    }

    #[inline(always)]
    fn children(&self, node: &HccNode, out: &mut Children<HccNode>) {
        self.hcc.children(node, out)
    }

    #[inline]
    fn for_each_triangle(&self, node: &HccNode, f: impl FnMut(u32, &Triangle)) {
        self.hcc.for_each_triangle(node, f)
    }

    fn triangle(&self, id: u32) -> Triangle {
        self.hcc.triangle(id)
    }

    fn triangle_count(&self) -> usize {
        self.hcc.triangle_count()
    }
}

impl Codec for HccOocBvh {
    const KIND: CodecKind = CodecKind::HccOoc;
    const MAGIC: [u8; 8] = file::MAGIC;
    /// Grid bits and which id maps to keep (default: 16 bits, tree order).
    type Options = OocOptions;
    type Error = OocError;

    fn encode(bvh: &CanonicalBvh, mesh: &Mesh, options: &OocOptions) -> Result<Self, OocError> {
        HccOocBvh::encode_with(bvh, mesh, options)
    }

    fn triangle_vertices(&self, id: u32) -> [u32; 3] {
        self.hcc.triangle_vertex_indices(id)
    }

    fn decoded_mesh(&self) -> Mesh {
        self.hcc.decoded_mesh()
    }

    fn mass(&self) -> MassProps {
        self.hcc.mass()
    }

    fn verify(&self) -> Result<(), OocError> {
        Ok(self.hcc.verify()?)
    }

    fn save(&self, path: &Path) -> Result<(), OocError> {
        HccOocBvh::save(self, path)
    }

    fn to_bytes(&self) -> Vec<u8> {
        self.file.clone()
    }

    /// Decodes the bytes into the i-HCCMesh (the options do not apply).
    fn from_bytes(bytes: &[u8], _: &OpenOptions) -> Result<Self, OocError> {
        HccOocBvh::from_bytes(bytes)
    }

    /// Reads the whole file and decodes it (the options do not apply).
    fn open(path: &Path, _: &OpenOptions) -> Result<Self, OocError> {
        HccOocBvh::open(path)
    }

    fn header_fields(&self) -> Vec<(&'static str, String)> {
        let mut out = vec![(
            "o-HCCMesh file",
            format!(
                "{} bytes, {:.2} a triangle",
                self.file.len(),
                self.file.len() as f64 / self.hcc.triangle_count().max(1) as f64
            ),
        )];
        out.extend(<HccBvh as Codec>::header_fields(&self.hcc));
        out
    }

    fn build_fields(&self) -> Vec<(&'static str, serde_json::Value)> {
        let n = self.hcc.triangle_count().max(1) as f64;
        let mut out = vec![(
            "file_bytes_per_triangle",
            (self.file.len() as f64 / n).into(),
        )];
        if let Some(s) = &self.sizes {
            let parts: serde_json::Map<String, serde_json::Value> = s
                .parts()
                .into_iter()
                .map(|(p, b)| (p.to_string(), (b / n).into()))
                .collect();
            out.push(("file_bytes_per_triangle_by_part", parts.into()));
        }
        let memory: serde_json::Map<String, serde_json::Value> = self
            .bytes_by_part()
            .into_iter()
            .map(|(p, b)| (p.to_string(), (b as f64 / n).into()))
            .collect();
        out.extend(
            <HccBvh as Codec>::build_fields(&self.hcc)
                .into_iter()
                .filter(|(k, _)| *k != "bytes_per_triangle_by_part"),
        );
        out.push(("bytes_per_triangle_by_part", memory.into()));
        out
    }
}
