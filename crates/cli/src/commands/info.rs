//! `lodkit info FILE`: a model's figures; for a `.mco` octree or a `.pop`
//! stream, what `lodkit mco info` / `lodkit pop stats` print (the same
//! code); for a calibration (`transforms.json`, COLMAP `cameras.txt` /
//! `images.txt`), the image set: cameras, image sizes and each view's
//! silhouette coverage.
use std::path::Path;

use anyhow::Result;
use lodkit_mesh::info::model_info;
use lodkit_particles::silhouette::{ImageSet, SilhouetteSource, calibration};
use serde::Serialize;

use crate::ui::Ui;

pub fn run(ui: &Ui, file: &Path, json: bool) -> Result<()> {
    if calibration::is_calibration(file) {
        return image_set(ui, file, json);
    }
    let ext = file
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("mco") => return super::mco::info(ui, file, false, json),
        Some("pop") => return super::pop::run_stats(ui, file, json),
        _ => {}
    }
    let model = super::load(ui, file)?;
    let info = model_info(&model);
    if json {
        super::print_json(&info)
    } else {
        crate::outln!("file: {}", file.display())?;
        crate::out!("{}", info.to_text())?;
        Ok(())
    }
}

#[derive(Serialize)]
struct ViewInfo {
    camera: String,
    image: String,
    mask: Option<String>,
    width: u32,
    height: u32,
    fx: f64,
    fy: f64,
    cx: f64,
    cy: f64,
    distortion: [f64; 4],
    centre: [f64; 3],
    /// Object pixels over all pixels.
    coverage: f64,
}

#[derive(Serialize)]
struct SetInfo {
    file: String,
    views: usize,
    sizes: Vec<String>,
    masks: usize,
    mean_coverage: f64,
    cameras: Vec<ViewInfo>,
}

fn image_set(ui: &Ui, file: &Path, json: bool) -> Result<()> {
    let step = ui.spinner(&format!("reading the image set of {}", file.display()));
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
    if json {
        return super::print_json(&info);
    }
    crate::outln!("file: {}", info.file)?;
    crate::outln!("kind: calibrated image set ({} views)", info.views)?;
    crate::outln!("image sizes: {}", info.sizes.join(", "))?;
    crate::outln!(
        "silhouettes: {} from mask images, {} from alpha; mean coverage {:.1} %",
        info.masks,
        info.views - info.masks,
        100.0 * info.mean_coverage
    )?;
    for c in &info.cameras {
        crate::outln!(
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
