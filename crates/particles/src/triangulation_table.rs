//! The 256-configuration look-up table of direct triangulation — §6.1.2,
//! §6.1.3 and Fig. 7 of Yemez & Schmitt, generated in code.
//!
//! A configuration is the ON/non-ON state of the eight cubes of a 2×2×2
//! neighbourhood; corner `j` sits at `(j & 1, j >> 1 & 1, j >> 2 & 1)`, the
//! child code of eq. (1). Under the 48 symmetries of the cube (6 axis
//! permutations × 8 reflections) the 256 configurations fall into 22
//! classes; the 17 with three or more ON cubes are the `C_1 … C_17` of
//! Fig. 7. The figure is missing from our copy of the paper, so the
//! numbering is ours, chosen to match the text: classes are ordered by the
//! number of ON cubes, planar before solid, then by the sorted squared
//! distances between the cubes. That makes `C_1–C_3` the three single
//! triangles of Fig. 5 (sides `1,1,√2`, `1,√2,√3`, `√2,√2,√2`) and
//! `C_4, C_5` the two planar four-cube cases with two possible
//! triangulations (a face square and a diagonal rectangle); `C_6 … C_17`
//! are the ambiguous ones, `C_6` being the frequent one Table 1 singles
//! out (a face triangle plus the opposite corner, the most frequent
//! ambiguous case on thinned surfaces; see `build`).
//!
//! For each configuration the table holds its class, its mesh graph `G_i`
//! (edges as a bit mask over the 28 corner pairs) and its triangle list
//! `T_i`: for the solid classes the convex hull of the ON cube centres,
//! a closed two-manifold whose square facets are split from their lowest
//! corner, oriented outwards (§6.2: "two-manifold closed convex surface
//! mesh").
use std::sync::OnceLock;

use lodkit_mesh::cube_symmetry::canonical;

/// Number of classes with at least three ON cubes.
pub const CLASS_COUNT: usize = 17;

/// Index of the corner pair `(a, b)`, `a ≠ b`, in `0..28`.
pub const fn pair(a: u8, b: u8) -> u32 {
    let (a, b) = if a < b {
        (a as u32, b as u32)
    } else {
        (b as u32, a as u32)
    };
    // Pairs (0,1)..(0,7), (1,2)..(1,7), ...
    a * (15 - a) / 2 + (b - a - 1)
}

/// Corner coordinates.
pub const fn corner(j: u8) -> [i32; 3] {
    [(j & 1) as i32, ((j >> 1) & 1) as i32, ((j >> 2) & 1) as i32]
}

/// How a configuration is triangulated.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Shape {
    /// Fewer than three ON cubes: nothing.
    None,
    /// `C_1–C_3`: one triangle.
    Triangle([u8; 3]),
    /// `C_4, C_5`: a planar quad in cyclic order; two triangulations.
    Quad([u8; 4]),
    /// `C_6+`: the closed hull, triangles oriented outwards.
    Solid(Vec<[u8; 3]>),
}

/// One entry of the table.
#[derive(Debug, Clone)]
pub struct Config {
    /// `1..=17`, or 0 for fewer than three ON cubes.
    pub class: u8,
    pub shape: Shape,
    /// Edges of the mesh graph `G_i` (quads: the four sides only).
    pub edges: u32,
    /// `Some((axis, side))` when every ON cube lies on one face of the
    /// neighbourhood (planar cases only).
    pub face: Option<(u8, u8)>,
    /// Solids: the pairs `(i, j)`, `i < j`, of hull triangles sharing an
    /// edge, in order (the dihedral angles §6.2 compares).
    pub adjacent: Vec<(u8, u8)>,
}

/// The generated table.
pub struct Table {
    pub configs: Vec<Config>,
    /// A representative configuration (the smallest mask) of each class.
    #[cfg_attr(not(test), allow(dead_code))] // the tests read it
    pub representatives: [u8; CLASS_COUNT],
    /// [`Table::configs`] in the 8 bytes per configuration a scan reads
    /// for every neighbourhood (2 KiB in all, where the configurations
    /// with their vectors spread over many cache lines).
    pub compact: [Compact; 256],
    /// Bit `m`: configuration `m` is a solid (`C_6+`).
    pub solid: [u64; 4],
}

/// How a configuration is triangulated, packed (see [`Table::compact`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Compact {
    /// As [`Config::class`].
    pub class: u8,
    /// 0 none, 1 a triangle, 2 a quad, 3 a solid ([`Shape`]).
    pub kind: u8,
    /// [`Config::face`]: 0 none, 1 the upper face along some axis, `2 +
    /// axis` the lower face along `axis`.
    pub face: u8,
    /// The triangle's or the quad's corners.
    pub corners: [u8; 4],
}

