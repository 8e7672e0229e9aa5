//! The info job (`lodkit info FILE`, `lodkit mco info`, `lodkit pop
//! stats`): a file's figures, as serde types a front-end prints as JSON
//! and as text (`Display`).
use std::path::Path;

use anyhow::{Context, Result, bail};
use lodkit_mco::{McoHeader, McoModel, McoStream};
use lodkit_mesh::io::cameras as calibration;
use lodkit_particles::silhouette::{ImageSet, SilhouetteSource};
use serde::Serialize;

use crate::progress::Progress;

/// What [`run`] found, by the kind of file.
#[derive(Debug)]
pub enum Info {
    /// A mesh, point cloud or range image, by its file name.
    Model {
        file: String,
        info: lodkit_mesh::info::Info,
    },
    /// A `.mco` octree ([`mco_file`]).
    Mco(McoFileInfo),
    /// A `.pop` stream ([`pop_stats`]).
    Pop(lodkit_particles::StreamStats),
    /// A calibrated image set ([`image_set`]).
    ImageSet(SetInfo),
}

/// Describes `path` by its kind: a calibration, a `.mco`, a `.pop`, or
/// any model `lodkit_mesh::io::load` reads. Errors name the file. Cost:
/// the file read and decoded once (every level of a `.pop`).
pub fn run(path: &Path, events: &Progress) -> Result<Info> {
    if calibration::is_calibration(path) {
        return Ok(Info::ImageSet(image_set(events, path)?));
    }
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("mco") => Ok(Info::Mco(mco_file(events, path, false)?)),
        Some("pop") => Ok(Info::Pop(pop_stats(events, path)?)),
        _ => {
            let model = crate::input::load(events, path)?;
            Ok(Info::Model {
                file: path.display().to_string(),
                info: lodkit_mesh::info::model_info(&model),
            })
        }
    }
}

/// Every level of a `.pop` stream decoded and triangulated, with its
/// figures. Errors name the file.
pub fn pop_stats(events: &Progress, path: &Path) -> Result<lodkit_particles::StreamStats> {
    let bytes = std::fs::read(path).with_context(|| format!("{}: cannot read", path.display()))?;
    let step = events.stage("decoding and triangulating every level");
    let s = lodkit_particles::stream_stats(&bytes, &lodkit_particles::TriangulateOptions::DEFAULT)
        .with_context(|| path.display().to_string())?;
    step.finish();
    Ok(s)
}

/// Largest `.mco` file read (as `McoModel::load`): 16 GiB.
pub const MAX_MCO_FILE_BYTES: u64 = 16 << 30;

/// Where a `.mco` file cut short stopped: what its complete chunks hold.
#[derive(Debug, Serialize, Clone, Copy)]
pub struct McoCut {
    /// Bytes present.
    pub bytes: u64,
    /// Bytes the header announces.
    pub file_bytes: u64,
    /// Complete chunks read, of `total_chunks`.
    pub chunks: usize,
    pub total_chunks: u32,
    /// The highest LOD number served, of the whole file's `total_max_lod`.
    pub max_lod: usize,
    pub total_max_lod: u32,
}

/// Reads a `.mco` file. A version-2 file cut short (a partial download or
/// copy) gives the model of its complete chunks, which serve every LOD
/// number they cover as the whole file would, and a note says
/// where it stopped; `strict` refuses it. Errors name the file. Returns
/// the model, what was cut, and the file's bytes.
pub fn load_mco(
    events: &Progress,
    path: &Path,
    strict: bool,
) -> Result<(McoModel, Option<McoCut>, Vec<u8>)> {
    let name = path.display().to_string();
    let len = std::fs::metadata(path).with_context(|| name.clone())?.len();
    if len > MAX_MCO_FILE_BYTES {
        bail!("{name}: {len} bytes is larger than the {MAX_MCO_FILE_BYTES}-byte limit");
    }
    let bytes = std::fs::read(path).with_context(|| name.clone())?;
    // A version-2 header that announces more bytes than the file holds: a
    // prefix. Anything else is read whole (and refused as the reader says).
    let mut probe = McoStream::new();
    let head = &bytes[..bytes.len().min(McoHeader::BYTES)];
    let header = match probe.push(head) {
        Ok(_) => probe.header().copied(),
        Err(_) => None,
    };
    let h = match header {
        Some(h) if len < h.file_bytes => h,
        _ => {
            let m = McoModel::from_bytes(&bytes).map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
            return Ok((m, None, bytes));
        }
    };
    if strict {
        bail!(
            "{name}: cut short: {len} bytes, the header says {} (--strict refuses a file cut short)",
            h.file_bytes
        );
    }
    let mut s = McoStream::new();
    s.push(&bytes).map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
    if s.chunks().is_empty() {
        bail!(
            "{name}: cut short at byte {len} of {}, before chunk 0 (LOD number 0) is complete",
            h.file_bytes
        );
    }
    let p = McoModel::from_prefix(&bytes).map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
    let cut = McoCut {
        bytes: len,
        file_bytes: h.file_bytes,
        chunks: p.chunks,
        total_chunks: h.chunks,
        max_lod: p.max_lod,
        total_max_lod: h.max_lod,
    };
    events.status(format!(
        "{name}: stopped at byte {} of {}, where chunk {} is incomplete; read the {} complete chunks of {} (LOD numbers 0..={} of 0..={}; --strict refuses a file cut short)",
        s.bytes_read(),
        h.file_bytes,
        p.chunks,
        p.chunks,
        h.chunks,
        p.max_lod,
        h.max_lod
    ));
    Ok((p.model, Some(cut), bytes))
}

