//! Machinery more than one codec uses: atomic file saves, the stored mass
//! properties, and recognising a codec file by its magic.

pub mod bits;
pub mod dict;
mod error;
pub mod le;
pub mod mass;
pub mod packed;
pub mod quant;
mod save;
mod store;

pub use error::FormatError;
pub use mass::{MASS_BYTES, MassProps};
pub use save::atomic_write;
pub use store::Store;

/// The first four bytes of every cbvh codec file (`CBVHRAC\0`, `CBVHPLN\0`).
pub const MAGIC_PREFIX: [u8; 4] = *b"CBVH";
