//! A virtual range scanner: ray-casts a mesh from several viewpoints into
//! range images, to reproduce the thesis's §4.4 experiment (scans from the
//! front, 45°, 90°, … of a model) on any mesh.
//!
//! Each view is an orthographic scanner (a laser-stripe scanner's parallel
//! rays) on a circle around the mesh's vertical (+y) axis: view `i` of `N`
//! looks at the bounding-box centre from azimuth `360° · i / N`, optionally
//! tilted by an elevation (alternately up and down with `alternate`). The image plane is a square as wide as the
//! bounding-box diagonal, so every view sees the whole model; rays are
//! cast through a `parry3d` BVH (the same kept crate `compare` uses).
//!
//! Sensor frame (what the range-grid PLY holds): x right, y up, the sensor
//! looking down −z, so surfaces facing the sensor have normals with
//! positive z — the Stanford scans' convention, which
//! [`crate::normals_estimation::range_image_samples`] relies on. The pose
//! maps sensor to world; the `.conf` written next to the scans stores it
//! as Stanford does (`bmesh FILE tx ty tz qx qy qz qw`, `world = R(q)ᵀ p +
//! t`), so `lodkit_mesh::io::conf::load_scans` reads the scans back posed.
//!
//! Noise (optional): Gaussian, along the ray, with the given standard
//! deviation in object units, from a seeded generator (deterministic).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use glam::{Mat3, Quat, Vec3};
use lodkit_mesh::{Pose, RangeImage, TriMesh};
use parry3d::query::{Ray, RayCast};
use rand_xoshiro::Xoshiro256PlusPlus;
use rand_xoshiro::rand_core::{Rng, SeedableRng};

use crate::{Error, Result};

/// Settings of the virtual range scanner ([`scan_mesh`]); the `Default`
/// is 8 views on the horizon, 256 × 256 samples, no noise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScanOptions {
    /// Number of views around the vertical axis.
    pub views: usize,
    /// Image width in samples (2..=8192).
    pub width: usize,
    /// Image height in samples (2..=8192).
    pub height: usize,
    /// Elevation of every view above the horizontal plane, degrees.
    pub elevation_deg: f32,
    /// Odd views look from below (−elevation) instead, so the views see
    /// both the top and the bottom of the model.
    pub alternate: bool,
    /// Standard deviation of the range noise (object units); 0 = none.
    pub noise: f32,
    /// Seed of the noise.
    pub seed: u64,
}

impl ScanOptions {
    /// The defaults: 8 views on the horizon, 256 × 256 samples, no noise.
    pub const DEFAULT: ScanOptions = ScanOptions {
        views: 8,
        width: 256,
        height: 256,
        elevation_deg: 0.0,
        alternate: false,
        noise: 0.0,
        seed: 1,
    };
}

impl Default for ScanOptions {
    fn default() -> Self {
        ScanOptions::DEFAULT
    }
}

/// Largest image side accepted (a guard against absurd allocations).
pub const MAX_SIDE: usize = 8192;

/// The sensor-to-world pose of view `i`.
pub fn view_pose(mesh_center: Vec3, i: usize, opts: &ScanOptions) -> Pose {
    let az = (i as f32 / opts.views.max(1) as f32) * std::f32::consts::TAU;
    let sign = if opts.alternate && i % 2 == 1 {
        -1.0
    } else {
        1.0
    };
    let el = sign * opts.elevation_deg.to_radians();
    // Direction from the centre towards the sensor = sensor +z.
    let z = Vec3::new(az.sin() * el.cos(), el.sin(), az.cos() * el.cos()).normalize();
    let up = if z.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
    let x = up.cross(z).normalize();
    let y = z.cross(x);
    Pose {
        rotation: Quat::from_mat3(&Mat3::from_cols(x, y, z)).normalize(),
        translation: mesh_center,
    }
}

