//! The one image decoder of lodkit (feature `images`): PNG (`png`, any
//! bit depth and colour type) and JPEG (`zune-jpeg`) to RGBA8, for
//! photographs (silhouettes) and textures alike; and what textures made
//! smaller need: an area-averaging resampler ([`resample`]) and the
//! encoders ([`encode_png`], [`encode_jpeg`], [`encode_like`]).
//!
//! Sizes are read from the header and bounded ([`MAX_SIDE`] a side,
//! [`MAX_PIXELS`] in all) before any pixel buffer is allocated, so a small
//! file whose header claims 16384² pixels costs nothing.

use std::path::Path;

use crate::io::input::read_file;

/// Largest image side accepted, in pixels.
pub const MAX_SIDE: u32 = 16_384;

/// Most pixels one image may have (64 Mi: 256 MiB as RGBA8).
pub const MAX_PIXELS: u64 = 1 << 26;

/// A PNG or JPEG decoded to RGBA8 ([`decode_rgba`]).
#[derive(Debug, Clone)]
pub struct RgbaImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width × height × 4` bytes, rows top to bottom.
    pub rgba: Vec<u8>,
    /// Whether some pixel is not opaque (an alpha channel opaque
    /// everywhere counts as none).
    pub has_alpha: bool,
}

/// Decodes a PNG (any bit depth and colour type) or JPEG (by its
/// signature) to RGBA8.
///
/// Sizes are read from the header and bounded (`1..=`[`MAX_SIDE`] a side,
/// at most [`MAX_PIXELS`]) before any pixel buffer is allocated. Errors: one
/// phrase saying what is wrong with the bytes (the caller names the
/// file). Cost: `O(width × height)`; memory about 12 bytes a pixel at
/// the peak.
pub fn decode_rgba(bytes: &[u8]) -> std::result::Result<RgbaImage, String> {
    decode(bytes)
}

fn check_size(w: u32, h: u32) -> std::result::Result<(), String> {
    if w == 0 || h == 0 || w > MAX_SIDE || h > MAX_SIDE {
        return Err(format!(
            "image size {w}x{h} is outside 1..={MAX_SIDE} a side"
        ));
    }
    if u64::from(w) * u64::from(h) > MAX_PIXELS {
        return Err(format!(
            "image size {w}x{h} is over the {MAX_PIXELS} pixels one image may have"
        ));
    }
    Ok(())
}

fn is_jpeg(bytes: &[u8]) -> bool {
    bytes.starts_with(&[0xFF, 0xD8, 0xFF])
}

/// Width and height of PNG or JPEG bytes, from the header only (nothing
/// is decoded). Errors: one phrase, as [`decode_rgba`].
pub fn image_size(bytes: &[u8]) -> std::result::Result<(u32, u32), String> {
    size_of(bytes)
}

/// Width and height of the PNG or JPEG at `path`, from its header only.
/// Errors name the file, one line.
pub fn header_size(path: &Path) -> std::result::Result<(u32, u32), String> {
    let bytes = read_file(path).map_err(|e| e.to_string())?;
    size_of(&bytes).map_err(|e| format!("{}: {e}", path.display()))
}

fn size_of(bytes: &[u8]) -> std::result::Result<(u32, u32), String> {
    if is_jpeg(bytes) {
        let mut d = zune_jpeg::JpegDecoder::new(bytes);
        d.decode_headers()
            .map_err(|e| format!("not a readable JPEG ({e:?})"))?;
        let i = d.info().ok_or("not a readable JPEG")?;
        Ok((u32::from(i.width), u32::from(i.height)))
    } else {
        let d = png::Decoder::new(std::io::Cursor::new(bytes));
        let r = d
            .read_info()
            .map_err(|e| format!("not a readable PNG or JPEG ({e})"))?;
        let (w, h) = r.info().size();
        Ok((w, h))
    }
}

fn decode(bytes: &[u8]) -> std::result::Result<RgbaImage, String> {
    let (w, h) = size_of(bytes)?;
    check_size(w, h)?;
    let px = w as usize * h as usize;
    if is_jpeg(bytes) {
        let opts = zune_jpeg::zune_core::options::DecoderOptions::default()
            .set_max_width(MAX_SIDE as usize)
            .set_max_height(MAX_SIDE as usize)
            .jpeg_set_out_colorspace(zune_jpeg::zune_core::colorspace::ColorSpace::RGB);
        let mut d = zune_jpeg::JpegDecoder::new_with_options(bytes, opts);
        let rgb = d
            .decode()
            .map_err(|e| format!("not a readable JPEG ({e:?})"))?;
        if rgb.len() != px * 3 {
            return Err("JPEG decoded to an unexpected size".into());
        }
        let mut rgba = Vec::with_capacity(px * 4);
        for p in rgb.chunks_exact(3) {
            rgba.extend_from_slice(&[p[0], p[1], p[2], 255]);
        }
        return Ok(RgbaImage {
            width: w,
            height: h,
            rgba,
            has_alpha: false,
        });
    }
    let mut d = png::Decoder::new_with_limits(
        std::io::Cursor::new(bytes),
        png::Limits {
            bytes: px * 8 + (1 << 20),
        },
    );
    d.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut r = d
        .read_info()
        .map_err(|e| format!("not a readable PNG ({e})"))?;
    let size = r.output_buffer_size().ok_or("PNG too large")?;
    if size > px * 8 {
        return Err("PNG frame larger than its size says".into());
    }
    let mut buf = vec![0u8; size];
    let info = r
        .next_frame(&mut buf)
        .map_err(|e| format!("not a readable PNG ({e})"))?;
    let (ct, _) = r.output_color_type();
    let ch = match ct {
        png::ColorType::Grayscale => 1,
        png::ColorType::GrayscaleAlpha => 2,
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        png::ColorType::Indexed => return Err("PNG palette was not expanded".into()),
    };
    let line = info.line_size;
    if line < w as usize * ch || buf.len() < line * h as usize {
        return Err("PNG rows shorter than its size says".into());
    }
    let rgba = if ch == 4 && line == w as usize * 4 {
        // Already RGBA8, rows packed: the decode buffer is the image.
        buf.truncate(px * 4);
        buf
    } else {
        to_rgba(&buf, line, w as usize, h as usize, ch)
    };
    // An alpha channel that is opaque everywhere says nothing about the
    // object (a photograph saved as RGBA): treated as no alpha.
    let has_alpha = (ch == 2 || ch == 4) && rgba.chunks_exact(4).any(|p| p[3] < 255);
    Ok(RgbaImage {
        width: w,
        height: h,
        rgba,
        has_alpha,
    })
}

/// Rows of `ch` channels (grey, grey + alpha, RGB, RGBA), `line` bytes
/// apart, as packed RGBA8.
fn to_rgba(buf: &[u8], line: usize, w: usize, h: usize, ch: usize) -> Vec<u8> {
    let mut rgba = Vec::with_capacity(w * h * 4);
    for y in 0..h {
        let row = &buf[y * line..y * line + w * ch];
        for p in row.chunks_exact(ch) {
            let v = match ch {
                1 => [p[0], p[0], p[0], 255],
                2 => [p[0], p[0], p[0], p[1]],
                3 => [p[0], p[1], p[2], 255],
                _ => [p[0], p[1], p[2], p[3]],
            };
            rgba.extend_from_slice(&v);
        }
    }
    rgba
}

/// The texels of `image` in the rectangle `[x0, y0, x1, y1)` (clamped to
/// the image, at least one texel) resampled to `width × height` (each at
/// least 1) by area averaging: each output texel is the rounded mean of
/// the source texels its area touches (a box filter; exact halving when
/// the sizes divide). Rows top to bottom, as [`RgbaImage`]. Cost: `O(rect
/// area + width × height)`; allocates the output only.
pub fn resample(image: &RgbaImage, rect: [u32; 4], width: u32, height: u32) -> RgbaImage {
    let x0 = rect[0].min(image.width - 1);
    let y0 = rect[1].min(image.height - 1);
    let (x1, y1) = (
        rect[2].clamp(x0 + 1, image.width),
        rect[3].clamp(y0 + 1, image.height),
    );
    let (cw, ch) = (u64::from(x1 - x0), u64::from(y1 - y0));
    let (ow, oh) = (u64::from(width.max(1)), u64::from(height.max(1)));
    let mut rgba = Vec::with_capacity((ow * oh * 4) as usize);
    let stride = image.width as usize * 4;
    for oy in 0..oh {
        let sy0 = u64::from(y0) + oy * ch / oh;
        let sy1 = (u64::from(y0) + ((oy + 1) * ch).div_ceil(oh)).max(sy0 + 1);
        for ox in 0..ow {
            let sx0 = u64::from(x0) + ox * cw / ow;
            let sx1 = (u64::from(x0) + ((ox + 1) * cw).div_ceil(ow)).max(sx0 + 1);
            let mut sum = [0u64; 4];
            for sy in sy0..sy1 {
                let row = &image.rgba[sy as usize * stride..][..stride];
                for p in row[sx0 as usize * 4..sx1 as usize * 4].chunks_exact(4) {
                    for k in 0..4 {
                        sum[k] += u64::from(p[k]);
                    }
                }
            }
            let n = (sy1 - sy0) * (sx1 - sx0);
            rgba.extend(sum.map(|s| ((s + n / 2) / n) as u8));
        }
    }
    RgbaImage {
        width: ow as u32,
        height: oh as u32,
        rgba,
        has_alpha: image.has_alpha,
    }
}

/// PNG bytes of `image`: 8-bit RGB when it is opaque ([`RgbaImage::has_alpha`]
/// false), else RGBA. Deterministic (same pixels, same bytes). Errors: one
/// phrase (an image whose buffer is not `width × height × 4` bytes).
pub fn encode_png(image: &RgbaImage) -> std::result::Result<Vec<u8>, String> {
    let mut bytes = Vec::new();
    let mut enc = png::Encoder::new(&mut bytes, image.width, image.height);
    let data: Vec<u8> = if image.has_alpha {
        enc.set_color(png::ColorType::Rgba);
        image.rgba.clone()
    } else {
        enc.set_color(png::ColorType::Rgb);
        image
            .rgba
            .chunks_exact(4)
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect()
    };
    enc.set_depth(png::BitDepth::Eight);
    enc.set_compression(png::Compression::Balanced);
    let fail = |e: png::EncodingError| format!("cannot encode a PNG ({e})");
    let mut writer = enc.write_header().map_err(fail)?;
    writer.write_image_data(&data).map_err(fail)?;
    writer.finish().map_err(fail)?;
    Ok(bytes)
}

/// Quality of the JPEGs lodkit writes (textures made smaller): 90 keeps
/// a photographic texture's detail at about a tenth of its PNG size.
pub const JPEG_QUALITY: u8 = 90;

/// Baseline JPEG bytes of `image` at `quality` (1..=100; alpha dropped),
/// 4:2:0 chroma subsampling. Deterministic (the scalar encoder, no
/// CPU-dependent paths). Errors: one phrase (a side over 65535 texels).
pub fn encode_jpeg(image: &RgbaImage, quality: u8) -> std::result::Result<Vec<u8>, String> {
    let (w, h) = (
        u16::try_from(image.width).map_err(|_| "image too wide for a JPEG".to_string())?,
        u16::try_from(image.height).map_err(|_| "image too tall for a JPEG".to_string())?,
    );
    let mut bytes = Vec::new();
    let enc = jpeg_encoder::Encoder::new(&mut bytes, quality.clamp(1, 100));
    enc.encode(&image.rgba, w, h, jpeg_encoder::ColorType::Rgba)
        .map_err(|e| format!("cannot encode a JPEG ({e})"))?;
    Ok(bytes)
}

/// `image` encoded in the format of `source` (the bytes it was decoded
/// from): JPEG ([`JPEG_QUALITY`]) for a JPEG source whose pixels are
/// opaque, else PNG. Returns the bytes and their MIME type. Errors: those
/// of the encoder.
pub fn encode_like(
    source: &[u8],
    image: &RgbaImage,
) -> std::result::Result<(Vec<u8>, &'static str), String> {
    if is_jpeg(source) && !image.has_alpha {
        Ok((encode_jpeg(image, JPEG_QUALITY)?, "image/jpeg"))
    } else {
        Ok((encode_png(image)?, "image/png"))
    }
}

/// Most pixels the images of one run may hold together (64 Mi: 64 views
/// of 1024², or one 8192² texture). Each decoded pixel costs 4 to 12 bytes
/// while decoding and some 8 kept (colour, silhouette, summed-area table),
/// so this keeps a run's images under about 700 MB.
pub const MAX_RUN_PIXELS: u64 = 1 << 26;

/// The pixels one run may still decode; every decode charges its header
/// size before allocating.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PixelBudget {
    left: u64,
}

