//! The 8-bit RGB raster the figures are drawn into, and its PNG encoding (8-bit RGB, no
//! alpha, written atomically through [`crate::io::write_atomic`]).

use crate::io::write_atomic;
use crate::{Error, Result};
use std::path::Path;

/// An 8-bit RGB image, rows stored top to bottom, pixels left to right.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RgbImage {
    pub width: u32,
    pub height: u32,
    /// `width · height` pixels; the pixel (x, y) is at `y · width + x`.
    pub pixels: Vec<[u8; 3]>,
}

impl RgbImage {
    /// An image of `width × height` pixels, all of colour `fill`.
    pub fn new(width: u32, height: u32, fill: [u8; 3]) -> Self {
        RgbImage {
            width,
            height,
            pixels: vec![fill; width as usize * height as usize],
        }
    }

    /// The pixel at column `x`, row `y` (row 0 on top), or `None` outside the image.
    pub fn get(&self, x: u32, y: u32) -> Option<[u8; 3]> {
        (x < self.width && y < self.height)
            .then(|| self.pixels[y as usize * self.width as usize + x as usize])
    }

    /// Sets the pixel at column `x`, row `y`; does nothing outside the image.
    pub fn set(&mut self, x: u32, y: u32, color: [u8; 3]) {
        if x < self.width && y < self.height {
            self.pixels[y as usize * self.width as usize + x as usize] = color;
        }
    }

    /// Fills the rectangle of `w × h` pixels whose top-left corner is (x, y), clipped to the image.
    pub fn fill_rect(&mut self, x: i64, y: i64, w: i64, h: i64, color: [u8; 3]) {
        let x0 = x.clamp(0, self.width as i64) as usize;
        let x1 = (x + w).clamp(0, self.width as i64) as usize;
        let y0 = y.clamp(0, self.height as i64) as usize;
        let y1 = (y + h).clamp(0, self.height as i64) as usize;
        for row in y0..y1 {
            let start = row * self.width as usize;
            self.pixels[start + x0..start + x1].fill(color);
        }
    }

    /// Copies `other` into this image with its top-left corner at (x, y), clipped to the image.
    pub fn blit(&mut self, other: &RgbImage, x: i64, y: i64) {
        for oy in 0..other.height as i64 {
            let ty = y + oy;
            if ty < 0 || ty >= self.height as i64 {
                continue;
            }
            for ox in 0..other.width as i64 {
                let tx = x + ox;
                if tx >= 0 && tx < self.width as i64 {
                    self.pixels[ty as usize * self.width as usize + tx as usize] =
                        other.pixels[oy as usize * other.width as usize + ox as usize];
                }
            }
        }
    }

    /// The number of pixels that differ from `background`.
    pub fn count_not(&self, background: [u8; 3]) -> usize {
        self.pixels.iter().filter(|&&p| p != background).count()
    }

    /// The pixels as one flat `r, g, b, r, g, b, …` slice.
    pub fn as_bytes(&self) -> &[u8] {
        self.pixels.as_flattened()
    }

    /// The pixels as one flat mutable `r, g, b, …` slice (what drawing libraries take).
    pub fn as_bytes_mut(&mut self) -> &mut [u8] {
        self.pixels.as_flattened_mut()
    }
}

/// Encodes `image` as an 8-bit RGB PNG into `out`.
fn encode_png(image: &RgbImage, out: &mut dyn std::io::Write, path: &Path) -> Result<()> {
    let mut encoder = png::Encoder::new(out, image.width, image.height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    // fdeflate's PNG-tuned compression: on a repair's picture (1200 × 800) about 5 ms where
    // zlib's default level took about 25 ms, for a file 1.7 times as large (270 kB, not 160 kB).
    encoder.set_compression(png::Compression::Fast);
    let fail = |e: png::EncodingError| match e {
        png::EncodingError::IoError(e) => Error::io(path, e),
        other => Error::format(path, format!("cannot encode PNG: {other}")),
    };
    let mut writer = encoder.write_header().map_err(fail)?;
    writer.write_image_data(image.as_bytes()).map_err(fail)?;
    writer.finish().map_err(fail)
}

/// Writes `image` to `path` as an 8-bit RGB PNG. The file appears only once it is complete: on
/// any error (an empty image, a missing folder, a full disk) nothing is left at `path`.
pub fn write_png(path: &Path, image: &RgbImage) -> Result<()> {
    if image.width == 0 || image.height == 0 {
        return Err(Error::format(
            path,
            format!(
                "cannot write an empty {}×{} image",
                image.width, image.height
            ),
        ));
    }
    if image.pixels.len() != image.width as usize * image.height as usize {
        return Err(Error::format(
            path,
            format!(
                "image has {} pixels, expected {}×{}",
                image.pixels.len(),
                image.width,
                image.height
            ),
        ));
    }
    write_atomic(path, |out| encode_png(image, out, path))
}