/// Scans `mesh` (object units) from `opts.views` views around its
/// vertical axis (see the module docs): one posed range image per view,
/// in view order, each `width × height` samples with a validity mask.
/// Deterministic (the noise comes from `opts.seed`). Errors
/// ([`Error::Input`]): an empty mesh, no views, a side below 2 or above
/// 8192. Cost: one BVH ray cast per sample.
pub fn scan_mesh(mesh: &TriMesh, opts: &ScanOptions) -> Result<Vec<RangeImage>> {
    if opts.views == 0 || opts.width < 2 || opts.height < 2 {
        return Err(Error::Input(
            "a scan needs at least 1 view and 2×2 samples".into(),
        ));
    }
    if opts.width > MAX_SIDE || opts.height > MAX_SIDE {
        return Err(Error::Input(format!(
            "scan size {}x{} exceeds {MAX_SIDE} per side",
            opts.width, opts.height
        )));
    }
    if mesh.faces.is_empty() {
        return Err(Error::Input("the mesh has no faces to scan".into()));
    }
    mesh.validate()
        .map_err(|e| Error::Input(format!("cannot scan the mesh: {e}")))?;
    let shape = parry3d::shape::TriMesh::new(mesh.positions.clone(), mesh.faces.clone())
        .map_err(|e| Error::Input(format!("cannot index the mesh: {e}")))?;
    let bbox = mesh.bbox();
    let center = bbox.center();
    let diag = bbox.diagonal().max(1e-12);
    let pitch = diag / (opts.width.max(opts.height) - 1) as f32;
    let mut rng = Gauss::new(opts.seed);
    let mut out = Vec::with_capacity(opts.views);
    for v in 0..opts.views {
        let pose = view_pose(center, v, opts);
        let (w, h) = (opts.width, opts.height);
        let mut points = vec![Vec3::ZERO; w * h];
        let mut valid = vec![false; w * h];
        for row in 0..h {
            for col in 0..w {
                let x = (col as f32 - (w - 1) as f32 * 0.5) * pitch;
                let y = (row as f32 - (h - 1) as f32 * 0.5) * pitch;
                let origin_s = Vec3::new(x, y, diag);
                let ray = Ray::new(pose.apply(origin_s), pose.apply_vector(Vec3::NEG_Z));
                if let Some(t) = shape.cast_local_ray(&ray, 2.0 * diag, true) {
                    let noise = if opts.noise > 0.0 {
                        rng.next() * opts.noise
                    } else {
                        0.0
                    };
                    let cell = row * w + col;
                    points[cell] = Vec3::new(x, y, diag - t + noise);
                    valid[cell] = true;
                }
            }
        }
        out.push(RangeImage {
            cols: w,
            rows: h,
            points,
            valid,
            colors: None,
            pose: Some(pose),
        });
    }
    Ok(out)
}

/// A range image as a Stanford range-grid PLY (binary little endian): the
/// valid points as `vertex`, one `range_grid` cell per lattice position
/// listing 0 or 1 vertex. Points are in the sensor frame (no pose).
pub fn range_grid_ply(r: &RangeImage) -> Vec<u8> {
    let valid: Vec<usize> = (0..r.points.len()).filter(|&i| r.valid[i]).collect();
    let mut header = String::new();
    let _ = write!(
        header,
        "ply\nformat binary_little_endian 1.0\ncomment made by lodkit scan\nobj_info num_cols {}\nobj_info num_rows {}\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nelement range_grid {}\nproperty list uchar int vertex_indices\nend_header\n",
        r.cols,
        r.rows,
        valid.len(),
        r.points.len()
    );
    let mut out = header.into_bytes();
    for &i in &valid {
        for c in r.points[i].to_array() {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
    let mut next = 0i32;
    for i in 0..r.points.len() {
        if r.valid[i] {
            out.push(1);
            out.extend_from_slice(&next.to_le_bytes());
            next += 1;
        } else {
            out.push(0);
        }
    }
    out
}

/// A Stanford `.conf` line for a scan file and its pose.
pub fn conf_line(file: &str, pose: &Pose) -> String {
    let q = pose.rotation.conjugate();
    let t = pose.translation;
    format!(
        "bmesh {file} {} {} {} {} {} {} {}\n",
        t.x, t.y, t.z, q.x, q.y, q.z, q.w
    )
}

/// Writes `scans` as Stanford range-grid PLY files `{stem}_{i:03}.ply`
/// into `dir` (created if missing) plus `{stem}.conf` with their poses,
/// which [`crate::build_from_conf`] and `lodkit_mesh::io::conf` read back;
/// returns the written paths (the `.conf` last). Each file is written
/// atomically; errors name the file.
pub fn write_scans(dir: &Path, stem: &str, scans: &[RangeImage]) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).map_err(|e| lodkit_mesh::Error::io(dir, e))?;
    let mut conf = String::from("# written by lodkit scan: bmesh FILE tx ty tz qx qy qz qw\n");
    let mut paths = Vec::new();
    for (i, s) in scans.iter().enumerate() {
        let name = format!("{stem}_{i:03}.ply");
        let path = dir.join(&name);
        lodkit_mesh::io::write_atomic(&path, &range_grid_ply(s))?;
        conf.push_str(&conf_line(&name, &s.pose.unwrap_or(Pose::IDENTITY)));
        paths.push(path);
    }
    let conf_path = dir.join(format!("{stem}.conf"));
    lodkit_mesh::io::write_atomic(&conf_path, conf.as_bytes())?;
    paths.push(conf_path);
    Ok(paths)
}

