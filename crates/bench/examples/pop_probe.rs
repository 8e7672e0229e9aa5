//! Development probe for §4.3/§6: encodes a model, then per level prints
//! particles, triangles, non-manifold triangles (edges used more than
//! twice), boundary edges and the configuration classes the non-manifold
//! triangles come from; then times decode + triangulation of the finest
//! level in CPU time (the development machine is shared, so wall time
//! overstates the work; criterion's `--bench pop` gives wall time).
//!
//! `cargo run --release -p lodkit-bench --example pop_probe -- FILE R
//! [baseline|entropy] [inner|outer] [relax_below] [iterations]`; FILE
//! `icosphere` is the bench's icosphere. `POP_PROBE_QUICK=1` skips the
//! per-level table and orientation, `POP_PROBE_EDGES=1` adds, per level,
//! the classes of the triangles on each non-manifold edge (`w`: an
//! ambiguous neighbourhood left whole), `POP_PROBE_THIN=1` first prints,
//! per level after thinning, the kept cubes with no IN face neighbour and
//! the 2×2×2 blocks holding 6 or 7–8 kept cubes.
use std::path::Path;
use std::time::Instant;

use lodkit_particles::non_manifold_triangles;
use lodkit_particles::triangulate_traced;
use lodkit_particles::{
    DecodeOptions, EncodeOptions, Mode, ThinningOptions, TriangulateOptions, decode, encode,
    triangulate,
};

/// CPU time of this (single-threaded) process in seconds: the machine is
/// shared, so wall time overstates the work.
fn cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(0.0, |ns| ns * 1e-9)
}

fn boundary_edges(faces: &[[u32; 3]]) -> usize {
    let mut e: Vec<u64> = faces
        .iter()
        .flat_map(|f| {
            (0..3).map(move |k| {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                (u64::from(a.min(b)) << 32) | u64::from(a.max(b))
            })
        })
        .collect();
    e.sort_unstable();
    let mut n = 0;
    let mut i = 0;
    while i < e.len() {
        let mut j = i;
        while j < e.len() && e[j] == e[i] {
            j += 1;
        }
        n += usize::from(j - i == 1);
        i = j;
    }
    n
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let file = a
        .get(1)
        .expect("usage: FILE R [mode] [inner|outer] [relax] [iters]");
    let depth: u8 = a.get(2).map_or(7, |v| v.parse().expect("R"));
    let mode = match a.get(3).map(String::as_str) {
        Some("entropy") => Mode::Entropy,
        _ => Mode::Baseline,
    };
    let defaults = ThinningOptions::DEFAULT;
    let outer = a.get(4).map_or(defaults.outer, |v| v.as_str() == "outer");
    let relax_below: u8 = a
        .get(5)
        .map_or(defaults.relax_below, |v| v.parse().expect("relax"));
    let iters: usize = a.get(6).map_or(20, |v| v.parse().expect("iters"));
    // `icosphere`: the bench input (an icosphere of level 6).
    let model = if file == "icosphere" {
        lodkit_mesh::Model::Mesh(lodkit_mesh::shapes::icosphere(6))
    } else {
        lodkit_mesh::io::load(Path::new(file)).expect("load")
    };
    let opts = EncodeOptions {
        depth: Some(depth),
        mode,
        thinning: ThinningOptions { outer, relax_below },
        ..EncodeOptions::DEFAULT
    };
    if std::env::var_os("POP_PROBE_THIN").is_some() {
        thinning_report(&model, depth, &opts.thinning);
    }
    let t0 = Instant::now();
    let bytes = encode(&model, &opts).expect("encode").bytes;
    println!(
        "{file} R={depth} {} outer={outer} relax_below={relax_below}: {} bytes, encode {:.2} s",
        mode.name(),
        bytes.len(),
        t0.elapsed().as_secs_f64()
    );
    let d = decode(&bytes, &DecodeOptions::default()).expect("decode");
    let t = TriangulateOptions {
        orient: false,
        ..TriangulateOptions::DEFAULT
    };
    println!(
        "{:>2} {:>8} {:>9} {:>6} {:>7} {:>7} {:>6} {:>6}  nm-triangles by class",
        "r", "particles", "triangles", "tri/p", "nm-tris", "nm%", "bound", "fallb"
    );
    let quick = std::env::var_os("POP_PROBE_QUICK").is_some();
    for r in 0..d.level_count() {
        if quick {
            break;
        }
        let s = d.surface(r as u8).expect("surface");
        let (tr, classes) = triangulate_traced(&s, &t);
        let nm = non_manifold_triangles(&tr.mesh);
        let mut hist = [0usize; 256];
        for (i, bad) in lodkit_mesh::topology::non_manifold_faces(&tr.mesh)
            .iter()
            .enumerate()
        {
            if *bad {
                hist[classes[i] as usize] += 1;
            }
        }
        let h: Vec<String> = hist
            .iter()
            .enumerate()
            .filter(|(_, n)| **n > 0)
            .map(|(c, n)| {
                let whole = if c >= 128 { "w" } else { "" };
                format!("C{}{whole}:{n}", c & 127)
            })
            .collect();
        if std::env::var_os("POP_PROBE_EDGES").is_some() {
            // Class tuples of the triangles on each edge used 3+ times.
            let mut sides: Vec<(u64, u8)> = Vec::new();
            for (i, f) in tr.mesh.faces.iter().enumerate() {
                for k in 0..3 {
                    let (a, b) = (f[k], f[(k + 1) % 3]);
                    sides.push((
                        (u64::from(a.min(b)) << 32) | u64::from(a.max(b)),
                        classes[i],
                    ));
                }
            }
            sides.sort_unstable();
            let mut pat: std::collections::BTreeMap<Vec<String>, usize> = Default::default();
            let mut i = 0;
            while i < sides.len() {
                let mut j = i;
                while j < sides.len() && sides[j].0 == sides[i].0 {
                    j += 1;
                }
                if j - i > 2 {
                    let mut c: Vec<String> = sides[i..j]
                        .iter()
                        .map(|x| format!("{}{}", x.1 & 127, if x.1 >= 128 { "w" } else { "" }))
                        .collect();
                    c.sort_unstable();
                    *pat.entry(c).or_default() += 1;
                }
                i = j;
            }
            let mut v: Vec<_> = pat.into_iter().collect();
            v.sort_by_key(|e| std::cmp::Reverse(e.1));
            let top: Vec<String> = v
                .iter()
                .take(12)
                .map(|(c, n)| format!("{c:?}x{n}"))
                .collect();
            println!("   nm edges by class tuple: {}", top.join(" "));
        }
        let f = tr.mesh.faces.len();
        println!(
            "{r:>2} {:>8} {:>9} {:>6.2} {:>7} {:>7.2} {:>6} {:>6}  {}",
            s.cells.len(),
            f,
            f as f64 / s.cells.len().max(1) as f64,
            nm,
            nm as f64 * 100.0 / f.max(1) as f64,
            boundary_edges(&tr.mesh.faces),
            tr.stats.fallbacks,
            h.join(" ")
        );
    }
    if iters == 0 {
        return;
    }
    for orient in [false, true] {
        if quick && orient {
            break;
        }
        let t = TriangulateOptions {
            orient,
            ..TriangulateOptions::DEFAULT
        };
        let mut tris = 0;
        let (mut td, mut tt) = (0.0, 0.0);
        for _ in 0..iters {
            let t0 = cpu_seconds();
            let d = decode(&bytes, &DecodeOptions::default()).expect("decode");
            let s = d.surface(d.header.depth).expect("surface");
            let t1 = cpu_seconds();
            tris = triangulate(&s, &t).mesh.faces.len();
            td += t1 - t0;
            tt += cpu_seconds() - t1;
        }
        let n = iters as f64;
        println!(
            "orient={orient}: {tris} tris, CPU ms per run: decode+surface {:.2}, triangulate {:.2}; decode+triangulate {:.2} M tris/s",
            td * 1e3 / n,
            tt * 1e3 / n,
            tris as f64 * n / (td + tt) / 1e6
        );
    }
}

