//! [`PlainError`].

/// What can go wrong reading, verifying or writing a plain BVH file.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum PlainError {
    /// The bytes do not start with the plain magic.
    #[error("not a cbvh plain BVH file (bad magic)")]
    BadMagic,
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
    /// A section (or the header) is shorter than it must be.
    #[error("the {section} section is truncated: need {need} bytes, have {have}")]
    Truncated {
        /// Section name.
        section: &'static str,
        /// Bytes needed.
        need: u64,
        /// Bytes present.
        have: u64,
    },
    /// A header field is inconsistent.
    #[error("bad header field {field}: {why}")]
    Header {
        /// The field.
        field: &'static str,
        /// What is wrong.
        why: String,
    },
    /// A checksum does not match: the file is damaged.
    #[error("the {section} section's checksum does not match: the file is damaged")]
    Checksum {
        /// The section.
        section: &'static str,
    },
    /// The tree or mesh breaks what queries rely on (found by `verify`).
    #[error("corrupted plain BVH: node {node}: {what}")]
    Corrupt {
        /// The node (or triangle / vertex, as `what` says).
        node: u64,
        /// What was found.
        what: &'static str,
    },
    /// Reading or writing the file failed.
    #[error("{path}: {message}")]
    Io {
        /// The file.
        path: String,
        /// The operating system's message.
        message: String,
    },
}