/// One chunk of a version-2 `.mco` file.
#[derive(Debug, Serialize)]
pub struct McoChunk {
    pub offset: u64,
    pub bytes: u64,
    pub first_lod: u32,
    pub last_lod: u32,
    pub nodes: u32,
    pub vertices: u32,
    pub triangles: u32,
}

/// `lodkit mco info`: a `.mco` file's format, chunks and model figures.
#[derive(Debug, Serialize)]
pub struct McoFileInfo {
    pub file: String,
    /// `.mco` format version (1: flat arrays, 2: LOD-ordered chunks).
    pub version: u32,
    pub file_bytes: u64,
    /// Where a file cut short stopped (`None`: the whole file was read);
    /// the rest describes its complete chunks.
    pub cut_short: Option<McoCut>,
    /// Version 2: the chunks in file order (a prefix through chunk `c`
    /// serves LOD numbers up to its `last_lod`).
    pub chunks: Vec<McoChunk>,
    /// The model's figures, after the file's.
    #[serde(flatten)]
    pub model: crate::report::McoModelInfo,
}

/// A `.mco` file's format, chunks, lattice, sizes and levels (`lodkit mco
/// info`, `lodkit info FILE.mco`); a cut-short file is read up to its last
/// complete chunk (refused with `strict`). Errors name the file. Cost:
/// the file read and its model decoded once.
pub fn mco_file(events: &Progress, path: &Path, strict: bool) -> Result<McoFileInfo> {
    let (model, cut, bytes) = load_mco(events, path, strict)?;
    let version = McoModel::file_version(&bytes).unwrap_or(0);
    let chunks = if version == 1 {
        Vec::new()
    } else {
        McoModel::chunk_table(&bytes)
            .with_context(|| path.display().to_string())?
            .into_iter()
            .map(|c| McoChunk {
                offset: c.offset,
                bytes: c.bytes,
                first_lod: c.first_lod,
                last_lod: c.last_lod,
                nodes: c.nodes,
                vertices: c.vertices,
                triangles: c.triangle_indices / 3,
            })
            .collect()
    };
    let info = McoFileInfo {
        file: path.display().to_string(),
        version,
        file_bytes: bytes.len() as u64,
        cut_short: cut,
        chunks,
        model: crate::report::McoModelInfo::of(&model),
    };
    Ok(info)
}