impl PixelBudget {
    /// A budget of `pixels`.
    pub const fn new(pixels: u64) -> PixelBudget {
        PixelBudget { left: pixels }
    }

    /// A run's budget, [`MAX_RUN_PIXELS`].
    pub const fn run() -> PixelBudget {
        PixelBudget::new(MAX_RUN_PIXELS)
    }

    /// Pixels still allowed.
    pub fn left(&self) -> u64 {
        self.left
    }

    /// Takes `width × height` pixels from the budget. Errors (one phrase):
    /// the image does not fit in what is left.
    pub fn charge(&mut self, width: u32, height: u32) -> std::result::Result<(), String> {
        let px = u64::from(width) * u64::from(height);
        if px > self.left {
            return Err(format!(
                "an image of {width}x{height} pixels does not fit in the {} pixels left of the \
                 run's budget of {MAX_RUN_PIXELS} (all its images together)",
                self.left
            ));
        }
        self.left -= px;
        Ok(())
    }
}

#[cfg(test)]
mod resample_tests {
    use super::*;

    fn image(w: u32, h: u32) -> RgbaImage {
        let rgba = (0..w * h)
            .flat_map(|i| [(i % w) as u8, (i / w) as u8, 7, 255])
            .collect();
        RgbaImage {
            width: w,
            height: h,
            rgba,
            has_alpha: false,
        }
    }

