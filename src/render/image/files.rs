//! The image files (feature `image-files`): PNG, and for turntables
//! animated PNG (APNG, lossless) or GIF (256 colours per frame, NeuQuant).

use std::path::Path;

use super::Image;
use crate::files::{AtomicFile, IoError};
use crate::render::error::RenderError;

impl Image {
    /// Writes the image as an 8-bit RGB PNG.
    pub fn save_png(&self, path: impl AsRef<Path>) -> Result<(), RenderError> {
        save_frames(std::slice::from_ref(self), path.as_ref(), None)
    }
}

/// Writes `frames` as an animated PNG looping forever at `fps` frames per
/// second (viewers without APNG support show the first frame).
pub fn save_apng(frames: &[Image], path: impl AsRef<Path>, fps: u16) -> Result<(), RenderError> {
    save_frames(frames, path.as_ref(), Some(fps.max(1)))
}

/// The size shared by all `frames`, checked non-zero.
fn frame_size(frames: &[Image]) -> Result<(u32, u32), RenderError> {
    let first = frames.first().ok_or(RenderError::NoFrames)?;
    let want = (first.width, first.height);
    if want.0 == 0 || want.1 == 0 {
        return Err(RenderError::ZeroSize {
            width: want.0,
            height: want.1,
        });
    }
    if let Some((frame, f)) = frames
        .iter()
        .enumerate()
        .find(|(_, f)| (f.width, f.height) != want)
    {
        return Err(RenderError::FrameSize {
            frame,
            got: (f.width, f.height),
            want,
        });
    }
    Ok(want)
}

/// The image file, written atomically ([`crate::files`]).
fn create(path: &Path) -> Result<AtomicFile, RenderError> {
    AtomicFile::create(path).map_err(|e| RenderError::Io(IoError::new(path, e)))
}

/// Makes the written file visible under its name.
fn commit(file: AtomicFile, path: &Path) -> Result<(), RenderError> {
    file.commit()
        .map_err(|e| RenderError::Io(IoError::new(path, e)))
}

/// Writes `frames` as a GIF looping forever at about `fps` frames per
/// second (GIF delays are whole hundredths of a second, at least 2), each
/// frame quantised to its own 256-colour palette.
pub fn save_gif(frames: &[Image], path: impl AsRef<Path>, fps: u16) -> Result<(), RenderError> {
    let path = path.as_ref();
    let (w, h) = frame_size(frames)?;
    let (Ok(gw), Ok(gh)) = (u16::try_from(w), u16::try_from(h)) else {
        return Err(RenderError::TooLargeForGif {
            width: w,
            height: h,
        });
    };
    let gif_err = |source| RenderError::Gif {
        path: path.to_path_buf(),
        source,
    };
    let mut file = create(path)?;
    let mut enc = gif::Encoder::new(&mut file, gw, gh, &[]).map_err(gif_err)?;
    enc.set_repeat(gif::Repeat::Infinite).map_err(gif_err)?;
    let delay = ((100.0 / fps.max(1) as f32).round() as u16).max(2);
    for f in frames {
        let mut frame = gif::Frame::from_rgb_speed(gw, gh, &f.data, 10);
        frame.delay = delay;
        enc.write_frame(&frame).map_err(gif_err)?;
    }
    enc.into_inner().map_err(gif_err)?;
    commit(file, path)
}

/// Writes an animation by the file's extension: `.gif` as GIF
/// ([`save_gif`]), anything else as animated PNG ([`save_apng`]).
pub fn save_animation(
    frames: &[Image],
    path: impl AsRef<Path>,
    fps: u16,
) -> Result<(), RenderError> {
    let path = path.as_ref();
    let gif = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gif"));
    if gif {
        save_gif(frames, path, fps)
    } else {
        save_apng(frames, path, fps)
    }
}

fn save_frames(frames: &[Image], path: &Path, fps: Option<u16>) -> Result<(), RenderError> {
    let want = frame_size(frames)?;
    let png_err = |source| RenderError::Png {
        path: path.to_path_buf(),
        source,
    };
    let mut file = create(path)?;
    let mut enc = png::Encoder::new(&mut file, want.0, want.1);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    enc.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
    if let Some(fps) = fps {
        enc.set_animated(frames.len() as u32, 0).map_err(png_err)?;
        enc.set_frame_delay(1, fps).map_err(png_err)?;
    }
    let mut writer = enc.write_header().map_err(png_err)?;
    for f in frames {
        writer.write_image_data(&f.data).map_err(png_err)?;
    }
    writer.finish().map_err(png_err)?;
    commit(file, path)
}
