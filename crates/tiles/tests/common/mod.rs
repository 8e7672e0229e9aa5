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

/// The cube of cell `(depth, xyz)` of the octree the crate documents
/// (the cube around `input`'s box, enlarged by 1e-6): lowest corner, side.
pub fn cell_cube(input: &TriMesh, depth: u8, xyz: [u32; 3]) -> (DVec3, f64) {
    let b = input.bbox();
    let (lo, hi) = (b.min.as_dvec3(), b.max.as_dvec3());
    let size = (hi - lo).max_element() * (1.0 + 1e-6);
    let origin = (lo + hi) * 0.5 - DVec3::splat(size * 0.5);
    let side = size / (1u64 << depth) as f64;
    (origin + DVec3::from_array(xyz.map(f64::from)) * side, side)
}

/// The input faces whose centroid lies in cell `(depth, xyz)` and is not
/// within `away` of any of the cubes `avoid` (lowest corner, side).
pub fn region_away(
    input: &TriMesh,
    depth: u8,
    xyz: [u32; 3],
    avoid: &[(DVec3, f64)],
    away: f64,
) -> TriMesh {
    let (lo, side) = cell_cube(input, depth, xyz);
    let gap = |(a, s): (DVec3, f64), p: DVec3, q: DVec3| {
        (a - q).max(p - (a + s)).max(DVec3::ZERO).length()
    };
    let avoid: Vec<(DVec3, f64)> = avoid
        .iter()
        .copied()
        .filter(|&c| gap(c, lo, lo + side) <= away)
        .collect();
    let mut faces = Vec::new();
    for f in &input.faces {
        let c: Vec3 = f.iter().map(|&v| input.positions[v as usize]).sum::<Vec3>() / 3.0;
        let rel = (c.as_dvec3() - lo) / side;
        if rel.min_element() < 0.0 || rel.max_element() >= 1.0 {
            continue;
        }
        let c = c.as_dvec3();
        let near = avoid.iter().any(|&cube| gap(cube, c, c) <= away);
        if !near {
            faces.push(*f);
        }
    }
    TriMesh::new(input.positions.clone(), faces)
}

/// The input faces whose centroid lies in cell `(depth, xyz)`.
pub fn region(input: &TriMesh, depth: u8, xyz: [u32; 3]) -> TriMesh {
    region_away(input, depth, xyz, &[], 0.0)
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

/// What a client shows when it draws depth `depth` everywhere it can:
/// every tile of that depth and every shallower leaf (skirts included).
pub fn drawn_at(ts: &ReadTileset, depth: u8) -> TriMesh {
    let mut cut = TriMesh::default();
    for t in &ts.tiles {
        if t.depth == depth || (t.depth < depth && t.children.is_empty()) {
            let Some(m) = &t.mesh else { continue };
            let base = cut.positions.len() as u32;
            cut.positions.extend_from_slice(&m.positions);
            cut.faces
                .extend(m.faces.iter().map(|f| f.map(|v| v + base)));
        }
    }
    cut
}

/// A tile's surface without its skirts: a skirt's triangles are drawn
/// both ways (a triangle and its reverse on the same vertices), a
/// surface's never.
pub fn without_skirts(m: &TriMesh) -> TriMesh {
    let key = |f: &[u32; 3]| {
        let mut k = *f;
        k.sort_unstable();
        k
    };
    let mut count = std::collections::HashMap::new();
    for f in &m.faces {
        *count.entry(key(f)).or_insert(0) += 1;
    }
    let faces = m
        .faces
        .iter()
        .filter(|f| count[&key(f)] == 1)
        .copied()
        .collect();
    TriMesh::new(m.positions.clone(), faces)
}

/// Honest errors, both ways, measured again with another seed: every
/// tile's surface lies within its `geometricError` of the input, and the
/// input of an internal tile's cell within it of its depth's tiles
/// ([`drawn_at`]), away from the cells of leaves shown beside them: there
/// the level's own faces are not in the tileset (the client shows the
/// leaf, and the sliver between the two is the skirts' business), so
/// input within the longest edge of the depth's tiles of such a cell is
/// left out. `slack` (≥ 1) allows for what samples miss.
pub fn assert_honest(ts: &ReadTileset, input: &TriMesh, slack: f64) {
    use lodkit_mesh::metrics::{CompareOptions, SurfaceIndex, one_sided};
    let diag = input.bbox().diagonal() as f64;
    let opts = CompareOptions {
        seed: 7,
        samples: Some(20_000),
        ..CompareOptions::default()
    };
    let whole = SurfaceIndex::new(input).unwrap();
    let depth = ts.tiles.iter().map(|t| t.depth).max().unwrap_or(0);
    let drawn: Vec<SurfaceIndex> = (0..=depth)
        .map(|d| SurfaceIndex::new(&drawn_at(ts, d)).unwrap())
        .collect();
    // The longest edge of each depth's tiles (skirts left out).
    let mut longest = vec![0.0f64; depth as usize + 1];
    for t in &ts.tiles {
        let Some(m) = &t.mesh else { continue };
        let m = without_skirts(m);
        for f in &m.faces {
            let p = f.map(|v| m.positions[v as usize]);
            for k in 0..3 {
                let l = p[k].distance(p[(k + 1) % 3]) as f64;
                longest[t.depth as usize] = longest[t.depth as usize].max(l);
            }
        }
    }
    for t in &ts.tiles {
        let Some(mesh) = &t.mesh else { continue };
        let surface = without_skirts(mesh);
        let off = one_sided(&surface, &whole, &opts).unwrap().max;
        let allowed = if t.children.is_empty() {
            t.error + 1e-6 * diag
        } else {
            t.error * slack + 1e-6 * diag
        };
        assert!(
            off <= allowed,
            "{}: tile {} from the input, geometricError {}",
            t.name,
            off,
            t.error
        );
        if !t.children.is_empty() {
            let leaves: Vec<(DVec3, f64)> = ts
                .tiles
                .iter()
                .filter(|l| l.children.is_empty() && l.depth <= t.depth)
                .map(|l| cell_cube(input, l.depth, l.xyz))
                .collect();
            let reg = region_away(input, t.depth, t.xyz, &leaves, longest[t.depth as usize]);
            if reg.faces.is_empty() {
                continue;
            }
            let uncovered = one_sided(&reg, &drawn[t.depth as usize], &opts)
                .unwrap()
                .max;
            assert!(
                uncovered <= allowed,
                "{}: input {} from its depth's tiles, geometricError {}",
                t.name,
                uncovered,
                t.error
            );
        }
    }
}
