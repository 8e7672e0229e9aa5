//! Materials of a textured mesh: what colours a visible sample when the
//! mesh comes with base-colour factors and textures (a scene's PBR
//! materials, an OBJ's `Kd` and `map_Kd`).
//!
//! The renderer takes textures already decoded (RGBA8, rows top to
//! bottom): decoding belongs to whoever read the file. A sample's colour
//! is the glTF base colour: the material's factor × the texture at the
//! sample's UV (bilinear, the sampler's wrap modes) × the vertex colour
//! when there is one, multiplied in sRGB space like the rest of the
//! shading (see [`crate::shade`]). UVs follow lodkit's convention (origin
//! bottom-left, `v` up, as OBJ stores them): `v = 1` is the image's first
//! row. Texel centres sit at `(i + ½) / width`.

use glam::{Vec2, Vec3};

/// How a texture coordinate outside `[0, 1]` is brought back.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wrap {
    /// Tiles the image (glTF 10497, the default).
    Repeat,
    /// Holds the edge texel (glTF 33071).
    Clamp,
    /// Tiles, every other copy mirrored (glTF 33648).
    Mirror,
}

impl Wrap {
    /// The wrap mode of a glTF sampler code; unknown codes repeat, as
    /// glTF's default does.
    pub fn from_gltf(code: u32) -> Wrap {
        match code {
            33071 => Wrap::Clamp,
            33648 => Wrap::Mirror,
            _ => Wrap::Repeat,
        }
    }

    /// Texel index `i` (any integer) brought into `0..n`.
    fn index(self, i: i64, n: i64) -> usize {
        let r = match self {
            Wrap::Repeat => i.rem_euclid(n),
            Wrap::Clamp => i.clamp(0, n - 1),
            Wrap::Mirror => {
                let m = i.rem_euclid(2 * n);
                if m < n { m } else { 2 * n - 1 - m }
            }
        };
        r as usize
    }
}

/// A decoded base-colour texture.
#[derive(Debug, Clone, PartialEq)]
pub struct TextureImage {
    /// Width in pixels, at least 1.
    pub width: u32,
    /// Height in pixels, at least 1.
    pub height: u32,
    /// `width × height × 4` bytes, RGBA8, rows top to bottom.
    pub rgba: Vec<u8>,
    /// Wrap modes in U and V.
    pub wrap: [Wrap; 2],
}

impl TextureImage {
    /// The texture's RGB (0..=255) at `uv`, bilinear between the four
    /// nearest texels. Non-finite UVs give texel (0, 0)'s neighbourhood.
    pub fn sample(&self, uv: Vec2) -> Vec3 {
        let (w, h) = (self.width as i64, self.height as i64);
        let fin = |x: f32| if x.is_finite() { x } else { 0.0 };
        // Bounded before the cast so a huge UV cannot overflow i64.
        let x = (fin(uv.x).clamp(-1e6, 1e6) as f64) * w as f64 - 0.5;
        let y = ((1.0 - fin(uv.y).clamp(-1e6, 1e6)) as f64) * h as f64 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let texel = |i: i64, j: i64| {
            let (i, j) = (self.wrap[0].index(i, w), self.wrap[1].index(j, h));
            let o = (j * self.width as usize + i) * 4;
            let p = &self.rgba[o..o + 3];
            Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32)
        };
        let top = texel(x0, y0) * (1.0 - fx) + texel(x0 + 1, y0) * fx;
        let bottom = texel(x0, y0 + 1) * (1.0 - fx) + texel(x0 + 1, y0 + 1) * fx;
        top * (1.0 - fy) + bottom * fy
    }
}

/// One material as the renderer sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Look {
    /// Base colour factor, RGB in `0..=1` (alpha is not drawn).
    pub factor: [f32; 3],
    /// Index into [`Materials::textures`]: the base-colour texture.
    pub texture: Option<usize>,
}

/// The materials of one mesh: one look per face.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Materials {
    /// One entry per face of the mesh: an index into `looks`, or
    /// [`Materials::NONE`] for a face drawn as an untextured mesh is.
    pub face_looks: Vec<u32>,
    /// The looks the faces refer to.
    pub looks: Vec<Look>,
    /// The textures the looks refer to.
    pub textures: Vec<TextureImage>,
}

