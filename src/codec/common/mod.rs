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
//! - [`atomic_write`]: atomic file saves (from [`crate::files`]).
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

pub use crate::files::atomic_write;
pub use error::FormatError;
pub use mass::{MASS_BYTES, MassAccumulator, MassProps};
pub use store::Store;

/// The first four bytes of every cbvh codec file (`CBVHRAC\0`, `CBVHPLN\0`).
pub const MAGIC_PREFIX: [u8; 4] = *b"CBVH";

/// Whether `root` is the bounds of the triangles: each face of `root`
/// within `slack[a]` of the same face of `bounds`, the union of the
/// triangles' decoded vertices (the codec's quantization step on its axis,
/// 0 for `f32` boxes), plus the rounding of coordinates of that magnitude.
/// Consumers rely on the root's box being the mesh's bounds
/// (`AnyCodec::root_box`; a renderer frames its camera from it), which a
/// containment check alone does not prove: a forged file with a looser
/// root still answers every query alike. Where the codec proves
/// containment elsewhere this adds tightness; where it does not (vertices
/// decoded from a grid, checked only against their own trees' boxes) it
/// also catches a grid that puts them outside the root.
pub fn root_matches(root: &crate::geom::Aabb, bounds: &crate::geom::Aabb, slack: [f32; 3]) -> bool {
    if bounds.is_empty() {
        // No vertex: nothing to match.
        return true;
    }
    (0..3).all(|a| {
        let size = bounds.min[a].abs().max(bounds.max[a].abs());
        let tol = f64::from(slack[a]) + 1e-6 * f64::from(size);
        (f64::from(bounds.min[a]) - f64::from(root.min[a])).abs() <= tol
            && (f64::from(root.max[a]) - f64::from(bounds.max[a])).abs() <= tol
    })
}