impl Compact {
    pub const NONE: u8 = 0;
    pub const TRIANGLE: u8 = 1;
    pub const QUAD: u8 = 2;
    pub const SOLID: u8 = 3;
}

fn nodes(mask: u8) -> Vec<u8> {
    (0..8).filter(|j| mask & (1 << j) != 0).collect()
}

fn sub(a: [i32; 3], b: [i32; 3]) -> [i32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn cross(a: [i32; 3], b: [i32; 3]) -> [i32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn dot(a: [i32; 3], b: [i32; 3]) -> i32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn coplanar(ns: &[u8]) -> bool {
    if ns.len() <= 3 {
        return true;
    }
    let p = |i: usize| corner(ns[i]);
    for i in 1..ns.len() {
        for j in i + 1..ns.len() {
            let n = cross(sub(p(i), p(0)), sub(p(j), p(0)));
            if n != [0, 0, 0] {
                return ns.iter().all(|&k| dot(n, sub(corner(k), p(0))) == 0);
            }
        }
    }
    true
}

/// Orders coplanar corners cyclically (around their centroid).
fn cyclic(ns: &[u8]) -> Vec<u8> {
    let c: [f64; 3] = {
        let mut s = [0.0; 3];
        for &k in ns {
            let p = corner(k);
            for a in 0..3 {
                s[a] += p[a] as f64 / ns.len() as f64;
            }
        }
        s
    };
    let p0 = corner(ns[0]);
    let n = {
        let mut n = [0, 0, 0];
        'o: for i in 1..ns.len() {
            for j in i + 1..ns.len() {
                n = cross(sub(corner(ns[i]), p0), sub(corner(ns[j]), p0));
                if n != [0, 0, 0] {
                    break 'o;
                }
            }
        }
        [n[0] as f64, n[1] as f64, n[2] as f64]
    };
    let u = [
        p0[0] as f64 - c[0],
        p0[1] as f64 - c[1],
        p0[2] as f64 - c[2],
    ];
    let v = [
        n[1] * u[2] - n[2] * u[1],
        n[2] * u[0] - n[0] * u[2],
        n[0] * u[1] - n[1] * u[0],
    ];
    let mut with_angle: Vec<(f64, u8)> = ns
        .iter()
        .map(|&k| {
            let p = corner(k);
            let d = [p[0] as f64 - c[0], p[1] as f64 - c[1], p[2] as f64 - c[2]];
            let x = d[0] * u[0] + d[1] * u[1] + d[2] * u[2];
            let y = d[0] * v[0] + d[1] * v[1] + d[2] * v[2];
            (y.atan2(x), k)
        })
        .collect();
    with_angle.sort_by(|a, b| a.0.total_cmp(&b.0));
    with_angle.into_iter().map(|(_, k)| k).collect()
}

/// Convex hull of ≥ 4 non-coplanar corners, triangles outward.
fn hull(ns: &[u8]) -> Vec<[u8; 3]> {
    let mut faces: Vec<([i32; 3], i32)> = Vec::new();
    let mut tris = Vec::new();
    for i in 0..ns.len() {
        for j in i + 1..ns.len() {
            for k in j + 1..ns.len() {
                let (a, b, c) = (corner(ns[i]), corner(ns[j]), corner(ns[k]));
                let mut n = cross(sub(b, a), sub(c, a));
                if n == [0, 0, 0] {
                    continue;
                }
                let sides: Vec<i32> = ns.iter().map(|&l| dot(n, sub(corner(l), a))).collect();
                if sides.iter().all(|&s| s <= 0) {
                } else if sides.iter().all(|&s| s >= 0) {
                    n = [-n[0], -n[1], -n[2]];
                } else {
                    continue;
                }
                let g = gcd(gcd(n[0].abs(), n[1].abs()), n[2].abs());
                let n = [n[0] / g, n[1] / g, n[2] / g];
                let off = dot(n, a);
                if faces.contains(&(n, off)) {
                    continue;
                }
                faces.push((n, off));
                let on: Vec<u8> = ns
                    .iter()
                    .copied()
                    .filter(|&l| dot(n, corner(l)) == off)
                    .collect();
                let mut ring = cyclic(&on);
                // Start the fan at the lowest corner.
                let lo = ring
                    .iter()
                    .enumerate()
                    .min_by_key(|(_, v)| **v)
                    .map(|(i, _)| i)
                    .unwrap_or(0);
                ring.rotate_left(lo);
                for t in 1..ring.len() - 1 {
                    let mut tri = [ring[0], ring[t], ring[t + 1]];
                    let tn = cross(
                        sub(corner(tri[1]), corner(tri[0])),
                        sub(corner(tri[2]), corner(tri[0])),
                    );
                    if dot(tn, n) < 0 {
                        tri.swap(1, 2);
                    }
                    tris.push(tri);
                }
            }
        }
    }
    tris
}

fn gcd(a: i32, b: i32) -> i32 {
    if b == 0 { a.max(1) } else { gcd(b, a % b) }
}

fn distance_key(ns: &[u8]) -> Vec<i32> {
    let mut d = Vec::new();
    for i in 0..ns.len() {
        for j in i + 1..ns.len() {
            let v = sub(corner(ns[i]), corner(ns[j]));
            d.push(dot(v, v));
        }
    }
    d.sort_unstable();
    d
}

fn build() -> Table {
    let mut canon: Vec<u8> = (0..=255u8)
        .filter(|m| m.count_ones() >= 3)
        .map(canonical)
        .collect();
    canon.sort_unstable();
    canon.dedup();
    let key = |m: u8| {
        let ns = nodes(m);
        let d = distance_key(&ns);
        // Among the ambiguous four-cube classes, the face triangle plus its
        // opposite corner comes first: it is by far the most frequent on
        // thinned surfaces (as Table 1 reports for C_6), so it is our C_6.
        let first = u8::from(!(ns.len() == 4 && d == [1, 1, 2, 2, 2, 3]));
        (m.count_ones(), !coplanar(&ns), first, d, m)
    };
    canon.sort_by_key(|&m| key(m));
    let mut representatives = [0u8; CLASS_COUNT];
    for (i, &m) in canon.iter().enumerate().take(CLASS_COUNT) {
        representatives[i] = m;
    }
    let mut configs = Vec::with_capacity(256);
    for mask in 0..=255u8 {
        let ns = nodes(mask);
        if ns.len() < 3 {
            configs.push(Config {
                class: 0,
                shape: Shape::None,
                edges: 0,
                face: None,
                adjacent: Vec::new(),
            });
            continue;
        }
        let c = canonical(mask);
        let class = canon
            .iter()
            .position(|&x| x == c)
            .map_or(0, |i| i as u8 + 1);
        let face = (0..3u8).find_map(|a| {
            let v = corner(ns[0])[a as usize];
            ns.iter()
                .all(|&k| corner(k)[a as usize] == v)
                .then_some((a, v as u8))
        });
        let shape = if ns.len() == 3 {
            Shape::Triangle([ns[0], ns[1], ns[2]])
        } else if coplanar(&ns) {
            let r = cyclic(&ns);
            Shape::Quad([r[0], r[1], r[2], r[3]])
        } else {
            Shape::Solid(hull(&ns))
        };
        let mut e = 0u32;
        let mut add = |a: u8, b: u8| e |= 1 << pair(a, b);
        match &shape {
            Shape::Triangle(t) => {
                add(t[0], t[1]);
                add(t[1], t[2]);
                add(t[2], t[0]);
            }
            Shape::Quad(q) => {
                for i in 0..4 {
                    add(q[i], q[(i + 1) % 4]);
                }
            }
            Shape::Solid(ts) => {
                for t in ts {
                    add(t[0], t[1]);
                    add(t[1], t[2]);
                    add(t[2], t[0]);
                }
            }
            Shape::None => {}
        }
        let mut adjacent = Vec::new();
        if let Shape::Solid(ts) = &shape {
            for (i, ti) in ts.iter().enumerate() {
                for (j, tj) in ts.iter().enumerate().skip(i + 1) {
                    if ti.iter().filter(|v| tj.contains(v)).count() == 2 {
                        adjacent.push((i as u8, j as u8));
                    }
                }
            }
        }
        configs.push(Config {
            class,
            shape,
            edges: e,
            face,
            adjacent,
        });
    }
    let mut compact = [Compact::default(); 256];
    let mut solid = [0u64; 4];
    for (m, c) in configs.iter().enumerate() {
        let (kind, corners) = match &c.shape {
            Shape::None => (Compact::NONE, [0; 4]),
            Shape::Triangle(t) => (Compact::TRIANGLE, [t[0], t[1], t[2], 0]),
            Shape::Quad(q) => (Compact::QUAD, *q),
            Shape::Solid(_) => (Compact::SOLID, [0; 4]),
        };
        if kind == Compact::SOLID {
            solid[m >> 6] |= 1 << (m & 63);
        }
        compact[m] = Compact {
            class: c.class,
            kind,
            face: match c.face {
                None => 0,
                Some((_, 1)) => 1,
                Some((axis, _)) => 2 + axis,
            },
            corners,
        };
    }
    Table {
        configs,
        representatives,
        compact,
        solid,
    }
}

/// The table, built on first use.
pub fn table() -> &'static Table {
    static T: OnceLock<Table> = OnceLock::new();
    T.get_or_init(build)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generated_table_is_the_one_the_streams_were_triangulated_with() {
        // FNV-1a of the whole table's debug text: a change to the generator
        // (or to `lodkit_mesh::cube_symmetry`) must not move one triangle.
        let t = table();
        let s = format!(
            "{:?}{:?}{:?}{:?}",
            t.configs, t.representatives, t.compact, t.solid
        );
        let h = s.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
            (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3)
        });
        assert_eq!((h, s.len()), (0xe914_5086_7a98_0deb, 57584));
    }

    #[test]
    fn symmetry_maps_every_configuration_to_one_of_17_classes() {
        let mut classes = std::collections::BTreeSet::new();
        let mut all = std::collections::BTreeSet::new();
        for m in 0..=255u8 {
            all.insert(canonical(m));
            if m.count_ones() >= 3 {
                classes.insert(canonical(m));
            }
        }
        assert_eq!(
            all.len(),
            22,
            "22 classes in all under the full octahedral group"
        );
        assert_eq!(classes.len(), CLASS_COUNT);
        let t = table();
        for m in 0..=255u8 {
            let c = &t.configs[m as usize];
            if m.count_ones() >= 3 {
                assert!((1..=17).contains(&c.class), "config {m:08b}");
                // Same class as its canonical representative.
                let rep = t.representatives[c.class as usize - 1];
                assert_eq!(canonical(m), rep);
            } else {
                assert_eq!(c.class, 0);
            }
        }
        // Every class has its representatives' counts: 3×3, 6×4, 3×5, 3×6, 1×7, 1×8.
        let counts: Vec<u32> = t.representatives.iter().map(|m| m.count_ones()).collect();
        assert_eq!(counts, [3, 3, 3, 4, 4, 4, 4, 4, 4, 5, 5, 5, 6, 6, 6, 7, 8]);
    }

    #[test]
    fn first_classes_are_the_three_triangles_and_the_two_quads() {
        let t = table();
        let key = |m: u8| distance_key(&nodes(m));
        assert_eq!(key(t.representatives[0]), [1, 1, 2]);
        assert_eq!(key(t.representatives[1]), [1, 2, 3]);
        assert_eq!(key(t.representatives[2]), [2, 2, 2]);
        assert!(matches!(
            t.configs[t.representatives[3] as usize].shape,
            Shape::Quad(_)
        ));
        assert!(matches!(
            t.configs[t.representatives[4] as usize].shape,
            Shape::Quad(_)
        ));
        assert_eq!(t.configs[0b1111].class, 4, "a face square is C4");
        for &m in &t.representatives[5..] {
            assert!(matches!(t.configs[m as usize].shape, Shape::Solid(_)));
        }
        assert_eq!(
            t.configs[0b1000_0111].class, 6,
            "face triangle 0,1,2 plus corner 7 is C6"
        );
    }

    #[test]
    fn solid_hulls_are_closed_two_manifolds_oriented_outwards() {
        let t = table();
        for m in 0..=255u8 {
            let Shape::Solid(tris) = &t.configs[m as usize].shape else {
                continue;
            };
            let ns = nodes(m);
            // Euler: V - E + F = 2 for a sphere; every edge used twice, once each way.
            let mut directed = std::collections::BTreeMap::new();
            for tri in tris {
                for i in 0..3 {
                    *directed.entry((tri[i], tri[(i + 1) % 3])).or_insert(0) += 1;
                }
            }
            for (&(a, b), &n) in &directed {
                assert_eq!(n, 1, "config {m:08b}");
                assert_eq!(directed.get(&(b, a)), Some(&1), "config {m:08b}");
            }
            let e = directed.len() / 2;
            assert_eq!(
                ns.len() as i32 - e as i32 + tris.len() as i32,
                2,
                "config {m:08b}"
            );
            // Outward: the centroid is behind every face.
            let c: Vec<f64> = (0..3)
                .map(|a| ns.iter().map(|&k| corner(k)[a] as f64).sum::<f64>() / ns.len() as f64)
                .collect();
            for tri in tris {
                let (a, b, cc) = (corner(tri[0]), corner(tri[1]), corner(tri[2]));
                let n = cross(sub(b, a), sub(cc, a));
                let d: f64 = (0..3).map(|k| n[k] as f64 * (c[k] - a[k] as f64)).sum();
                assert!(d < 0.0, "config {m:08b}");
            }
            assert_eq!(t.configs[m as usize].edges.count_ones() as usize, e);
        }
    }

    #[test]
    fn pair_indices_cover_0_to_27_once() {
        let mut seen = [false; 28];
        for a in 0..8u8 {
            for b in a + 1..8 {
                let p = pair(a, b) as usize;
                assert!(!seen[p]);
                seen[p] = true;
                assert_eq!(pair(b, a) as usize, p);
            }
        }
        assert!(seen.iter().all(|s| *s));
    }
}
