//! Compressed and quantised glTF → a plain GLB, before reading:
//! `KHR_mesh_quantization` (integer POSITION / NORMAL / TEXCOORD_n become
//! float accessors), `EXT_meshopt_compression` and
//! `KHR_meshopt_compression` (each compressed view decoded with
//! meshoptimizer's decoders, `meshopt` feature), and a one-line refusal of
//! `KHR_draco_mesh_compression` (no maintained Rust Draco decoder exists);
//! and `KHR_texture_transform` (gltfpack's UV dequantisation among others)
//! baked into the UVs it applies to (see [`texture_transforms`]).
//!
//! The output has one buffer (the GLB BIN chunk) holding every input
//! buffer once (plain views keep pointing into it, so views that alias one
//! range are not copied apart), the decoded compressed views, then the
//! float copies of the quantised accessors (one copy per distinct
//! view, offset and layout); the extensions are removed from
//! `extensionsUsed` / `extensionsRequired`. Anything else in the document
//! is kept as it is and read as usual.
//!
//! **Bounds**: decoded views and float copies together may not exceed
//! [`MAX_EXPANSION`] times the input's bytes (plus 1 MiB), checked from the
//! declared sizes before decoding; every view and accessor extent is
//! checked in 64-bit arithmetic; an offset, length, stride or count that
//! is not a whole number ≥ 0 (`byteOffset: -4`), a decoder error or a view
//! whose declared size disagrees with `count × byteStride` is a one-line
//! error, as is a JSON that names one of these extensions but does not
//! parse (a number out of range, `1e999`).

use std::borrow::Cow;
use std::path::Path;

use serde_json::{Value, json};

use super::buffers::decode_base64;
use super::glb::{GLB_MAGIC, join_glb, split_glb};
use crate::error::ParseError;
use crate::parse_err;

/// Decoded views and dequantised copies may be at most this many times the
/// file's size (plus 1 MiB): meshoptimizer's codecs stay well inside it on
/// real data (a few times for vertices, about 10 for indices), and a
/// hostile file cannot ask for more than this much memory.
pub const MAX_EXPANSION: u64 = 64;

const DRACO: &str = "KHR_draco_mesh_compression";
const QUANTIZATION: &str = "KHR_mesh_quantization";
const MESHOPT: [&str; 2] = ["EXT_meshopt_compression", "KHR_meshopt_compression"];
const TRANSFORM: &str = "KHR_texture_transform";
/// A material's texture slots, as JSON paths from the material.
const TEXTURE_SLOTS: [&[&str]; 5] = [
    &["pbrMetallicRoughness", "baseColorTexture"],
    &["pbrMetallicRoughness", "metallicRoughnessTexture"],
    &["normalTexture"],
    &["occlusionTexture"],
    &["emissiveTexture"],
];

