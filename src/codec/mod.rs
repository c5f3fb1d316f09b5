//! Codecs: each turns a [`CanonicalBvh`](crate::build::CanonicalBvh) and its
//! mesh into one storage form, owns that form's bit layouts, and implements
//! [`NodeCursor`](crate::cursor::NodeCursor) over it.
//!
//! - [`plain`]: the uncompressed reference (the papers' "Ori."): 32-byte
//!   nodes, an `f32` vertex array and `u32` triangle indices.
//! - [`racbvh`]: RACBVH (Kim et al. 2010): clusters of consecutive nodes,
//!   front-based structure coding, predicted quantized boxes, a dictionary
//!   coder and a cache of decompressed clusters.
//! - [`common`]: what several codecs share (atomic saves, stored mass
//!   properties, file magic).

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
