//! What `lodkit build` reports about the continuous LOD: the model built
//! from virtual scans of the input (the thesis's §4.4 experiment), and its
//! extractions at fractions of full size with their Metro errors against
//! the input.

use lodkit_mesh::TriMesh;
use lodkit_mesh::metrics::{CompareOptions, compare};

use crate::Result;
use crate::model::McoModel;
use crate::pipeline::{Options, build_from_range_images};
use crate::scanner::{ScanOptions, scan_mesh};

/// Scans recommended for `lodkit build`: 8 views, alternately 30° above
/// and below the horizon, 300 × 300 samples each.
pub const BUILD_SCANS: ScanOptions = ScanOptions {
    views: 8,
    width: 300,
    height: 300,
    elevation_deg: 30.0,
    alternate: true,
    noise: 0.0,
    seed: 1,
};

/// Scans `mesh` and builds the continuous model from the scans.
pub fn build_from_virtual_scans(
    mesh: &TriMesh,
    scans: &ScanOptions,
    opts: &Options,
) -> Result<McoModel> {
    let images = scan_mesh(mesh, scans)?;
    build_from_range_images(&images, opts)
}

/// One extraction measured against the reference.
#[derive(Debug, Clone, PartialEq)]
pub struct ExtractionError {
    /// Requested fraction of the full triangle count, in per cent.
    pub percent: f64,
    pub lod: usize,
    pub triangles: usize,
    /// Symmetric mean and max (Hausdorff) distance, object units.
    pub mean: f64,
    pub max: f64,
    /// The mean as a percentage of the bounding-box diagonal.
    pub mean_pct: f64,
}

/// Extractions at `percents` of full size, each compared with `reference`
/// (Metro, `samples` per kind; `None` = the compare default).
pub fn extraction_errors(
    model: &McoModel,
    reference: &TriMesh,
    percents: &[f64],
    samples: Option<usize>,
) -> Result<Vec<ExtractionError>> {
    let full = model.full_triangles();
    let opts = CompareOptions {
        samples,
        ..Default::default()
    };
    let mut out = Vec::with_capacity(percents.len());
    let mut idx = Vec::new();
    for &percent in percents {
        let target = ((full as f64 * percent / 100.0).round() as usize).max(1);
        let lod = model.extract_triangles(target, &mut idx);
        let mesh = model.mesh_from_indices(&idx);
        if mesh.faces.is_empty() {
            continue;
        }
        let r = compare(&mesh, reference, &opts)?;
        out.push(ExtractionError {
            percent,
            lod,
            triangles: mesh.faces.len(),
            mean: r.symmetric.mean,
            max: r.symmetric.max,
            mean_pct: r.symmetric.mean_pct,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_grow_as_the_budget_shrinks() {
        let sphere = lodkit_mesh::shapes::icosphere(4);
        let scans = ScanOptions {
            width: 64,
            height: 64,
            ..BUILD_SCANS
        };
        let m = build_from_virtual_scans(
            &sphere,
            &scans,
            &Options {
                resolution: Some(24),
            },
        )
        .unwrap();
        let rows = extraction_errors(&m, &sphere, &[100.0, 10.0, 1.0], Some(20_000)).unwrap();
        assert_eq!(rows.len(), 3);
        assert!(rows[0].mean < 0.5 * m.grid.cube as f64, "{rows:?}");
        assert!(
            rows[0].mean <= rows[1].mean && rows[1].mean <= rows[2].mean,
            "{rows:?}"
        );
        assert!(rows[2].triangles < rows[1].triangles);
    }
}
