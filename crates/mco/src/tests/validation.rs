//! Every table of a loaded model is checked against the others before the
//! model is used (`mco_file::validate`): one hand-mutated file per table,
//! version 1 (flat arrays, every table stored) and version 2 (the tables
//! it stores), each refused with one line naming what disagrees, never
//! accepted with a table that could size an allocation wrongly.

use crate::McoModel;
use crate::mco_file::decode;
use crate::mco_file::v1::{HEADER_BYTES, NODE_BYTES, encode};
use crate::model::Node;
use crate::pipeline::{Options, build_from_mesh};

fn model() -> McoModel {
    build_from_mesh(
        &lodkit_mesh::shapes::icosphere(3),
        &Options {
            resolution: Some(12),
        },
    )
    .unwrap()
}

/// Byte offsets of the version-1 arrays (`docs/formats/mco.md`).
struct Layout {
    positions: usize,
    nodes: usize,
    metric: usize,
    prio: usize,
    tris: usize,
    lod: usize,
    groups: usize,
    acc: usize,
    patches: usize,
    subs: usize,
    deps: usize,
}

impl Layout {
    fn of(m: &McoModel) -> Layout {
        let v = m.vertices.len();
        let n = m.nodes.len();
        let positions = HEADER_BYTES;
        // Positions and normals (12 bytes each), then colours (4): colours
        // have no cross-reference but their count, shared with positions.
        let nodes = positions + 28 * v;
        let metric = nodes + NODE_BYTES * n;
        let prio = metric + 4 * n;
        let tris = prio + 4 * n;
        let lod = tris + 4 * m.tris.len();
        let groups = lod + 4 * m.lod.len();
        let acc = groups + 4 * m.groups.len();
        let patches = acc + 4 * m.acc.len();
        let subs = patches + 12 * m.patches.len();
        let deps = subs + 8 * m.subs.len();
        Layout {
            positions,
            nodes,
            metric,
            prio,
            tris,
            lod,
            groups,
            acc,
            patches,
            subs,
            deps,
        }
    }
    /// Offset of node `i`'s field at `field` bytes into its record.
    fn node(&self, i: u32, field: usize) -> usize {
        self.nodes + NODE_BYTES * i as usize + field
    }
}

fn put(b: &mut [u8], at: usize, x: u32) {
    b[at..at + 4].copy_from_slice(&x.to_le_bytes());
}

/// The version-1 file of `m` changed by `f`, checksum fixed, decoded: it
/// must be refused, with one line containing `what`.
fn refused(m: &McoModel, what: &str, f: impl FnOnce(&Layout, &mut Vec<u8>)) {
    let mut b = encode(m);
    f(&Layout::of(m), &mut b);
    let body = b.len() - 4;
    let crc = crc32fast::hash(&b[..body]);
    b[body..].copy_from_slice(&crc.to_le_bytes());
    match decode(&b) {
        Ok(_) => panic!("accepted a file whose {what} was changed"),
        Err(e) => {
            assert!(!e.contains('\n'), "{e}");
            assert!(e.contains(what), "expected {what:?} in {e:?}");
        }
    }
}

/// Field offsets inside a node record.
const PARENT: usize = 12;
const FIRST_CHILD: usize = 16;
const DEPS_START: usize = 28;
const TRI_COUNT: usize = 32;
const CHILD_COUNT: usize = 36;
const LEVEL: usize = 37;

/// A node with children other than the root, a leaf, and an expanded node
/// with balance dependencies.
fn picks(m: &McoModel) -> (u32, u32, u32) {
    let inner = (1..m.nodes.len() as u32)
        .find(|&i| m.nodes[i as usize].child_count > 0)
        .unwrap();
    let leaf = (0..m.nodes.len() as u32)
        .find(|&i| m.nodes[i as usize].child_count == 0 && m.nodes[i as usize].tri_count > 0)
        .unwrap();
    let with_deps = (0..m.nodes.len() as u32)
        .find(|&i| m.nodes[i as usize].deps_count > 0 && m.prio[i as usize] != u32::MAX)
        .unwrap();
    (inner, leaf, with_deps)
}

#[test]
fn the_unmutated_file_and_the_shipped_seeds_load() {
    let m = model();
    assert_eq!(decode(&encode(&m)).unwrap(), m);
    // The seeds live apart from `fuzz/corpus/`, which `scripts/fuzz.sh`
    // minimises and renames after every run.
    let corpus = concat!(env!("CARGO_MANIFEST_DIR"), "/fuzz/seeds");
    for f in [
        "mco/bunny_res8.mco",
        "mco_v2/bunny_res8.mco",
        "mco_v2/bunny_res16.mco",
    ] {
        let bytes = std::fs::read(format!("{corpus}/{f}")).unwrap();
        McoModel::from_bytes(&bytes).unwrap_or_else(|e| panic!("{f}: {e}"));
    }
}

#[test]
fn a_triangle_table_that_disagrees_with_the_triangles_is_refused() {
    let m = model();
    let k = m.max_lod() / 2;
    // The probe's case: a huge count that `extract` would reserve.
    refused(&m, "triangle table", |l, b| {
        put(b, l.acc + 4 * k, 2_000_000_000)
    });
    refused(&m, "triangle table gives", |l, b| {
        put(b, l.acc, m.acc[0] + 1)
    });
    let last = m.max_lod();
    refused(&m, "triangle table", |l, b| {
        put(b, l.acc + 4 * last, m.acc[last] - 1)
    });
}

