//! Codecs: each turns a [`CanonicalBvh`](crate::build::CanonicalBvh) and its
//! mesh into one storage form, owns that form's bit layouts, and implements
//! [`NodeCursor`](crate::cursor::NodeCursor) over it.
//!
//! - [`plain`]: the uncompressed reference (the papers' "Ori."): 32-byte
//!   nodes, an `f32` vertex array and `u32` triangle indices.
//! - [`racbvh`]: RACBVH (Kim et al. 2010): clusters of consecutive nodes,
//!   front-based structure coding, predicted quantized boxes, a dictionary
//!   coder and a cache of decompressed clusters.
//! - [`common`]: machinery more than one codec uses (bit streams, the
//!   dictionary coder, the conservative quantizer, owned-or-mapped storage,
//!   packed arrays, little-endian readers, [`FormatError`](common::FormatError),
//!   atomic saves, stored mass properties, file magic).
//!
//! A codec's folder holds what is its own: its layouts and constants
//! (`node.rs`, `file.rs`), `encode.rs`, `decode.rs`, its error type, and
//! whatever else only it needs. In RACBVH: `context.rs` (coder contexts),
//! `mesh.rs` (the stored mesh), `tree.rs` (the tree and its figures),
//! `cache.rs` (decompressed clusters), `complete.rs` (BV completion),
//! `access.rs` (the random-access API), `tricache.rs` (each thread's decoded
//! triangles), `cursor.rs` and `verify.rs`. `common` imports nothing from a
//! codec, and no codec imports another.

pub mod common;
pub mod hcc;
pub mod plain;
pub mod racbvh;

/// Memory of a stored structure, by component.
pub trait ByteSize {
    /// `(part name, bytes)` for every component, in a stable order.
    fn bytes_by_part(&self) -> Vec<(&'static str, usize)>;

    /// Total bytes over all parts.
    fn bytes_total(&self) -> usize {
        self.bytes_by_part().iter().map(|p| p.1).sum()
    }
}
