//! `tileset.json` and the external tilesets: 3D Tiles 1.1, z-up.
//!
//! Frames: tile contents are glTF, y-up; 3D Tiles clients (CesiumJS,
//! 3DTilesRendererJS) turn glTF content from y-up to the tileset's z-up
//! (`(x, y, z) ↦ (x, −z, y)`) themselves, so no root `transform` is
//! written and an input that stands upright in y-up stands upright in the
//! tileset. Bounding boxes are in that z-up frame.
//!
//! External tilesets: a node at a depth that is a positive multiple of
//! [`SUBTREE_LEVELS`] is written as its own `tiles/D-X-Y-Z.json` (its
//! subtree to the next such depth), referenced from its parent's file by
//! a content-less tile of the same box and error; so the first file a
//! client reads lists at most `8^SUBTREE_LEVELS` tiles (about
//! `4^SUBTREE_LEVELS` on a surface), written without indentation.

use lodkit_mesh::Aabb;
use serde_json::{Value, json};

use crate::octree_partition::Octree;

/// Levels of the tree per tileset file (root file: depths 0, 1, 2).
pub const SUBTREE_LEVELS: u8 = 3;

/// Per node: what the JSON needs.
pub struct NodeInfo {
    /// Content bounding box (y-up, object units), and its children's.
    pub bbox: Aabb,
    /// `geometricError` (object units, monotone: ≥ every child's).
    pub error: f64,
    /// Whether the node has a tile content file.
    pub content: bool,
}

/// The `box` of a y-up box, in the z-up frame: centre, then three
/// half-axes (each at least `pad`, so no axis is degenerate).
fn zup_box(b: &Aabb, pad: f64) -> Value {
    let c = b.center().as_dvec3();
    let h = (b.size().as_dvec3() * 0.5).max(glam::DVec3::splat(pad));
    json!([c.x, -c.z, c.y, h.x, 0.0, 0.0, 0.0, h.z, 0.0, 0.0, 0.0, h.y])
}

fn asset() -> Value {
    json!({ "version": "1.1", "generator": concat!("lodkit-tiles ", env!("CARGO_PKG_VERSION")) })
}

/// How a tile's children refine it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Refine {
    /// Children replace the tile (meshes: each level is the whole surface).
    Replace,
    /// Children are drawn with the tile (points: each point stored once).
    Add,
}

impl Refine {
    fn name(self) -> &'static str {
        match self {
            Refine::Replace => "REPLACE",
            Refine::Add => "ADD",
        }
    }
}

/// Every tileset file: `(path relative to the output folder, JSON bytes)`,
/// `tileset.json` first. `tileset_error` is the top-level
/// `geometricError` (the error of showing nothing). `REPLACE` refinement,
/// no root transform.
pub fn tileset_files(
    tree: &Octree,
    info: &[NodeInfo],
    tileset_error: f64,
) -> Vec<(String, Vec<u8>)> {
    tileset_files_with(tree, info, tileset_error, Refine::Replace, None)
}

/// [`tileset_files`] with a refinement and, when `origin` is given, a root
/// `transform` translating the content (coordinates relative to `origin`)
/// to `origin` in the tileset's z-up frame: large coordinates (a LAS
/// file's projected metres or feet) stay exact in `f64` while the tiles
/// hold small `f32` offsets.
pub fn tileset_files_with(
    tree: &Octree,
    info: &[NodeInfo],
    tileset_error: f64,
    refine: Refine,
    origin: Option<[f64; 3]>,
) -> Vec<(String, Vec<u8>)> {
    let pad = tree.grid.size * 1e-6;
    let mut files = Vec::new();
    let mut pending = vec![0usize];
    while let Some(top) = pending.pop() {
        let key = tree.nodes[top].key;
        let (path, prefix, error) = if top == 0 {
            ("tileset.json".to_string(), "tiles/", tileset_error)
        } else {
            (format!("tiles/{}.json", key.name()), "", info[top].error)
        };
        let mut root = tile(tree, info, top, prefix, pad, refine, &mut pending);
        if let (0, Some([x, y, z]), Value::Object(t)) = (top, origin, &mut root) {
            let m = [
                1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, x, y, z, 1.0,
            ];
            t.insert("transform".into(), json!(m));
        }
        let doc = json!({ "asset": asset(), "geometricError": error, "root": root });
        let mut bytes = serde_json::to_vec(&doc).unwrap_or_default();
        bytes.push(b'\n');
        files.push((path, bytes));
    }
    files[1..].sort_by(|a, b| a.0.cmp(&b.0));
    files
}

/// The tile of node `n` with its subtree down to the next external
/// tileset depth; nodes at that depth are queued in `pending`.
fn tile(
    tree: &Octree,
    info: &[NodeInfo],
    n: usize,
    prefix: &str,
    pad: f64,
    refine: Refine,
    pending: &mut Vec<usize>,
) -> Value {
    let node = &tree.nodes[n];
    let mut t = serde_json::Map::new();
    t.insert(
        "boundingVolume".into(),
        json!({ "box": zup_box(&info[n].bbox, pad) }),
    );
    t.insert("geometricError".into(), json!(info[n].error));
    t.insert("refine".into(), json!(refine.name()));
    if info[n].content {
        t.insert(
            "content".into(),
            json!({ "uri": format!("{prefix}{}.glb", node.key.name()) }),
        );
    }
    let mut children = Vec::new();
    for &c in &node.children {
        let ck = tree.nodes[c].key;
        if ck.depth.is_multiple_of(SUBTREE_LEVELS) {
            pending.push(c);
            children.push(json!({
                "boundingVolume": { "box": zup_box(&info[c].bbox, pad) },
                "geometricError": info[c].error,
                "content": { "uri": format!("{prefix}{}.json", ck.name()) },
            }));
        } else {
            children.push(tile(tree, info, c, prefix, pad, refine, pending));
        }
    }
    if !children.is_empty() {
        t.insert("children".into(), Value::Array(children));
    }
    Value::Object(t)
}