impl Materials {
    /// A face without material (lodkit-mesh's `NO_MATERIAL`).
    pub const NONE: u32 = u32::MAX;

    /// Checks every index and buffer size against `faces` faces; the
    /// message names what is wrong.
    pub(crate) fn check(&self, faces: usize) -> Result<(), String> {
        if self.face_looks.len() != faces {
            return Err(format!(
                "{} face materials for {faces} faces",
                self.face_looks.len()
            ));
        }
        if let Some(&l) = self
            .face_looks
            .iter()
            .find(|&&l| l != Self::NONE && l as usize >= self.looks.len())
        {
            return Err(format!(
                "material {l} is beyond the {} materials",
                self.looks.len()
            ));
        }
        for (i, l) in self.looks.iter().enumerate() {
            if l.texture.is_some_and(|t| t >= self.textures.len()) {
                return Err(format!("material {i} names a missing texture"));
            }
            if !l.factor.iter().all(|f| f.is_finite()) {
                return Err(format!("material {i} has a non-finite colour factor"));
            }
        }
        for (i, t) in self.textures.iter().enumerate() {
            let n = t.width as usize * t.height as usize * 4;
            if t.width == 0 || t.height == 0 || t.rgba.len() != n {
                return Err(format!(
                    "texture {i}: {} bytes for {}x{} RGBA pixels",
                    t.rgba.len(),
                    t.width,
                    t.height
                ));
            }
        }
        Ok(())
    }

    /// The base colour (0..=255) of face `face` at `uv` (`None`: the mesh
    /// has no UVs, so the factor alone), or `None` for a face without
    /// material.
    pub(crate) fn colour(&self, face: usize, uv: Option<Vec2>) -> Option<Vec3> {
        let l = self.face_looks[face];
        if l == Self::NONE {
            return None;
        }
        let look = &self.looks[l as usize];
        let factor = Vec3::from_array(look.factor);
        Some(match (look.texture, uv) {
            (Some(t), Some(uv)) => self.textures[t].sample(uv) * factor,
            _ => factor * 255.0,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn checker() -> TextureImage {
        // 2 × 2: black, white / white, black (rows top to bottom).
        let (b, w) = ([0u8, 0, 0, 255], [255u8, 255, 255, 255]);
        TextureImage {
            width: 2,
            height: 2,
            rgba: [b, w, w, b].concat(),
            wrap: [Wrap::Repeat; 2],
        }
    }

    #[test]
    fn texel_centres_give_their_texel_and_v_up_reads_the_top_row_at_1() {
        let t = checker();
        assert_eq!(t.sample(Vec2::new(0.25, 0.75)), Vec3::ZERO);
        assert_eq!(t.sample(Vec2::new(0.75, 0.75)), Vec3::splat(255.0));
        assert_eq!(t.sample(Vec2::new(0.25, 0.25)), Vec3::splat(255.0));
        // Half way between two texels: their mean.
        assert_eq!(t.sample(Vec2::new(0.5, 0.75)), Vec3::splat(127.5));
    }

    #[test]
    fn wrap_modes_bring_indices_back() {
        assert_eq!(Wrap::Repeat.index(-1, 4), 3);
        assert_eq!(Wrap::Clamp.index(-1, 4), 0);
        assert_eq!(Wrap::Clamp.index(9, 4), 3);
        assert_eq!(Wrap::Mirror.index(4, 4), 3);
        assert_eq!(Wrap::Mirror.index(-1, 4), 0);
        assert_eq!(Wrap::from_gltf(33071), Wrap::Clamp);
        // Tiling: one period over gives the same colour.
        let t = checker();
        assert_eq!(
            t.sample(Vec2::new(1.25, 0.75)),
            t.sample(Vec2::new(0.25, 0.75))
        );
        assert!(t.sample(Vec2::new(f32::NAN, 1e30)).is_finite());
    }

    #[test]
    fn check_names_a_bad_index() {
        let m = Materials {
            face_looks: vec![0, 2],
            looks: vec![Look {
                factor: [1.0; 3],
                texture: None,
            }],
            textures: vec![],
        };
        assert!(m.check(2).unwrap_err().contains("material 2"));
        assert!(m.check(3).unwrap_err().contains("for 3 faces"));
    }
}
