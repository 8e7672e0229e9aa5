//! The readers: a COLMAP text model (`cameras.txt` + `images.txt`) and
//! NeRF's `transforms.json`, to a [`Calibration`].
//!
//! **Paths.** Every name a calibration file holds goes through
//! [`resolve_inside`]: relative, no `..`, no scheme, inside the folder it
//! is relative to (the JSON file's folder; for COLMAP the image folder,
//! COLMAP's own convention for `NAME`). NeRF paths are percent-decoded
//! first. **Errors** are one line naming the file, the camera (frame index
//! or image id and its name) and what is wrong.
use std::path::{Path, PathBuf};

use glam::{DMat3, DQuat, DVec3};

use super::{
    COLMAP_DIR, Calibration, IMAGES_DIR, Lens, MASKS_DIR, MAX_VIEWS, TRANSFORMS_FILE, View,
};
use crate::Intrinsics;
use crate::error::{Error, Result};
use crate::image::MAX_SIDE;
use crate::io::input::{lexically_inside, read_file, resolve_inside, strip_bom};

fn err<T>(file: &Path, msg: impl std::fmt::Display) -> Result<T> {
    Err(Error::Parse {
        path: file.to_path_buf(),
        message: msg.to_string(),
    })
}

/// Reads a calibration: a `transforms.json` (any `.json`), a COLMAP
/// `cameras.txt` or `images.txt` (the other file is its sibling), or a
/// folder holding `transforms.json`, `sparse/0/cameras.txt`,
/// `sparse/cameras.txt` or `cameras.txt`.
///
/// Cost: the file's size, plus one image header when a NeRF file gives no
/// image size. Errors: one line naming the file and the camera.
pub fn read(path: &Path) -> Result<Calibration> {
    let path = if path.is_dir() {
        let found = [
            TRANSFORMS_FILE.to_string(),
            format!("{COLMAP_DIR}/cameras.txt"),
            "sparse/cameras.txt".to_string(),
            "cameras.txt".to_string(),
        ]
        .iter()
        .map(|n| path.join(n))
        .find(|p| p.is_file());
        match found {
            Some(p) => p,
            None => {
                return err(
                    path,
                    "holds no transforms.json, sparse/0/cameras.txt or cameras.txt",
                );
            }
        }
    } else {
        path.to_path_buf()
    };
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase());
    match name.as_deref() {
        Some(n) if n.ends_with(".json") => read_transforms(&path),
        Some("cameras.txt") => read_colmap(&path, &path.with_file_name("images.txt")),
        Some("images.txt") => read_colmap(&path.with_file_name("cameras.txt"), &path),
        _ => err(
            &path,
            "is not a calibration: give a transforms.json or a COLMAP cameras.txt / images.txt",
        ),
    }
}

fn read_text(path: &Path) -> Result<String> {
    let bytes = read_file(path)?;
    match std::str::from_utf8(strip_bom(&bytes)) {
        Ok(s) => Ok(s.to_string()),
        Err(e) => err(
            path,
            format!("is not UTF-8 text (byte {})", e.valid_up_to()),
        ),
    }
}

fn finite(file: &Path, what: &str, v: f64) -> Result<f64> {
    if v.is_finite() && v.abs() <= 1e12 {
        Ok(v)
    } else {
        err(
            file,
            format!("{what} is {v}, not a finite number of at most 1e12"),
        )
    }
}

