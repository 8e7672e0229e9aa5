//! A progressive stream (`.pop`) of any input, what `lodkit pop encode`
//! runs: a mesh is coded as it is; a point cloud or a range image is
//! coded from its **reconstructed surface**, at the depth whose leaves
//! number about its samples, as `lodkit build` codes it.
//!
//! Why not the raw samples by default: the particles of a scan's raw
//! points sit one per occupied leaf, and an octree fine enough to keep
//! the scan's detail (about one sample a leaf) has leaves that miss
//! samples, so its direct triangulation falls apart. Measured on the
//! LMS400 laser scan (460,400 points): the samples' own depth (3 points a
//! leaf) keeps 60,688 particles, an eighth of the input; one level deeper,
//! 385,297 particles triangulate to half the surface's area. Coded from
//! the marching-cube reconstruction (`lodkit-mco`, its full cut), the
//! stream keeps 715,724 particles and the whole surface, in about 13 s.
//! [`StreamSource::Samples`] keeps the paper's direct path (§3: points
//! straight into the octree) for a user who wants it.

use anyhow::{Result, anyhow};
use lodkit_mesh::{Model, TriMesh};
use lodkit_particles::{EncodeOptions, Encoded, encode};
use serde::Serialize;

use crate::build_all::progressive::{encode_near, surface_depth};
use crate::measure::sample_count;
use crate::progress::Progress;

/// What a cloud's or range image's stream codes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum StreamSource {
    /// The reconstructed surface (the default).
    #[default]
    Surface,
    /// The samples as they are (the paper's direct path).
    Samples,
}

/// What was coded, beside the encoder's own report.
#[derive(Debug, Clone, Serialize)]
pub struct StreamPlan {
    /// `"mesh"`, `"surface"` (a reconstruction of the samples) or
    /// `"samples"`.
    pub source: &'static str,
    /// The input's samples: a mesh's vertices, a cloud's finite points, a
    /// range image's valid pixels.
    pub samples: usize,
    /// The reconstruction's lattice resolution and full-cut triangles,
    /// when the surface was reconstructed.
    pub reconstruction: Option<(u32, usize)>,
}

/// Encodes `model` (read from `name`, which errors name) with `opts`.
///
/// A mesh, or any input with [`StreamSource::Samples`], goes to
/// [`lodkit_particles::encode`] as it is. A point cloud or range image
/// with [`StreamSource::Surface`] is first reconstructed
/// ([`lodkit_mco::build_from_models`] at its default lattice) and its
/// full cut encoded: at `opts.depth` when set, otherwise at the depth
/// whose leaves number about the input's samples (within 2× of them,
/// one level deeper or shallower tried when the first count falls
/// outside). Errors: the reconstruction's or the encoder's, naming
/// `name`; a reconstruction with no triangles. Cost: one `mco build` of
/// the input (seconds per million samples) and one or two encodings.
pub fn encode_model(
    model: &Model,
    name: &str,
    opts: &EncodeOptions,
    source: StreamSource,
    events: &Progress,
) -> Result<(Encoded, StreamPlan)> {
    let samples = sample_count(model).0;
    let direct = |what| -> Result<(Encoded, StreamPlan)> {
        let step = events.spinner("encoding octree particles");
        let e = encode(model, opts).map_err(|e| anyhow!("{name}: {e}"))?;
        step.finish();
        Ok((
            e,
            StreamPlan {
                source: what,
                samples,
                reconstruction: None,
            },
        ))
    };
    match (model, source) {
        (Model::Mesh(_), _) => direct("mesh"),
        (_, StreamSource::Samples) => direct("samples"),
        (_, StreamSource::Surface) => {
            let step = events.spinner(&format!("reconstructing the {}'s surface", model.kind()));
            let mco = lodkit_mco::build_from_models(
                std::slice::from_ref(model),
                &lodkit_mco::Options::DEFAULT,
            )
            .map_err(|e| anyhow!("{name}: {e}"))?;
            let surface: TriMesh = mco.mesh_at_lod(mco.max_lod());
            step.finish();
            if surface.faces.is_empty() {
                return Err(anyhow!("{name}: the reconstruction has no triangles"));
            }
            let resolution = mco.grid().resolution();
            let triangles = surface.faces.len();
            let auto = opts.depth.is_none();
            let opts = EncodeOptions {
                depth: opts.depth.or_else(|| surface_depth(&surface, samples)),
                ..*opts
            };
            let source = Model::Mesh(surface);
            let step = events.spinner("encoding octree particles");
            let e = if auto {
                encode_near(&source, &opts, samples)
            } else {
                encode(&source, &opts).map_err(Into::into)
            }
            .map_err(|e| anyhow!("{name}: {e}"))?;
            step.finish();
            Ok((
                e,
                StreamPlan {
                    source: "surface",
                    samples,
                    reconstruction: Some((resolution, triangles)),
                },
            ))
        }
    }
}
