//! How meshes and scenes are written: vertex normals, GLB compression, and
//! which formats a mesh result may go to.

use std::path::Path;

use anyhow::Result;
use lodkit_mesh::Model;

/// The output options of the jobs that write meshes (`convert`,
/// `simplify`, `lods`, `build`).
#[derive(Debug, Clone, Copy, Default)]
pub struct OutputOptions {
    /// Vertex normals of what is written: keep, none, or smooth with a
    /// crease angle in [`crate::limits::CREASE_DEGREES`]. `None`: smooth
    /// (60°) for .glb outputs of meshes without normals, keep otherwise.
    pub normals: Option<lodkit_mesh::normals::NormalsMode>,
    /// Write .glb outputs compressed (EXT_meshopt_compression with
    /// KHR_mesh_quantization; needs the `compress` feature).
    pub compress: bool,
}

impl OutputOptions {
    /// The normals mode for `mesh` written as `format` (see [`OutputOptions::normals`]).
    pub fn normals_for(
        &self,
        mesh: &lodkit_mesh::TriMesh,
        format: lodkit_mesh::io::Format,
    ) -> lodkit_mesh::normals::NormalsMode {
        use lodkit_mesh::normals::NormalsMode;
        match (self.normals, format) {
            (Some(m), _) => m,
            (None, lodkit_mesh::io::Format::Glb) => NormalsMode::default_for(mesh),
            (None, _) => NormalsMode::Keep,
        }
    }

    /// `scene` as `--normals` asks, each mesh on its own (as
    /// [`OutputOptions::normals_for`] decides for one mesh; face order and
    /// face materials unchanged). `--compress` for an output that is not
    /// .glb is refused (exit 2).
    pub fn scene(
        &self,
        mut scene: lodkit_mesh::Scene,
        output: &std::path::Path,
    ) -> anyhow::Result<lodkit_mesh::Scene> {
        let format =
            lodkit_mesh::io::Format::from_path(output).unwrap_or(lodkit_mesh::io::Format::Glb);
        self.check(Some(format), &output.display().to_string())?;
        for m in &mut scene.meshes {
            if let std::borrow::Cow::Owned(x) = self.normals_for(&m.mesh, format).apply(&m.mesh) {
                m.mesh = x;
            }
        }
        Ok(scene)
    }

    /// Refuses `--compress` for an output that is not .glb (exit 2).
    pub fn check(&self, format: Option<lodkit_mesh::io::Format>, what: &str) -> anyhow::Result<()> {
        if self.compress && format != Some(lodkit_mesh::io::Format::Glb) {
            return Err(crate::usage::usage(format!(
                "--compress applies to .glb outputs, not to {what}"
            )));
        }
        Ok(())
    }

    /// The GLB writer's options.
    pub fn glb(&self) -> lodkit_mesh::io::gltf::GlbOptions {
        lodkit_mesh::io::gltf::GlbOptions {
            compress: self.compress,
        }
    }

    /// `model` as `format` bytes with these options: normals first (a
    /// mesh only), then the GLB writer with `compress`, or
    /// [`lodkit_mesh::io::encode`] for every other format.
    pub fn encode(
        &self,
        format: lodkit_mesh::io::Format,
        model: &lodkit_mesh::Model,
        opts: lodkit_mesh::io::WriteOptions,
    ) -> Result<Vec<u8>, lodkit_mesh::ParseError> {
        use lodkit_mesh::Model;
        use lodkit_mesh::io::Format;
        let changed;
        let model = match model {
            Model::Mesh(m) => match self.normals_for(m, format).apply(m) {
                std::borrow::Cow::Borrowed(_) => model,
                std::borrow::Cow::Owned(x) => {
                    changed = Model::Mesh(x);
                    &changed
                }
            },
            _ => model,
        };
        if format == Format::Glb && self.compress {
            lodkit_mesh::io::check_readable(format, model)?;
            return lodkit_mesh::io::gltf::write_model_glb(model, &self.glb());
        }
        lodkit_mesh::io::encode(format, model, opts)
    }
}

/// What writing `model` as `format` keeps, in words for the `wrote` line:
/// a conversion that drops something (a mesh's faces into a point format)
/// is said, never silent.
pub fn written_as(model: &Model, format: Option<lodkit_mesh::io::Format>) -> String {
    use lodkit_mesh::io::Format;
    let points = matches!(format, Some(Format::Xyz | Format::Pts));
    match model {
        Model::Mesh(m) if points => format!(
            "{} points: the mesh's vertices; its {} faces are dropped, {} holds points only",
            m.positions.len(),
            m.faces.len(),
            format.map_or("the format", |f| f.name())
        ),
        Model::Range(r) if points => {
            format!("{} points of the range image", r.to_point_cloud().len())
        }
        other => other.kind().to_string(),
    }
}

/// Refuses (exit 2) to write a mesh result to a points-only format, where
/// its faces would be dropped.
pub fn mesh_output(path: &Path) -> Result<lodkit_mesh::io::Format> {
    use lodkit_mesh::io::Format;
    match Format::from_path(path) {
        Some(Format::Xyz | Format::Pts) => Err(crate::usage::usage(format!(
            "{}: this command writes a mesh; .xyz, .pts and .txt hold points only (use .ply, .obj, .stl or .glb)",
            path.display()
        ))),
        Some(Format::Gltf) => Err(crate::usage::usage(format!(
            "{}: meshes are written as .glb, not .gltf",
            path.display()
        ))),
        Some(f) => Ok(f),
        None => Err(crate::usage::usage(format!(
            "{}: unknown output extension (expected .ply, .obj, .stl or .glb)",
            path.display()
        ))),
    }
}
