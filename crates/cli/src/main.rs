//! `lodkit` — every level of detail from dense 3D scans.
//!
//! Exit codes: 0 success, 1 bad input or failure (one line on stderr naming
//! the file and the problem), 2 usage error (from clap, or a request these
//! options or this build cannot serve: `--compress` without its feature).

#![forbid(unsafe_code)]

mod args;
mod commands;
mod ui;
mod viewer_assets;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};

use crate::ui::Ui;

#[derive(Parser)]
#[command(
    name = "lodkit",
    version,
    about = "Every level of detail from dense 3D scans: meshes, point clouds and range images",
    after_help = "Examples:\n  lodkit build --out out/                 # the built-in Stanford bunny\n  lodkit info scan.ply --json\n  lodkit convert scan.ply scan.glb\n  lodkit compare original.ply simplified.ply"
)]
struct Cli {
    #[command(flatten)]
    global: Global,
    #[command(subcommand)]
    command: Command,
}

#[derive(Args, Clone, Copy)]
struct Global {
    /// Print nothing but errors (and the requested output file contents).
    #[arg(short, long, global = true, conflicts_with = "verbose")]
    quiet: bool,
    /// Print more detail (timings of each stage).
    #[arg(short, long, global = true)]
    verbose: bool,
}

#[derive(Subcommand)]
enum Command {
    /// Simplify one mesh to a triangle budget or an error bound (HQMS).
    #[command(
        after_help = "Examples:\n  lodkit simplify bunny.ply -o bunny_10k.ply --target 10000\n  lodkit simplify scan.ply -o lod.glb --ratio 0.1 --lock-border"
    )]
    Simplify(commands::simplify::SimplifyArgs),
    /// A discrete LOD chain: PLY per level, one GLB, lods.json.
    #[command(
        after_help = "Examples:\n  lodkit lods bunny.ply --out lods/\n  lodkit lods scan.ply --out lods/ --ratios 0.5,0.2,0.05,0.01"
    )]
    Lods(commands::lods::LodsArgs),
    /// A 3D Tiles 1.1 tileset: an octree of levels, measured errors.
    #[command(after_help = "Examples:\n  lodkit tiles scan.ply --out scan_tiles/")]
    Tiles(commands::tiles::TilesArgs),
    /// Synthetic test meshes of any size, streamed to disk.
    #[command(
        subcommand,
        after_help = "Examples:\n  lodkit generate blob --triangles 100000000 -o big.ply\n  lodkit generate subdivided bunny.ply --triangles 100000000 -o big_bunny.ply"
    )]
    Generate(commands::generate::GenerateCmd),
    /// Describe a mesh, point cloud or range image (counts, bbox, topology, defects), a .mco octree or a .pop stream.
    #[command(
        after_help = "Examples:\n  lodkit info bunny.ply\n  lodkit info scan.glb --json\n  lodkit info out/bunny.mco   # as `lodkit mco info`\n  lodkit info out/bunny.pop   # as `lodkit pop stats`"
    )]
    Info {
        /// Input file (.ply, .obj, .stl, .gltf, .glb, .xyz, .pts, .mco, .pop).
        file: PathBuf,
        /// Print the report as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Convert between formats, keeping every attribute the target can hold.
    #[command(
        after_help = "Examples:\n  lodkit convert bunny.ply bunny.glb\n  lodkit convert part.stl -o part.obj\n  lodkit convert scan.ply scan.ply --ascii"
    )]
    Convert {
        input: PathBuf,
        /// Output file; the format follows its extension (.ply, .obj, .stl, .glb, .xyz, .pts).
        #[arg(
            value_parser = ui::value::output(&["ply", "obj", "stl", "glb", "xyz", "pts", "txt"], "the converted model"),
            required_unless_present = "output_file",
            conflicts_with = "output_file"
        )]
        output: Option<PathBuf>,
        /// The output file, as `-o FILE` like every other command (same as
        /// the positional OUTPUT).
        #[arg(
            short = 'o',
            long = "output",
            id = "output_file",
            value_name = "OUTPUT",
            value_parser = ui::value::output(&["ply", "obj", "stl", "glb", "xyz", "pts", "txt"], "the converted model")
        )]
        output_file: Option<PathBuf>,
        /// Write ASCII PLY/STL instead of binary.
        #[arg(long)]
        ascii: bool,
        /// Weld vertices closer than this distance (object units, a finite
        /// number >= 0) before writing.
        #[arg(long, value_name = "DIST", value_parser = ui::value::Real::NON_NEGATIVE.f32())]
        weld: Option<f32>,
        /// Merge every mesh, primitive and instance into one mesh, dropping
        /// materials (by default .glb and .obj outputs keep them).
        #[arg(long)]
        merge: bool,
        /// Print what was written as JSON.
        #[arg(long)]
        json: bool,
        #[command(flatten)]
        out: ui::OutputArgs,
    },
    /// Metro-style surface distance between two meshes (Hausdorff, mean, RMS).
    #[command(
        after_help = "Examples:\n  lodkit compare bunny.ply bunny_lod2.ply\n  lodkit compare a.obj b.glb --samples 2000000 --json"
    )]
    Compare(commands::compare::CompareArgs),
    /// Progressive octree particle streams (.pop): encode, decode a level, stats.
    #[command(subcommand)]
    Pop(commands::pop::PopCommand),
    /// The main job: every level of detail of a model, with a report.
    #[command(
        after_help = "Examples:\n  lodkit build --out out/              # the built-in Stanford bunny\n  lodkit build scan.ply --out out/scan"
    )]
    Build(commands::build::BuildArgs),
    /// Virtual range scanner: range-grid PLY files and a .conf from N views of a mesh.
    Scan(commands::scan::ScanArgs),
    /// Continuous LOD (marching cube octree): build, extract, info.
    #[command(subcommand)]
    Mco(commands::mco::McoCommand),
    /// Serve the viewer and the models over HTTP (ranges, ETags), on loopback by default.
    #[command(after_help = commands::serve::AFTER_HELP)]
    Serve(commands::serve::ServeArgs),
    /// A picture of a mesh, cloud, .mco cut or .pop level, or a calibrated ring of views.
    #[command(
        after_help = "Examples:\n  lodkit render bunny.ply -o bunny.png --view 30,20 --size 800x600\n  lodkit render bunny.mco --triangles 5000 -o cut.png\n  lodkit render bunny.ply --ring 36 --elevations -30,0,30 --out views/"
    )]
    Render(commands::render::RenderArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    // Ctrl-C / SIGTERM during a write removes its temp file (the handler
    // starts at the first write, so `serve` keeps its own Ctrl-C).
    lodkit_mesh::io::interrupt::remove_temp_files_on_signal();
    // No output of a run may replace a file the run read.
    lodkit_mesh::io::overwrite_guard::refuse_overwriting_inputs();
    let ui = Ui::new(cli.global.quiet, cli.global.verbose);
    let result = match cli.command {
        Command::Info { file, json } => commands::info::run(&ui, &file, json),
        Command::Convert {
            input,
            output,
            output_file,
            ascii,
            weld,
            merge,
            json,
            out,
        } => {
            // clap guarantees exactly one of the two output spellings.
            let output = output.or(output_file).unwrap_or_default();
            let opts = commands::convert::ConvertOptions {
                ascii,
                weld,
                merge,
                json,
            };
            commands::convert::run(&ui, &input, &output, &opts, &out.options())
        }
        Command::Compare(args) => commands::compare::run(&ui, &args),
        Command::Simplify(args) => commands::simplify::run(&ui, &args),
        Command::Lods(args) => commands::lods::run(&ui, &args),
        Command::Tiles(args) => commands::tiles::run(&ui, &args),
        Command::Generate(cmd) => commands::generate::run(&ui, &cmd),
        Command::Build(args) => commands::build::run(&ui, &args),
        Command::Scan(args) => commands::scan::run(&ui, &args),
        Command::Mco(cmd) => commands::mco::run(&ui, &cmd),
        Command::Pop(cmd) => commands::pop::run(&ui, &cmd),
        Command::Serve(args) => commands::serve::run(&ui, &args),
        Command::Render(args) => commands::render::run(&ui, &args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // The reader of our stdout went away (`| head`): nothing to report.
        Err(e) if ui::is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            ui.error(&e);
            let usage = e.downcast_ref::<ui::Usage>().is_some();
            ExitCode::from(if usage { 2 } else { 1 })
        }
    }
}
