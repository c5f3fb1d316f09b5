//! [`PlainError`].

use crate::codec::common::FormatError;

/// What can go wrong reading, verifying or writing a plain BVH file.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum PlainError {
    /// A version this build cannot read.
    #[error(
        "plain BVH file version {found} is not supported (this build reads version {supported}); rebuild it with `cbvh build MESH --codec plain -o FILE`"
    )]
    Version {
        /// The file's version.
        found: u32,
        /// The version this build reads.
        supported: u32,
    },
    /// The bytes are not a well-formed file: bad magic, a truncated
    /// section, a bad header field or a checksum that does not match.
    #[error(transparent)]
    Format(#[from] FormatError),
    /// The tree or mesh breaks what queries rely on (found by `verify`).
    #[error("corrupted plain BVH: node {node}: {what}")]
    Corrupt {
        /// The node (or triangle / vertex, as `what` says).
        node: u64,
        /// What was found.
        what: &'static str,
    },
    /// Reading or writing a file failed.
    #[error(transparent)]
    Io(#[from] crate::files::IoError),
}