/// The file as a plain GLB when it uses one of the extensions above, with
/// the bytes of input it was made from (the file and its external
/// buffers); `None` when it uses none of them.
pub(super) fn expand(
    bytes: &[u8],
    base_dir: Option<&Path>,
) -> Result<Option<(Vec<u8>, u64)>, ParseError> {
    let unbom = crate::io::input::strip_bom(bytes);
    let (json_bytes, bin) = if bytes.starts_with(GLB_MAGIC) {
        split_glb(bytes)?
    } else {
        (unbom, None)
    };
    let mentions = |s: &str| json_bytes.windows(s.len()).any(|w| w == s.as_bytes());
    if !(mentions(DRACO)
        || mentions(QUANTIZATION)
        || mentions("_meshopt_compression")
        || mentions(TRANSFORM))
    {
        return Ok(None);
    }
    // A JSON that names an extension must parse here: the `gltf` crate
    // skips unknown extensions without reading their numbers, so a value
    // out of range (`1e999`) there would be silently dropped.
    let mut doc = match serde_json::from_slice::<Value>(json_bytes) {
        Ok(d) => d,
        Err(e) if serde_json::from_slice::<serde::de::IgnoredAny>(json_bytes).is_ok() => {
            return Err(parse_err!("glTF JSON: {e}"));
        }
        Err(_) => return Ok(None),
    };
    let listed: Vec<String> = ["extensionsUsed", "extensionsRequired"]
        .iter()
        .filter_map(|k| doc.get(*k).and_then(Value::as_array))
        .flatten()
        .filter_map(|v| v.as_str().map(str::to_string))
        .collect();
    let has = |e: &str| listed.iter().any(|l| l == e);
    if has(DRACO) {
        return Err(ParseError::new(
            "KHR_draco_mesh_compression (Draco geometry) is not supported: there is no maintained \
             Rust Draco decoder; re-export the file without Draco (or with EXT_meshopt_compression)",
        ));
    }
    let meshopt: Vec<&str> = MESHOPT.iter().copied().filter(|e| has(e)).collect();
    if !meshopt.is_empty() && !cfg!(feature = "meshopt") {
        return Err(parse_err!(
            "{}: meshopt-compressed geometry needs lodkit built with the `compress` feature \
             (meshoptimizer, C++): cargo install lodkit --features compress",
            meshopt[0]
        ));
    }
    if meshopt.is_empty() && !has(QUANTIZATION) && !has(TRANSFORM) {
        return Ok(None);
    }
    // Every buffer's bytes (fallback buffers have none).
    let buffers = doc["buffers"].as_array().cloned().unwrap_or_default();
    let mut data: Vec<Option<Cow<[u8]>>> = Vec::with_capacity(buffers.len());
    let mut source = bytes.len() as u64;
    for (i, b) in buffers.iter().enumerate() {
        let fallback = MESHOPT
            .iter()
            .any(|e| b["extensions"][*e]["fallback"].as_bool() == Some(true));
        data.push(if fallback {
            None
        } else {
            let d = buffer_bytes(i, b, bin, base_dir)?;
            if let Cow::Owned(d) = &d {
                source = source.saturating_add(d.len() as u64);
            }
            Some(d)
        });
    }
    let budget = source.saturating_mul(MAX_EXPANSION).saturating_add(1 << 20);

    // Every buffer once into one new BIN…
    let mut out: Vec<u8> = Vec::new();
    let mut base: Vec<Option<u64>> = Vec::with_capacity(data.len());
    for d in &data {
        base.push(d.as_ref().map(|d| {
            while !out.len().is_multiple_of(4) {
                out.push(0);
            }
            let at = out.len() as u64;
            out.extend_from_slice(d);
            at
        }));
    }
    // …then every compressed view, decoded; plain views point into their
    // buffer's copy.
    let mut used = 0u64;
    let views = doc["bufferViews"].as_array().cloned().unwrap_or_default();
    let mut new_views = Vec::with_capacity(views.len());
    for (i, v) in views.iter().enumerate() {
        let what = format!("buffer view {i}");
        let ext = MESHOPT.iter().find_map(|e| v["extensions"].get(*e));
        let (offset, length) = match ext {
            Some(x) => {
                let length = uint(&what, v, "byteLength", None)?;
                used = used.saturating_add(length);
                if used > budget {
                    return Err(parse_err!(
                        "buffer view {i}: decoded views exceed {budget} bytes ({MAX_EXPANSION}x the file)"
                    ));
                }
                let decoded = decode_view(i, x, length, &data)?;
                while !out.len().is_multiple_of(4) {
                    out.push(0);
                }
                let at = out.len() as u64;
                out.extend_from_slice(&decoded);
                (at, decoded.len() as u64)
            }
            None => {
                let len = slice(i, v, &data)?.len() as u64;
                let b = uint(&what, v, "buffer", None)? as usize;
                let start = uint(&what, v, "byteOffset", Some(0))?;
                let at = base.get(b).copied().flatten().unwrap_or(0);
                (at + start, len)
            }
        };
        let mut nv = v.clone();
        let o = nv
            .as_object_mut()
            .ok_or_else(|| parse_err!("buffer view {i} is not an object"))?;
        o.insert("buffer".into(), json!(0));
        o.insert("byteOffset".into(), json!(offset));
        o.insert("byteLength".into(), json!(length));
        strip(o, &MESHOPT);
        new_views.push(nv);
    }

    // Quantised attributes → float copies.
    let accessors = doc["accessors"].as_array().cloned().unwrap_or_default();
    let mut new_accessors = accessors.clone();
    let mut dequantised = vec![false; accessors.len()];
    // One float copy per distinct source (view, offset, layout): accessors
    // that alias one another share it, with its bounds.
    let mut copies: std::collections::BTreeMap<String, (usize, Value, Value)> =
        std::collections::BTreeMap::new();
    let meshes = doc["meshes"].as_array().cloned().unwrap_or_default();
    for mesh in &meshes {
        for prim in mesh["primitives"].as_array().into_iter().flatten() {
            let Some(attrs) = prim["attributes"].as_object() else {
                continue;
            };
            for (name, a) in attrs {
                let float = name == "POSITION" || name == "NORMAL" || name.starts_with("TEXCOORD_");
                let Some(ai) = a.as_u64().map(|a| a as usize) else {
                    continue;
                };
                if !float || ai >= accessors.len() || dequantised[ai] {
                    continue;
                }
                let acc = &accessors[ai];
                if acc["componentType"].as_u64() == Some(5126) || acc.get("sparse").is_some() {
                    continue;
                }
                dequantised[ai] = true;
                let key = [
                    "bufferView",
                    "byteOffset",
                    "componentType",
                    "normalized",
                    "count",
                    "type",
                ]
                .map(|k| acc.get(k).map_or("-".to_string(), Value::to_string))
                .join(" ");
                let (view, lo, hi) = match copies.get(&key) {
                    Some((view, lo, hi)) => (*view, lo.clone(), hi.clone()),
                    None => {
                        let floats = dequantise(ai, acc, &new_views, &out)?;
                        used = used.saturating_add(floats.len() as u64 * 4);
                        if used > budget {
                            return Err(parse_err!(
                                "accessor {ai}: dequantised data exceeds {budget} bytes ({MAX_EXPANSION}x the file)"
                            ));
                        }
                        let comps = components(acc)?;
                        let mut lo = vec![f32::INFINITY; comps];
                        let mut hi = vec![f32::NEG_INFINITY; comps];
                        for e in floats.chunks_exact(comps) {
                            for k in 0..comps {
                                lo[k] = lo[k].min(e[k]);
                                hi[k] = hi[k].max(e[k]);
                            }
                        }
                        while !out.len().is_multiple_of(4) {
                            out.push(0);
                        }
                        let offset = out.len();
                        for f in &floats {
                            out.extend_from_slice(&f.to_le_bytes());
                        }
                        new_views.push(json!({
                            "buffer": 0,
                            "byteOffset": offset,
                            "byteLength": floats.len() * 4,
                            "target": 34962,
                        }));
                        let (lo, hi) = (json!(lo), json!(hi));
                        copies.insert(key, (new_views.len() - 1, lo.clone(), hi.clone()));
                        (new_views.len() - 1, lo, hi)
                    }
                };
                let na = new_accessors[ai]
                    .as_object_mut()
                    .ok_or_else(|| parse_err!("accessor {ai} is not an object"))?;
                na.insert("bufferView".into(), json!(view));
                na.insert("byteOffset".into(), json!(0));
                na.insert("componentType".into(), json!(5126));
                na.insert("normalized".into(), json!(false));
                if name == "POSITION" {
                    na.insert("min".into(), lo);
                    na.insert("max".into(), hi);
                } else {
                    na.remove("min");
                    na.remove("max");
                }
            }
        }
    }
    if has(TRANSFORM) {
        let mut state = Expanded {
            views: new_views,
            accessors: new_accessors,
            bin: out,
            used,
            budget,
        };
        texture_transforms(&mut doc, &mut state)?;
        (new_views, new_accessors, out) = (state.views, state.accessors, state.bin);
    }
    while !out.len().is_multiple_of(4) {
        out.push(0);
    }
    doc["bufferViews"] = Value::Array(new_views);
    doc["accessors"] = Value::Array(new_accessors);
    doc["buffers"] = json!([{ "byteLength": out.len() }]);
    for key in ["extensionsUsed", "extensionsRequired"] {
        if let Some(list) = doc.get_mut(key).and_then(Value::as_array_mut) {
            list.retain(|e| {
                e.as_str()
                    .is_none_or(|s| s != QUANTIZATION && s != TRANSFORM && !MESHOPT.contains(&s))
            });
        }
    }
    let js = serde_json::to_vec(&doc).map_err(|e| parse_err!("glTF JSON: {e}"))?;
    join_glb(js, &out).map(|glb| Some((glb, source)))
}

