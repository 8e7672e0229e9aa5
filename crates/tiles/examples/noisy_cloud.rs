//! Writes a deterministic test cloud as binary PLY: `N` points on a
//! sphere of radius 1 with bumps and fine noise, coloured by position
//! (`x y z` float, `red green blue` uchar; 15 B a point). The benchmark
//! input of `bench/tiles_points.sh`.
//!
//! Usage: `cargo run --release -p lodkit-tiles --example noisy_cloud -- N OUT.ply`

use std::io::{BufWriter, Write};

/// SplitMix64: the same stream on every machine.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn main() -> std::io::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let (Some(n), Some(out)) = (args.get(1).and_then(|s| s.parse::<u64>().ok()), args.get(2))
    else {
        eprintln!("usage: noisy_cloud N OUT.ply");
        std::process::exit(2);
    };
    let mut w = BufWriter::with_capacity(1 << 20, std::fs::File::create(out)?);
    write!(
        w,
        "ply\nformat binary_little_endian 1.0\nelement vertex {n}\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n"
    )?;
    let mut rng = Rng(7);
    for _ in 0..n {
        // A uniform direction, a radius with bumps and noise.
        let z = 2.0 * rng.unit() - 1.0;
        let a = std::f64::consts::TAU * rng.unit();
        let s = (1.0 - z * z).sqrt();
        let (x, y) = (s * a.cos(), s * a.sin());
        let r =
            1.0 + 0.1 * (5.0 * x).sin() * (4.0 * y).cos() * (3.0 * z).sin() + 0.002 * rng.unit();
        let p = [x * r, y * r, z * r];
        for c in p {
            w.write_all(&(c as f32).to_le_bytes())?;
        }
        let rgb = p.map(|c| ((c * 0.5 + 0.5).clamp(0.0, 1.0) * 255.0) as u8);
        w.write_all(&rgb)?;
    }
    w.flush()
}
