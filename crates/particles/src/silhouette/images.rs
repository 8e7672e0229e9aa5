//! Each view's image (decoded by `lodkit_mesh::image`) and silhouette,
//! from a mask image, the alpha channel or a background colour key.
//!
//! Sizes are read from the header and bounded (`lodkit_mesh::image::MAX_SIDE` a side, and
//! `lodkit_mesh::image::MAX_RUN_PIXELS` for all the images of one run, `PixelBudget`)
//! before any pixel buffer is allocated, so a small file whose header
//! claims 16384² pixels costs nothing; a size that disagrees with the
//! calibration's intrinsics is an error naming the camera.
use std::path::Path;

use lodkit_mesh::image::{RgbaImage, decode_rgba, image_size};
use lodkit_mesh::io::cameras::View;
use lodkit_mesh::io::input::read_file;

use crate::error::{Error, Result};

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

/// Reads and decodes `path` when its header says `size` (checked before
/// any pixel is decoded); `mismatch` words the error when it does not.
fn read_image(
    file: &Path,
    who: &str,
    path: &Path,
    what: &str,
    size: (u32, u32),
    mismatch: &dyn Fn(u32, u32) -> String,
) -> Result<RgbaImage> {
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
    let (w, h) = image_size(&bytes).map_err(bad)?;
    if (w, h) != size {
        return Err(Error::Input(format!(
            "{}: {who}: {}",
            file.display(),
            mismatch(w, h)
        )));
    }
    decode_rgba(&bytes).map_err(|e| {
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