/// The plain file being made: views, accessors and the one BIN, with the
/// expansion budget.
struct Expanded {
    views: Vec<Value>,
    accessors: Vec<Value>,
    bin: Vec<u8>,
    used: u64,
    budget: u64,
}

/// One UV transform of `KHR_texture_transform`: offset, rotation
/// (radians, counter-clockwise), scale.
#[derive(Clone, Copy, PartialEq)]
struct UvTransform {
    offset: [f32; 2],
    rotation: f32,
    scale: [f32; 2],
}

impl UvTransform {
    const IDENTITY: UvTransform = UvTransform {
        offset: [0.0, 0.0],
        rotation: 0.0,
        scale: [1.0, 1.0],
    };

    fn bits(&self) -> [u32; 5] {
        [
            self.offset[0],
            self.offset[1],
            self.rotation,
            self.scale[0],
            self.scale[1],
        ]
        .map(f32::to_bits)
    }

    /// The spec's `T · R · S` applied to `(u, v)` in glTF's UV frame
    /// (origin top-left): `u' = ox + cos·su·u + sin·sv·v`,
    /// `v' = oy − sin·su·u + cos·sv·v`.
    fn apply(&self, u: f32, v: f32) -> (f32, f32) {
        let (s, c) = self.rotation.sin_cos();
        let (x, y) = (u * self.scale[0], v * self.scale[1]);
        (
            self.offset[0] + c * x + s * y,
            self.offset[1] - s * x + c * y,
        )
    }
}

