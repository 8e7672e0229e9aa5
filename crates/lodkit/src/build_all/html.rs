//! `report.html`: the build's results as a person looks at them — renders
//! of the input and of every level of each form from one view, an error
//! heat map with its scale, error charts, the tables with each column
//! explained, and the stage timings ([`super::html_page`] writes the
//! page).

use anyhow::Result;
use lodkit_mesh::TriMesh;
use lodkit_mesh::metrics::Reference;
use lodkit_render::{Camera, RenderOptions, colour_scale, render};
use plotters::style::{BLUE, GREEN, RED, RGBColor};

use super::chart::{Series, error_chart, log_chart};
use super::continuous::Continuous;
use super::html_page::{Block, Picture, Table, colour_bar, page};
use super::progressive::Progressive;
use crate::lod_chain::write::Chain;
use crate::measure::{Measured, Sampling};

/// Side of every render, pixels: small, so the build stays fast and the
/// page light.
pub const RENDER_SIZE: u32 = 256;

/// Everything the page shows.
pub struct Inputs<'a> {
    pub name: &'a str,
    pub intro: Vec<String>,
    pub reference: &'a Reference<'a>,
    pub sampling: Sampling,
    pub chain: &'a Chain,
    pub continuous: &'a Continuous,
    pub progressive: &'a Progressive,
    pub timings: &'a [(String, f64)],
    /// Degenerate products, one line each (shown first when any).
    pub degenerate: &'a [String],
    /// A scene input's materials (its merged faces' looks), so the input
    /// and the HQMS levels are drawn textured.
    pub materials: Option<&'a lodkit_render::Materials>,
}