/// Per level after thinning: ON cubes, those with no IN face neighbour
/// (kept by the topology test, or where outer thinning is off), and
/// 2×2×2 blocks by ON count (6, 7–8).
fn thinning_report(model: &lodkit_mesh::Model, depth: u8, t: &ThinningOptions) {
    use lodkit_particles::internals::{BuildOptions, FACES, Label, Octree, morton, unmorton};
    let mut tree = Octree::build(
        model,
        &BuildOptions {
            depth: Some(depth),
            sidedness: None,
        },
    )
    .expect("octree");
    lodkit_particles::internals::thin(&mut tree, t);
    println!(
        "{:>2} {:>8} {:>8} {:>8} {:>8}",
        "r", "on", "no-in", "blk6", "blk7+"
    );
    for r in 1..=depth {
        let lv = &tree.levels[r as usize];
        let on: Vec<u64> = (0..lv.cells.len())
            .filter(|&i| lv.label[i] == Label::On)
            .map(|i| lv.cells[i])
            .collect();
        let set: std::collections::HashSet<u64> = on.iter().copied().collect();
        let no_in = on
            .iter()
            .filter(|&&m| {
                let c = unmorton(m);
                FACES
                    .iter()
                    .all(|&d| tree.neighbour_label(r, c, d) != Label::In)
            })
            .count();
        let mut origins: std::collections::HashSet<[u32; 3]> = Default::default();
        for &m in &on {
            let c = unmorton(m);
            for k in 0..8u32 {
                let o = [
                    c[0].wrapping_sub(k & 1),
                    c[1].wrapping_sub((k >> 1) & 1),
                    c[2].wrapping_sub(k >> 2),
                ];
                if o.iter().all(|&v| v < (1 << r)) {
                    origins.insert(o);
                }
            }
        }
        let (mut b6, mut b7) = (0, 0);
        for o in &origins {
            let n = (0..8u32)
                .filter(|&k| {
                    let c = [o[0] + (k & 1), o[1] + ((k >> 1) & 1), o[2] + (k >> 2)];
                    c.iter().all(|&v| v < (1 << r)) && set.contains(&morton(c))
                })
                .count();
            b6 += usize::from(n == 6);
            b7 += usize::from(n > 6);
        }
        println!("{r:>2} {:>8} {:>8} {:>8} {:>8}", on.len(), no_in, b6, b7);
    }
}
