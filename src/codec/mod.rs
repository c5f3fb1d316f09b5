//! Codecs: each turns a [`CanonicalBvh`](crate::build::CanonicalBvh) and its
//! mesh into one storage form, owns that form's bit layouts, and implements
//! the [`Codec`] contract (traversal through
//! [`NodeCursor`](crate::cursor::NodeCursor), rays through
//! [`RayCursor`](crate::query::RayCursor), sizes by part, vertex indices,
//! the decoded mesh, mass properties, its self-contained file).
//!
//! - [`any`]: the registry, the one place that names every codec:
//!   [`CodecKind`] (the names the CLI, the sims and JSON use), [`AnyCodec`]
//!   (an encoded codec, whichever it is), [`AnyOptions`], opening any codec
//!   file by its magic, and [`with_codec!`](crate::with_codec), which binds
//!   the concrete codec so that traversals stay monomorphized. The parry
//!   shape, the renderer, the CLI and the sims ask it; none lists codecs.
//! - [`plain`]: the uncompressed reference (the papers' "Ori."): 32-byte
//!   nodes, an `f32` vertex array and `u32` triangle indices.
//! - [`hcc`]: HCCMesh (Kim et al. 2010): a high-level tree over low-level
//!   trees of fewer than 512 vertices, 4-byte nodes whose boxes come from
//!   vertex indices and the parent's box, tree templates, per-tree vertex
//!   arrays (i-HCCMesh), with an optional multi-triangle-leaf form.
//! - [`racbvh`]: RACBVH (Kim et al. 2010): clusters of consecutive nodes,
//!   front-based structure coding, predicted quantized boxes, a dictionary
//!   coder and a cache of decompressed clusters.
//! - [`clbvh`]: CLBVH (Benthin et al. 2018): an 8-wide tree with float
//!   inner nodes and 72-byte compressed multi-leaf nodes whose leaf data
//!   follows them; `clbvh` (pre-gathered leaves) and `clbvh-compact`
//!   (de-duplicated vertex indices).
//! - [`common`]: machinery more than one codec uses (bit streams, the
//!   dictionary coder, the conservative quantizer, owned-or-mapped storage,
//!   packed arrays, little-endian readers, [`FormatError`](common::FormatError),
//!   atomic saves (from [`crate::files`]), stored mass properties, file
//!   magic).
//!
//! # A codec's folder
//!
//! Every codec folder (`plain`, `hcc`, `hcc/ooc`, `clbvh`, `racbvh`) has
//! one layout, so that the same thing is in the same file in each:
//!
//! | file | what it holds |
//! |---|---|
//! | `mod.rs` | the module docs (the paper's choices and ours), the options type with its [`CodecOptions`] impl (`SETTINGS`, `from_settings`; plain's options are `()`), the main type's struct definition with its accessors and figures (stats, [`ByteSize`]), and the re-exports that make the public paths (`codec::plain::PlainBvh`, …) |
//! | `encode.rs` | building the main type from a [`CanonicalBvh`](crate::build::CanonicalBvh) and its mesh |
//! | `cursor.rs` | the [`NodeCursor`](crate::cursor::NodeCursor) and [`RayCursor`](crate::query::RayCursor) impls, and the node handle type |
//! | `decode.rs` | only where the codec decodes stored records apart from the cursor: RACBVH's clusters, the o-HCCMesh file into an i-HCCMesh |
//! | `file.rs` | its self-contained file: the layout, magic and version, `to_bytes` and `from_bytes` (the contract's default `save` and `open` write and read them; the memory-mapped codecs, RACBVH and the o-HCCMesh, also have their own `open`) |
//! | `verify.rs` | `verify`, the second validation tier, where it is more than a few lines |
//! | `error.rs` | its error type |
//! | `contract.rs` | the thin `impl Codec`, delegating to the codec's own methods |
//! | `node.rs` | the bit layouts of its stored nodes and words |
//!
//! An impl block lives in the file whose job it does, whichever type it is
//! on (the o-HCCMesh's `encode.rs` also holds `HccBvh::to_ooc`). Two
//! departures: i-HCCMesh's node handle, [`HccNode`](hcc::HccNode), stays in
//! `hcc/node.rs` with the words it decodes, because the cursor, `trace.rs`
//! and the o-HCCMesh's cursor and paged trees all use it (and
//! `hcc::node::HccNode` is a public path); the o-HCCMesh has no `node.rs`
//! (its trees decode to i-HCCMesh words), and its out-of-core `verify` is
//! the paged trees' own, in `paged.rs`.
//!
//! Beside these, a folder holds whatever else only its codec needs: its
//! own ray traversal behind the cursor's `RayCursor` (`trace.rs`: HCC,
//! CLBVH), its out-of-core builder from a chunked model (`stream.rs`:
//! RACBVH, o-HCCMesh), and its parts. In HCC: `decompose.rs`,
//! `canonical.rs`, `template.rs`, `pair.rs`, `block.rs`, `ids.rs`,
//! `vertices.rs`, `grid16.rs`; in the o-HCCMesh: `model.rs`, `rebuild.rs`,
//! `paged.rs` (the out-of-core mode); in CLBVH: `collapse.rs`, `simd.rs`;
//! in RACBVH: `context.rs` (coder contexts), `mesh.rs` (the stored mesh),
//! `cache.rs` (decompressed clusters), `complete.rs` (BV completion),
//! `access.rs` (the random-access API), `nodecache.rs` (decoded nodes),
//! `tricache.rs` (each thread's decoded triangles). `common` imports
//! nothing from a codec, and no codec imports another.
//!
//! This folder knows neither parry nor rapier.
//!
//! # What a new codec adds
//!
//! 1. Its folder, `codec/<name>/`, laid out as above: `mod.rs` (the module
//!    docs, the options type, the main type with [`ByteSize`]),
//!    `encode.rs` (from `&CanonicalBvh` and the mesh into a `Result`; a
//!    value that does not fit is an error), `cursor.rs`
//!    ([`NodeCursor`](crate::cursor::NodeCursor) with conservative boxes;
//!    a binary codec needs only `for_each_child`, a wide one also overrides
//!    `children` to write its child boxes into the batch's lanes at once;
//!    and [`RayCursor`](crate::query::RayCursor), an empty `impl` for the
//!    generic ray traversals, or overriding `closest_hit`, `any_hit` or
//!    `closest_hits_within` with a traversal of its own that gives the
//!    same hits, tested against the generic one), `file.rs` (its
//!    self-contained file: magic, version, `to_bytes` and `from_bytes`
//!    through the shared frame ([`Frame`]), two-tier validation; the
//!    contract's default `save` writes it atomically and its default
//!    `open` reads it, so a codec overrides them only to map its file),
//!    `verify.rs`, `error.rs` (a `thiserror` enum with fields and an
//!    `Io(#[from] IoError)` variant: [`IoError`](crate::IoError) is the
//!    crate's one I/O error, with the path) and `node.rs`.
//! 2. `impl Codec` in `codec/<name>/contract.rs`, thin: delegating to the
//!    codec's own methods. A codec that can build from a chunked model
//!    (`stream.rs`) overrides `encode_streamed` and sets
//!    `BUILDS_OUT_OF_CORE`; `cbvh build` then offers it out of core, by
//!    the registry, with no line of its own.
//! 3. Its options from a front end's [`Settings`]: `impl CodecOptions`
//!    for its options type, next to it (`SETTINGS`, its own
//!    `CODEC.KEY=VALUE` settings with the values each takes, the one
//!    place their bounds are stated; `VERTEX_BITS`, if it quantizes
//!    vertices; and `from_settings`, which reads them and the common
//!    settings it uses, leaf size and vertex bits, and checks them). The
//!    contract refuses any other key under the codec's name, and any value
//!    its declaration does not take (`Codec::options_from`), for every
//!    codec whether in use or not. `cbvh build`, the drop tests and their
//!    `--set` then take them; no front-end file names a codec's options.
//! 4. One entry in the `registry!` invocation in [`any`] (variant, type,
//!    options field, name, summary) and one arm in
//!    [`with_codec!`](crate::with_codec); the compiler points at the arm if
//!    it is missing. The CLI's `--codec`, the sims' `--shapes`, the
//!    renderer, `cbvh info` and the parry shape then know the codec.
//! 5. One line in the shared codec test suite (`tests/suite/codec_suite.rs`),
//!    which runs every test on every codec. The mutation harness
//!    (`examples/support/mutate.rs`, run by `tests/mutation.rs`) attacks
//!    every registered codec's default file by itself; a variant with other
//!    options is a line in its `EXTRA_VARIANTS`.
//! 6. Its name and paper in the README's list of codecs.

pub mod any;
pub mod clbvh;
pub mod common;
mod contract;
pub mod hcc;
pub mod plain;
pub mod racbvh;
pub mod settings;

pub use any::{AnyCodec, AnyOptions, CodecError, CodecFileError, CodecKind, UnknownCodec};
pub use common::container::Frame;
pub use common::page_cache::CacheStats;
pub use contract::{Codec, OpenOptions, StreamedReport};
pub use settings::{CodecOptions, Settings, SettingsError};

/// Memory of a stored structure, by component.
pub trait ByteSize {
    /// `(part name, bytes)` for every component, in a stable order.
    fn bytes_by_part(&self) -> Vec<(&'static str, usize)>;

    /// Total bytes over all parts.
    fn bytes_total(&self) -> usize {
        self.bytes_by_part().iter().map(|p| p.1).sum()
    }
}
