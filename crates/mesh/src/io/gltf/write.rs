//! Writing: meshes or points → accessors in one BIN chunk + `gltf-json`
//! document → GLB (see the module docs of `io::gltf` for the layouts).
//!
//! The stages are separate functions so that each layout is one block:
//! [`Builder::primitive`] / [`Builder::points_primitive`] (one level's
//! accessors, plain or quantised and compressed), [`Builder::node`] (a
//! named node with its extras and the dequantisation transform), then the
//! layout — siblings ([`write_glb_with`]), an `MSFT_lod` chain
//! ([`write_lod_glb`]) or one point cloud ([`write_points_glb`]) — and
//! [`Builder::finish`] (buffers, extension lists, the container).

use std::collections::BTreeMap;

use glam::{Vec2, Vec3};
use gltf::json;
use json::accessor::{ComponentType as C, Type as T};
use json::buffer::Target::{ArrayBuffer, ElementArrayBuffer};
use json::validation::Checked::Valid;

use super::codec::{Codec, encode_view, reorder_for_codec};
use super::color::srgb8_to_linear;
use super::glb::join_glb;
use super::lod_links::{MSFT_LOD, check_coverage, link_lods};
use crate::error::ParseError;
use crate::mesh::{Aabb, PointCloud, TriMesh};
use crate::parse_err;

/// Options for the GLB writers.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GlbOptions {
    /// Quantise the attributes (`KHR_mesh_quantization`) and compress every
    /// buffer view with meshoptimizer's codecs (`EXT_meshopt_compression`);
    /// see the module docs. Needs the `meshopt` feature (C++); without it
    /// the writers return an error saying so.
    pub compress: bool,
}

/// One level of an `MSFT_lod` chain for [`write_lod_glb`].
#[derive(Clone, Debug)]
pub struct LodLevel<'a> {
    /// Node and mesh name (the chain's convention: `NAME_LOD0`, `NAME_LOD1`, …).
    pub name: String,
    /// The level's mesh.
    pub mesh: &'a TriMesh,
    /// The node's `extras` (an object; the writer adds `triangles` and
    /// `vertices`).
    pub extras: serde_json::Map<String, serde_json::Value>,
    /// The smallest screen coverage (projected area ÷ viewport area, in
    /// `[0, 1]`) at which this level is to be shown: `MSFT_screencoverage`,
    /// lowered where needed so the chain's values strictly decrease
    /// ([`screen_coverages`](super::screen_coverages)).
    pub coverage: f64,
}

/// Position quantisation shared by every level of a file: 14-bit unsigned
/// integers on a uniform grid over the union of the levels' boxes, undone
/// by the node's translation + uniform scale (so all levels line up on the
/// same grid). 14 bits is gltfpack's default: 1/16383 of the largest
/// extent.
#[derive(Clone, Copy, Debug)]
pub(super) struct Quantise {
    pub(super) origin: Vec3,
    pub(super) step: f32,
    /// On a grid shared between files ([`super::QuantGrid`]): `origin`
    /// and `step` are exact on it, integers are computed in `f64` and
    /// span the whole `u16` range.
    pub(super) shared: bool,
}

const POSITION_BITS: u32 = 14;

impl Quantise {
    fn over(bbox: Aabb) -> Quantise {
        let extent = (bbox.max - bbox.min).max_element();
        let levels = ((1u32 << POSITION_BITS) - 1) as f32;
        let step = if extent > 0.0 && (extent / levels).is_normal() {
            extent / levels
        } else {
            1.0
        };
        Quantise {
            origin: bbox.min,
            step,
            shared: false,
        }
    }

    fn q(&self, p: Vec3) -> [u16; 3] {
        if self.shared {
            // Exact: origin and step are on the grid, the difference of
            // two f32 is exact in f64 and the step is a power of two.
            return std::array::from_fn(|k| {
                ((p[k] as f64 - self.origin[k] as f64) / self.step as f64)
                    .round()
                    .clamp(0.0, u16::MAX as f64) as u16
            });
        }
        let max = ((1u32 << POSITION_BITS) - 1) as f32;
        ((p - self.origin) / self.step)
            .round()
            .clamp(Vec3::ZERO, Vec3::splat(max))
            .to_array()
            .map(|c| c as u16)
    }
}