impl std::fmt::Display for McoFileInfo {
    /// The text `lodkit mco info` prints, one line each.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "file: {}", self.file)?;
        match &self.cut_short {
            Some(c) => writeln!(
                f,
                "format: version {}, cut short: {} of {} bytes, {} of {} chunks complete (LOD numbers 0..={} of 0..={}); below, what they hold",
                self.version,
                c.bytes,
                c.file_bytes,
                c.chunks,
                c.total_chunks,
                c.max_lod,
                c.total_max_lod
            )?,
            None => writeln!(
                f,
                "format: version {}, {} bytes{}",
                self.version,
                self.file_bytes,
                if self.chunks.is_empty() {
                    String::new()
                } else {
                    format!(" in {} chunks", self.chunks.len())
                }
            )?,
        }
        writeln!(
            f,
            "lattice: resolution {}, cube {:.6}, octree depth {}",
            self.model.resolution, self.model.cube, self.model.depth
        )?;
        writeln!(
            f,
            "vertices: {} (every level, {} crack-patch substitutions)",
            self.model.vertices, self.model.crack_patches
        )?;
        writeln!(
            f,
            "nodes: {}; LOD array: {} nodes in {} LOD numbers",
            self.model.nodes, self.model.lod_array, self.model.lod_numbers
        )?;
        writeln!(
            f,
            "triangles at full resolution: {}",
            self.model.full_triangles
        )?;
        writeln!(f, "built from {} samples", self.model.input_samples)?;
        writeln!(f, "level  nodes  triangles (0 = leaf cubes)")?;
        for r in &self.model.levels {
            writeln!(f, "{:>5}  {:>5}  {:>9}", r.level, r.nodes, r.triangles)?;
        }
        if !self.chunks.is_empty() {
            writeln!(
                f,
                "chunk     offset     bytes  LOD numbers      nodes  vertices  triangles"
            )?;
            for (i, c) in self.chunks.iter().enumerate() {
                writeln!(
                    f,
                    "{:>5} {:>10} {:>9}  {:>5}..={:<5} {:>8} {:>9} {:>10}",
                    i, c.offset, c.bytes, c.first_lod, c.last_lod, c.nodes, c.vertices, c.triangles
                )?;
            }
        }
        Ok(())
    }
}

/// One view of a calibrated image set.
#[derive(Debug, Serialize)]
pub struct ViewInfo {
    pub camera: String,
    pub image: String,
    pub mask: Option<String>,
    pub width: u32,
    pub height: u32,
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
    pub distortion: [f64; 4],
    pub centre: [f64; 3],
    /// Object pixels over all pixels.
    pub coverage: f64,
}

/// A calibrated image set: its cameras, image sizes and silhouettes.
#[derive(Debug, Serialize)]
pub struct SetInfo {
    pub file: String,
    pub views: usize,
    pub sizes: Vec<String>,
    pub masks: usize,
    pub mean_coverage: f64,
    pub cameras: Vec<ViewInfo>,
}

/// The image set of a calibration (`transforms.json`, COLMAP
/// `cameras.txt` / `images.txt`): cameras, image sizes and each view's
/// silhouette coverage. Errors name the file. Cost: every image decoded
/// once.
pub fn image_set(events: &Progress, file: &Path) -> Result<SetInfo> {
    let step = events.spinner(&format!("reading the image set of {}", file.display()));
    let set = ImageSet::load(file, SilhouetteSource::Auto)?;
    step.finish();
    let views = &set.calibration.views;
    let cameras: Vec<ViewInfo> = views
        .iter()
        .enumerate()
        .map(|(i, v)| ViewInfo {
            camera: v.label.clone(),
            image: v.image.display().to_string(),
            mask: v.mask.as_ref().map(|m| m.display().to_string()),
            width: v.lens.width,
            height: v.lens.height,
            fx: v.lens.fx,
            fy: v.lens.fy,
            cx: v.lens.cx,
            cy: v.lens.cy,
            distortion: [v.lens.k1, v.lens.k2, v.lens.p1, v.lens.p2],
            centre: v.centre().to_array(),
            coverage: set.coverage(i),
        })
        .collect();
    let mut sizes: Vec<String> = cameras
        .iter()
        .map(|c| format!("{}x{}", c.width, c.height))
        .collect();
    sizes.sort();
    sizes.dedup();
    let info = SetInfo {
        file: file.display().to_string(),
        views: views.len(),
        sizes,
        masks: views.iter().filter(|v| v.mask.is_some()).count(),
        mean_coverage: cameras.iter().map(|c| c.coverage).sum::<f64>()
            / cameras.len().max(1) as f64,
        cameras,
    };
    Ok(info)
}

impl std::fmt::Display for SetInfo {
    /// The text `lodkit info` prints for an image set.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "file: {}", self.file)?;
        writeln!(f, "kind: calibrated image set ({} views)", self.views)?;
        writeln!(f, "image sizes: {}", self.sizes.join(", "))?;
        writeln!(
            f,
            "silhouettes: {} from mask images, {} from alpha; mean coverage {:.1} %",
            self.masks,
            self.views - self.masks,
            100.0 * self.mean_coverage
        )?;
        for c in &self.cameras {
            writeln!(
                f,
                "  {}: {}x{}, f = {:.1}, {:.1}, centre ({:.3}, {:.3}, {:.3}), coverage {:.1} %",
                c.camera,
                c.width,
                c.height,
                c.fx,
                c.fy,
                c.centre[0],
                c.centre[1],
                c.centre[2],
                100.0 * c.coverage
            )?;
        }
        Ok(())
    }
}
