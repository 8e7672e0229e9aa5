//! The continuous-model build (`lodkit mco build`, `pylodkit.mco.build`):
//! meshes, point clouds and range scans added one at a time to one marching
//! cube octree (`lodkit-mco`).
use anyhow::{Context, Result, bail};
use lodkit_mco::{IncrementalBuilder, McoModel, Options, densify_meshes, grid_for, samples_of};
use lodkit_mesh::Model;
use serde::Serialize;

use crate::progress::Progress;

/// One input added to the lattice.
#[derive(Debug, Clone, Serialize)]
pub struct Added {
    pub input: String,
    pub samples: usize,
    pub cubes_recomputed: usize,
    pub surface_cubes: usize,
}

/// Builds one model of `models` (each named for messages), on one lattice
/// of `resolution` leaf cubes along the longest axis (within
/// [`crate::limits::MCO_RESOLUTION`]); `None`: one mesh gets a lattice
/// whose full cut has about its triangle count, anything else the paper's
/// cube of twice the sample spacing. Meshes are densified onto the
/// lattice; scans and clouds take Hoppe's tangential rule, closed meshes
/// band-edge pruning (a closed model). Sends a note with the lattice and
/// one per input added. Errors: an input with no usable samples, named; a
/// `resolution` whose build would need more than
/// [`lodkit_mco::MAX_BUILD_BYTES`] is a [`crate::usage::Usage`]. Cost:
/// about the lattice's surface cubes in memory and time (the estimate
/// [`lodkit_mco::estimate_build_bytes`] bounds).
pub fn build_model(
    models: &[(String, Model)],
    resolution: Option<u32>,
    events: &Progress,
) -> Result<(McoModel, Vec<Added>)> {
    let samples = models
        .iter()
        .map(|(name, m)| samples_of(m).with_context(|| name.clone()))
        .collect::<Result<Vec<_>>>()?;
    if samples.iter().all(|s| s.is_empty()) {
        let names: Vec<String> = models.iter().map(|(n, _)| n.clone()).collect();
        bail!("{}: no usable samples", names.join(", "));
    }
    let plain: Vec<Model> = models.iter().map(|(_, m)| m.clone()).collect();
    // One mesh keeps its detail: a lattice whose full cut has about its
    // triangle count, as `lodkit build` makes it (scans take the paper's
    // default, twice their sample spacing).
    let resolution = match (resolution, plain.as_slice()) {
        (None, [Model::Mesh(mesh)]) => {
            lodkit_mco::mesh_resolution(mesh, lodkit_mco::MAX_BUILD_BYTES / 4)
                .with_context(|| models[0].0.clone())?
        }
        (r, _) => r,
    };
    if let Some(r) = resolution {
        // A resolution the user chose that needs more memory than a build
        // may take is a bad option value (exit 2), not bad input.
        let bytes = lodkit_mco::estimate_build_bytes(&plain, &Options { resolution })?;
        if bytes > lodkit_mco::MAX_BUILD_BYTES {
            return Err(crate::usage::usage(format!(
                "--resolution {r}: the build would need about {:.1} GB of memory, more than its {:.1} GB limit; use a lower resolution",
                bytes as f64 / 1e9,
                lodkit_mco::MAX_BUILD_BYTES as f64 / 1e9
            )));
        }
    }
    let grid = grid_for(&plain, &samples, &Options { resolution })?;
    let samples = densify_meshes(&plain, samples, &grid);
    events.status(format!(
        "lattice: resolution {}, cube {:.6}, octree depth {}",
        grid.resolution(),
        grid.cube(),
        grid.depth()
    ));
    let mut builder = IncrementalBuilder::new(grid);
    // Scan data has edges: Hoppe's tangential rule (meshes build without it).
    if plain.iter().any(|m| !matches!(m, Model::Mesh(_))) {
        builder = builder.with_tangential_rule();
    } else if lodkit_mco::all_closed_meshes(&plain) {
        // Closed meshes give closed models (`band_edge_pruning.rs`).
        builder = builder.with_band_edge_pruning();
    }
    let mut added = Vec::new();
    for ((name, _), s) in models.iter().zip(&samples) {
        let r = builder.add(s);
        events.status(format!(
            "added {name}: {} samples, {} cubes recomputed, {} surface cubes",
            r.samples, r.cubes_recomputed, r.surface_cubes
        ));
        added.push(Added {
            input: name.clone(),
            samples: r.samples,
            cubes_recomputed: r.cubes_recomputed,
            surface_cubes: r.surface_cubes,
        });
    }
    let step = events.spinner("building the octree");
    let model = builder.build()?;
    step.finish();
    Ok((model, added))
}
