//! Writing: levels → accessors in one BIN chunk + `gltf-json` document →
//! GLB (see the module docs of `io::gltf` for the layout).

use std::collections::BTreeMap;

use glam::{Vec2, Vec3};
use gltf::json;

use super::color::srgb8_to_linear;
use super::glb::join_glb;
use crate::error::ParseError;
use crate::mesh::TriMesh;
use crate::parse_err;

/// Builds the BIN chunk and the JSON objects that point into it.
pub(super) struct Builder {
    pub(super) bin: Vec<u8>,
    pub(super) root: json::Root,
}

impl Builder {
    /// Appends `bytes` as a new 4-byte-aligned buffer view and an accessor
    /// over it; returns the accessor's index.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn accessor(
        &mut self,
        bytes: &[u8],
        count: usize,
        component: json::accessor::ComponentType,
        ty: json::accessor::Type,
        normalized: bool,
        target: json::buffer::Target,
        min_max: Option<(json::Value, json::Value)>,
    ) -> json::Index<json::Accessor> {
        debug_assert!(self.bin.len().is_multiple_of(4));
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let view = self.root.push(json::buffer::View {
            buffer: json::Index::new(0),
            byte_length: bytes.len().into(),
            byte_offset: Some(offset.into()),
            byte_stride: None,
            name: None,
            target: Some(json::validation::Checked::Valid(target)),
            extensions: None,
            extras: None,
        });
        let (min, max) = match min_max {
            Some((a, b)) => (Some(a), Some(b)),
            None => (None, None),
        };
        self.root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: count.into(),
            component_type: json::validation::Checked::Valid(json::accessor::GenericComponentType(
                component,
            )),
            extensions: None,
            extras: None,
            type_: json::validation::Checked::Valid(ty),
            min,
            max,
            name: None,
            normalized,
            sparse: None,
        })
    }
}

pub(super) fn le_bytes<const N: usize, T: Copy>(items: &[T], f: impl Fn(T) -> [u8; N]) -> Vec<u8> {
    let mut v = Vec::with_capacity(items.len() * N);
    for &x in items {
        v.extend_from_slice(&f(x));
    }
    v
}

