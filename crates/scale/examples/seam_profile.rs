//! Where an out-of-core result's error lies relative to the block cuts:
//! `cargo run --release -p lodkit-scale --example seam_profile -- IN.ply OUT.ply G`
//! measures every input vertex's distance to OUT's surface and bins it by
//! its distance to the nearest cut plane of the `G³` grid over IN's box (in
//! block sides), so errors concentrated along the seams show up as a hot
//! first bin.

use lodkit_mesh::metrics::SurfaceIndex;
use rayon::prelude::*;

fn main() -> Result<(), String> {
    let a: Vec<String> = std::env::args().collect();
    if a.len() != 4 {
        return Err("usage: seam_profile IN.ply OUT.ply G".into());
    }
    let load =
        |p: &str| lodkit_mesh::io::load_mesh(std::path::Path::new(p)).map_err(|e| e.to_string());
    let (input, out) = (load(&a[1])?, load(&a[2])?);
    let g: f32 = a[3].parse().map_err(|e| format!("G: {e}"))?;
    let (mut lo, mut hi) = (input.positions[0], input.positions[0]);
    for p in &input.positions {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let cell = (hi - lo) / g;
    let idx = SurfaceIndex::new(&out).map_err(|e| e.to_string())?;
    const EDGES: [f32; 6] = [0.0, 0.01, 0.03, 0.1, 0.2, 0.51];
    let bins = input
        .positions
        .par_iter()
        .map(|&p| {
            let q = (p - lo) / cell;
            // Distance to the nearest interior cut plane, in block sides.
            let seam = q
                .to_array()
                .iter()
                .map(|&x| {
                    let k = x.round().clamp(1.0, g - 1.0);
                    (x - k).abs()
                })
                .fold(f32::MAX, f32::min);
            let b = EDGES
                .windows(2)
                .position(|w| seam < w[1])
                .unwrap_or(EDGES.len() - 2);
            (b, idx.distance(p) as f64)
        })
        .fold(
            || vec![(0u64, 0f64, 0f64); EDGES.len() - 1],
            |mut acc, (b, d)| {
                acc[b].0 += 1;
                acc[b].1 += d;
                acc[b].2 = acc[b].2.max(d);
                acc
            },
        )
        .reduce(
            || vec![(0u64, 0f64, 0f64); EDGES.len() - 1],
            |mut x, y| {
                for (a, b) in x.iter_mut().zip(y) {
                    a.0 += b.0;
                    a.1 += b.1;
                    a.2 = a.2.max(b.2);
                }
                x
            },
        );
    println!("seam distance (block sides)   vertices        mean         max");
    for (i, (n, s, m)) in bins.iter().enumerate() {
        println!(
            "[{:.2}, {:.2})               {:>10}  {:.4e}  {:.4e}",
            EDGES[i],
            EDGES[i + 1],
            n,
            s / (*n).max(1) as f64,
            m
        );
    }
    Ok(())
}
