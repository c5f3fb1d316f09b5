//! [`OocError`].

use super::super::HccError;
use crate::codec::common::FormatError;

/// What can stop an o-HCCMesh encode or decode.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum OocError {
    /// The i-HCCMesh encode under it failed.
    #[error(transparent)]
    Hcc(#[from] HccError),
    /// o-HCCMesh codes quantized vertices only.
    #[error(
        "o-HCCMesh codes quantized vertices (parallelogram residuals on the grid): set vertex bits (16 is the paper's), not f32"
    )]
    NotQuantized,
    /// An i-HCCMesh that is not laid out as the i-HCCMesh encoder lays
    /// trees out (a damaged or foreign structure).
    #[error("low-level tree {tree}: {what}; the i-HCCMesh is not one this build's encoder wrote")]
    NotCanonical {
        /// The low-level tree (`u32::MAX`: the high-level tree).
        tree: u32,
        /// What differs.
        what: &'static str,
    },
    /// Bytes that break the file frame (magic, truncation, checksums,
    /// header fields) or a dictionary.
    #[error(transparent)]
    Format(#[from] FormatError),
    /// A version this build cannot read.
    #[error(
        "o-HCCMesh file version {found} is not supported (this build reads version {supported}); rebuild it with `cbvh build MESH --codec hcc-ooc -o FILE`"
    )]
    Version {
        /// The file's version.
        found: u32,
        /// The version this build reads.
        supported: u32,
    },
    /// A coded tree that breaks the format's rules.
    #[error("o-HCCMesh low-level tree {tree}: {what}; the file is damaged, rebuild it")]
    Corrupt {
        /// The low-level tree (`u32::MAX`: the high-level tree or the
        /// file as a whole).
        tree: u32,
        /// What is wrong.
        what: &'static str,
    },
    /// The out-of-core build cannot do what it was asked (id maps), or a
    /// chunk could not be read or built.
    #[error("out-of-core build: {0}")]
    OutOfCore(String),
    /// Reading or writing a file failed.
    #[error(transparent)]
    Io(#[from] crate::files::IoError),
}