/// Builds the BIN chunk and the JSON objects that point into it (the
/// one-mesh layouts here and the scene layouts of `materials_write`).
pub(super) struct Builder {
    bin: Vec<u8>,
    pub(super) root: json::Root,
    compress: bool,
    pub(super) quantise: Option<Quantise>,
    /// The uncompressed size of the compressed views (the fallback buffer).
    fallback_len: usize,
    /// `EXT_meshopt_compression` objects of the views, added after
    /// serialisation (gltf-json has no field for them).
    view_extensions: Vec<(usize, serde_json::Value)>,
    used: Vec<&'static str>,
    required: Vec<&'static str>,
}

const MESHOPT: &str = "EXT_meshopt_compression";
const QUANTIZATION: &str = "KHR_mesh_quantization";

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

/// glTF's linear colours in normalised u16: sRGB → linear in u16 is
/// lossless for RGBA8 (in u8 it is not), so `write → read` gives the same
/// colours back.
fn color_u16_bytes(colors: &[[u8; 4]]) -> Vec<u8> {
    let q = |c: u8| ((srgb8_to_linear(c) * 65535.0).round() as u16).to_le_bytes();
    le_bytes(colors, |c: [u8; 4]| {
        let [r0, r1] = q(c[0]);
        let [g0, g1] = q(c[1]);
        let [b0, b1] = q(c[2]);
        let [a0, a1] = (c[3] as u16 * 257).to_le_bytes();
        [r0, r1, g0, g1, b0, b1, a0, a1]
    })
}

/// Unit normals through meshoptimizer's octahedral filter at 8 bits (the
/// decoder's output is normalised i8 xyz plus a pad byte).
#[cfg(feature = "meshopt")]
fn octahedral_normals(normals: &[Vec3]) -> Vec<u8> {
    let unit: Vec<[f32; 4]> = normals
        .iter()
        .map(|n| {
            let n = n.try_normalize().unwrap_or(Vec3::Z);
            [n.x, n.y, n.z, 0.0]
        })
        .collect();
    meshopt::encode_filter_oct::<i8>(&unit, 8)
        .iter()
        .flat_map(|c| c.map(|x| x as u8))
        .collect()
}

#[cfg(not(feature = "meshopt"))]
fn octahedral_normals(normals: &[Vec3]) -> Vec<u8> {
    vec![0; normals.len() * 4]
}

impl Builder {
    pub(super) fn new(opts: &GlbOptions, quantise: Option<Aabb>) -> Result<Builder, ParseError> {
        if opts.compress && !cfg!(feature = "meshopt") {
            return Err(ParseError::new(
                "--compress needs lodkit built with the `compress` feature (meshoptimizer, C++): \
                 cargo install lodkit --features compress",
            ));
        }
        Ok(Builder {
            bin: Vec::new(),
            root: json::Root {
                asset: json::Asset {
                    generator: Some(format!("lodkit {}", env!("CARGO_PKG_VERSION"))),
                    ..Default::default()
                },
                ..Default::default()
            },
            compress: opts.compress,
            quantise: if opts.compress {
                quantise.map(Quantise::over)
            } else {
                None
            },
            fallback_len: 0,
            view_extensions: Vec::new(),
            used: Vec::new(),
            required: Vec::new(),
        })
    }

    /// Links `nodes` as one `MSFT_lod` chain ([`link_lods`]) and marks the
    /// extension used when there is more than one; returns the node
    /// extensions for [`Builder::finish`].
    pub(super) fn link_lods(
        &mut self,
        nodes: &[json::Index<json::Node>],
        coverage: &[f64],
        triangles: &[usize],
    ) -> Result<Vec<(usize, serde_json::Value)>, ParseError> {
        let ext = link_lods(&mut self.root, nodes, coverage, triangles)?;
        if !ext.is_empty() {
            self.uses(MSFT_LOD, false);
        }
        Ok(ext)
    }