/// Material `i`'s UV transform per UV set, from its texture slots' own
/// `KHR_texture_transform` (identity where a slot has none); the
/// extension's `texCoord` override moves the slot to that set. Slots on
/// one set must agree (the transform is baked into that set's UVs), and
/// values must be finite: otherwise a one-line error.
fn material_transforms(i: usize, m: &Value) -> Result<Vec<(u64, UvTransform)>, ParseError> {
    let mut sets: Vec<(u64, UvTransform)> = Vec::new();
    for path in TEXTURE_SLOTS {
        let info = path.iter().fold(m, |v, k| &v[*k]);
        if !info.is_object() {
            continue;
        }
        let x = &info["extensions"][TRANSFORM];
        let set = x["texCoord"]
            .as_u64()
            .or_else(|| info["texCoord"].as_u64())
            .unwrap_or(0);
        // A value that is not a number, or that is beyond f32 (`1e39`), is
        // an error rather than the default.
        let num = |v: &Value, d: f32| match v {
            Value::Null => d,
            v => v.as_f64().map_or(f32::NAN, |f| f as f32),
        };
        let t = UvTransform {
            offset: [num(&x["offset"][0], 0.0), num(&x["offset"][1], 0.0)],
            rotation: num(&x["rotation"], 0.0),
            scale: [num(&x["scale"][0], 1.0), num(&x["scale"][1], 1.0)],
        };
        if !t.bits().iter().all(|b| f32::from_bits(*b).is_finite()) {
            return Err(parse_err!(
                "material {i}: {TRANSFORM} has a value that is not a finite number"
            ));
        }
        match sets.iter().find(|(s, _)| *s == set) {
            Some((_, other)) if *other != t => {
                return Err(parse_err!(
                    "material {i}: its textures transform UV set {set} differently ({TRANSFORM}); \
                     lodkit bakes one transform into each UV set"
                ));
            }
            Some(_) => {}
            None => sets.push((set, t)),
        }
    }
    sets.retain(|(_, t)| *t != UvTransform::IDENTITY);
    Ok(sets)
}