pub(super) fn vec3_bytes(v: &[Vec3]) -> Vec<u8> {
    let mut out = Vec::with_capacity(v.len() * 12);
    for p in v {
        for c in p.to_array() {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
    out
}

/// Writes the levels as one GLB (see the module docs for the layout).
///
/// Errors: no levels, a level with no faces, a level that breaks the
/// [`TriMesh`] invariant (index out of range, attribute length, non-finite
/// value), or more data than a GLB can hold (4 GiB).
pub fn write_glb(levels: &[(&str, &TriMesh)]) -> Result<Vec<u8>, ParseError> {
    use json::accessor::{ComponentType as C, Type as T};
    use json::buffer::Target::{ArrayBuffer, ElementArrayBuffer};
    use json::validation::Checked::Valid;

    if levels.is_empty() {
        return Err(ParseError::new("GLB: no levels to write"));
    }
    let mut b = Builder {
        bin: Vec::new(),
        root: json::Root {
            asset: json::Asset {
                generator: Some(format!("lodkit {}", env!("CARGO_PKG_VERSION"))),
                ..Default::default()
            },
            ..Default::default()
        },
    };
    let mut nodes = Vec::new();
    for (name, m) in levels {
        m.validate()
            .map_err(|e| parse_err!("GLB level '{name}': {e}"))?;
        if m.faces.is_empty() {
            return Err(parse_err!("GLB level '{name}' has no faces"));
        }
        let n = m.positions.len();
        let bbox = m.bbox();
        let mut attributes = BTreeMap::new();
        let pos = b.accessor(
            &vec3_bytes(&m.positions),
            n,
            C::F32,
            T::Vec3,
            false,
            ArrayBuffer,
            Some((
                json::Value::from(bbox.min.to_array().to_vec()),
                json::Value::from(bbox.max.to_array().to_vec()),
            )),
        );
        attributes.insert(Valid(json::mesh::Semantic::Positions), pos);
        if let Some(normals) = &m.normals {
            let a = b.accessor(
                &vec3_bytes(normals),
                n,
                C::F32,
                T::Vec3,
                false,
                ArrayBuffer,
                None,
            );
            attributes.insert(Valid(json::mesh::Semantic::Normals), a);
        }
        if let Some(colors) = &m.colors {
            let q = |c: u8| ((srgb8_to_linear(c) * 65535.0).round() as u16).to_le_bytes();
            let bytes = le_bytes(colors, |c: [u8; 4]| {
                let [r0, r1] = q(c[0]);
                let [g0, g1] = q(c[1]);
                let [b0, b1] = q(c[2]);
                let [a0, a1] = (c[3] as u16 * 257).to_le_bytes();
                [r0, r1, g0, g1, b0, b1, a0, a1]
            });
            let a = b.accessor(&bytes, n, C::U16, T::Vec4, true, ArrayBuffer, None);
            attributes.insert(Valid(json::mesh::Semantic::Colors(0)), a);
        }
        if let Some(uvs) = &m.uvs {
            let bytes = le_bytes(uvs, |t: Vec2| {
                let [u0, u1, u2, u3] = t.x.to_le_bytes();
                let [v0, v1, v2, v3] = (1.0 - t.y).to_le_bytes();
                [u0, u1, u2, u3, v0, v1, v2, v3]
            });
            let a = b.accessor(&bytes, n, C::F32, T::Vec2, false, ArrayBuffer, None);
            attributes.insert(Valid(json::mesh::Semantic::TexCoords(0)), a);
        }
        let flat: Vec<u32> = m.faces.iter().flatten().copied().collect();
        let indices = if n < u16::MAX as usize {
            let bytes = le_bytes(&flat, |i: u32| (i as u16).to_le_bytes());
            b.accessor(
                &bytes,
                flat.len(),
                C::U16,
                T::Scalar,
                false,
                ElementArrayBuffer,
                None,
            )
        } else {
            let bytes = le_bytes(&flat, |i: u32| i.to_le_bytes());
            b.accessor(
                &bytes,
                flat.len(),
                C::U32,
                T::Scalar,
                false,
                ElementArrayBuffer,
                None,
            )
        };
        let label = format!("{name} ({} triangles)", m.faces.len());
        let mesh = b.root.push(json::Mesh {
            extensions: None,
            extras: None,
            name: Some(label.clone()),
            primitives: vec![json::mesh::Primitive {
                attributes,
                extensions: None,
                extras: None,
                indices: Some(indices),
                material: None,
                mode: Valid(json::mesh::Mode::Triangles),
                targets: None,
            }],
            weights: None,
        });
        let extras = serde_json::value::to_raw_value(&serde_json::json!({
            "triangles": m.faces.len(),
            "vertices": n,
        }))
        .map_err(|e| parse_err!("GLB: {e}"))?;
        nodes.push(b.root.push(json::Node {
            camera: None,
            children: None,
            extensions: None,
            extras: Some(extras),
            matrix: None,
            mesh: Some(mesh),
            name: Some(label),
            rotation: None,
            scale: None,
            translation: None,
            skin: None,
            weights: None,
        }));
    }
    let bin_len = b.bin.len();
    if bin_len > u32::MAX as usize - 1024 {
        return Err(parse_err!(
            "GLB: {bin_len} bytes of geometry, over the 4 GiB GLB limit"
        ));
    }
    b.root.push(json::Buffer {
        byte_length: bin_len.into(),
        name: None,
        uri: None,
        extensions: None,
        extras: None,
    });
    let scene = b.root.push(json::Scene {
        extensions: None,
        extras: None,
        name: None,
        nodes,
    });
    b.root.scene = Some(scene);

    let js = serde_json::to_vec(&b.root).map_err(|e| parse_err!("GLB: {e}"))?;
    join_glb(js, &b.bin)
}