fn check_lens(file: &Path, who: &str, l: &Lens) -> Result<()> {
    if l.width == 0 || l.height == 0 || l.width > MAX_SIDE || l.height > MAX_SIDE {
        return err(
            file,
            format!(
                "{who}: image size {}x{} is outside 1..={MAX_SIDE} a side",
                l.width, l.height
            ),
        );
    }
    for (n, v) in [("fx", l.fx), ("fy", l.fy)] {
        if !(v.is_finite() && v > 0.0 && v <= 1e9) {
            return err(
                file,
                format!("{who}: focal length {n} = {v} is not in (0, 1e9] pixels"),
            );
        }
    }
    for (n, v) in [
        ("cx", l.cx),
        ("cy", l.cy),
        ("k1", l.k1),
        ("k2", l.k2),
        ("p1", l.p1),
        ("p2", l.p2),
    ] {
        if !(v.is_finite() && v.abs() <= 1e9) {
            return err(
                file,
                format!("{who}: {n} = {v} is not a finite number of at most 1e9"),
            );
        }
    }
    Ok(())
}

// ---------------------------------------------------------------- COLMAP

/// The image folder of a COLMAP model in `model_dir`, as the folder the
/// names are kept inside and the prefix of every name: `P` and `images/`
/// for a model in `P/sparse/N` or `P/sparse` (COLMAP's project layout),
/// else `model_dir` and `images/` when `model_dir/images` exists, else
/// `model_dir` and no prefix. So `images/` itself is inside the folder
/// checked: an image folder that is a symlink out of it is refused.
fn colmap_image_dir(model_dir: &Path) -> (PathBuf, &'static str) {
    let mut p = model_dir.to_path_buf();
    for _ in 0..2 {
        if p.file_name().is_some_and(|n| n == "sparse")
            && let Some(project) = p.parent()
        {
            return (project.to_path_buf(), "images/");
        }
        match p.parent() {
            Some(q) => p = q.to_path_buf(),
            None => break,
        }
    }
    if model_dir.join(IMAGES_DIR).is_dir() {
        (model_dir.to_path_buf(), "images/")
    } else {
        (model_dir.to_path_buf(), "")
    }
}

fn read_colmap(cameras: &Path, images: &Path) -> Result<Calibration> {
    let ctext = read_text(cameras)?;
    let itext = read_text(images)?;
    parse_colmap(cameras, &ctext, images, &itext)
}

