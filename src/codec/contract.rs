//! [`Codec`]: the contract every codec implements, and [`OpenOptions`] for
//! opening a codec's file.

use std::path::Path;

use super::ByteSize;
use super::any::CodecKind;
use super::common::MassProps;
use super::common::container::Frame;
use super::common::page_cache::CacheStats;
use super::settings::{CodecOptions, Settings, SettingsError};
use crate::build::chunked::{ChunkedMesh, Progress};
use crate::build::{BuildOptions, CanonicalBvh};
use crate::contact::EdgeFlags;
use crate::files::IoError;
use crate::mesh::Mesh;
use crate::query::RayCursor;

/// One storage form of a BVH with its mesh: encoded from the canonical tree,
/// traversed through [`NodeCursor`](crate::cursor::NodeCursor) and ray cast
/// through [`RayCursor`] (a trait over it), sized by part through
/// [`ByteSize`], stored in a self-contained file.
///
/// The registry ([`super::any`]) names every codec once and dispatches to
/// its implementation of this trait; the parry shape, the renderer, the CLI
/// and the sims go through the registry, never through a codec directly.
/// Implementations are thin: each codec's `contract.rs` delegates to the
/// codec's own methods.
pub trait Codec: RayCursor + ByteSize + Send + Sync + Sized + 'static {
    /// The codec's registry entry (its name in the CLI, the sims and JSON).
    const KIND: CodecKind;

    /// The first eight bytes of the codec's file, by which
    /// [`AnyCodec::open`](super::AnyCodec::open) recognises it.
    const MAGIC: [u8; 8];

    /// Where the codec file's section table lies and what its sections
    /// are called: what its reader and writer go through, and what a tool
    /// reads a file's sections with without knowing the codec.
    const FRAME: Frame;

    /// Encoding settings, made from a front end's [`Settings`] by
    /// [`CodecOptions`].
    type Options: CodecOptions + Clone + Default + std::fmt::Debug + Send + Sync;

    /// What can go wrong encoding, opening, verifying or saving: a failed
    /// read or write is an [`IoError`] naming the file.
    type Error: std::error::Error + From<IoError> + Send + Sync + 'static;

    /// The codec's options from a front end's [`Settings`]: a setting
    /// under the codec's name whose key is not among its options'
    /// [`CodecOptions::SETTINGS`], or whose value its declaration does not
    /// take, is refused ([`Settings::check`]), then the options type makes
    /// itself ([`CodecOptions::from_settings`]). Errors name the setting,
    /// before any work.
    fn options_from(settings: &Settings) -> Result<Self::Options, SettingsError> {
        settings.check(Self::KIND.name(), <Self::Options as CodecOptions>::SETTINGS)?;
        Self::Options::from_settings(settings)
    }

    /// Encodes `bvh`, built over `mesh`. A value that does not fit the
    /// codec's layout is an error, never a truncation.
    fn encode(
        bvh: &CanonicalBvh,
        mesh: &Mesh,
        options: &Self::Options,
    ) -> Result<Self, Self::Error>;

    /// [`Codec::encode`], calling `progress(done, total)` as work finishes
    /// (for codecs whose encoding takes long enough to show; by default
    /// nothing is reported).
    fn encode_with_progress(
        bvh: &CanonicalBvh,
        mesh: &Mesh,
        options: &Self::Options,
        progress: &(dyn Fn(u64, u64) + Sync),
    ) -> Result<Self, Self::Error> {
        let _ = progress;
        Self::encode(bvh, mesh, options)
    }

    /// The vertex indices of triangle `id` (an id a leaf reported), into
    /// [`Codec::decoded_mesh`]'s vertices: what smooth shading needs.
    fn triangle_vertices(&self, id: u32) -> [u32; 3];

    /// The mesh as stored (quantized vertices decoded), triangle `k` being
    /// the triangle the cursor reports as id `k`, which is the input's
    /// triangle `k`: every codec reports the input's ids by default. An
    /// option may renumber them (hcc's tree order,
    /// [`HccOptions::triangle_ids`](super::hcc::HccOptions::triangle_ids));
    /// the decoded mesh's triangles are then the input's permuted, and
    /// every id the codec reports or takes is in that numbering.
    fn decoded_mesh(&self) -> Mesh;

    /// Mass properties at density 1, computed from the original mesh when
    /// encoded and stored with the codec.
    fn mass(&self) -> MassProps;

    /// The active-edge flags of the triangles by id (the ids the cursor
    /// reports), computed once from the codec's own triangles when encoded
    /// ([`edges::of_cursor`](super::common::edges::of_cursor)) and stored
    /// in its file ([`edges`](super::common::edges)).
    fn edge_flags(&self) -> &EdgeFlags;

    /// Proves everything a query relies on (the second validation tier:
    /// one parent per node, nested boxes, leaves containing their
    /// triangles, indices in range, checksums).
    fn verify(&self) -> Result<(), Self::Error>;

    /// Writes the codec's self-contained file, atomically
    /// ([`files::save`](crate::files::save)): by default the bytes of
    /// [`Codec::to_bytes`]. A codec that keeps its file's bytes (the
    /// memory-mapped ones) writes them without the copy.
    fn save(&self, path: &Path) -> Result<(), Self::Error> {
        Ok(crate::files::save(path, &self.to_bytes())?)
    }

    /// The codec's file as bytes (what [`Codec::save`] writes).
    fn to_bytes(&self) -> Vec<u8>;

    /// Reads the bytes of the codec's file, checking them in O(header)
    /// (the first validation tier); [`Codec::verify`] is not run, whatever
    /// `options.verify` says.
    fn from_bytes(bytes: &[u8], options: &OpenOptions) -> Result<Self, Self::Error>;

    /// Opens the codec's file, checking it as [`Codec::from_bytes`] does;
    /// [`Codec::verify`] is not run, whatever `options.verify` says. By
    /// default the whole file is read into memory and given to
    /// [`Codec::from_bytes`]; the codecs that read on demand override it
    /// to map the file instead.
    fn open(path: &Path, options: &OpenOptions) -> Result<Self, Self::Error> {
        Self::from_bytes(&crate::files::read(path)?, options)
    }

    /// The codec's own header fields for `cbvh info` (the registry adds
    /// the codec's name, the triangle count and the mass).
    fn header_fields(&self) -> Vec<(&'static str, String)>;

    /// The figures `cbvh build` reports after encoding (node counts,
    /// compression figures), as JSON values.
    #[cfg(feature = "serde")]
    fn build_fields(&self) -> Vec<(&'static str, serde_json::Value)>;

    /// For a codec that decodes into a cache under a byte budget (RACBVH's
    /// clusters): the budget field of `options`. `None` (the default) for
    /// a codec without a cache.
    fn cache_budget(options: &mut Self::Options) -> Option<&mut usize> {
        let _ = options;
        None
    }

    /// Whether the encoding depends on a cache budget set through
    /// [`AnyOptions::with_cache_budget`](super::AnyOptions::with_cache_budget)
    /// (RACBVH sizes its clusters so that the budget holds enough of them,
    /// [`Codec::fit_cache_budget`]): a front end that wants a small cache
    /// then encodes for it rather than re-opening a tree encoded for a
    /// large one. `false` by default.
    const ENCODES_FOR_CACHE_BUDGET: bool = false;

    /// Fits `options` to the cache budget just set in them
    /// ([`Codec::cache_budget`]); nothing by default. Called by
    /// [`AnyOptions::with_cache_budget`](super::AnyOptions::with_cache_budget),
    /// never by the encoder, which takes its options as they are.
    fn fit_cache_budget(options: &mut Self::Options) {
        let _ = options;
    }

    /// Whether the codec builds out of core
    /// ([`Codec::encode_streamed`] gives `Some`): a front end offers the
    /// out-of-core build for these codecs and refuses it for the others
    /// before any work. `false` by default.
    const BUILDS_OUT_OF_CORE: bool = false;

    /// Builds the codec's file from a model read into spatial chunks
    /// ([`ChunkedMesh`]), holding a few chunks in memory at a time, and
    /// writes it to `out` atomically; `progress` hears each phase. `None`
    /// (the default) for a codec that builds only in memory; a codec that
    /// overrides it sets [`Codec::BUILDS_OUT_OF_CORE`].
    fn encode_streamed(
        input: &ChunkedMesh,
        build_options: &BuildOptions,
        options: &Self::Options,
        out: &Path,
        progress: Progress<'_>,
    ) -> Option<Result<StreamedReport, Self::Error>> {
        let _ = (input, build_options, options, out, progress);
        None
    }

    /// For a codec with a cache: its counters (budget, bytes held,
    /// decodes, hits). `None` (the default) for a codec without one, or
    /// one that decoded everything up front (hcc-ooc pre-loaded).
    fn cache_stats(&self) -> Option<CacheStats> {
        None
    }

    /// For a codec with a cache: decodes the whole tree once (so that the
    /// cache holds all of it, if its budget allows), then returns the same
    /// codec over the same bytes with a cache of `budget(bytes the cache
    /// held)`. `None` (the default) for a codec without a cache.
    fn with_cache_budget_of(
        &self,
        budget: &dyn Fn(usize) -> usize,
    ) -> Option<Result<Self, Self::Error>> {
        let _ = budget;
        None
    }
}

/// What an out-of-core build wrote ([`Codec::encode_streamed`]), in a
/// form every codec shares, for a front end's report.
#[derive(Clone, Debug, PartialEq)]
pub struct StreamedReport {
    /// Chunks built.
    pub chunks: usize,
    /// The largest chunk's triangles.
    pub largest_chunk: u64,
    /// Edges shared by two chunks, paired after the chunks were built.
    pub paired_edges: u64,
    /// The codec's own counts (RACBVH's nodes and clusters, the
    /// o-HCCMesh's low-level trees).
    pub counts: Vec<(&'static str, u64)>,
    /// The file's bytes by part, named as the codec's in-memory form
    /// names them.
    pub parts: Vec<(&'static str, f64)>,
}

/// How to open a codec file ([`AnyCodec::open`](super::AnyCodec::open)).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct OpenOptions {
    /// Run the codec's `verify` (everything a query relies on) before
    /// handing the codec out: on by default. Skip it only for files you
    /// wrote yourself; an unverified file can make queries panic, loop or
    /// answer wrongly.
    pub verify: bool,
    /// Codecs that decode into a cache (RACBVH's clusters): its byte
    /// budget. Codecs without a cache ignore it.
    pub cache_budget_bytes: usize,
}

impl Default for OpenOptions {
    fn default() -> Self {
        Self {
            verify: true,
            cache_budget_bytes: 64 << 20,
        }
    }
}
