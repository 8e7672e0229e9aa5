//! Checks that two `.mco` files draw the same meshes: the same LOD count
//! and accumulation table, and at LOD numbers spread over the whole range
//! the same triangles — compared by their vertices' positions, normals and
//! colours, so vertex and node numbering may differ. For speed work that
//! reorders the build's arrays without meaning to change its output (the
//! files are then not byte-identical, and `mco_build_driver`'s CRC cannot tell).
//!
//! ```text
//! MCO_OUT=/tmp/a.mco cargo run --release -p lodkit-bench --example mco_build_driver -- 640000 1
//! # … change the build …
//! MCO_OUT=/tmp/b.mco cargo run --release -p lodkit-bench --example mco_build_driver -- 640000 1
//! cargo run --release -p lodkit-bench --example mco_compare_models -- /tmp/a.mco /tmp/b.mco
//! ```

use std::path::Path;
use std::process::ExitCode;

use lodkit_mco::McoModel;

/// A triangle as its corners' bits (position, normal, colour), rotated so
/// the smallest corner comes first (orientation kept).
type Corner = ([u32; 3], [u32; 3], [u8; 4]);

fn triangles(m: &McoModel, k: usize) -> Vec<[Corner; 3]> {
    let mut idx = Vec::new();
    m.extract_lod(k, &mut idx);
    let (positions, normals, colors) = (m.positions(), m.normals(), m.colors());
    let mut out: Vec<[Corner; 3]> = idx
        .chunks_exact(3)
        .map(|t| {
            let c: [Corner; 3] = std::array::from_fn(|j| {
                let i = t[j] as usize;
                (
                    positions[i].to_array().map(f32::to_bits),
                    normals[i].to_array().map(f32::to_bits),
                    colors[i],
                )
            });
            let r = (0..3).min_by_key(|&j| c[j]).expect("three corners");
            [c[r], c[(r + 1) % 3], c[(r + 2) % 3]]
        })
        .collect();
    out.sort_unstable();
    out
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().collect();
    if args.len() != 3 {
        eprintln!("usage: mco_compare_models A.mco B.mco");
        return ExitCode::FAILURE;
    }
    let a = McoModel::load(Path::new(&args[1])).expect("the first model");
    let b = McoModel::load(Path::new(&args[2])).expect("the second model");
    let acc = |m: &McoModel| {
        (0..=m.max_lod())
            .map(|k| m.triangles_at_lod(k))
            .collect::<Vec<_>>()
    };
    if a.max_lod() != b.max_lod() || acc(&a) != acc(&b) {
        println!(
            "different LOD tables: {} vs {} LOD numbers",
            a.max_lod(),
            b.max_lod()
        );
        return ExitCode::FAILURE;
    }
    let n = a.max_lod();
    let mut ks: Vec<usize> = (0..=64).map(|s| s * n / 64).collect();
    ks.extend([1, 2, 3, n.saturating_sub(1)]);
    ks.sort_unstable();
    ks.dedup();
    for &k in &ks {
        let (ta, tb) = (triangles(&a, k), triangles(&b, k));
        if ta != tb {
            let diff = ta.iter().zip(&tb).filter(|(x, y)| x != y).count();
            println!(
                "LOD {k}: {} vs {} triangles, {diff} differ",
                ta.len(),
                tb.len()
            );
            return ExitCode::FAILURE;
        }
    }
    println!(
        "same meshes at {} LOD numbers of {n} ({} vs {} vertices)",
        ks.len(),
        a.positions().len(),
        b.positions().len()
    );
    ExitCode::SUCCESS
}
