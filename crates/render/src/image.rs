//! Images and masks, and their PNG bytes.
//!
//! PNG bytes are deterministic: fixed DEFLATE level and row filter, and no
//! chunk that carries a time, a path or the encoder's name. The bytes can
//! change only with the `png` crate's compressor (pinned by `Cargo.lock`).

use crate::RenderError;

/// DEFLATE level of every PNG written (zlib's default trade-off).
pub const PNG_DEFLATE_LEVEL: u8 = 6;

/// An RGBA8 image, rows top to bottom, 4 bytes a pixel, straight (not
/// premultiplied) alpha.
///
/// A [`render`](crate::render()) output has alpha = the fraction of the
/// pixel's samples the object covers, RGB = the mean colour of those
/// samples, and RGB = the background colour where alpha is 0.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width × height × 4` bytes.
    pub pixels: Vec<u8>,
}

/// An 8-bit single-channel mask, rows top to bottom: 255 where the object
/// covers at least one sample of the pixel, 0 elsewhere.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Mask {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width × height` bytes, each 0 or 255.
    pub pixels: Vec<u8>,
}

impl Image {
    /// The pixel at column `x`, row `y` (`x < width`, `y < height`).
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 4] {
        let i = (y as usize * self.width as usize + x as usize) * 4;
        [
            self.pixels[i],
            self.pixels[i + 1],
            self.pixels[i + 2],
            self.pixels[i + 3],
        ]
    }

    /// The object mask: 255 where alpha > 0.
    pub fn mask(&self) -> Mask {
        Mask {
            width: self.width,
            height: self.height,
            pixels: self
                .pixels
                .chunks_exact(4)
                .map(|p| if p[3] > 0 { 255 } else { 0 })
                .collect(),
        }
    }

    /// The image composited over `background` with alpha 255 everywhere:
    /// what a picture for people wants (a viewer shows no checkerboard).
    pub fn over(&self, background: [u8; 3]) -> Image {
        let mut pixels = self.pixels.clone();
        for p in pixels.chunks_exact_mut(4) {
            let a = p[3] as u32;
            for c in 0..3 {
                p[c] = ((p[c] as u32 * a + background[c] as u32 * (255 - a) + 127) / 255) as u8;
            }
            p[3] = 255;
        }
        Image {
            width: self.width,
            height: self.height,
            pixels,
        }
    }

    /// PNG bytes (8-bit RGBA). Same image, same bytes. Cost: one DEFLATE
    /// pass over the pixels. Errors only if the encoder fails (an image of
    /// zero size).
    pub fn to_png(&self) -> Result<Vec<u8>, RenderError> {
        encode_png(self.width, self.height, png::ColorType::Rgba, &self.pixels)
    }
}

impl Mask {
    /// Fraction of the pixels that are 255.
    pub fn coverage(&self) -> f64 {
        if self.pixels.is_empty() {
            return 0.0;
        }
        self.pixels.iter().filter(|&&p| p != 0).count() as f64 / self.pixels.len() as f64
    }

    /// Whether pixel (`x`, `y`) is object (false outside the image).
    pub fn get(&self, x: i64, y: i64) -> bool {
        x >= 0
            && y >= 0
            && x < self.width as i64
            && y < self.height as i64
            && self.pixels[y as usize * self.width as usize + x as usize] != 0
    }

    /// PNG bytes (8-bit greyscale), deterministic as [`Image::to_png`].
    pub fn to_png(&self) -> Result<Vec<u8>, RenderError> {
        encode_png(
            self.width,
            self.height,
            png::ColorType::Grayscale,
            &self.pixels,
        )
    }
}

fn encode_png(w: u32, h: u32, colour: png::ColorType, data: &[u8]) -> Result<Vec<u8>, RenderError> {
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, w, h);
    enc.set_color(colour);
    enc.set_depth(png::BitDepth::Eight);
    enc.set_deflate_compression(png::DeflateCompression::Level(PNG_DEFLATE_LEVEL));
    enc.set_filter(png::Filter::Adaptive);
    let fail = |e: png::EncodingError| RenderError::Png(e.to_string());
    let mut writer = enc.write_header().map_err(fail)?;
    writer.write_image_data(data).map_err(fail)?;
    writer.finish().map_err(fail)?;
    Ok(out)
}
