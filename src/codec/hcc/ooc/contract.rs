//! The `hcc-ooc` codec's [`Codec`] contract, delegating to the decoded
//! i-HCCMesh or the paged trees.

use crate::codec::common::container::Frame;
use std::path::Path;

use super::super::HccBvh;
use super::{HccOocBvh, Mode, OocError, OocOptions, file};
use crate::build::chunked::{ChunkedMesh, Progress};
use crate::build::{BuildOptions, CanonicalBvh};
#[cfg(feature = "serde")]
use crate::codec::ByteSize;
use crate::codec::common::{MassProps, Store};
use crate::codec::{Codec, CodecKind, OpenOptions, StreamedReport};
use crate::contact::EdgeFlags;
use crate::cursor::NodeCursor;
use crate::mesh::Mesh;

impl Codec for HccOocBvh {
    const KIND: CodecKind = CodecKind::HccOoc;
    const MAGIC: [u8; 8] = file::MAGIC;
    const FRAME: Frame = file::FRAME;
    /// Grid bits and which id maps to keep (default: 16 bits, tree order).
    type Options = OocOptions;
    type Error = OocError;

    fn encode(bvh: &CanonicalBvh, mesh: &Mesh, options: &OocOptions) -> Result<Self, OocError> {
        HccOocBvh::encode_with(bvh, mesh, options)
    }

    fn triangle_vertices(&self, id: u32) -> [u32; 3] {
        match &self.mode {
            Mode::Whole { hcc, .. } => hcc.triangle_vertex_indices(id),
            Mode::Paged(p) => p.triangle_vertices(id),
        }
    }

    fn decoded_mesh(&self) -> Mesh {
        match &self.mode {
            Mode::Whole { hcc, .. } => hcc.decoded_mesh(),
            Mode::Paged(p) => p.decoded_mesh(),
        }
    }

    fn mass(&self) -> MassProps {
        match &self.mode {
            Mode::Whole { hcc, .. } => hcc.mass(),
            Mode::Paged(p) => p.mass(),
        }
    }

    fn edge_flags(&self) -> &EdgeFlags {
        HccOocBvh::edge_flags(self)
    }

    /// Pre-loaded: the i-HCCMesh's verification. Out of core: every tree
    /// decoded (outside the cache) and checked against the stored
    /// high-level tree.
    fn verify(&self) -> Result<(), OocError> {
        match &self.mode {
            Mode::Whole { hcc, .. } => Ok(hcc.verify()?),
            Mode::Paged(p) => p.verify(),
        }
    }

    fn save(&self, path: &Path) -> Result<(), OocError> {
        HccOocBvh::save(self, path)
    }

    fn to_bytes(&self) -> Vec<u8> {
        self.file_bytes().to_vec()
    }

    /// Decoded whole if the i-HCCMesh fits `options.cache_budget_bytes`,
    /// else out of core with a cache of that many bytes.
    fn from_bytes(bytes: &[u8], options: &OpenOptions) -> Result<Self, OocError> {
        HccOocBvh::from_bytes_with_budget(bytes, options.cache_budget_bytes)
    }

    /// Read and decoded whole if the i-HCCMesh fits
    /// `options.cache_budget_bytes`, else memory-mapped and decoded on
    /// demand into a cache of that many bytes.
    fn open(path: &Path, options: &OpenOptions) -> Result<Self, OocError> {
        HccOocBvh::open_with_budget(path, options.cache_budget_bytes)
    }

    const BUILDS_OUT_OF_CORE: bool = true;

    /// [`ooc::encode_streamed`](super::encode_streamed).
    fn encode_streamed(
        input: &ChunkedMesh,
        build_options: &BuildOptions,
        options: &OocOptions,
        out: &Path,
        progress: Progress<'_>,
    ) -> Option<Result<StreamedReport, OocError>> {
        Some(
            super::encode_streamed(input, build_options, options, out, progress)
                .map(|made| made.report()),
        )
    }

    fn header_fields(&self) -> Vec<(&'static str, String)> {
        let file = self.file_bytes().len();
        let n = self.triangle_count().max(1) as f64;
        let mut out = vec![(
            "o-HCCMesh file",
            format!("{file} bytes, {:.2} a triangle", file as f64 / n),
        )];
        match &self.mode {
            Mode::Whole { hcc, .. } => {
                out.push(("mode", "pre-loaded (decoded whole when opened)".into()));
                out.extend(<HccBvh as Codec>::header_fields(hcc));
            }
            Mode::Paged(p) => {
                let c = p.cache_stats();
                out.push((
                    "mode",
                    format!(
                        "out of core: trees decoded on demand into a cache of {} bytes \
                         ({:.1} % of the {} bytes the whole i-HCCMesh takes)",
                        c.budget_bytes,
                        100.0 * c.budget_bytes as f64 / p.decoded_estimate().max(1) as f64,
                        p.decoded_estimate()
                    ),
                ));
                out.extend(p.header_fields());
            }
        }
        out
    }

    #[cfg(feature = "serde")]
    fn build_fields(&self) -> Vec<(&'static str, serde_json::Value)> {
        let n = self.triangle_count().max(1) as f64;
        let mut out = vec![(
            "file_bytes_per_triangle",
            (self.file_bytes().len() as f64 / n).into(),
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
        match &self.mode {
            Mode::Whole { hcc, .. } => out.extend(
                <HccBvh as Codec>::build_fields(hcc)
                    .into_iter()
                    .filter(|(k, _)| *k != "bytes_per_triangle_by_part"),
            ),
            Mode::Paged(p) => {
                out.push(("out_of_core", true.into()));
                out.push((
                    "decoded_bytes_per_triangle",
                    (p.decoded_estimate() as f64 / n).into(),
                ));
                out.push((
                    "cache_budget_bytes",
                    (p.cache_stats().budget_bytes as u64).into(),
                ));
            }
        }
        out.push(("bytes_per_triangle_by_part", memory.into()));
        out
    }

    fn cache_stats(&self) -> Option<crate::codec::CacheStats> {
        HccOocBvh::cache_stats(self)
    }

    fn cache_budget(options: &mut OocOptions) -> Option<&mut usize> {
        Some(&mut options.cache_budget_bytes)
    }

    /// Re-opens the same bytes with a cache of `budget(bytes of the whole
    /// i-HCCMesh)` (the header's estimate out of core), out of core when
    /// that is less than the whole.
    fn with_cache_budget_of(
        &self,
        budget: &dyn Fn(usize) -> usize,
    ) -> Option<Result<Self, OocError>> {
        let b = budget(self.decoded_bytes());
        // The same bytes: a mapped file stays mapped (shared), not copied.
        let file = match &self.mode {
            Mode::Whole { file, .. } => Store::Owned(file.clone()),
            Mode::Paged(p) => p.file().clone(),
        };
        Some(HccOocBvh::with_budget(file, b))
    }
}
