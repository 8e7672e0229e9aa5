//! The serde types that front-ends print or return as a job's figures,
//! one definition each (`lods.json`, `lodkit mco info --json`,
//! pylodkit's `McoModel.info()`). The build's own `report.md` and `report.html` are
//! written by [`crate::build_all`].

use serde::Serialize;

/// One octree level of a `.mco` model.
#[derive(Debug, Clone, Serialize)]
pub struct McoLevel {
    pub level: usize,
    pub nodes: usize,
    pub triangles: usize,
}

/// A `.mco` model's figures (no file fields): its lattice (resolution,
/// cube edge in object units, octree depth), sizes and levels.
#[derive(Debug, Clone, Serialize)]
pub struct McoModelInfo {
    pub resolution: u32,
    pub cube: f32,
    pub depth: u32,
    pub vertices: usize,
    pub nodes: usize,
    pub lod_array: usize,
    pub lod_numbers: usize,
    pub full_triangles: usize,
    pub crack_patches: usize,
    pub input_samples: u64,
    pub levels: Vec<McoLevel>,
}

impl McoModelInfo {
    /// The figures of `model`. Cost: its levels, once.
    pub fn of(model: &lodkit_mco::McoModel) -> Self {
        let m = model.info();
        McoModelInfo {
            resolution: m.grid.resolution(),
            cube: m.grid.cube(),
            depth: m.grid.depth(),
            vertices: m.vertices,
            nodes: m.nodes,
            lod_array: m.lod_array,
            lod_numbers: m.lod_numbers,
            full_triangles: m.full_triangles,
            crack_patches: m.crack_patches,
            input_samples: m.input_samples,
            levels: m
                .levels
                .iter()
                .enumerate()
                .map(|(level, l)| McoLevel {
                    level,
                    nodes: l.nodes,
                    triangles: l.triangles,
                })
                .collect(),
        }
    }
}

/// One level of a chain, as `lods.json` lists it (errors in object
/// units; NaN, written as null, where not measured).
#[derive(Debug, Serialize)]
pub struct Level {
    pub level: usize,
    pub file: String,
    pub target_triangles: usize,
    pub triangles: usize,
    pub vertices: usize,
    pub estimated_error: f32,
    pub measured_mean_error: f64,
    pub measured_max_error: f64,
    pub seconds: f64,
    pub stop: String,
}

/// `lods.json`: the input and every level.
#[derive(Debug, Serialize)]
pub struct Lods {
    pub input: String,
    pub input_triangles: usize,
    pub input_vertices: usize,
    pub glb: String,
    pub levels: Vec<Level>,
}