    pub(super) fn uses(&mut self, ext: &'static str, required: bool) {
        if !self.used.contains(&ext) {
            self.used.push(ext);
        }
        if required && !self.required.contains(&ext) {
            self.required.push(ext);
        }
    }

    fn align_bin(&mut self) {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
    }

    /// Appends `bytes` as a plain buffer view of the BIN chunk (4-byte
    /// aligned, no target, never compressed): an image's bytes.
    pub(super) fn raw_view(&mut self, bytes: &[u8]) -> json::Index<json::buffer::View> {
        self.plain_view(bytes, None)
    }

    /// Appends `bytes` as an uncompressed buffer view of the BIN chunk
    /// (4-byte aligned) with the given target.
    fn plain_view(
        &mut self,
        bytes: &[u8],
        target: Option<json::buffer::Target>,
    ) -> json::Index<json::buffer::View> {
        self.align_bin();
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.align_bin();
        self.root.push(json::buffer::View {
            buffer: json::Index::new(0),
            byte_length: bytes.len().into(),
            byte_offset: Some(offset.into()),
            byte_stride: None,
            name: None,
            target: target.map(Valid),
            extensions: None,
            extras: None,
        })
    }

    /// Appends `bytes` (`count` elements) as a new buffer view — plain, or
    /// compressed with `codec` when compressing — and an accessor over it;
    /// returns the accessor's index.
    #[allow(clippy::too_many_arguments)]
    fn accessor(
        &mut self,
        bytes: &[u8],
        count: usize,
        component: C,
        ty: T,
        normalized: bool,
        codec: Codec,
        min_max: Option<(json::Value, json::Value)>,
    ) -> Result<json::Index<json::Accessor>, ParseError> {
        let target = match codec {
            Codec::Attributes(_) | Codec::Octahedral => ArrayBuffer,
            Codec::Triangles(_) => ElementArrayBuffer,
        };
        let view = if self.compress {
            let encoded = encode_view(bytes, count, codec)?;
            self.align_bin();
            let at = self.bin.len();
            self.bin.extend_from_slice(&encoded);
            self.align_bin();
            let offset = self.fallback_len;
            self.fallback_len += bytes.len().next_multiple_of(4);
            let (stride, mode) = match codec {
                Codec::Attributes(s) => (s, "ATTRIBUTES"),
                Codec::Octahedral => (4, "ATTRIBUTES"),
                Codec::Triangles(s) => (s, "TRIANGLES"),
            };
            let view = self.root.push(json::buffer::View {
                buffer: json::Index::new(1),
                byte_length: bytes.len().into(),
                byte_offset: Some(offset.into()),
                byte_stride: matches!(codec, Codec::Attributes(_) | Codec::Octahedral)
                    .then_some(json::buffer::Stride(stride)),
                name: None,
                target: Some(Valid(target)),
                extensions: None,
                extras: None,
            });
            let mut ext = serde_json::json!({
                "buffer": 0,
                "byteOffset": at,
                "byteLength": encoded.len(),
                "byteStride": stride,
                "count": count,
                "mode": mode,
            });
            if codec == Codec::Octahedral {
                ext["filter"] = "OCTAHEDRAL".into();
            }
            self.view_extensions.push((view.value(), ext));
            view
        } else {
            let view = self.plain_view(bytes, Some(target));
            // Quantised positions are padded to 8 bytes: say the stride.
            if let Codec::Attributes(stride) = codec
                && stride != ty.multiplicity() * component.size()
            {
                self.root.buffer_views[view.value()].byte_stride =
                    Some(json::buffer::Stride(stride));
            }
            view
        };
        let (min, max) = match min_max {
            Some((a, b)) => (Some(a), Some(b)),
            None => (None, None),
        };
        Ok(self.root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: count.into(),
            component_type: Valid(json::accessor::GenericComponentType(component)),
            extensions: None,
            extras: None,
            type_: Valid(ty),
            min,
            max,
            name: None,
            normalized,
            sparse: None,
        }))
    }

    /// The vertex attributes of `positions` (and optional normals, colours,
    /// UVs): float (plain) or quantised (compressing).
    fn attributes(
        &mut self,
        positions: &[Vec3],
        normals: Option<&[Vec3]>,
        colors: Option<&[[u8; 4]]>,
        uvs: Option<&[Vec2]>,
    ) -> Result<
        BTreeMap<json::validation::Checked<json::mesh::Semantic>, json::Index<json::Accessor>>,
        ParseError,
    > {
        use json::mesh::Semantic;
        let n = positions.len();
        let mut attributes = BTreeMap::new();
        let pos = match self.quantise {
            Some(q) => {
                self.uses(QUANTIZATION, true);
                let qs: Vec<[u16; 3]> = positions.iter().map(|&p| q.q(p)).collect();
                let (mut lo, mut hi) = ([u16::MAX; 3], [0u16; 3]);
                for p in &qs {
                    for k in 0..3 {
                        lo[k] = lo[k].min(p[k]);
                        hi[k] = hi[k].max(p[k]);
                    }
                }
                let bytes = le_bytes(&qs, |p: [u16; 3]| {
                    let [a, b] = p[0].to_le_bytes();
                    let [c, d] = p[1].to_le_bytes();
                    let [e, f] = p[2].to_le_bytes();
                    [a, b, c, d, e, f, 0, 0]
                });
                self.accessor(
                    &bytes,
                    n,
                    C::U16,
                    T::Vec3,
                    false,
                    Codec::Attributes(8),
                    Some((
                        json::Value::from(lo.to_vec()),
                        json::Value::from(hi.to_vec()),
                    )),
                )?
            }
            None => {
                let bbox = Aabb::from_points(positions);
                self.accessor(
                    &vec3_bytes(positions),
                    n,
                    C::F32,
                    T::Vec3,
                    false,
                    Codec::Attributes(12),
                    Some((
                        json::Value::from(bbox.min.to_array().to_vec()),
                        json::Value::from(bbox.max.to_array().to_vec()),
                    )),
                )?
            }
        };
        attributes.insert(Valid(Semantic::Positions), pos);
        if let Some(normals) = normals {
            let a = if self.compress {
                // The octahedral filter (gltfpack's choice for normals)
                // leaves two varying bytes instead of three: ~40% smaller.
                let bytes = octahedral_normals(normals);
                self.accessor(&bytes, n, C::I8, T::Vec3, true, Codec::Octahedral, None)?
            } else {
                self.accessor(
                    &vec3_bytes(normals),
                    n,
                    C::F32,
                    T::Vec3,
                    false,
                    Codec::Attributes(12),
                    None,
                )?
            };
            attributes.insert(Valid(Semantic::Normals), a);
        }
        if let Some(colors) = colors {
            let bytes = color_u16_bytes(colors);
            let a = self.accessor(&bytes, n, C::U16, T::Vec4, true, Codec::Attributes(8), None)?;
            attributes.insert(Valid(Semantic::Colors(0)), a);
        }
        if let Some(uvs) = uvs {
            let unit = uvs
                .iter()
                .all(|t| (0.0..=1.0).contains(&t.x) && (0.0..=1.0).contains(&t.y));
            let a = if self.compress && unit {
                // Normalised u16 keeps 1/65535 of the texture: finer than any
                // texture lodkit meets, and half the bytes of f32.
                let q = |x: f32| ((x * 65535.0).round() as u16).to_le_bytes();
                let bytes = le_bytes(uvs, |t: Vec2| {
                    let [a, b] = q(t.x);
                    let [c, d] = q(1.0 - t.y);
                    [a, b, c, d]
                });
                self.accessor(&bytes, n, C::U16, T::Vec2, true, Codec::Attributes(4), None)?
            } else {
                let bytes = le_bytes(uvs, |t: Vec2| {
                    let [u0, u1, u2, u3] = t.x.to_le_bytes();
                    let [v0, v1, v2, v3] = (1.0 - t.y).to_le_bytes();
                    [u0, u1, u2, u3, v0, v1, v2, v3]
                });
                self.accessor(
                    &bytes,
                    n,
                    C::F32,
                    T::Vec2,
                    false,
                    Codec::Attributes(8),
                    None,
                )?
            };
            attributes.insert(Valid(Semantic::TexCoords(0)), a);
        }
        Ok(attributes)
    }

    /// One triangle primitive for `m` (checked); compressing reorders its
    /// triangles and vertices for the codecs first (the same surface).
    pub(super) fn primitive(
        &mut self,
        name: &str,
        m: &TriMesh,
    ) -> Result<json::mesh::Primitive, ParseError> {
        m.validate()
            .map_err(|e| parse_err!("GLB level '{name}': {e}"))?;
        if m.faces.is_empty() {
            return Err(parse_err!("GLB level '{name}' has no faces"));
        }
        let reordered;
        let m = if self.compress {
            reordered = reorder_for_codec(m);
            &reordered
        } else {
            m
        };
        let n = m.positions.len();
        let attributes = self.attributes(
            &m.positions,
            m.normals.as_deref(),
            m.colors.as_deref(),
            m.uvs.as_deref(),
        )?;
        let flat: Vec<u32> = m.faces.iter().flatten().copied().collect();
        // u16 when every index fits below 65535 (the primitive-restart
        // value is reserved), u32 otherwise.
        let indices = if n < u16::MAX as usize {
            let bytes = le_bytes(&flat, |i: u32| (i as u16).to_le_bytes());
            self.accessor(
                &bytes,
                flat.len(),
                C::U16,
                T::Scalar,
                false,
                Codec::Triangles(2),
                None,
            )?
        } else {
            let bytes = le_bytes(&flat, |i: u32| i.to_le_bytes());
            self.accessor(
                &bytes,
                flat.len(),
                C::U32,
                T::Scalar,
                false,
                Codec::Triangles(4),
                None,
            )?
        };
        Ok(json::mesh::Primitive {
            attributes,
            extensions: None,
            extras: None,
            indices: Some(indices),
            material: None,
            mode: Valid(json::mesh::Mode::Triangles),
            targets: None,
        })
    }

    /// One `POINTS` primitive for `cloud`.
    pub(super) fn points_primitive(
        &mut self,
        cloud: &PointCloud,
    ) -> Result<json::mesh::Primitive, ParseError> {
        cloud
            .validate()
            .map_err(|e| parse_err!("GLB points: {e}"))?;
        if cloud.positions.is_empty() {
            return Err(ParseError::new("GLB: the point cloud has no points"));
        }
        let attributes = self.attributes(
            &cloud.positions,
            cloud.normals.as_deref(),
            cloud.colors.as_deref(),
            None,
        )?;
        Ok(json::mesh::Primitive {
            attributes,
            extensions: None,
            extras: None,
            indices: None,
            material: None,
            mode: Valid(json::mesh::Mode::Points),
            targets: None,
        })
    }

    /// A mesh of one primitive and the node that places it: named `name`,
    /// with `extras`, and the dequantisation transform when positions are
    /// quantised.
    pub(super) fn node(
        &mut self,
        name: &str,
        primitive: json::mesh::Primitive,
        extras: serde_json::Map<String, serde_json::Value>,
    ) -> Result<json::Index<json::Node>, ParseError> {
        let mesh = self.root.push(json::Mesh {
            extensions: None,
            extras: None,
            name: Some(name.to_string()),
            primitives: vec![primitive],
            weights: None,
        });
        let extras = serde_json::value::to_raw_value(&serde_json::Value::Object(extras))
            .map_err(|e| parse_err!("GLB: {e}"))?;
        let (translation, scale) = match self.quantise {
            Some(q) => (Some(q.origin.to_array()), Some([q.step; 3])),
            None => (None, None),
        };
        Ok(self.root.push(json::Node {
            camera: None,
            children: None,
            extensions: None,
            extras: Some(extras),
            matrix: None,
            mesh: Some(mesh),
            name: Some(name.to_string()),
            rotation: None,
            scale,
            translation,
            skin: None,
            weights: None,
        }))
    }

    /// The buffers, the scene of `roots`, the extension lists and the
    /// `node_extensions` patched in; then the GLB container.
    pub(super) fn finish(
        mut self,
        roots: Vec<json::Index<json::Node>>,
        node_extensions: Vec<(usize, serde_json::Value)>,
    ) -> Result<Vec<u8>, ParseError> {
        self.align_bin();
        let bin_len = self.bin.len();
        if bin_len > u32::MAX as usize - 1024 || self.fallback_len > u32::MAX as usize {
            return Err(parse_err!(
                "GLB: {} bytes of geometry, over the 4 GiB GLB limit",
                bin_len.max(self.fallback_len)
            ));
        }
        self.root.push(json::Buffer {
            byte_length: bin_len.into(),
            name: None,
            uri: None,
            extensions: None,
            extras: None,
        });
        if self.compress {
            self.uses(MESHOPT, true);
            self.root.push(json::Buffer {
                byte_length: self.fallback_len.into(),
                name: None,
                uri: None,
                extensions: None,
                extras: None,
            });
        }
        let scene = self.root.push(json::Scene {
            extensions: None,
            extras: None,
            name: None,
            nodes: roots,
        });
        self.root.scene = Some(scene);
        let mut doc = serde_json::to_value(&self.root).map_err(|e| parse_err!("GLB: {e}"))?;
        let patch = |doc: &mut serde_json::Value, list: &str, i: usize, name: &str, v| {
            doc[list][i]
                .as_object_mut()
                .expect("gltf-json writes objects")
                .entry("extensions")
                .or_insert_with(|| serde_json::json!({}))[name] = v;
        };
        for (i, v) in std::mem::take(&mut self.view_extensions) {
            patch(&mut doc, "bufferViews", i, MESHOPT, v);
        }
        if self.compress {
            patch(
                &mut doc,
                "buffers",
                1,
                MESHOPT,
                serde_json::json!({"fallback": true}),
            );
        }
        for (i, v) in node_extensions {
            patch(&mut doc, "nodes", i, MSFT_LOD, v);
        }
        if !self.used.is_empty() {
            doc["extensionsUsed"] = serde_json::json!(self.used);
        }
        if !self.required.is_empty() {
            doc["extensionsRequired"] = serde_json::json!(self.required);
        }
        let js = serde_json::to_vec(&doc).map_err(|e| parse_err!("GLB: {e}"))?;
        join_glb(js, &self.bin)
    }
}