#[test]
fn each_node_field_is_checked_against_the_tree() {
    let m = model();
    let (inner, leaf, with_deps) = picks(&m);
    let nd: Node = m.nodes[inner as usize];
    refused(&m, "parent", |l, b| put(b, l.node(inner, PARENT), leaf));
    refused(&m, "parent", |l, b| {
        put(b, l.node(inner, FIRST_CHILD), nd.first_child + 1)
    });
    refused(&m, "not one tree", |l, b| {
        b[l.node(inner, CHILD_COUNT)] = nd.child_count - 1
    });
    refused(&m, "octant", |l, b| {
        b[l.node(leaf, LEVEL)] = 1;
    });
    refused(&m, "octant", |l, b| {
        let c = m.nodes[leaf as usize].coord[0];
        put(b, l.node(leaf, 0), c ^ 2)
    });
    // One more triangle: still in range of the triangle array, so only the
    // triangle table can tell.
    refused(&m, "triangle table", |l, b| {
        let t = m.nodes[leaf as usize].tri_count + 1;
        b[l.node(leaf, TRI_COUNT)..][..2].copy_from_slice(&t.to_le_bytes())
    });
    refused(&m, "balance dependencies out of range", |l, b| {
        put(b, l.node(with_deps, DEPS_START), m.deps.len() as u32)
    });
}

#[test]
fn each_array_is_checked_against_the_others() {
    let m = model();
    let (inner, leaf, with_deps) = picks(&m);
    let v = m.vertices.len() as u32;
    refused(&m, "triangle index", |l, b| put(b, l.tris + 8, v));
    refused(&m, "not finite", |l, b| {
        put(b, l.positions + 4, f32::NAN.to_bits())
    });
    refused(&m, "LOD metric", |l, b| {
        put(b, l.metric + 4 * inner as usize, f32::INFINITY.to_bits())
    });
    // The LOD array names another node than the priority numbers say.
    refused(&m, "priority number", |l, b| put(b, l.lod + 4, leaf));
    refused(&m, "have a priority number", |l, b| {
        put(b, l.prio + 4 * leaf as usize, 3)
    });
    refused(&m, "priority number", |l, b| {
        let n = m.lod[2];
        put(b, l.prio + 4 * n as usize, m.prio[n as usize] + 1)
    });
    // A child expanded before its parent, both tables swapped together.
    let child = m.lod[m.groups[1] as usize..]
        .iter()
        .copied()
        .find(|&n| {
            m.nodes[n as usize].parent == 0
                && m.groups[m.prio[n as usize] as usize] - m.groups[m.prio[n as usize] as usize - 1]
                    == 1
        })
        .unwrap();
    refused(&m, "before its parent", |l, b| {
        let at = m.lod.iter().position(|&x| x == child).unwrap();
        put(b, l.lod, child);
        put(b, l.lod + 4 * at, 0);
        put(b, l.prio, m.prio[child as usize]);
        put(b, l.prio + 4 * child as usize, 1);
    });
    refused(&m, "expands no node", |l, b| put(b, l.groups + 4, 0));
    refused(&m, "LOD groups cover", |l, b| {
        let g = m.groups.len() - 1;
        put(b, l.groups + 4 * g, m.groups[g] - 1)
    });
    refused(&m, "patch", |l, b| put(b, l.patches, m.nodes.len() as u32));
    refused(&m, "crack-patch vertex", |l, b| put(b, l.subs + 4, v));
    // A balance dependency expanded only after the node that needs it.
    let nd = m.nodes[with_deps as usize];
    let later = m.lod[m.lod.len() - 1];
    assert!(m.prio[later as usize] > m.prio[with_deps as usize]);
    refused(&m, "balance dependency", |l, b| {
        put(b, l.deps + 4 * nd.deps_start as usize, later)
    });
    refused(&m, "node reference", |l, b| {
        put(b, l.deps + 4 * nd.deps_start as usize, m.nodes.len() as u32)
    });
}

/// Version 2 stores the deps, metrics and counts; the accumulation table
/// is recomputed from the triangles, so it always agrees with them.
#[test]
fn version_2_tables_are_checked_the_same_way() {
    let m = model();
    let (inner, _, with_deps) = picks(&m);
    let v2 = |m: &McoModel| crate::mco_file::v2::decode(&m.to_bytes());
    let back = v2(&m).unwrap();
    for k in 0..=m.max_lod() {
        assert_eq!(back.triangles_at_lod(k), m.triangles_at_lod(k));
    }
    let mut bad = m.clone();
    let later = m.lod[m.lod.len() - 1];
    bad.deps[m.nodes[with_deps as usize].deps_start as usize] = later;
    let e = v2(&bad).unwrap_err();
    assert!(e.contains("balance dependency"), "{e}");
    let mut bad = m.clone();
    bad.metric[inner as usize] = f32::NAN;
    let e = v2(&bad).unwrap_err();
    assert!(e.contains("LOD metric"), "{e}");
    // A header total that the chunks do not add up to.
    let mut bytes = m.to_bytes();
    let nodes = u32::from_le_bytes(bytes[64..68].try_into().unwrap());
    bytes[64..68].copy_from_slice(&(nodes + 1).to_le_bytes());
    let crc = crc32fast::hash(&bytes[..crate::mco_file::v2::HEADER_BYTES - 4]);
    let h = crate::mco_file::v2::HEADER_BYTES;
    bytes[h - 4..h].copy_from_slice(&crc.to_le_bytes());
    let e = crate::mco_file::v2::decode(&bytes).unwrap_err();
    assert!(e.contains("totals"), "{e}");
}