fn parse_colmap(cameras: &Path, ctext: &str, images: &Path, itext: &str) -> Result<Calibration> {
    let mut lenses: Vec<(u64, Lens)> = Vec::new();
    for (no, line) in ctext.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let at = format!("line {}", no + 1);
        let t: Vec<&str> = line.split_whitespace().collect();
        if t.len() < 4 {
            return err(
                cameras,
                format!("{at}: expected CAMERA_ID MODEL WIDTH HEIGHT PARAMS…"),
            );
        }
        let id: u64 = t[0].parse().or_else(|_| {
            err(
                cameras,
                format!("{at}: camera id '{}' is not a whole number", clip(t[0])),
            )
        })?;
        let who = format!("{at}, camera {id}");
        let dim = |s: &str| -> Result<u32> {
            s.parse::<u32>().or_else(|_| {
                err(
                    cameras,
                    format!("{who}: image size '{}' is not a whole number", clip(s)),
                )
            })
        };
        let (w, h) = (dim(t[2])?, dim(t[3])?);
        let mut ps = Vec::new();
        for s in &t[4..] {
            let v: f64 = s.parse().or_else(|_| {
                err(
                    cameras,
                    format!("{who}: parameter '{}' is not a number", clip(s)),
                )
            })?;
            ps.push(finite(cameras, &format!("{who}: a parameter"), v)?);
        }
        let want = match t[1] {
            "SIMPLE_PINHOLE" => 3,
            "PINHOLE" => 4,
            "SIMPLE_RADIAL" => 4,
            "RADIAL" => 5,
            "OPENCV" => 8,
            m => {
                return err(
                    cameras,
                    format!(
                        "{who}: camera model '{}' is not one of SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV",
                        clip(m)
                    ),
                );
            }
        };
        if ps.len() != want {
            return err(
                cameras,
                format!(
                    "{who}: {} takes {want} parameters, the line has {}",
                    t[1],
                    ps.len()
                ),
            );
        }
        let mut l = Lens {
            intrinsics: Intrinsics {
                width: w,
                height: h,
                fx: ps[0],
                fy: ps[0],
                cx: ps[1],
                cy: ps[2],
            },
            k1: 0.0,
            k2: 0.0,
            p1: 0.0,
            p2: 0.0,
        };
        match t[1] {
            "PINHOLE" | "OPENCV" => {
                l.intrinsics.fy = ps[1];
                l.intrinsics.cx = ps[2];
                l.intrinsics.cy = ps[3];
                if t[1] == "OPENCV" {
                    (l.k1, l.k2, l.p1, l.p2) = (ps[4], ps[5], ps[6], ps[7]);
                }
            }
            "SIMPLE_RADIAL" => l.k1 = ps[3],
            "RADIAL" => (l.k1, l.k2) = (ps[3], ps[4]),
            _ => {}
        }
        check_lens(cameras, &who, &l)?;
        if lenses.iter().any(|(i, _)| *i == id) {
            return err(cameras, format!("{who}: camera id {id} is listed twice"));
        }
        if lenses.len() >= MAX_VIEWS {
            return err(cameras, format!("lists more than {MAX_VIEWS} cameras"));
        }
        lenses.push((id, l));
    }
    if lenses.is_empty() {
        return err(cameras, "lists no camera");
    }
    let model_dir = images.parent().unwrap_or(Path::new("."));
    let (base, prefix) = colmap_image_dir(model_dir);
    // Masks sit in `masks/` beside `images/`.
    let (mask_base, mask_prefix) = if prefix.is_empty() {
        (base.with_file_name(MASKS_DIR), "")
    } else {
        (base.clone(), "masks/")
    };
    let mut views = Vec::new();
    // images.txt alternates a pose line and a line of 2-D points (which
    // may be empty); comments are skipped, blank lines count.
    let mut pose_line = true;
    for (no, line) in itext.lines().enumerate() {
        let trimmed = line.trim();
        if trimmed.starts_with('#') {
            continue;
        }
        if !pose_line {
            pose_line = true;
            // X Y POINT3D_ID triples (or nothing): a file without these
            // lines would otherwise read every second image as one.
            let t: Vec<&str> = trimmed.split_whitespace().collect();
            if !t.len().is_multiple_of(3) || t.iter().any(|s| s.parse::<f64>().is_err()) {
                return err(
                    images,
                    format!(
                        "line {}: expected the POINTS2D line (X Y POINT3D_ID triples, or an empty \
                         line) after the pose line above; images.txt has two lines per image",
                        no + 1
                    ),
                );
            }
            continue;
        }
        if trimmed.is_empty() {
            continue;
        }
        pose_line = false;
        let at = format!("line {}", no + 1);
        let t: Vec<&str> = trimmed.split_whitespace().collect();
        if t.len() < 10 {
            return err(
                images,
                format!("{at}: expected IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME"),
            );
        }
        let id = t[0];
        let name = t[9..].join(" ");
        let who = format!("{at}, image {} ({})", clip(id), clip(&name));
        let mut n = [0f64; 7];
        for (k, s) in t[1..8].iter().enumerate() {
            let v: f64 = s
                .parse()
                .or_else(|_| err(images, format!("{who}: '{}' is not a number", clip(s))))?;
            n[k] = finite(images, &format!("{who}: a pose value"), v)?;
        }
        let q = DQuat::from_xyzw(n[1], n[2], n[3], n[0]);
        let len = q.length();
        if !(len > 1e-6 && len.is_finite()) {
            return err(
                images,
                format!("{who}: the rotation quaternion has length {len}"),
            );
        }
        let cam: u64 = t[8].parse().or_else(|_| {
            err(
                images,
                format!("{who}: camera id '{}' is not a whole number", clip(t[8])),
            )
        })?;
        let Some(&(_, lens)) = lenses.iter().find(|(i, _)| *i == cam) else {
            return err(
                images,
                format!("{who}: camera {cam} is not in {}", cameras.display()),
            );
        };
        // The name alone must pass the rule (no `..`, not absolute), then
        // with its folder prefix, inside the project folder.
        let image = lexically_inside(&base, &name)
            .and_then(|_| resolve_inside(&base, &format!("{prefix}{name}")))
            .or_else(|why| err(images, format!("{who}: image name {why}")))?;
        // A mask beside it in `masks/`, by the same name or with `.png`
        // added; through the same path rule (a symlink out is refused).
        let mut mask = None;
        for m in [name.clone(), format!("{name}.png")] {
            match resolve_inside(&mask_base, &format!("{mask_prefix}{m}")) {
                Ok(p) if p.is_file() => {
                    mask = Some(p);
                    break;
                }
                Ok(_) => {}
                Err(why) => return err(images, format!("{who}: mask {why}")),
            }
        }
        if views.len() >= MAX_VIEWS {
            return err(images, format!("lists more than {MAX_VIEWS} images"));
        }
        views.push(View {
            label: format!("image {} ({})", clip(id), clip(&name)),
            image,
            mask,
            lens,
            rotation: DMat3::from_quat(q / len),
            translation: DVec3::new(n[4], n[5], n[6]),
        });
    }
    if views.is_empty() {
        return err(images, "lists no image");
    }
    Ok(Calibration {
        file: images.to_path_buf(),
        views,
        bbox: None,
    })
}