/// The union of the levels' boxes.
pub(super) fn union_box<'a>(meshes: impl Iterator<Item = &'a [Vec3]>) -> Aabb {
    let mut b: Option<Aabb> = None;
    for p in meshes {
        let x = Aabb::from_points(p);
        b = Some(match b {
            None => x,
            Some(y) => Aabb {
                min: y.min.min(x.min),
                max: y.max.max(x.max),
            },
        });
    }
    b.unwrap_or(Aabb {
        min: Vec3::ZERO,
        max: Vec3::ZERO,
    })
}

pub(super) fn counts(m: &TriMesh) -> serde_json::Map<String, serde_json::Value> {
    let mut e = serde_json::Map::new();
    e.insert("triangles".into(), m.faces.len().into());
    e.insert("vertices".into(), m.positions.len().into());
    e
}

/// Writes the levels as one GLB, one node per level, all siblings in the
/// default scene (see the module docs for the layout).
///
/// Errors: no levels, a level with no faces, a level that breaks the
/// [`TriMesh`] invariant (index out of range, attribute length, non-finite
/// value), or more data than a GLB can hold (4 GiB).
pub fn write_glb(levels: &[(&str, &TriMesh)]) -> Result<Vec<u8>, ParseError> {
    write_glb_with(levels, &GlbOptions::default())
}

