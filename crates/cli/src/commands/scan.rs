//! `lodkit scan MESH --views N --size WxH --out DIR`: the virtual range
//! scanner (range-grid PLY files plus a Stanford `.conf`).
use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::Args;
use lodkit_mco::{ScanOptions, scan_mesh, write_scans};

use crate::ui::Ui;

#[derive(Args)]
pub struct ScanArgs {
    /// Mesh to scan (.ply, .obj, .stl, .gltf, .glb).
    pub mesh: PathBuf,
    /// Views around the vertical (+y) axis, evenly spaced (8 → 0°, 45°, 90°, …).
    #[arg(long, default_value_t = 8)]
    pub views: usize,
    /// Samples per image, WIDTHxHEIGHT.
    #[arg(long, default_value = "256x256", value_name = "WxH")]
    pub size: String,
    /// Output directory (created if missing).
    #[arg(long, short)]
    pub out: PathBuf,
    /// Elevation of the views above the horizontal plane, degrees.
    #[arg(long, default_value_t = 0.0)]
    pub elevation: f32,
    /// Odd views look from below (−elevation), to see the bottom too.
    #[arg(long)]
    pub alternate: bool,
    /// Gaussian range noise, standard deviation in object units.
    #[arg(long, default_value_t = 0.0)]
    pub noise: f32,
    /// Seed of the noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

fn parse_size(s: &str) -> Result<(usize, usize)> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .with_context(|| format!("--size '{s}': expected WIDTHxHEIGHT, e.g. 256x256"))?;
    let n = |v: &str| -> Result<usize> {
        v.trim()
            .parse()
            .with_context(|| format!("--size '{s}': '{v}' is not a count"))
    };
    Ok((n(w)?, n(h)?))
}

pub fn run(ui: &Ui, args: &ScanArgs) -> Result<()> {
    let (width, height) = parse_size(&args.size)?;
    if !(args.noise >= 0.0 && args.noise.is_finite()) {
        bail!("--noise must be a finite, non-negative distance");
    }
    let mesh = super::load_mesh(ui, &args.mesh)?;
    let opts = ScanOptions {
        views: args.views,
        width,
        height,
        elevation_deg: args.elevation,
        alternate: args.alternate,
        noise: args.noise,
        seed: args.seed,
    };
    let step = ui.spinner(&format!("scanning from {} views", args.views));
    let scans = scan_mesh(&mesh, &opts).with_context(|| args.mesh.display().to_string())?;
    step.finish();
    let stem = args
        .mesh
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scan".into());
    let paths = write_scans(&args.out, &stem, &scans)?;
    for (p, s) in paths.iter().zip(&scans) {
        ui.status(format!(
            "wrote {} ({} samples)",
            p.display(),
            s.valid_count()
        ));
    }
    ui.status(format!(
        "wrote {}",
        paths.last().expect("the .conf").display()
    ));
    Ok(())
}