fn clip(s: &str) -> String {
    let mut end = s.len().min(48);
    while !s.is_char_boundary(end) {
        end -= 1;
    }
    let mut out: String = s[..end]
        .chars()
        .map(|c| if c.is_control() { '?' } else { c })
        .collect();
    if end < s.len() {
        out.push('…');
    }
    out
}

// ---------------------------------------------------------------- NeRF

fn percent_decode(s: &str) -> std::result::Result<String, String> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let v = b
                .get(i + 1..i + 3)
                .and_then(|h| std::str::from_utf8(h).ok())
                .and_then(|h| u8::from_str_radix(h, 16).ok())
                .ok_or_else(|| format!("'{}' has a bad %-escape", clip(s)))?;
            out.push(v);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).map_err(|_| format!("'{}' is not UTF-8 once decoded", clip(s)))
}

type Json = serde_json::Value;

fn number(file: &Path, who: &str, obj: &Json, key: &str) -> Result<Option<f64>> {
    match obj.get(key) {
        None | Some(Json::Null) => Ok(None),
        Some(v) => match v.as_f64() {
            Some(x) => finite(file, &format!("{who}{key}"), x).map(Some),
            None => err(file, format!("{who}{key} is not a number")),
        },
    }
}

fn read_transforms(path: &Path) -> Result<Calibration> {
    let text = read_text(path)?;
    parse_transforms(path, &text)
}