/// [`write_glb`] with options (`compress`). Nodes and meshes are named
/// `"{name} ({triangles} triangles)"`, node extras hold `triangles` and
/// `vertices`. Errors as [`write_glb`], and `compress` without the
/// `meshopt` feature.
pub fn write_glb_with(
    levels: &[(&str, &TriMesh)],
    opts: &GlbOptions,
) -> Result<Vec<u8>, ParseError> {
    if levels.is_empty() {
        return Err(ParseError::new("GLB: no levels to write"));
    }
    let bbox = union_box(levels.iter().map(|(_, m)| m.positions.as_slice()));
    let mut b = Builder::new(opts, Some(bbox))?;
    let mut nodes = Vec::new();
    for (name, m) in levels {
        let prim = b.primitive(name, m)?;
        let label = format!("{name} ({} triangles)", m.faces.len());
        nodes.push(b.node(&label, prim, counts(m))?);
    }
    b.finish(nodes, Vec::new())
}

/// Writes an LOD chain as one GLB that engines read as one object: level 0
/// is the scene's only root node and carries `MSFT_lod` (`ids`: the other
/// levels' nodes, finest first) and `extras.MSFT_screencoverage` (each
/// level's [`LodLevel::coverage`], made strictly decreasing by the levels'
/// triangle counts: [`screen_coverages`](super::screen_coverages)); the other levels'
/// nodes are outside the scene, so a loader without `MSFT_lod` shows level
/// 0 alone. `MSFT_lod` is used, not required. Each node and mesh is named
/// [`LodLevel::name`]; node extras are [`LodLevel::extras`] plus
/// `triangles` and `vertices`.
///
/// Errors: as [`write_glb_with`]; a non-finite or out-of-range coverage.
pub fn write_lod_glb(levels: &[LodLevel<'_>], opts: &GlbOptions) -> Result<Vec<u8>, ParseError> {
    if levels.is_empty() {
        return Err(ParseError::new("GLB: no levels to write"));
    }
    let bbox = union_box(levels.iter().map(|l| l.mesh.positions.as_slice()));
    let mut b = Builder::new(opts, Some(bbox))?;
    let mut nodes = Vec::new();
    for l in levels {
        check_coverage(&l.name, l.coverage)?;
        let prim = b.primitive(&l.name, l.mesh)?;
        let mut extras = l.extras.clone();
        extras.extend(counts(l.mesh));
        nodes.push(b.node(&l.name, prim, extras)?);
    }
    let coverage: Vec<f64> = levels.iter().map(|l| l.coverage).collect();
    let triangles: Vec<usize> = levels.iter().map(|l| l.mesh.faces.len()).collect();
    let node_extensions = b.link_lods(&nodes, &coverage, &triangles)?;
    b.finish(vec![nodes[0]], node_extensions)
}

/// Writes a point cloud as one GLB: one node `name` with one `POINTS`
/// primitive (POSITION, and NORMAL and COLOR_0 when the cloud has them,
/// stored as for meshes; a zero normal is written as +Z, since glTF asks
/// for unit normals). Node extras hold `points`.
///
/// Errors: an empty or invalid cloud, over 4 GiB, `compress` without the
/// `meshopt` feature.
pub fn write_points_glb(
    name: &str,
    cloud: &PointCloud,
    opts: &GlbOptions,
) -> Result<Vec<u8>, ParseError> {
    let bbox = union_box(std::iter::once(cloud.positions.as_slice()));
    let mut b = Builder::new(opts, Some(bbox))?;
    let prim = b.points_primitive(cloud)?;
    let mut extras = serde_json::Map::new();
    extras.insert("points".into(), cloud.positions.len().into());
    let node = b.node(name, prim, extras)?;
    b.finish(vec![node], Vec::new())
}

/// A model as a GLB: a mesh as one node named `mesh` ([`write_glb_with`]),
/// a point cloud or a range image's valid samples as one `POINTS` node
/// named `points` ([`write_points_glb`]). Errors as those.
pub fn write_model_glb(
    model: &crate::mesh::Model,
    opts: &GlbOptions,
) -> Result<Vec<u8>, ParseError> {
    use crate::mesh::Model;
    match model {
        Model::Mesh(m) => write_glb_with(&[("mesh", m)], opts),
        Model::Points(p) => write_points_glb("points", p, opts),
        Model::Range(r) => write_points_glb("points", &r.to_point_cloud(), opts),
    }
}
