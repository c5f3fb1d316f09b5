//! RACBVH's [`Codec`] contract, delegating to [`RacBvh`]'s own methods.

use crate::codec::common::container::Frame;
use std::path::Path;

use super::{RacBvh, RacError, RacOptions, file};
use crate::build::chunked::{ChunkedMesh, Progress};
use crate::build::{BuildOptions, CanonicalBvh};
use crate::codec::common::MassProps;
use crate::codec::{Codec, CodecKind, OpenOptions, StreamedReport};
use crate::contact::EdgeFlags;
use crate::mesh::Mesh;

impl Codec for RacBvh {
    const KIND: CodecKind = CodecKind::Racbvh;
    const MAGIC: [u8; 8] = file::MAGIC;
    const FRAME: Frame = file::FRAME;
    type Options = RacOptions;
    type Error = RacError;

    fn encode(bvh: &CanonicalBvh, mesh: &Mesh, options: &RacOptions) -> Result<Self, RacError> {
        RacBvh::encode(bvh, mesh, options)
    }

    /// Clusters are compressed in parallel; `progress` counts clusters.
    fn encode_with_progress(
        bvh: &CanonicalBvh,
        mesh: &Mesh,
        options: &RacOptions,
        progress: &(dyn Fn(u64, u64) + Sync),
    ) -> Result<Self, RacError> {
        RacBvh::encode_with_progress(bvh, mesh, options, progress)
    }

    fn triangle_vertices(&self, id: u32) -> [u32; 3] {
        self.triangle_indices(id)
    }

    fn decoded_mesh(&self) -> Mesh {
        RacBvh::decoded_mesh(self)
    }

    fn mass(&self) -> MassProps {
        RacBvh::mass(self)
    }

    fn edge_flags(&self) -> &EdgeFlags {
        RacBvh::edge_flags(self)
    }

    fn verify(&self) -> Result<(), RacError> {
        RacBvh::verify(self)
    }

    fn to_bytes(&self) -> Vec<u8> {
        RacBvh::to_bytes(self)
    }

    /// With a cluster cache of `options.cache_budget_bytes`.
    fn from_bytes(bytes: &[u8], options: &OpenOptions) -> Result<Self, RacError> {
        RacBvh::from_bytes(bytes, options.cache_budget_bytes)
    }

    /// Memory-maps the file (clusters decoded on demand) with a cluster
    /// cache of `options.cache_budget_bytes`.
    fn open(path: &Path, options: &OpenOptions) -> Result<Self, RacError> {
        RacBvh::open(path, options.cache_budget_bytes)
    }

    const BUILDS_OUT_OF_CORE: bool = true;

    /// [`racbvh::encode_streamed`](super::encode_streamed).
    fn encode_streamed(
        input: &ChunkedMesh,
        build_options: &BuildOptions,
        options: &RacOptions,
        out: &Path,
        progress: Progress<'_>,
    ) -> Option<Result<StreamedReport, RacError>> {
        Some(
            super::encode_streamed(input, build_options, options, out, progress)
                .map(|made| made.report()),
        )
    }

    fn header_fields(&self) -> Vec<(&'static str, String)> {
        RacBvh::header_fields(self)
    }

    #[cfg(feature = "serde")]
    fn build_fields(&self) -> Vec<(&'static str, serde_json::Value)> {
        let st = self.stats();
        vec![
            ("nodes", st.nodes.into()),
            ("clusters", st.cluster_count.into()),
            ("cluster_nodes", self.cluster_nodes().into()),
            ("bits", self.header.bits.into()),
            ("bits_per_node_tree", st.bits_per_node_tree.into()),
            ("bits_per_node_bv", st.bits_per_node_bv.into()),
            (
                "compression_ratio_vs_plain",
                st.compression_ratio_vs_plain.into(),
            ),
            ("mesh_bytes_per_triangle", st.mesh_bytes_per_triangle.into()),
            ("compression_seconds", st.compression_seconds.into()),
        ]
    }

    /// The cluster size is chosen from the budget
    /// ([`RacOptions::cluster_nodes_for_budget`]).
    const ENCODES_FOR_CACHE_BUDGET: bool = true;

    fn fit_cache_budget(options: &mut RacOptions) {
        options.cluster_nodes = options.cluster_nodes_for_budget();
    }

    fn cache_stats(&self) -> Option<crate::codec::CacheStats> {
        Some(RacBvh::cache_stats(self))
    }

    fn cache_budget(options: &mut RacOptions) -> Option<&mut usize> {
        Some(&mut options.cache_budget_bytes)
    }

    /// Measures what the whole tree decodes to ([`RacBvh::decoded_bytes`]:
    /// every cluster decoded once, outside the cache, so a file opened with
    /// a small cache measures the same as one whose cache holds it all),
    /// then re-opens the same bytes with a cache of `budget(decoded)`.
    fn with_cache_budget_of(
        &self,
        budget: &dyn Fn(usize) -> usize,
    ) -> Option<Result<Self, RacError>> {
        Some(
            self.decoded_bytes()
                .map(|decoded| self.with_cache_budget(budget(decoded))),
        )
    }
}
