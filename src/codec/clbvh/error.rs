//! [`ClError`].

use crate::codec::common::FormatError;

/// What can go wrong encoding, reading, verifying or writing a CLBVH.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ClError {
    /// The leaf size `M` is out of range.
    #[error("the CLBVH leaf size must be between 1 and {max}, got {got}")]
    LeafSize {
        /// The size asked for.
        got: usize,
        /// The largest allowed.
        max: usize,
    },
    /// The canonical tree has larger leaves than the CLBVH leaf size.
    #[error(
        "the canonical tree has up to {canonical} triangles a leaf, more than the CLBVH leaf size {leaf_size}; build it with max_leaf_triangles ≤ {leaf_size}"
    )]
    CanonicalLeaves {
        /// The canonical tree's leaf size.
        canonical: usize,
        /// The CLBVH leaf size.
        leaf_size: usize,
    },
    /// The tree was not built over this mesh.
    #[error("the tree holds {tree} triangles but the mesh has {mesh}")]
    MeshMismatch {
        /// Triangles in the tree.
        tree: usize,
        /// Triangles in the mesh.
        mesh: usize,
    },
    /// A node index or arena offset does not fit a 30-bit child reference.
    #[error("too many {what} for a CLBVH: {value} (at most {max})")]
    TooLarge {
        /// What overflowed.
        what: &'static str,
        /// Its value.
        value: u64,
        /// The largest allowed.
        max: u64,
    },
    /// A multi-leaf node's box is too large for an `f32` quantization step.
    #[error(
        "a multi-leaf node's box {min:?}..{max:?} is too large to quantize in f32; scale the mesh down"
    )]
    Extent {
        /// Box minimum.
        min: [f32; 3],
        /// Box maximum.
        max: [f32; 3],
    },
    /// The file's frame (magic, header, section table, checksums) is bad.
    #[error(transparent)]
    Format(#[from] FormatError),
    /// A version this build cannot read.
    #[error(
        "CLBVH file version {found} is not supported (this build reads version {supported}); rebuild it with `cbvh build MESH --codec clbvh -o FILE`"
    )]
    Version {
        /// The file's version.
        found: u32,
        /// The version this build reads.
        supported: u32,
    },
    /// The tree breaks what queries rely on (found by `verify`).
    #[error("corrupted CLBVH: {what} (at {at})")]
    Corrupt {
        /// Where: a node index, arena word offset or triangle id, as `what`
        /// says.
        at: u64,
        /// What was found.
        what: &'static str,
    },
    /// Reading or writing a file failed.
    #[error(transparent)]
    Io(#[from] crate::files::IoError),
}