fn parse_transforms(path: &Path, text: &str) -> Result<Calibration> {
    let root: Json = match serde_json::from_str(text) {
        Ok(v) => v,
        Err(e) => return err(path, format!("is not valid JSON ({e})")),
    };
    if !root.is_object() {
        return err(path, "is not a JSON object with `frames`");
    }
    let dir = path.parent().unwrap_or(Path::new("."));
    let Some(frames) = root.get("frames").and_then(Json::as_array) else {
        return err(path, "has no `frames` array");
    };
    if frames.is_empty() {
        return err(path, "`frames` is empty");
    }
    if frames.len() > MAX_VIEWS {
        return err(
            path,
            format!("lists {} frames, over {MAX_VIEWS}", frames.len()),
        );
    }
    let bbox = match root.get("object_bbox") {
        Some(b) => {
            let corner = |k: &str| -> Option<DVec3> {
                let a = b.get(k)?.as_array()?;
                if a.len() != 3 {
                    return None;
                }
                let v: Option<Vec<f64>> = a.iter().map(Json::as_f64).collect();
                let v = v?;
                let p = DVec3::new(v[0], v[1], v[2]);
                p.is_finite().then_some(p)
            };
            match (corner("min"), corner("max")) {
                (Some(lo), Some(hi)) if lo.cmple(hi).all() => Some((lo, hi)),
                _ => return err(path, "object_bbox is not {min: [x, y, z], max: [x, y, z]}"),
            }
        }
        None => None,
    };
    let mut views = Vec::with_capacity(frames.len());
    for (i, f) in frames.iter().enumerate() {
        let file_path = f.get("file_path").and_then(Json::as_str);
        let shown = file_path.map_or(String::from("no file_path"), clip);
        let who = format!("frame {i} ({shown})");
        let Some(file_path) = file_path else {
            return err(path, format!("{who}: has no file_path string"));
        };
        let resolve = |p: &str, what: &str, png: bool| -> Result<PathBuf> {
            let mut p =
                percent_decode(p).or_else(|why| err(path, format!("{who}: {what} {why}")))?;
            // The original NeRF scenes name `./train/r_0` for
            // `train/r_0.png`: the extension is added to the name, and the
            // name with it passes the one path rule.
            if png {
                let lexical = lexically_inside(dir, &p)
                    .or_else(|why| err(path, format!("{who}: {what} {why}")))?;
                if lexical.extension().is_none() && !lexical.is_file() {
                    p.push_str(".png");
                }
            }
            resolve_inside(dir, &p).or_else(|why| err(path, format!("{who}: {what} {why}")))
        };
        let image = resolve(file_path, "file_path", true)?;
        let mask = match f.get("mask_path") {
            None | Some(Json::Null) => None,
            Some(Json::String(m)) => Some(resolve(m, "mask_path", false)?),
            Some(_) => return err(path, format!("{who}: mask_path is not a string")),
        };
        // Per-frame intrinsics override the shared ones (nerfstudio).
        let key = |k: &str| -> Result<Option<f64>> {
            match number(path, &format!("{who}: "), f, k)? {
                Some(v) => Ok(Some(v)),
                None => number(path, "", &root, k),
            }
        };
        let (w, h) = match (key("w")?, key("h")?) {
            (Some(w), Some(h)) => (w, h),
            _ => {
                let (w, h) = crate::image::header_size(&image)
                    .or_else(|e| err(path, format!("{who}: no w, h given, and {e}")))?;
                (f64::from(w), f64::from(h))
            }
        };
        let side = |v: f64| -> Result<u32> {
            if v.fract() == 0.0 && v >= 1.0 && v <= f64::from(MAX_SIDE) {
                Ok(v as u32)
            } else {
                err(
                    path,
                    format!("{who}: image size {w}x{h} is outside 1..={MAX_SIDE} a side"),
                )
            }
        };
        let (width, height) = (side(w)?, side(h)?);
        let fx = match (key("fl_x")?, key("camera_angle_x")?) {
            (Some(f), _) => f,
            (None, Some(a)) => {
                if !(a > 0.0 && a < std::f64::consts::PI) {
                    return err(path, format!("{who}: camera_angle_x {a} is outside (0, π)"));
                }
                0.5 * w / (0.5 * a).tan()
            }
            (None, None) => {
                return err(path, format!("{who}: has neither fl_x nor camera_angle_x"));
            }
        };
        let fy = match (key("fl_y")?, key("camera_angle_y")?) {
            (Some(f), _) => f,
            (None, Some(a)) if a > 0.0 && a < std::f64::consts::PI => 0.5 * h / (0.5 * a).tan(),
            _ => fx,
        };
        let lens = Lens {
            intrinsics: Intrinsics {
                width,
                height,
                fx,
                fy,
                cx: key("cx")?.unwrap_or(w * 0.5),
                cy: key("cy")?.unwrap_or(h * 0.5),
            },
            k1: key("k1")?.unwrap_or(0.0),
            k2: key("k2")?.unwrap_or(0.0),
            p1: key("p1")?.unwrap_or(0.0),
            p2: key("p2")?.unwrap_or(0.0),
        };
        check_lens(path, &who, &lens)?;
        let m = matrix(f.get("transform_matrix")).ok_or(()).or_else(|_| {
            err(
                path,
                format!("{who}: transform_matrix is not a 4×4 array of finite numbers"),
            )
        })?;
        if m[3] != [0.0, 0.0, 0.0, 1.0] {
            return err(
                path,
                format!(
                    "{who}: transform_matrix's bottom row is {:?}, not [0, 0, 0, 1] (not a rigid camera pose)",
                    m[3]
                ),
            );
        }
        // Camera-to-world, OpenGL axes: columns right, up, back; the
        // OpenCV frame flips up and back.
        let right = DVec3::new(m[0][0], m[1][0], m[2][0]);
        let up = DVec3::new(m[0][1], m[1][1], m[2][1]);
        let back = DVec3::new(m[0][2], m[1][2], m[2][2]);
        let centre = DVec3::new(m[0][3], m[1][3], m[2][3]);
        let c2w = DMat3::from_cols(right, -up, -back);
        let ortho = (c2w.transpose() * c2w - DMat3::IDENTITY)
            .to_cols_array()
            .iter()
            .fold(0.0f64, |a, v| a.max(v.abs()));
        if ortho > 1e-3 || c2w.determinant() < 0.0 {
            return err(
                path,
                format!(
                    "{who}: transform_matrix's 3×3 part is not a rotation (scaled, sheared or mirrored)"
                ),
            );
        }
        let rotation = c2w.transpose();
        views.push(View {
            label: who,
            image,
            mask,
            lens,
            rotation,
            translation: -(rotation * centre),
        });
    }
    Ok(Calibration {
        file: path.to_path_buf(),
        views,
        bbox,
    })
}

