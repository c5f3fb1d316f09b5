//! Opening any cbvh codec file, chosen by its magic: the one place that
//! knows which magic belongs to which codec (until the codec registry).

use std::io::Read;
use std::path::{Path, PathBuf};

use super::Codec;
use crate::codec::plain::{PlainBvh, PlainError};
use crate::codec::racbvh::{RacBvh, RacError};

/// A codec's own error, whichever the codec.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum CodecError {
    /// From the plain codec.
    #[error(transparent)]
    Plain(#[from] PlainError),
    /// From the RACBVH codec.
    #[error(transparent)]
    Racbvh(#[from] RacError),
}

/// What can go wrong opening a codec file.
#[derive(Debug, thiserror::Error)]
pub enum CodecFileError {
    /// The file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// The file starts with no codec magic.
    #[error(
        "{path}: not a cbvh codec file (no known magic); give a mesh (.off, .ply, .obj, .stl) \
         or a file written by `cbvh build ... -o FILE`"
    )]
    NotACodecFile {
        /// The file.
        path: PathBuf,
    },
    /// A plain file is damaged or forged.
    #[error("{path}: {source}")]
    Plain {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        #[source]
        source: PlainError,
    },
    /// A RACBVH file is damaged or forged.
    #[error("{path}: {source}")]
    Racbvh {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        #[source]
        source: RacError,
    },
    /// `verify` found the file's contents inconsistent.
    #[error("{path}: verify failed: {source}; the file is damaged: rebuild it with `cbvh build`")]
    Verify {
        /// The file.
        path: PathBuf,
        /// What `verify` found.
        #[source]
        source: CodecError,
    },
}

/// How to open a codec file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct OpenOptions {
    /// Run the codec's `verify` (everything a query relies on) before
    /// handing the codec out: on by default. Skip it only for files you
    /// wrote yourself; an unverified file can make queries panic, loop or
    /// answer wrongly.
    pub verify: bool,
    /// RACBVH: byte budget of the decompressed-cluster cache.
    pub cache_budget_bytes: usize,
}

impl Default for OpenOptions {
    fn default() -> Self {
        Self {
            verify: true,
            cache_budget_bytes: 64 << 20,
        }
    }
}

/// The codec whose magic `head` starts with, as its name.
fn codec_of_magic(head: &[u8]) -> Option<&'static str> {
    if head.starts_with(&crate::codec::plain::file::MAGIC) {
        Some("plain")
    } else if head.starts_with(&crate::codec::racbvh::file::MAGIC) {
        Some("racbvh")
    } else {
        None
    }
}

/// The codec name of the file at `path` if it starts with a codec magic
/// (`None` for a mesh or anything else, or a file that cannot be read).
pub fn codec_file_kind(path: &Path) -> Option<&'static str> {
    let mut head = [0u8; 8];
    let mut f = std::fs::File::open(path).ok()?;
    f.read_exact(&mut head).ok()?;
    codec_of_magic(&head)
}

/// Opens the codec file at `path`, whatever its codec (chosen by its magic,
/// not its extension), and verifies it unless `options` say not to.
/// RACBVH files are memory-mapped (clusters decoded on demand); plain files
/// are read into memory.
pub fn open_codec(path: &Path, options: &OpenOptions) -> Result<Codec, CodecFileError> {
    let p = || path.to_path_buf();
    let codec = match codec_file_kind(path) {
        Some("plain") => Codec::Plain(
            PlainBvh::open(path).map_err(|source| CodecFileError::Plain { path: p(), source })?,
        ),
        Some(_) => Codec::Racbvh(Box::new(
            RacBvh::open(path, options.cache_budget_bytes)
                .map_err(|source| CodecFileError::Racbvh { path: p(), source })?,
        )),
        None => {
            // Distinguish an unreadable file from a foreign one.
            std::fs::File::open(path).map_err(|source| CodecFileError::Io { path: p(), source })?;
            return Err(CodecFileError::NotACodecFile { path: p() });
        }
    };
    if options.verify {
        codec
            .verify()
            .map_err(|source| CodecFileError::Verify { path: p(), source })?;
    }
    Ok(codec)
}
