//! 8-bit sRGB images and, with the `image-files` feature, their output:
//! PNG, and for turntables animated PNG (APNG, lossless) or GIF (256
//! colours per frame, NeuQuant).

use glam::Vec3A;

#[cfg(feature = "image-files")]
mod files;
#[cfg(feature = "image-files")]
pub use files::{save_animation, save_apng, save_gif};

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
}
