//! Images and silhouettes: PNG (`png`) and JPEG (`zune-jpeg`) decoded to
//! RGB, and each view's silhouette from a mask image, the alpha channel or
//! a background colour key.
//!
//! Sizes are read from the header and bounded ([`MAX_SIDE`] a side, and
//! [`MAX_RUN_PIXELS`] for all the images of one run, [`PixelBudget`])
//! before any pixel buffer is allocated, so a small file whose header
//! claims 16384² pixels costs nothing; a size that disagrees with the
//! calibration's intrinsics is an error naming the camera.
use std::path::Path;

use lodkit_mesh::io::input::read_file;

use crate::error::{Error, Result};
use crate::silhouette::calibration::{MAX_SIDE, View};

/// Where silhouettes come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SilhouetteSource {
    /// A view's mask image when the calibration names one (or the
    /// layout's `masks/` folder holds it), else the image's alpha channel.
    #[default]
    Auto,
    /// The alpha channel: a pixel with alpha > 0 is the object (an alpha
    /// channel opaque everywhere counts as none).
    Alpha,
    /// The mask images: a pixel of grey value ≥ 128 is the object.
    Masks,
    /// Background colour key: a pixel whose every channel is within
    /// `tolerance` of `colour` is background, any other is the object.
    Key {
        /// The background colour.
        colour: [u8; 3],
        /// Largest per-channel difference still counted as background.
        tolerance: u8,
    },
}

/// A decoded view: RGB pixels and the silhouette.
#[derive(Debug, Clone)]
pub struct ViewImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width × height × 3` bytes, rows top to bottom.
    pub rgb: Vec<u8>,
    /// `width × height` flags: the object covers the pixel.
    pub silhouette: Vec<bool>,
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

/// A PNG or JPEG decoded to RGBA8 ([`decode_rgba`]).
#[derive(Debug, Clone)]
pub struct Decoded {
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
/// signature) to RGBA8; the one image decoder of lodkit, used for
/// photographs here and for textures by `lodkit render`.
///
/// Sizes are read from the header and bounded (`1..=MAX_SIDE` a side,
/// [`crate::silhouette::calibration::MAX_SIDE`], at most
/// [`MAX_RUN_PIXELS`]) before any pixel buffer is allocated. Errors: one
/// phrase saying what is wrong with the bytes (the caller names the
/// file). Cost: `O(width × height)`; memory about 12 bytes a pixel at
/// the peak.
pub fn decode_rgba(bytes: &[u8]) -> std::result::Result<Decoded, String> {
    decode(bytes)
}

fn check_size(w: u32, h: u32) -> std::result::Result<(), String> {
    if w == 0 || h == 0 || w > MAX_SIDE || h > MAX_SIDE {
        return Err(format!(
            "image size {w}x{h} is outside 1..={MAX_SIDE} a side"
        ));
    }
    if u64::from(w) * u64::from(h) > MAX_RUN_PIXELS {
        return Err(format!(
            "image size {w}x{h} is over the {MAX_RUN_PIXELS} pixels one run may decode"
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

/// Width and height of a PNG or JPEG from its header only.
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

fn decode(bytes: &[u8]) -> std::result::Result<Decoded, String> {
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
        return Ok(Decoded {
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
    Ok(Decoded {
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

/// Reads and decodes `path` when its header says `size` (checked before
/// any pixel is decoded); `mismatch` words the error when it does not.
fn read_image(
    file: &Path,
    who: &str,
    path: &Path,
    what: &str,
    size: (u32, u32),
    mismatch: &dyn Fn(u32, u32) -> String,
) -> Result<Decoded> {
    if !path.is_file() {
        return Err(Error::Input(format!(
            "{}: {who}: {what} {} is missing",
            file.display(),
            path.display()
        )));
    }
    let bytes =
        read_file(path).map_err(|e| Error::Input(format!("{}: {who}: {e}", file.display())))?;
    let bad = |e: String| {
        Error::Input(format!(
            "{}: {who}: {what} {}: {e}",
            file.display(),
            path.display()
        ))
    };
    let (w, h) = size_of(&bytes).map_err(bad)?;
    if (w, h) != size {
        return Err(Error::Input(format!(
            "{}: {who}: {}",
            file.display(),
            mismatch(w, h)
        )));
    }
    decode(&bytes).map_err(|e| {
        Error::Input(format!(
            "{}: {who}: {what} {}: {e}",
            file.display(),
            path.display()
        ))
    })
}

/// Loads `view`'s image and silhouette (`file`, the calibration, names
/// errors). Errors: a missing or unreadable image or mask, a size that is
/// not the intrinsics' `width × height`, no silhouette source.
pub fn load(file: &Path, view: &View, source: SilhouetteSource) -> Result<ViewImage> {
    let who = &view.label;
    let (w, h) = (view.lens.width, view.lens.height);
    let img = read_image(file, who, &view.image, "image", (w, h), &|iw, ih| {
        format!(
            "image {} is {iw}x{ih}, the intrinsics say {w}x{h}",
            view.image.display()
        )
    })?;
    let source = match source {
        SilhouetteSource::Auto if view.mask.is_some() => SilhouetteSource::Masks,
        SilhouetteSource::Auto if img.has_alpha => SilhouetteSource::Alpha,
        SilhouetteSource::Auto => {
            return Err(Error::Input(format!(
                "{}: {who}: image {} has no alpha channel and no mask is named; give --key-colour",
                file.display(),
                view.image.display()
            )));
        }
        s => s,
    };
    let silhouette: Vec<bool> = match source {
        SilhouetteSource::Alpha => {
            if !img.has_alpha {
                return Err(Error::Input(format!(
                    "{}: {who}: image {} has no alpha channel",
                    file.display(),
                    view.image.display()
                )));
            }
            img.rgba.chunks_exact(4).map(|p| p[3] > 0).collect()
        }
        SilhouetteSource::Masks => {
            let Some(mp) = &view.mask else {
                return Err(Error::Input(format!(
                    "{}: {who}: no mask image is named for it",
                    file.display()
                )));
            };
            let m = read_image(file, who, mp, "mask", (w, h), &|mw, mh| {
                format!("mask {} is {mw}x{mh}, the image is {w}x{h}", mp.display())
            })?;
            m.rgba.chunks_exact(4).map(|p| p[0] >= 128).collect()
        }
        SilhouetteSource::Key { colour, tolerance } => img
            .rgba
            .chunks_exact(4)
            .map(|p| (0..3).any(|c| p[c].abs_diff(colour[c]) > tolerance))
            .collect(),
        SilhouetteSource::Auto => unreachable!("resolved above"),
    };
    let mut rgb = Vec::with_capacity(w as usize * h as usize * 3);
    for p in img.rgba.chunks_exact(4) {
        rgb.extend_from_slice(&p[..3]);
    }
    Ok(ViewImage {
        width: w,
        height: h,
        rgb,
        silhouette,
    })
}

/// Decodes image bytes (the fuzz target's entry): width and height.
#[doc(hidden)]
pub fn decode_for_fuzzing(bytes: &[u8]) -> std::result::Result<(u32, u32), String> {
    decode(bytes).map(|d| (d.width, d.height))
}
