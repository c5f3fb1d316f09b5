//! 8-bit sRGB images and, with the `image-files` feature, their output:
//! PNG, and for turntables animated PNG (APNG, lossless) or GIF (256
//! colours per frame, NeuQuant).

#[cfg(feature = "image-files")]
use std::fs::File;
#[cfg(feature = "image-files")]
use std::io::BufWriter;
#[cfg(feature = "image-files")]
use std::path::Path;

use glam::Vec3A;

#[cfg(feature = "image-files")]
use super::error::RenderError;

/// An RGB image, 8 bits per channel (sRGB), rows top to bottom.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Image {
    width: u32,
    height: u32,
    data: Vec<u8>,
}

/// Linear `[0, ∞)` to an 8-bit sRGB value (values above 1 clip).
#[inline]
pub fn linear_to_srgb8(c: f32) -> u8 {
    let c = if c.is_finite() {
        c.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let s = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

impl Image {
    /// A black image.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            data: vec![0; width as usize * height as usize * 3],
        }
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The pixels, `[r, g, b]` row by row.
    pub fn data(&self) -> &[u8] {
        &self.data
    }

    /// The pixel at `(x, y)`, row 0 at the top.
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 3] {
        let i = (y as usize * self.width as usize + x as usize) * 3;
        [self.data[i], self.data[i + 1], self.data[i + 2]]
    }

    /// Sets pixel `(x, y)` from a linear colour.
    pub fn set_linear(&mut self, x: u32, y: u32, c: Vec3A) {
        let i = (y as usize * self.width as usize + x as usize) * 3;
        self.data[i] = linear_to_srgb8(c.x);
        self.data[i + 1] = linear_to_srgb8(c.y);
        self.data[i + 2] = linear_to_srgb8(c.z);
    }

    /// Copies `block` (`w × h` pixels, RGB) to `(x0, y0)`.
    pub(crate) fn blit(&mut self, x0: u32, y0: u32, w: u32, h: u32, block: &[u8]) {
        let row = w as usize * 3;
        for y in 0..h as usize {
            let dst = ((y0 as usize + y) * self.width as usize + x0 as usize) * 3;
            self.data[dst..dst + row].copy_from_slice(&block[y * row..(y + 1) * row]);
        }
    }

    /// The fraction of pixels that differ between two images of one size
    /// (1.0 when the sizes differ).
    pub fn fraction_differing(&self, other: &Image) -> f64 {
        if (self.width, self.height) != (other.width, other.height) {
            return 1.0;
        }
        let n = self
            .data
            .chunks_exact(3)
            .zip(other.data.chunks_exact(3))
            .filter(|(a, b)| a != b)
            .count();
        n as f64 / (self.width as f64 * self.height as f64).max(1.0)
    }

    /// Mean brightness (0–255) of the `(2r+1)²` block around `(x, y)`,
    /// clipped to the image.
    pub fn mean_around(&self, x: u32, y: u32, r: u32) -> f64 {
        let (mut sum, mut n) = (0u64, 0u64);
        for yy in y.saturating_sub(r)..(y + r + 1).min(self.height) {
            for xx in x.saturating_sub(r)..(x + r + 1).min(self.width) {
                sum += self.pixel(xx, yy).iter().map(|&c| c as u64).sum::<u64>();
                n += 3;
            }
        }
        sum as f64 / n.max(1) as f64
    }

    /// Writes the image as an 8-bit RGB PNG (feature `image-files`).
    #[cfg(feature = "image-files")]
    pub fn save_png(&self, path: impl AsRef<Path>) -> Result<(), RenderError> {
        save_frames(std::slice::from_ref(self), path.as_ref(), None)
    }
}

#[cfg(feature = "image-files")]
/// Writes `frames` as an animated PNG looping forever at `fps` frames per
/// second (viewers without APNG support show the first frame).
pub fn save_apng(frames: &[Image], path: impl AsRef<Path>, fps: u16) -> Result<(), RenderError> {
    save_frames(frames, path.as_ref(), Some(fps.max(1)))
}

#[cfg(feature = "image-files")]
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

#[cfg(feature = "image-files")]
fn create(path: &Path) -> Result<BufWriter<File>, RenderError> {
    File::create(path)
        .map(BufWriter::new)
        .map_err(|source| RenderError::Io {
            path: path.to_path_buf(),
            source,
        })
}

#[cfg(feature = "image-files")]
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
    let mut enc = gif::Encoder::new(create(path)?, gw, gh, &[]).map_err(gif_err)?;
    enc.set_repeat(gif::Repeat::Infinite).map_err(gif_err)?;
    let delay = ((100.0 / fps.max(1) as f32).round() as u16).max(2);
    for f in frames {
        let mut frame = gif::Frame::from_rgb_speed(gw, gh, &f.data, 10);
        frame.delay = delay;
        enc.write_frame(&frame).map_err(gif_err)?;
    }
    enc.into_inner().map_err(gif_err)?;
    Ok(())
}

#[cfg(feature = "image-files")]
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

#[cfg(feature = "image-files")]
fn save_frames(frames: &[Image], path: &Path, fps: Option<u16>) -> Result<(), RenderError> {
    let want = frame_size(frames)?;
    let png_err = |source| RenderError::Png {
        path: path.to_path_buf(),
        source,
    };
    let mut enc = png::Encoder::new(create(path)?, want.0, want.1);
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
    writer.finish().map_err(png_err)
}