    #[test]
    fn halving_averages_each_two_by_two_block() {
        let s = resample(&image(8, 6), [0, 0, 8, 6], 4, 3);
        assert_eq!((s.width, s.height), (4, 3));
        // Texel (1, 1): x 2..4, y 2..4, means 2.5 each, rounded up.
        assert_eq!(&s.rgba[(4 + 1) * 4..][..4], &[3, 3, 7, 255]);
        let crop = resample(&image(8, 6), [2, 1, 5, 4], 3, 3);
        assert_eq!(&crop.rgba[..4], &[2, 1, 7, 255]);
    }

    #[test]
    fn an_encoded_png_decodes_to_the_same_pixels() {
        let im = image(5, 3);
        let back = decode_rgba(&encode_png(&im).unwrap()).unwrap();
        assert_eq!((back.width, back.height), (5, 3));
        assert_eq!(back.rgba, im.rgba);
    }

    #[test]
    fn an_encoded_jpeg_decodes_to_about_the_same_pixels() {
        let im = image(16, 8);
        let jpeg = encode_jpeg(&im, JPEG_QUALITY).unwrap();
        assert!(is_jpeg(&jpeg));
        let back = decode_rgba(&jpeg).unwrap();
        assert_eq!((back.width, back.height), (16, 8));
        let worst = back
            .rgba
            .iter()
            .zip(&im.rgba)
            .map(|(a, b)| a.abs_diff(*b))
            .max();
        assert!(worst.unwrap() <= 12, "{worst:?}");
        assert_eq!(encode_like(&jpeg, &im).unwrap().1, "image/jpeg");
        assert_eq!(
            encode_like(&encode_png(&im).unwrap(), &im).unwrap().1,
            "image/png"
        );
    }
}