/// `KHR_texture_transform` baked into the UVs: every primitive whose
/// material transforms a UV set gets a float copy of that set's accessor
/// with the transform applied (one copy per accessor and transform, shared
/// by the primitives that agree), and the extension is removed from the
/// materials, so readers that ignore it (lodkit's own) see the UVs it
/// meant. A `texCoord` override becomes the slot's `texCoord`.
fn texture_transforms(doc: &mut Value, x: &mut Expanded) -> Result<(), ParseError> {
    let materials = doc["materials"].as_array().cloned().unwrap_or_default();
    let transforms = materials
        .iter()
        .enumerate()
        .map(|(i, m)| material_transforms(i, m))
        .collect::<Result<Vec<_>, _>>()?;
    let mut copies: std::collections::BTreeMap<(usize, [u32; 5]), usize> =
        std::collections::BTreeMap::new();
    // `get_mut` throughout: indexing a JSON value mutably inserts missing
    // keys and panics on non-objects, and this is a hostile file's JSON.
    let mut meshes = doc.get_mut("meshes").map(Value::take);
    for prim in meshes
        .as_mut()
        .and_then(Value::as_array_mut)
        .into_iter()
        .flatten()
        .filter_map(|m| m.get_mut("primitives").and_then(Value::as_array_mut))
        .flatten()
    {
        let Some(sets) = prim["material"]
            .as_u64()
            .and_then(|mi| transforms.get(mi as usize))
        else {
            continue;
        };
        for (set, t) in sets {
            let name = format!("TEXCOORD_{set}");
            let Some(ai) = prim["attributes"][&name].as_u64().map(|a| a as usize) else {
                continue;
            };
            let key = (ai, t.bits());
            let copy = match copies.get(&key) {
                Some(&c) => c,
                None => {
                    let acc = x
                        .accessors
                        .get(ai)
                        .cloned()
                        .ok_or_else(|| parse_err!("accessor {ai} does not exist"))?;
                    if acc.get("sparse").is_some() || components(&acc)? != 2 {
                        return Err(parse_err!(
                            "accessor {ai}: {TRANSFORM} on UVs that are sparse or not VEC2"
                        ));
                    }
                    let mut uv = dequantise(ai, &acc, &x.views, &x.bin)?;
                    for p in uv.chunks_exact_mut(2) {
                        (p[0], p[1]) = t.apply(p[0], p[1]);
                    }
                    x.used = x.used.saturating_add(uv.len() as u64 * 4);
                    if x.used > x.budget {
                        return Err(parse_err!(
                            "accessor {ai}: transformed UVs exceed {} bytes ({MAX_EXPANSION}x the file)",
                            x.budget
                        ));
                    }
                    while !x.bin.len().is_multiple_of(4) {
                        x.bin.push(0);
                    }
                    let offset = x.bin.len();
                    for f in &uv {
                        x.bin.extend_from_slice(&f.to_le_bytes());
                    }
                    x.views.push(json!({
                        "buffer": 0,
                        "byteOffset": offset,
                        "byteLength": uv.len() * 4,
                        "target": 34962,
                    }));
                    x.accessors.push(json!({
                        "bufferView": x.views.len() - 1,
                        "componentType": 5126,
                        "count": uv.len() / 2,
                        "type": "VEC2",
                    }));
                    copies.insert(key, x.accessors.len() - 1);
                    x.accessors.len() - 1
                }
            };
            if let Some(a) = prim.get_mut("attributes").and_then(Value::as_object_mut) {
                a.insert(name, json!(copy));
            }
        }
    }
    if let Some(m) = meshes {
        doc["meshes"] = m;
    }
    let materials = doc.get_mut("materials").and_then(Value::as_array_mut);
    for m in materials.into_iter().flatten() {
        for path in TEXTURE_SLOTS {
            let info = path.iter().try_fold(&mut *m, |v, k| v.get_mut(*k));
            let Some(o) = info.and_then(Value::as_object_mut) else {
                continue;
            };
            if let Some(set) = o
                .get("extensions")
                .and_then(|e| e[TRANSFORM]["texCoord"].as_u64())
            {
                o.insert("texCoord".into(), json!(set));
            }
            strip(o, &[TRANSFORM]);
        }
    }
    Ok(())
}

fn strip(o: &mut serde_json::Map<String, Value>, names: &[&str]) {
    if let Some(e) = o.get_mut("extensions").and_then(Value::as_object_mut) {
        for n in names {
            e.remove(*n);
        }
        if e.is_empty() {
            o.remove("extensions");
        }
    }
}

