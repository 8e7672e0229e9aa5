//! Reading a written tileset back, as a client would: every JSON file with
//! serde, every tile with the glTF reader.
#![allow(dead_code)]

use std::path::Path;

use glam::{DVec3, Vec3};
use lodkit_mesh::TriMesh;
use serde_json::Value;

/// One tile of a tileset read back.
pub struct ReadTile {
    /// `D-X-Y-Z`.
    pub name: String,
    pub depth: u8,
    pub xyz: [u32; 3],
    pub error: f64,
    /// z-up box: centre, half extents (axis-aligned as written).
    pub centre: DVec3,
    pub half: DVec3,
    /// The tile's content, read back.
    pub mesh: Option<TriMesh>,
    /// Indices of children in the list.
    pub children: Vec<usize>,
}

pub struct ReadTileset {
    pub tileset_error: f64,
    pub tiles: Vec<ReadTile>,
    /// Every JSON file read.
    pub json_files: usize,
}

fn load_json(path: &Path) -> Value {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let v: Value = serde_json::from_slice(&bytes).expect("valid JSON");
    assert_eq!(v["asset"]["version"], "1.1", "{}", path.display());
    v
}

fn parse_name(uri: &str) -> (String, u8, [u32; 3]) {
    let stem = Path::new(uri)
        .file_stem()
        .unwrap()
        .to_str()
        .unwrap()
        .to_string();
    let p: Vec<u32> = stem.split('-').map(|s| s.parse().unwrap()).collect();
    (stem, p[0] as u8, [p[1], p[2], p[3]])
}

fn walk(
    t: &Value,
    base: &Path,
    out: &mut ReadTileset,
    from_external: Option<(String, u8, [u32; 3])>,
) -> usize {
    let b: Vec<f64> = t["boundingVolume"]["box"]
        .as_array()
        .expect("a box")
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(b.len(), 12);
    let error = t["geometricError"].as_f64().expect("geometricError");
    let uri = t["content"]["uri"].as_str().map(str::to_string);
    if let Some(u) = &uri
        && u.ends_with(".json")
    {
        // An external tileset: its root stands for this tile.
        let path = base.join(u);
        let doc = load_json(&path);
        out.json_files += 1;
        assert!(
            doc["geometricError"].as_f64().unwrap()
                >= doc["root"]["geometricError"].as_f64().unwrap()
        );
        assert_eq!(doc["root"]["geometricError"].as_f64(), Some(error));
        assert!(
            t.get("children").is_none(),
            "a tile with an external tileset has no children"
        );
        return walk(
            &doc["root"],
            path.parent().unwrap(),
            out,
            Some(parse_name(u)),
        );
    }
    let (name, depth, xyz, mesh) = match &uri {
        Some(u) => {
            assert!(!u.contains("..") && !u.starts_with('/'));
            let path = base.join(u);
            let bytes = std::fs::read(&path).unwrap();
            let m = match lodkit_mesh::io::gltf::read_model(&bytes, None).expect("a readable tile")
            {
                lodkit_mesh::Model::Mesh(m) => m,
                _ => panic!("{u}: a mesh tile"),
            };
            assert!(m.normals.is_some(), "{u}: every tile has normals");
            assert!(!m.faces.is_empty());
            let (n, d, xyz) = parse_name(u);
            (n, d, xyz, Some(m))
        }
        None => {
            let (n, d, xyz) = from_external
                .clone()
                .unwrap_or(("0-0-0-0".into(), 0, [0; 3]));
            (n, d, xyz, None)
        }
    };
    let id = out.tiles.len();
    out.tiles.push(ReadTile {
        name,
        depth,
        xyz,
        error,
        centre: DVec3::new(b[0], b[1], b[2]),
        half: DVec3::new(b[3], b[7], b[11]),
        mesh,
        children: Vec::new(),
    });
    if let Some(cs) = t["children"].as_array() {
        for c in cs {
            let k = walk(c, base, out, None);
            out.tiles[id].children.push(k);
        }
    }
    id
}

/// Reads `dir/tileset.json` and everything it names.
pub fn read_tileset(dir: &Path) -> ReadTileset {
    let doc = load_json(&dir.join("tileset.json"));
    assert_eq!(doc["root"]["refine"], "REPLACE");
    let mut out = ReadTileset {
        tileset_error: doc["geometricError"].as_f64().unwrap(),
        tiles: Vec::new(),
        json_files: 1,
    };
    walk(&doc["root"], dir, &mut out, None);
    out
}

/// The input faces whose centroid lies in cell `(depth, xyz)` of the
/// octree the crate documents (the cube around the box, enlarged by 1e-6).
pub fn region(input: &TriMesh, depth: u8, xyz: [u32; 3]) -> TriMesh {
    let b = input.bbox();
    let (lo, hi) = (b.min.as_dvec3(), b.max.as_dvec3());
    let size = (hi - lo).max_element() * (1.0 + 1e-6);
    let origin = (lo + hi) * 0.5 - DVec3::splat(size * 0.5);
    let n = 1u64 << depth;
    let mut faces = Vec::new();
    for f in &input.faces {
        let c: Vec3 = f.iter().map(|&v| input.positions[v as usize]).sum::<Vec3>() / 3.0;
        let rel = (c.as_dvec3() - origin) / size * n as f64;
        let cell = |v: f64| (v.floor().max(0.0) as u64).min(n - 1) as u32;
        if [cell(rel.x), cell(rel.y), cell(rel.z)] == xyz {
            faces.push(*f);
        }
    }
    TriMesh::new(input.positions.clone(), faces)
}

/// Every file under `dir` with its bytes, sorted by relative path.
pub fn all_files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let rel = p.strip_prefix(dir).unwrap().to_string_lossy().into_owned();
                out.push((rel, std::fs::read(&p).unwrap()));
            }
        }
    }
    out.sort();
    out
}
