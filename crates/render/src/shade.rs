//! Shading of visible samples: ambient plus Lambert from a headlight.
//!
//! The light is a directional headlight along the viewing direction, so
//! every view is lit the same way relative to the camera and a ring of
//! views has no dark side. Lighting is two-sided (`|n·l|`): open scans
//! show their inside through holes, and inconsistently wound faces shade
//! like their neighbours. Colours are multiplied in sRGB space (no
//! linearisation): cheap, and what simple scan viewers do.

use glam::{Vec2, Vec3};
use lodkit_mesh::TriMesh;

use crate::texture::Materials;

/// Light reaching every surface regardless of its orientation.
pub const AMBIENT: f32 = 0.22;
/// Headlight strength: a surface facing the camera gets `AMBIENT + DIFFUSE`.
pub const DIFFUSE: f32 = 0.78;
/// Brightness of the farthest point of a cloud without normals.
pub const FAR_POINT_BRIGHTNESS: f32 = 0.45;

/// Where the shader finds a visible sample's normal and colour.
pub(crate) enum Surface<'a> {
    /// Faces: smooth normals interpolated from `vertex_normals` when
    /// given, else each face's own normal.
    Mesh {
        mesh: &'a TriMesh,
        vertex_normals: Option<&'a [Vec3]>,
        face_normals: Vec<Vec3>,
        colours: Option<&'a [[u8; 4]]>,
        /// Base colour factors and textures, when the mesh has materials.
        materials: Option<&'a Materials>,
    },
    /// Points: the point's normal when given, else unlit but darkened
    /// with depth (nearest at full brightness, farthest at
    /// [`FAR_POINT_BRIGHTNESS`]) so the shape reads without normals.
    Points {
        normals: Option<&'a [Vec3]>,
        colours: Option<&'a [[u8; 4]]>,
        /// Inverse depths of the nearest and farthest point in view.
        inv_z_range: (f32, f32),
    },
}

/// Shades the sample covered by element `id` at barycentrics `bary`, lit
/// from direction `light` (unit, towards the camera); `base` is the colour
/// of an element without colours. Returns sRGB in `0..=255` as `f32`.
pub(crate) fn shade(
    s: &Surface<'_>,
    id: u32,
    bary: Vec3,
    inv_z: f32,
    light: Vec3,
    base: Vec3,
) -> Vec3 {
    let id = id as usize;
    match s {
        Surface::Mesh {
            mesh,
            vertex_normals,
            face_normals,
            colours,
            materials,
        } => {
            let f = mesh.faces[id];
            let n = match vertex_normals {
                Some(vn) => (vn[f[0] as usize] * bary.x
                    + vn[f[1] as usize] * bary.y
                    + vn[f[2] as usize] * bary.z)
                    .normalize_or_zero(),
                None => face_normals[id],
            };
            let c = match colours {
                Some(c) => {
                    rgb(c[f[0] as usize]) * bary.x
                        + rgb(c[f[1] as usize]) * bary.y
                        + rgb(c[f[2] as usize]) * bary.z
                }
                None => base,
            };
            // A material's base colour replaces the clay colour, and
            // multiplies vertex colours (glTF's base colour).
            let material = materials.and_then(|m| {
                let uv = mesh.uvs.as_ref().map(|t| {
                    let p = |k: usize| -> Vec2 { t[f[k] as usize] };
                    p(0) * bary.x + p(1) * bary.y + p(2) * bary.z
                });
                m.colour(id, uv)
            });
            let c = match (material, colours) {
                (Some(m), Some(_)) => c * m / 255.0,
                (Some(m), None) => m,
                (None, _) => c,
            };
            c * (AMBIENT + DIFFUSE * n.dot(light).abs())
        }
        Surface::Points {
            normals,
            colours,
            inv_z_range: (near, far),
        } => {
            let c = colours.map_or(base, |c| rgb(c[id]));
            match normals {
                Some(n) => c * (AMBIENT + DIFFUSE * n[id].normalize_or_zero().dot(light).abs()),
                None => {
                    // Depth cue, linear in depth between the nearest and farthest point.
                    let z = 1.0 / inv_z;
                    let (zn, zf) = (1.0 / near, 1.0 / far);
                    let t = if zf > zn {
                        ((z - zn) / (zf - zn)).clamp(0.0, 1.0)
                    } else {
                        0.0
                    };
                    c * (1.0 - (1.0 - FAR_POINT_BRIGHTNESS) * t)
                }
            }
        }
    }
}

fn rgb(c: [u8; 4]) -> Vec3 {
    Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32)
}