/// Buffer `i`'s bytes: the BIN chunk, a base64 data URI, or a file inside
/// `base_dir` (the same rules as plain files, `buffers.rs`).
fn buffer_bytes<'a>(
    i: usize,
    b: &Value,
    bin: Option<&'a [u8]>,
    base_dir: Option<&Path>,
) -> Result<Cow<'a, [u8]>, ParseError> {
    let Some(uri) = b["uri"].as_str() else {
        if i != 0 {
            return Err(parse_err!(
                "buffer {i} has no uri: only buffer 0 may be the GLB BIN chunk"
            ));
        }
        return bin
            .map(Cow::Borrowed)
            .ok_or_else(|| parse_err!("buffer {i} has no uri and there is no GLB BIN chunk"));
    };
    if let Some(rest) = uri.strip_prefix("data:") {
        let (_, data) = rest
            .split_once(";base64,")
            .ok_or_else(|| parse_err!("buffer {i}: data URI is not base64"))?;
        return decode_base64(data)
            .map(Cow::Owned)
            .map_err(|e| parse_err!("buffer {i}: data URI is not valid base64: {e}"));
    }
    let dir = base_dir.ok_or_else(|| {
        parse_err!("buffer {i}: external file but no directory to resolve it against")
    })?;
    let rel = super::buffers::percent_decode(uri)?;
    let path = crate::io::input::resolve_inside(dir, &rel)
        .map_err(|why| parse_err!("buffer {i}: URI {why}"))?;
    crate::io::input::read_file(&path)
        .map(Cow::Owned)
        .map_err(|e| parse_err!("buffer {i}: {e}"))
}

/// `obj[key]` as a whole number ≥ 0; `default` when absent (an error
/// naming `what` and the key when there is no default), an error when it
/// is anything else (`-4`, `1.5`, a string): never read as 0.
fn uint(what: &str, obj: &Value, key: &str, default: Option<u64>) -> Result<u64, ParseError> {
    match obj.get(key) {
        None => default.ok_or_else(|| parse_err!("{what} has no {key}")),
        Some(v) => v
            .as_u64()
            .ok_or_else(|| parse_err!("{what}: {key} {} is not a whole number >= 0", clip_json(v))),
    }
}

fn clip_json(v: &Value) -> String {
    crate::error::clip(&v.to_string(), 32).to_string()
}

/// `byteOffset .. + byteLength` of buffer `buffer` in `data`, checked.
fn range<'a>(
    what: &str,
    obj: &Value,
    data: &'a [Option<Cow<'_, [u8]>>],
) -> Result<&'a [u8], ParseError> {
    let b = uint(what, obj, "buffer", None)?;
    let b = usize::try_from(b).unwrap_or(usize::MAX);
    let start = uint(what, obj, "byteOffset", Some(0))?;
    let len = uint(what, obj, "byteLength", None)?;
    let src = data
        .get(b)
        .and_then(|d| d.as_deref())
        .ok_or_else(|| parse_err!("{what}: buffer {b} is missing or has no data"))?;
    match start.checked_add(len) {
        Some(end) if end <= src.len() as u64 => Ok(&src[start as usize..end as usize]),
        _ => Err(parse_err!(
            "{what} (bytes {start}..+{len}) is outside buffer {b}, which has {} bytes",
            src.len()
        )),
    }
}

fn slice<'a>(
    i: usize,
    v: &Value,
    data: &'a [Option<Cow<'_, [u8]>>],
) -> Result<&'a [u8], ParseError> {
    range(&format!("buffer view {i}"), v, data)
}

