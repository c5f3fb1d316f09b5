//! Machinery more than one codec uses. Nothing here knows a codec: errors
//! are [`FormatError`]s, which each codec's error wraps.
//!
//! - [`bits`]: bit streams written and read least-significant bit first,
//!   Exp-Golomb codes, zig-zag.
//! - [`dict`]: the per-context dictionary coder (RACBVH §4.4).
//! - [`static_dict`]: the static dictionary coder with the optimal
//!   dictionary size (HCCMesh §5.2).
//! - [`quant`]: conservative quantization of boxes on a grid over a box
//!   (min rounded down, max up), at any bit count.
//! - [`Store`] (`store.rs`): a codec's bytes, owned or a range of a
//!   memory-mapped file.
//! - [`packed`]: frame-of-reference arrays of `u32` with O(1) access, and
//!   [`bits_for`](packed::bits_for).
//! - [`page_cache`]: decoded pages (clusters, low-level trees) in a sharded
//!   LRU under a byte budget, with per-thread pins.
//! - [`le`]: little-endian readers at a byte offset.
//! - [`container`]: the frame of every codec file (magic, section table,
//!   header checksum), written and checked.
//! - [`FormatError`] (`error.rs`): bad magic, truncation, bad header
//!   fields, checksum mismatches, values out of range, corrupted codes.
//! - [`atomic_write`]: atomic file saves (from [`crate::atomic`]).
//! - [`mass`]: the stored mass properties.
//! - [`edges`]: the edge-flags section every codec file ends with (the
//!   active edges of [`EdgeFlags`](crate::contact::EdgeFlags), computed
//!   when encoding, coded through per-context static dictionaries).
//! - [`MAGIC_PREFIX`]: how every codec file starts.

pub mod bits;
pub mod container;
pub mod dict;
pub mod edges;
mod error;
pub mod huge;
pub mod le;
pub mod mass;
pub mod packed;
pub mod page_cache;
pub mod quant;
pub mod static_dict;
mod store;

pub use crate::atomic::atomic_write;
pub use error::FormatError;
pub use mass::{MASS_BYTES, MassAccumulator, MassProps};
pub use store::Store;

/// The first four bytes of every cbvh codec file (`CBVHRAC\0`, `CBVHPLN\0`).
pub const MAGIC_PREFIX: [u8; 4] = *b"CBVH";
