//! `lodkit scan MESH --views N --size WxH --out DIR`: the virtual range
//! scanner (range-grid PLY files plus a Stanford `.conf`).
use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;
use lodkit_mco::{ScanOptions, scan_mesh, write_scans};
use serde::Serialize;

use crate::ui::Ui;
use crate::ui::value::{self, Real};

/// Most views of one scan.
const MAX_VIEWS: usize = 360;
/// Most samples per image side.
const MAX_SIDE: u32 = 4096;
/// Most samples over all views (views × width × height): about 20 bytes
/// each while scanning and writing, so well under 1 GB.
const MAX_TOTAL_SAMPLES: u64 = 1 << 25;

#[derive(Args)]
pub struct ScanArgs {
    /// Mesh to scan (.ply, .obj, .stl, .gltf, .glb).
    pub mesh: PathBuf,
    /// Views around the vertical (+y) axis, evenly spaced (8 → 0°, 45°, 90°, …), in 1..=360.
    #[arg(long, default_value_t = 8, value_parser = value::int(1usize, MAX_VIEWS))]
    pub views: usize,
    /// Samples per image, WIDTHxHEIGHT, each side in 2..=4096 (and at most
    /// 33554432 samples over all views).
    #[arg(long, default_value = "256x256", value_name = "WxH", value_parser = value::size(2, MAX_SIDE))]
    pub size: (u32, u32),
    /// Output directory (created if missing).
    #[arg(long, value_name = "DIR", short_alias = 'o')]
    pub out: PathBuf,
    /// Elevation of the views above the horizontal plane, degrees in [-90, 90].
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true,
          value_parser = lodkit::limits::ELEVATION.f32())]
    pub elevation: f32,
    /// Odd views look from below (−elevation), to see the bottom too.
    #[arg(long)]
    pub alternate: bool,
    /// Gaussian range noise, standard deviation in object units (a finite number >= 0).
    #[arg(long, default_value_t = 0.0, value_parser = Real::NON_NEGATIVE.f32())]
    pub noise: f32,
    /// Seed of the noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Print what was written as JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Serialize)]
struct Written {
    file: String,
    samples: usize,
}

#[derive(Serialize)]
struct Report {
    input: String,
    views: usize,
    width: u32,
    height: u32,
    scans: Vec<Written>,
    conf: String,
}

pub fn run(ui: &Ui, args: &ScanArgs) -> Result<()> {
    let (width, height) = args.size;
    let total = args.views as u64 * width as u64 * height as u64;
    if total > MAX_TOTAL_SAMPLES {
        return Err(crate::ui::usage(format!(
            "--views {} at --size {width}x{height} is {total} samples; at most {MAX_TOTAL_SAMPLES} over all views",
            args.views
        )));
    }
    let mesh = super::load_mesh(ui, &args.mesh)?;
    let opts = ScanOptions {
        views: args.views,
        width: width as usize,
        height: height as usize,
        elevation_deg: args.elevation,
        alternate: args.alternate,
        noise: args.noise,
        seed: args.seed,
    };
    let step = ui.stage(&format!("scanning from {} views", args.views));
    let scans = scan_mesh(&mesh, &opts).with_context(|| args.mesh.display().to_string())?;
    step.finish();
    let stem = args
        .mesh
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scan".into());
    let paths = write_scans(&args.out, &stem, &scans)?;
    let conf = paths.last().expect("the .conf").display().to_string();
    let written: Vec<Written> = paths
        .iter()
        .zip(&scans)
        .map(|(p, s)| Written {
            file: p.display().to_string(),
            samples: s.valid_count(),
        })
        .collect();
    if args.json {
        return super::print_json(&Report {
            input: args.mesh.display().to_string(),
            views: args.views,
            width,
            height,
            scans: written,
            conf,
        });
    }
    for w in &written {
        ui.status(format!("wrote {} ({} samples)", w.file, w.samples));
    }
    ui.status(format!("wrote {conf}"));
    Ok(())
}