/// The page (deterministic except inside its `varies` block).
pub fn report(i: &Inputs) -> Result<String> {
    let mesh = i.reference.mesh();
    let diagonal = mesh.bbox().diagonal() as f64;
    let camera = Camera::orbit(&mesh.bbox(), 30.0, 20.0, 35.0, 1.0)
        .map_err(|e| anyhow::anyhow!("{}: cannot frame the model: {e}", i.name))?;
    let opts = RenderOptions {
        width: RENDER_SIZE,
        height: RENDER_SIZE,
        supersample: 2,
        ..RenderOptions::DEFAULT
    };
    let picture = |img: lodkit_render::Image, caption: String| -> Result<Picture> {
        let png = img
            .over(opts.background)
            .to_png()
            .map_err(|e| anyhow::anyhow!("{caption}: {e}"))?;
        Ok(Picture { caption, png })
    };
    // The input and the HQMS levels of a scene, with its materials.
    let mut looks = i.materials.cloned();
    let mut textured = |m: &TriMesh, faces: Option<&Vec<u32>>, caption: String| {
        let img = match (&mut looks, faces) {
            (Some(l), Some(f)) => {
                l.face_looks.clone_from(f);
                lodkit_render::render_textured(m, l, &camera, &opts)
            }
            _ => render(m, &camera, &opts),
        }
        .map_err(|e| anyhow::anyhow!("{caption}: {e}"))?;
        picture(img, caption)
    };
    let shot = |m: &TriMesh, caption: String| -> Result<Picture> {
        let img = render(m, &camera, &opts).map_err(|e| anyhow::anyhow!("{caption}: {e}"))?;
        picture(img, caption)
    };
    let pct = |x: f64| {
        if diagonal > 0.0 {
            100.0 * x / diagonal
        } else {
            0.0
        }
    };
    let abs_pct = |m: Option<f64>| match m {
        Some(x) if x.is_finite() => format!("{x:.3e} ({:.3} %)", pct(x)),
        _ => "-".to_string(),
    };
    let samples = |m: &Option<Measured>| m.map_or("-".into(), |m| m.samples.to_string());

    let mut b: Vec<Block> = i.intro.iter().cloned().map(Block::Text).collect();
    for d in i.degenerate {
        b.push(Block::Text(format!(
            "Warning: degenerate {d}; the build failed."
        )));
    }
    b.push(Block::Text(format!(
        "All errors are distances to the input surface in object units, with the same figure as a \
         percentage of its bounding-box diagonal ({diagonal:.6}) beside it. Errors {}.",
        i.sampling.describe().replace('`', "")
    )));

    // Renders: one view for every picture.
    b.push(Block::Heading(
        "Every level, seen from the same view".into(),
    ));
    b.push(Block::Text(
        "One camera (azimuth 30°, elevation 20°, framing the input's bounding box) for every picture; \
         flat-shaded, both sides drawn."
            .into(),
    ));
    let input_faces = i.materials.map(|m| &m.face_looks);
    b.push(Block::Gallery(vec![textured(
        mesh,
        input_faces,
        format!("input: {} triangles", mesh.faces.len()),
    )?]));
    let mut pics = Vec::new();
    for (k, (l, m)) in i.chain.lods.levels.iter().zip(&i.chain.meshes).enumerate() {
        let faces = i.chain.face_materials.as_ref().and_then(|f| f.get(k));
        pics.push(textured(
            m,
            faces,
            format!("HQMS level {}: {} triangles", l.level, l.triangles),
        )?);
    }
    b.push(Block::Text("Discrete LOD chain (HQMS):".into()));
    b.push(Block::Gallery(pics));
    let mut pics = Vec::new();
    for c in &i.continuous.cuts {
        pics.push(shot(
            &c.mesh,
            format!(
                "MCO cut at {} %: LOD {}, {} triangles",
                c.percent,
                c.lod,
                c.mesh.faces.len()
            ),
        )?);
    }
    b.push(Block::Text("Marching cube octree cuts:".into()));
    b.push(Block::Gallery(pics));
    let mut pics = Vec::new();
    for l in i
        .progressive
        .levels
        .iter()
        .filter(|l| !l.mesh.faces.is_empty())
    {
        pics.push(shot(
            &l.mesh,
            format!(
                "stream level {} (N = {}): {} triangles, {} bytes",
                l.level,
                l.precision,
                l.mesh.faces.len(),
                l.bytes_so_far
            ),
        )?);
    }
    b.push(Block::Text(
        "Progressive stream levels (octree particles):".into(),
    ));
    b.push(Block::Gallery(pics));

    // Heat map of the coarsest HQMS level.
    if let Some((l, m)) = i
        .chain
        .lods
        .levels
        .iter()
        .zip(&i.chain.meshes)
        .rev()
        .find(|(_, m)| !m.faces.is_empty())
    {
        let d = i.reference.index().distances(&m.positions);
        let max = d.iter().copied().fold(0.0f32, f32::max);
        let colours = d
            .iter()
            .map(|&x| {
                let [r, g, b] = colour_scale(if max > 0.0 { x / max } else { 0.0 });
                [r, g, b, 255]
            })
            .collect();
        let heat = TriMesh {
            colors: Some(colours),
            ..m.clone()
        };
        b.push(Block::Heading("Error heat map".into()));
        b.push(Block::Text(format!(
            "HQMS level {} ({} triangles), each vertex coloured by its distance to the input \
             (as `lodkit compare --heatmap` does); colours are interpolated across faces.",
            l.level, l.triangles
        )));
        b.push(Block::Gallery(vec![shot(
            &heat,
            format!("HQMS level {}: distance to the input", l.level),
        )?]));
        b.push(Block::Svg(colour_bar(
            colour_scale,
            "0",
            &format!("{:.3e} ({:.3} % of the diagonal)", max, pct(max as f64)),
        )));
    }

    // Charts.
    b.push(Block::Heading("Error against size".into()));
    let chain_pts = |f: fn(&Measured) -> f64| -> Vec<(f64, f64)> {
        i.chain
            .lods
            .levels
            .iter()
            .zip(&i.chain.measured)
            .filter_map(|(l, m)| m.as_ref().map(|m| (l.triangles as f64, f(m))))
            .collect()
    };
    let cut_pts = |f: fn(&Measured) -> f64| -> Vec<(f64, f64)> {
        i.continuous
            .cuts
            .iter()
            .filter_map(|c| c.mco.as_ref().map(|m| (c.mesh.faces.len() as f64, f(m))))
            .collect()
    };
    let pop_pts = |f: fn(&Measured) -> f64, x: fn(&super::progressive::StreamLevel) -> f64| {
        i.progressive
            .levels
            .iter()
            .filter_map(|l| l.measured.as_ref().map(|m| (x(l), f(m))))
            .collect::<Vec<_>>()
    };
    let estimated: Vec<(f64, f64)> = i
        .chain
        .lods
        .levels
        .iter()
        .map(|l| (l.triangles as f64, l.estimated_error as f64))
        .collect();
    let grey = RGBColor(120, 120, 120);
    let mut series = vec![Series {
        name: "HQMS estimated (quadric bound)",
        points: estimated,
        color: grey,
    }];
    if i.sampling.measures() {
        series.extend([
            Series {
                name: "HQMS max",
                points: chain_pts(|m| m.max),
                color: RED,
            },
            Series {
                name: "HQMS mean",
                points: chain_pts(|m| m.mean),
                color: RGBColor(240, 150, 150),
            },
            Series {
                name: "MCO max",
                points: cut_pts(|m| m.max),
                color: BLUE,
            },
            Series {
                name: "MCO mean",
                points: cut_pts(|m| m.mean),
                color: RGBColor(150, 150, 240),
            },
            Series {
                name: ".pop max",
                points: pop_pts(|m| m.max, |l| l.mesh.faces.len() as f64),
                color: GREEN,
            },
            Series {
                name: ".pop mean",
                points: pop_pts(|m| m.mean, |l| l.mesh.faces.len() as f64),
                color: RGBColor(140, 200, 140),
            },
        ]);
    }
    series.retain(|s| !s.points.is_empty());
    b.push(Block::Svg(error_chart(
        &format!("{}: error against triangle count, every form", i.name),
        &series,
    )?));
    if i.sampling.measures() {
        let s = [
            Series {
                name: ".pop max",
                points: pop_pts(|m| m.max, |l| l.bytes_so_far as f64),
                color: GREEN,
            },
            Series {
                name: ".pop mean",
                points: pop_pts(|m| m.mean, |l| l.bytes_so_far as f64),
                color: BLUE,
            },
        ];
        if s.iter().any(|s| !s.points.is_empty()) {
            b.push(Block::Svg(log_chart(
                &format!("{}: .pop error against bytes received", i.name),
                "bytes received",
                &s,
            )?));
        }
    }

    // Tables.
    let col = |h: &str, why: &str| (h.to_string(), why.to_string());
    let mean_col = col(
        "measured mean",
        "Mean distance over the samples of both surfaces, the larger of the two directions (Metro's mean), object units and % of the diagonal.",
    );
    let max_col = col(
        "measured max",
        "Largest distance found over the samples of both directions: the symmetric Hausdorff distance as far as the samples resolve it.",
    );
    let samples_col = col(
        "samples",
        "Samples of each kind (vertices, edges, faces) per direction used for this row's measurement.",
    );
    b.push(Block::Heading("Discrete LOD chain (HQMS)".into()));
    b.push(Block::Table(Table {
        columns: vec![
            col("level", "Level of the chain; level 0 is the input, each level is simplified from the previous one to half its triangles."),
            col("file", "The level's PLY in the output folder."),
            col("triangles", "Triangles of the level."),
            col("vertices", "Vertices of the level."),
            samples_col.clone(),
            col("estimated error", "The simplifier's own bound: each vertex accumulates the quadric error of every collapse it survived, and this is the largest. Sums of per-collapse bounds grow faster than the true distance (errors of successive collapses overlap and partly cancel), so it exceeds the measured maximum; it costs nothing to compute."),
            mean_col.clone(),
            max_col.clone(),
            col("stopped", "Why the level stopped where it did."),
        ],
        rows: std::iter::once(vec![
            "0".into(),
            format!("{}.ply", i.name),
            mesh.faces.len().to_string(),
            mesh.positions.len().to_string(),
            "-".into(),
            "0".into(),
            "0".into(),
            "0".into(),
            "input".into(),
        ])
        .chain(i.chain.lods.levels.iter().zip(&i.chain.measured).map(|(l, m)| {
            vec![
                l.level.to_string(),
                format!("lods/{}", l.file),
                l.triangles.to_string(),
                l.vertices.to_string(),
                samples(m),
                abs_pct(Some(l.estimated_error as f64)),
                abs_pct(m.map(|m| m.mean)),
                abs_pct(m.map(|m| m.max)),
                l.stop.clone(),
            ]
        }))
        .collect(),
    }));
    b.push(Block::Heading(
        "Continuous LOD (marching cube octree)".into(),
    ));
    b.push(Block::Table(Table {
        columns: vec![
            col("% of full", "The cut's triangle budget as a fraction of the model's full-resolution triangle count."),
            col("LOD", "The LOD number of the cut nearest that budget."),
            col("triangles", "Triangles of the cut (and of the HQMS simplification beside it)."),
            samples_col.clone(),
            col("MCO mean", "Measured mean distance of the cut to the input."),
            col("MCO max", "Measured maximum distance of the cut to the input; for a reconstructed input it includes what the reconstruction missed, not only the cut."),
            col("HQMS mean", "Measured mean distance of HQMS simplifying the input to the same triangle count."),
            col("HQMS max", "Measured maximum distance of that HQMS simplification."),
        ],
        rows: i
            .continuous
            .cuts
            .iter()
            .map(|c| {
                vec![
                    c.percent.to_string(),
                    c.lod.to_string(),
                    c.mesh.faces.len().to_string(),
                    samples(&c.mco),
                    abs_pct(c.mco.map(|m| m.mean)),
                    abs_pct(c.mco.map(|m| m.max)),
                    abs_pct(c.hqms.map(|m| m.mean)),
                    abs_pct(c.hqms.map(|m| m.max)),
                ]
            })
            .collect(),
    }));
    b.push(Block::Heading(
        "Progressive stream (octree particles)".into(),
    ));
    b.push(Block::Text(format!(
        "{} ({} bytes): any prefix of whole chunks decodes; each row is what a reader shows after receiving the bytes so far.",
        i.progressive.file, i.progressive.bytes
    )));
    b.push(Block::Table(Table {
        columns: vec![
            col("level", "Octree level r of the particles shown."),
            col("N", "Bits per coordinate of the decoded positions (N = r from the level chunks alone; the refinement layers bring the finest level to the stream's full precision)."),
            col("bytes so far", "Stream bytes a reader needs to show this row (header included)."),
            col("particles", "Particles (occupied octree cells kept after thinning) at this level."),
            col("triangles", "Triangles of the direct triangulation of the particles."),
            samples_col,
            col("mean error", "Measured mean distance of the triangulated level to the input."),
            col("max error", "Measured maximum distance of the triangulated level to the input."),
        ],
        rows: i
            .progressive
            .levels
            .iter()
            .map(|l| {
                vec![
                    l.level.to_string(),
                    l.precision.to_string(),
                    l.bytes_so_far.to_string(),
                    l.particles.to_string(),
                    l.mesh.faces.len().to_string(),
                    samples(&l.measured),
                    abs_pct(l.measured.map(|m| m.mean)),
                    abs_pct(l.measured.map(|m| m.max)),
                ]
            })
            .collect(),
    }));

    // Timings: the one part that changes from run to run.
    b.push(Block::Varies(vec![
        Block::Heading("Stage timings".into()),
        Block::Table(Table {
            columns: vec![
                col("stage", "One stage of this build, in the order run."),
                col("seconds", "Its wall time on this machine, this run."),
            ],
            rows: i
                .timings
                .iter()
                .map(|(s, t)| vec![s.clone(), format!("{t:.3}")])
                .collect(),
        }),
    ]));
    Ok(page(&format!("lodkit build report: {}", i.name), &b))
}
