//! The arguments more than one command takes: the simplifier's options
//! and the out-of-core budget (`simplify`, `lods`). Ranges come from
//! [`lodkit::limits`].

use clap::Args;
use lodkit::limits;
use lodkit_simplify::{AttributeWeights, Options, Target};

use crate::ui::value;

/// Options shared by `simplify` and `lods`.
#[derive(Args, Debug, Clone)]
pub struct SimplifyOpts {
    /// Stop before any collapse whose estimated object-space error (input
    /// units, a finite number >= 0) would exceed E.
    #[arg(long, value_name = "E", value_parser = limits::MAX_ERROR.f32())]
    pub max_error: Option<f32>,
    /// Keep border vertices (edges with one face) in place.
    #[arg(long)]
    pub lock_border: bool,
    /// Keep every hole and open rim (the paper's hole filling is on by default).
    #[arg(long)]
    pub no_fill_holes: bool,
    /// Records in the replacement-selection heap, in 1..=16777216 (2^24:
    /// its memory grows with it).
    #[arg(long, default_value_t = Options::DEFAULT_HEAP_SIZE, value_name = "N",
          value_parser = value::range(limits::HEAP_SIZE))]
    pub heap_size: usize,
    /// Weight of normals in the cost (relative to the bounding-box extent), in [0, 1000000].
    #[arg(long, default_value_t = AttributeWeights::DEFAULT.normal, value_name = "W", value_parser = limits::WEIGHT.f32())]
    pub normal_weight: f32,
    /// Weight of colours in the cost, in [0, 1000000].
    #[arg(long, default_value_t = AttributeWeights::DEFAULT.color, value_name = "W", value_parser = limits::WEIGHT.f32())]
    pub color_weight: f32,
    /// Weight of UVs in the cost, in [0, 1000000].
    #[arg(long, default_value_t = AttributeWeights::DEFAULT.uv, value_name = "W", value_parser = limits::WEIGHT.f32())]
    pub uv_weight: f32,
    /// Remove components smaller than this fraction of the bounding-box
    /// diagonal first, in [0, 1) (1 would remove every component).
    #[arg(long, value_name = "FRACTION", value_parser = limits::PRUNE.f32())]
    pub prune: Option<f32>,
    /// Merge every mesh, primitive and instance into one mesh, dropping
    /// materials (by default .glb and .obj outputs keep them, one
    /// primitive per material, borders kept closed).
    #[arg(long)]
    pub merge: bool,
}

impl SimplifyOpts {
    /// The simplifier's options with `target`.
    pub fn options(&self, target: Target) -> Options {
        Options {
            target,
            max_error: self.max_error,
            lock_border: self.lock_border,
            fill_holes: !self.no_fill_holes,
            heap_size: self.heap_size,
            weights: AttributeWeights {
                normal: self.normal_weight,
                color: self.color_weight,
                uv: self.uv_weight,
            },
            prune: self.prune,
            ..Options::DEFAULT
        }
    }
}

/// `--memory` and `--ray`, shared by `simplify` and `lods`.
#[derive(Args, Debug)]
pub struct OutOfCoreArgs {
    /// Memory budget, in 1M..=1P bytes (K, M, G, T, P: powers of 1024; e.g.
    /// 8G, 512M). A binary PLY or STL whose in-core estimate (80 bytes per face)
    /// exceeds it is simplified out of core, in blocks staged beside the
    /// output (--target or --ratio; normals, colours, UVs kept), with the in-core
    /// error when SIZE is at least 320 bytes per target face. Default: a
    /// third of the machine's memory.
    #[arg(long, value_name = "SIZE", value_parser = value::bytes(*limits::MEMORY.start(), *limits::MEMORY.end()))]
    pub memory: Option<u64>,
    /// Run the blocks of an out-of-core run as Ray tasks: `local` starts a
    /// local cluster for the run, `auto` or HOST:PORT joins a running one
    /// (every node must see the output's folder at the same path). Needs a
    /// Python with pylodkit and ray (`python3`, or $LODKIT_PYTHON). The
    /// output is the same bytes as without.
    #[arg(long, value_name = "ADDRESS", value_parser = value::ray_address)]
    pub ray: Option<String>,
}

impl OutOfCoreArgs {
    /// The library's budget and runner.
    pub fn options(&self) -> lodkit::plan::OutOfCore {
        lodkit::plan::OutOfCore {
            memory: self.memory,
            ray: self.ray.clone(),
        }
    }
}
