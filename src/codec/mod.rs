//! Codecs: each turns a [`CanonicalBvh`](crate::build::CanonicalBvh) and its
//! mesh into one storage form, owns that form's bit layouts, and implements
//! the [`Codec`] contract (traversal through
//! [`NodeCursor`](crate::cursor::NodeCursor), sizes by part, vertex indices,
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
//! - [`racbvh`]: RACBVH (Kim et al. 2010): clusters of consecutive nodes,
//!   front-based structure coding, predicted quantized boxes, a dictionary
//!   coder and a cache of decompressed clusters.
//! - [`common`]: what several codecs share (atomic saves, stored mass
//!   properties, file magic).
//!
//! This folder knows neither parry nor rapier.
//!
//! # What a new codec adds
//!
//! 1. Its folder, `codec/<name>/`: `encode.rs` (from `&CanonicalBvh` and the
//!    mesh into a `Result`; a value that does not fit is an error), the
//!    cursor (`decode.rs`, [`NodeCursor`](crate::cursor::NodeCursor) with
//!    conservative boxes), `file.rs` (its self-contained file: magic,
//!    version, two-tier validation, atomic save), `error.rs` (a `thiserror`
//!    enum with fields), [`ByteSize`], and `mod.rs` with the module docs
//!    (the paper's choices and ours).
//! 2. `impl Codec` in `codec/<name>/contract.rs`, thin: delegating to the
//!    codec's own methods.
//! 3. One entry in the `registry!` invocation in [`any`] (variant, type,
//!    options field, name, summary) and one arm in
//!    [`with_codec!`](crate::with_codec); the compiler points at the arm if
//!    it is missing. The CLI's `--codec`, the sims' `--shapes`, the
//!    renderer, `cbvh info` and the parry shape then know the codec.
//! 4. One line in the shared codec test suite (`tests/codec_suite.rs`),
//!    which runs every test on every codec.
//! 5. Its name and paper in the README's list of codecs.

pub mod any;
pub mod common;
mod contract;
pub mod plain;
pub mod racbvh;

pub use any::{AnyCodec, AnyOptions, CodecError, CodecFileError, CodecKind, UnknownCodec};
pub use contract::{Codec, OpenOptions};

/// Memory of a stored structure, by component.
pub trait ByteSize {
    /// `(part name, bytes)` for every component, in a stable order.
    fn bytes_by_part(&self) -> Vec<(&'static str, usize)>;

    /// Total bytes over all parts.
    fn bytes_total(&self) -> usize {
        self.bytes_by_part().iter().map(|p| p.1).sum()
    }
}