/// One compressed view through meshoptimizer's decoders.
#[cfg(feature = "meshopt")]
fn decode_view(
    i: usize,
    x: &Value,
    length: u64,
    data: &[Option<Cow<'_, [u8]>>],
) -> Result<Vec<u8>, ParseError> {
    let src = range(&format!("buffer view {i}'s compressed data"), x, data)?;
    let what = format!("buffer view {i}'s meshopt extension");
    let count = uint(&what, x, "count", None)?;
    let stride = uint(&what, x, "byteStride", None)?;
    if count.checked_mul(stride) != Some(length) || count == 0 {
        return Err(parse_err!(
            "buffer view {i}: meshopt count {count} x byteStride {stride} is not its byteLength {length}"
        ));
    }
    let count = count as usize;
    let bad = |e: meshopt::Error| parse_err!("buffer view {i}: meshopt decoder: {e:?}");
    /// One element of `N` bytes (the decoder takes the size from the type).
    #[derive(Clone, Copy)]
    #[repr(transparent)]
    struct Elem<const N: usize>([u8; N]);
    impl<const N: usize> Default for Elem<N> {
        fn default() -> Self {
            Elem([0; N])
        }
    }
    fn vertices<const N: usize>(src: &[u8], count: usize) -> Result<Vec<u8>, meshopt::Error> {
        Ok(meshopt::decode_vertex_buffer::<Elem<N>>(src, count)?
            .iter()
            .flat_map(|e| e.0)
            .collect())
    }
    let mut out = match (x["mode"].as_str(), stride) {
        (Some("ATTRIBUTES"), s) if s.is_multiple_of(4) && s <= 256 => {
            // The decoder takes the element size as its type: dispatch on
            // the sizes glTF attributes use.
            match s {
                4 => vertices::<4>(src, count),
                8 => vertices::<8>(src, count),
                12 => vertices::<12>(src, count),
                16 => vertices::<16>(src, count),
                20 => vertices::<20>(src, count),
                24 => vertices::<24>(src, count),
                28 => vertices::<28>(src, count),
                32 => vertices::<32>(src, count),
                36 => vertices::<36>(src, count),
                40 => vertices::<40>(src, count),
                48 => vertices::<48>(src, count),
                64 => vertices::<64>(src, count),
                _ => {
                    return Err(parse_err!(
                        "buffer view {i}: meshopt attribute stride {s} is not supported"
                    ));
                }
            }
            .map_err(bad)?
        }
        (Some("TRIANGLES"), 2) => meshopt::decode_index_buffer::<u16>(src, count)
            .map_err(bad)?
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect(),
        (Some("TRIANGLES"), 4) => meshopt::decode_index_buffer::<u32>(src, count)
            .map_err(bad)?
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect(),
        (Some("INDICES"), 2) => meshopt::decode_index_sequence::<u16>(src, count)
            .map_err(bad)?
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect(),
        (Some("INDICES"), 4) => meshopt::decode_index_sequence::<u32>(src, count)
            .map_err(bad)?
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect(),
        (m, s) => {
            return Err(parse_err!(
                "buffer view {i}: meshopt mode {} with byteStride {s} is not supported",
                m.unwrap_or("(none)")
            ));
        }
    };
    match x["filter"].as_str() {
        None | Some("NONE") => {}
        Some("OCTAHEDRAL") if stride == 4 => {
            let mut v: Vec<[i8; 4]> = out
                .chunks_exact(4)
                .map(|c| [c[0] as i8, c[1] as i8, c[2] as i8, c[3] as i8])
                .collect();
            meshopt::decode_filter_oct(&mut v);
            out = v.iter().flatten().map(|&b| b as u8).collect();
        }
        Some("OCTAHEDRAL") if stride == 8 => {
            let mut v: Vec<[i16; 4]> = out
                .chunks_exact(8)
                .map(|c| std::array::from_fn(|k| i16::from_le_bytes([c[2 * k], c[2 * k + 1]])))
                .collect();
            meshopt::decode_filter_oct(&mut v);
            out = v.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
        }
        Some("QUATERNION") if stride == 8 => {
            let mut v: Vec<[i16; 4]> = out
                .chunks_exact(8)
                .map(|c| std::array::from_fn(|k| i16::from_le_bytes([c[2 * k], c[2 * k + 1]])))
                .collect();
            meshopt::decode_filter_quat(&mut v);
            out = v.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
        }
        Some("EXPONENTIAL") if stride.is_multiple_of(4) => {
            let mut v: Vec<[u32; 1]> = out
                .chunks_exact(4)
                .map(|c| [u32::from_le_bytes([c[0], c[1], c[2], c[3]])])
                .collect();
            meshopt::decode_filter_exp(&mut v);
            out = v.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
        }
        Some(f) => {
            return Err(parse_err!(
                "buffer view {i}: meshopt filter {f} with byteStride {stride} is not supported"
            ));
        }
    }
    Ok(out)
}

#[cfg(not(feature = "meshopt"))]
fn decode_view(
    i: usize,
    _: &Value,
    _: u64,
    _: &[Option<Cow<'_, [u8]>>],
) -> Result<Vec<u8>, ParseError> {
    Err(parse_err!(
        "buffer view {i}: meshopt decoding needs the `meshopt` feature"
    ))
}

fn components(acc: &Value) -> Result<usize, ParseError> {
    Ok(match acc["type"].as_str() {
        Some("SCALAR") => 1,
        Some("VEC2") => 2,
        Some("VEC3") => 3,
        Some("VEC4") => 4,
        t => return Err(parse_err!("accessor type {t:?} cannot be dequantised")),
    })
}

/// Accessor `ai`'s elements as floats (glTF's rules for normalised
/// integers: `max(c / (2^(b-1) - 1), -1)` signed, `c / (2^b - 1)` unsigned;
/// plain integers and floats as they are).
fn dequantise(ai: usize, acc: &Value, views: &[Value], bin: &[u8]) -> Result<Vec<f32>, ParseError> {
    let comps = components(acc)?;
    let what = format!("accessor {ai}");
    let ct = uint(&what, acc, "componentType", None)?;
    let size = match ct {
        5120 | 5121 => 1,
        5122 | 5123 => 2,
        5125 | 5126 => 4,
        _ => {
            return Err(parse_err!(
                "accessor {ai}: component type {ct} cannot be dequantised"
            ));
        }
    };
    let normalized = acc["normalized"].as_bool().unwrap_or(false);
    let count = uint(&what, acc, "count", None)?;
    let vi = usize::try_from(uint(&what, acc, "bufferView", None)?).unwrap_or(usize::MAX);
    let view = views
        .get(vi)
        .ok_or_else(|| parse_err!("accessor {ai}: buffer view {vi} does not exist"))?;
    let elem = (comps * size) as u64;
    let vwhat = format!("buffer view {vi}");
    let stride = uint(&vwhat, view, "byteStride", Some(elem))?;
    if stride < elem || count == 0 {
        return Err(parse_err!(
            "accessor {ai}: stride {stride} or count {count} is invalid for its {elem}-byte elements"
        ));
    }
    let acc_offset = uint(&what, acc, "byteOffset", Some(0))?;
    let view_offset = uint(&vwhat, view, "byteOffset", Some(0))?;
    let vlen = uint(&vwhat, view, "byteLength", None)?;
    let base = view_offset.saturating_add(acc_offset);
    let end = (count - 1)
        .checked_mul(stride)
        .and_then(|x| x.checked_add(elem))
        .and_then(|x| x.checked_add(acc_offset));
    if end.is_none_or(|e| e > vlen) || view_offset.saturating_add(vlen) > bin.len() as u64 {
        return Err(parse_err!(
            "accessor {ai}: {count} elements do not fit in buffer view {vi}"
        ));
    }
    let mut out = Vec::with_capacity(count as usize * comps);
    for e in 0..count {
        let at = (base + e * stride) as usize;
        for k in 0..comps {
            let p = at + k * size;
            let c = &bin[p..p + size];
            let x = match ct {
                5120 => {
                    let v = c[0] as i8 as f32;
                    if normalized { (v / 127.0).max(-1.0) } else { v }
                }
                5121 => {
                    let v = c[0] as f32;
                    if normalized { v / 255.0 } else { v }
                }
                5122 => {
                    let v = i16::from_le_bytes([c[0], c[1]]) as f32;
                    if normalized {
                        (v / 32767.0).max(-1.0)
                    } else {
                        v
                    }
                }
                5123 => {
                    let v = u16::from_le_bytes([c[0], c[1]]) as f32;
                    if normalized { v / 65535.0 } else { v }
                }
                5125 => u32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f32,
                _ => f32::from_le_bytes([c[0], c[1], c[2], c[3]]),
            };
            out.push(x);
        }
    }
    Ok(out)
}
