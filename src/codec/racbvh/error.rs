//! [`RacError`].

use super::file;
use crate::codec::common::FormatError;

/// What can go wrong encoding, reading or decoding a RACBVH.
#[derive(Clone, Debug, thiserror::Error, PartialEq)]
pub enum RacError {
    /// An option is out of range.
    #[error("{what} = {value} is not allowed: use {expected}")]
    Option {
        /// The option.
        what: &'static str,
        /// Its value.
        value: u64,
        /// What is allowed.
        expected: String,
    },
    /// The mesh cannot be stored.
    #[error("the mesh cannot be compressed: {0}")]
    InvalidMesh(String),
    /// The tree does not satisfy what the codec needs.
    #[error("the tree cannot be compressed: {0}")]
    InvalidTree(String),
    /// The bytes are not a well-formed file: bad magic, a truncated
    /// section, a bad header field, or coded data that breaks its code.
    #[error(transparent)]
    Format(#[from] FormatError),
    /// A version this build cannot read.
    #[error("RACBVH version {0} is not supported (this build reads version {ver})", ver = file::VERSION)]
    Version(u32),
    /// Corrupted data (outside a cluster).
    #[error("corrupted RACBVH data: {0}")]
    Corrupt(&'static str),
    /// A cluster's data is corrupted.
    #[error("cluster {cluster} is corrupted: {what}")]
    CorruptCluster {
        /// The cluster.
        cluster: u32,
        /// What was found.
        what: &'static str,
    },
    /// A node breaks what queries rely on (found by `verify`).
    #[error("node {node} is corrupted: {what} (the file is damaged: rebuild it)")]
    CorruptNode {
        /// The node.
        node: u32,
        /// What was found.
        what: &'static str,
    },
    /// The out-of-core build could not read or build a chunk, or the
    /// model is beyond what it numbers.
    #[error("out-of-core build: {0}")]
    OutOfCore(String),
    /// Reading or writing a file failed.
    #[error(transparent)]
    Io(#[from] crate::files::IoError),
    /// A node index out of range.
    #[error("node {node} does not exist (the tree has {count} nodes)")]
    NoSuchNode {
        /// The index asked for.
        node: u32,
        /// Number of nodes.
        count: u32,
    },
}