/// Box–Muller normal deviates from a seeded xoshiro256++ generator.
struct Gauss(Xoshiro256PlusPlus);

impl Gauss {
    fn new(seed: u64) -> Self {
        Gauss(Xoshiro256PlusPlus::seed_from_u64(seed))
    }
    /// Uniform in (0, 1): 24 random bits, centred in their interval, so
    /// `ln` never sees 0.
    fn uniform(&mut self) -> f32 {
        ((self.0.next_u64() >> 40) as f32 + 0.5) / (1u64 << 24) as f32
    }
    fn next(&mut self) -> f32 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (std::f32::consts::TAU * v).cos()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scans_of_a_sphere_lie_on_it_and_round_trip_through_ply_and_conf() {
        let sphere = lodkit_mesh::shapes::icosphere(3);
        let opts = ScanOptions {
            views: 4,
            width: 32,
            height: 24,
            ..Default::default()
        };
        let scans = scan_mesh(&sphere, &opts).unwrap();
        assert_eq!(scans.len(), 4);
        for s in &scans {
            assert!(s.valid_count() > 100);
            let pose = s.pose.unwrap();
            for (p, _) in s.points.iter().zip(&s.valid).filter(|(_, v)| **v) {
                let w = pose.apply(*p);
                assert!((w.length() - 1.0).abs() < 0.02, "{w}");
                // Facing the sensor: z in the sensor frame is positive.
                assert!(p.z > 0.0);
            }
        }
        let dir = tempfile::tempdir().unwrap();
        let paths = write_scans(dir.path(), "sphere", &scans).unwrap();
        let back = lodkit_mesh::io::conf::load_scans(paths.last().unwrap()).unwrap();
        assert_eq!(back.len(), 4);
        for ((_, b), a) in back.iter().zip(&scans) {
            assert_eq!((b.cols, b.rows), (a.cols, a.rows));
            assert_eq!(b.valid, a.valid);
            let (pa, pb) = (a.pose.unwrap(), b.pose.unwrap());
            for (p, v) in a.points.iter().zip(&a.valid) {
                if *v {
                    assert!(pa.apply(*p).distance(pb.apply(*p)) < 1e-5);
                }
            }
        }
    }

    #[test]
    fn noise_is_deterministic_and_bad_sizes_are_errors() {
        let sphere = lodkit_mesh::shapes::icosphere(2);
        let opts = ScanOptions {
            views: 1,
            width: 16,
            height: 16,
            noise: 0.01,
            ..Default::default()
        };
        assert_eq!(
            scan_mesh(&sphere, &opts).unwrap(),
            scan_mesh(&sphere, &opts).unwrap()
        );
        let bad = ScanOptions { views: 0, ..opts };
        assert!(scan_mesh(&sphere, &bad).is_err());
        let huge = ScanOptions {
            width: MAX_SIDE + 1,
            ..opts
        };
        assert!(scan_mesh(&sphere, &huge).is_err());
    }
}
