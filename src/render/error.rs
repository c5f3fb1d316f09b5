//! What can stop a render or its output.

use crate::build::BuildError;

/// A render or image-output error.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// Width or height is zero.
    #[error("the image must be at least 1 × 1 pixels, got {width} × {height}")]
    ZeroSize {
        /// Requested width.
        width: u32,
        /// Requested height.
        height: u32,
    },
    /// A turntable needs at least one frame.
    #[error("a turntable needs at least one frame")]
    NoFrames,
    /// The frames of an animation differ in size.
    #[error(
        "animation frame {frame} is {got:?} pixels but frame 0 is {want:?}; render all frames at one size"
    )]
    FrameSize {
        /// Index of the offending frame.
        frame: usize,
        /// Its size.
        got: (u32, u32),
        /// The first frame's size.
        want: (u32, u32),
    },
    /// The output file could not be created or written.
    #[error("cannot write {0}")]
    Io(#[source] crate::files::IoError),
    /// The PNG encoder failed.
    #[cfg(feature = "image-files")]
    #[error("cannot encode {path} as PNG: {source}")]
    Png {
        /// The file.
        path: std::path::PathBuf,
        /// Why.
        source: png::EncodingError,
    },
    /// The GIF encoder failed.
    #[cfg(feature = "image-files")]
    #[error("cannot encode {path} as GIF: {source}")]
    Gif {
        /// The file.
        path: std::path::PathBuf,
        /// Why.
        source: gif::EncodingError,
    },
    /// GIF sizes are 16-bit.
    #[error(
        "a GIF can be at most 65535 × 65535 pixels, got {width} × {height}; write an animated PNG instead"
    )]
    TooLargeForGif {
        /// Requested width.
        width: u32,
        /// Requested height.
        height: u32,
    },
    /// Building a BVH for a mesh failed.
    #[error("cannot build a BVH for mesh {mesh}: {source}")]
    Build {
        /// Index of the mesh in the list given.
        mesh: usize,
        /// Why.
        source: BuildError,
    },
}