fn matrix(v: Option<&Json>) -> Option<[[f64; 4]; 4]> {
    let rows = v?.as_array()?;
    if rows.len() < 3 || rows.len() > 4 {
        return None;
    }
    let mut m = [
        [0.0, 0.0, 0.0, 0.0],
        [0.0; 4],
        [0.0; 4],
        [0.0, 0.0, 0.0, 1.0],
    ];
    for (r, row) in rows.iter().enumerate() {
        let row = row.as_array()?;
        if row.len() != 4 {
            return None;
        }
        for (c, x) in row.iter().enumerate() {
            let x = x.as_f64()?;
            if !x.is_finite() || x.abs() > 1e12 {
                return None;
            }
            m[r][c] = x;
        }
    }
    Some(m)
}

/// Parses a calibration from bytes (the fuzz target's entry): `json`
/// picks the layout; for COLMAP `bytes` is `cameras.txt`, a NUL byte,
/// `images.txt`. Paths are resolved against a folder that does not exist,
/// so no image is read. Returns the view count.
#[doc(hidden)]
pub fn parse_for_fuzzing(json: bool, bytes: &[u8]) -> Result<usize> {
    let dir = Path::new("lodkit-fuzz-no-such-folder");
    let text = |b: &[u8]| {
        std::str::from_utf8(b)
            .map(str::to_owned)
            .map_err(|e| Error::Invalid(e.to_string()))
    };
    let r = if json {
        parse_transforms(&dir.join("transforms.json"), &text(bytes)?)
    } else {
        let (a, b) = match bytes.iter().position(|&c| c == 0) {
            Some(i) => (&bytes[..i], &bytes[i + 1..]),
            None => (bytes, &[][..]),
        };
        parse_colmap(
            &dir.join("cameras.txt"),
            &text(a)?,
            &dir.join("images.txt"),
            &text(b)?,
        )
    };
    r.map(|c| c.views.len())
}
