//! The error type of mesh loading and saving.

use std::fmt;
use std::path::PathBuf;

/// Where in a file an error was found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Place {
    /// A 1-based line of a text file.
    Line(usize),
    /// A byte offset into a binary file.
    Byte(u64),
    /// Not known (for example a mesh checked after it was built in memory).
    Unknown,
}

impl fmt::Display for Place {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Place::Line(l) => write!(f, "line {l}"),
            Place::Byte(b) => write!(f, "byte offset {b}"),
            Place::Unknown => write!(f, "unknown position"),
        }
    }
}

/// Everything that can go wrong reading or writing a mesh file.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// The file could not be opened, read or written.
    #[error(transparent)]
    Io(#[from] crate::files::IoError),
    /// The extension names no supported format.
    #[error("{path}: unknown mesh extension {ext:?}; use one of .off, .ply, .obj, .stl")]
    UnknownExtension {
        /// The file.
        path: PathBuf,
        /// The extension found (empty when there is none).
        ext: String,
    },
    /// The file ends before the data its header announces.
    #[error("{path}: file is truncated at {place}: expected {expected}")]
    Truncated {
        /// The file.
        path: PathBuf,
        /// Where the data ran out.
        place: Place,
        /// What was still expected.
        expected: String,
    },
    /// The extension names a format that can be read but not written, or
    /// no format at all; only `.ply` (binary) and `.obj` can be written.
    #[error(
        "{path}: cannot write a mesh with extension {ext:?}; only .ply and .obj can be written"
    )]
    UnsupportedWrite {
        /// The file.
        path: PathBuf,
        /// The extension found (empty when there is none).
        ext: String,
    },
    /// A face refers to a vertex that does not exist.
    #[error(
        "{path}: {place}: face {face} uses vertex index {index}, but the mesh has only {vertices} vertices"
    )]
    IndexOutOfRange {
        /// The file.
        path: PathBuf,
        /// Where the face is.
        place: Place,
        /// The face number (0-based, in file order).
        face: usize,
        /// The offending index, as the file writes it (1-based in OBJ,
        /// 0-based in OFF and PLY).
        index: u64,
        /// How many vertices the mesh has.
        vertices: usize,
    },
    /// A vertex coordinate is NaN or infinite.
    #[error("{path}: {place}: vertex {vertex} has a non-finite coordinate (NaN or infinity)")]
    NonFinite {
        /// The file.
        path: PathBuf,
        /// Where the vertex is.
        place: Place,
        /// The vertex number (0-based).
        vertex: usize,
    },
    /// A coordinate is finite but too large for `f32` ray and contact tests.
    #[error(
        "{path}: vertex {vertex} has a coordinate of magnitude {value:e}; cbvh supports coordinates \
         up to ±{limit:e} (beyond that f32 triangle tests overflow): scale the mesh down or move it \
         nearer the origin"
    )]
    CoordinateTooLarge {
        /// The file (or mesh source).
        path: PathBuf,
        /// The vertex number (0-based).
        vertex: usize,
        /// The largest magnitude among its coordinates.
        value: f32,
        /// The supported limit, [`MAX_COORDINATE`](super::MAX_COORDINATE).
        limit: f32,
    },
    /// The file holds no faces at all.
    #[error("{path}: the mesh has no faces; cbvh needs at least one triangle")]
    NoFaces {
        /// The file.
        path: PathBuf,
    },
    /// Anything else malformed: a bad header, a bad number, a bad keyword.
    #[error("{path}: {place}: {message}")]
    Malformed {
        /// The file.
        path: PathBuf,
        /// Where the problem is.
        place: Place,
        /// What is wrong, and what was expected.
        message: String,
    },
}
