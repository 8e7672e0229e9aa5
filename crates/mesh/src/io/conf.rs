//! Stanford `.conf` alignment files (Scanalyze's format).
//!
//! One scan per line: `bmesh FILE tx ty tz qx qy qz qw` — a translation and
//! a unit quaternion with `w` last. For the Stanford data the scan-to-world
//! transform is `world = R(q)ᵀ · p + t`: rotate by the quaternion's
//! conjugate, then translate (checked numerically against the bunny
//! reconstruction). `mesh` lines are read like `bmesh`; `camera` lines, blank
//! lines and `#` comments are ignored; any other keyword is an error, so a
//! scan is never dropped silently. `FILE` is relative to the `.conf` file's
//! folder and may not contain whitespace.

use std::path::{Path, PathBuf};

use glam::{Quat, Vec3};

use crate::error::{Error, ParseError, Result};
use crate::mesh::{Model, Pose, RangeImage};
use crate::parse_err;

/// One `bmesh FILE tx ty tz qx qy qz qw` line.
#[derive(Debug, Clone, PartialEq)]
pub struct ConfEntry {
    /// The scan's file name, relative to the `.conf` file's directory.
    pub file: String,
    /// Scan-to-world transform.
    pub pose: Pose,
}

/// Parses a `.conf` file's text into its scan entries, in file order.
///
/// Fails with the line number on a malformed `bmesh`/`mesh` line (not
/// exactly 8 fields after the keyword, a value that is not a finite
/// number, a zero quaternion or one whose length overflows `f32`, a
/// translation beyond [`super::MAX_COORDINATE`]) or an unknown keyword. The quaternion is
/// normalised before its conjugate becomes `pose.rotation`.
pub fn read(text: &str) -> Result<Vec<ConfEntry>, ParseError> {
    let text = text.strip_prefix('\u{FEFF}').unwrap_or(text);
    let mut entries = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line_no = i + 1;
        let mut words = line.split_ascii_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        match keyword {
            "bmesh" | "mesh" => {}
            "camera" => continue,
            k if k.starts_with('#') => continue,
            k => {
                let shown: String = k.chars().take(40).collect();
                return Err(parse_err!("line {line_no}: unknown keyword '{shown}'"));
            }
        }
        let fields: Vec<&str> = words.collect();
        let [file, numbers @ ..] = fields.as_slice() else {
            return Err(parse_err!(
                "line {line_no}: {keyword} line has no file name"
            ));
        };
        if numbers.len() != 7 {
            return Err(parse_err!(
                "line {line_no}: expected '{keyword} FILE tx ty tz qx qy qz qw', found {} numbers",
                numbers.len()
            ));
        }
        let mut v = [0.0f32; 7];
        for (out, word) in v.iter_mut().zip(numbers) {
            *out = word
                .parse::<f32>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| {
                    let shown: String = word.chars().take(40).collect();
                    parse_err!("line {line_no}: '{shown}' is not a finite number")
                })?;
        }
        let [tx, ty, tz, qx, qy, qz, qw] = v;
        let q = Quat::from_xyzw(qx, qy, qz, qw);
        let len = q.length();
        // Finite components can still overflow the squared length (any
        // component beyond ~1.8e19 makes `len` infinite and `q / len` zero,
        // a rotation that collapses the scan to a point): the normalised
        // quaternion must be a unit quaternion, or the line is refused.
        let unit = q / len;
        if len <= 1e-6 {
            return Err(parse_err!(
                "line {line_no}: rotation quaternion ({qx} {qy} {qz} {qw}) has zero length"
            ));
        }
        if !len.is_finite() || !unit.is_finite() || (unit.length() - 1.0).abs() > 1e-3 {
            return Err(parse_err!(
                "line {line_no}: rotation quaternion ({qx} {qy} {qz} {qw}) cannot be normalised \
                 (its length overflows 32-bit floats)"
            ));
        }
        let translation = Vec3::new(tx, ty, tz);
        if translation.abs().max_element() > super::MAX_COORDINATE {
            return Err(parse_err!(
                "line {line_no}: translation ({tx:e} {ty:e} {tz:e}) is beyond the supported \
                 coordinate range of ±{:e}",
                super::MAX_COORDINATE
            ));
        }
        entries.push(ConfEntry {
            file: (*file).to_string(),
            pose: Pose {
                rotation: unit.conjugate(),
                translation,
            },
        });
    }
    Ok(entries)
}

/// Loads every scan a `.conf` file lists, as range images with their pose
/// set, paired with the scan's path (the `.conf` folder joined with FILE).
///
/// Fails if the `.conf` cannot be read or parsed, if a scan name is not a
/// relative path inside the `.conf`'s folder
/// ([`super::input::resolve_inside`]: no `..`, no absolute path, no URI),
/// or if a scan cannot be loaded or is not a range image (a PLY with a
/// `range_grid` element). The `.conf` and every scan are read through
/// [`super::input::read_file`] (regular files only, size-capped).
pub fn load_scans(conf_path: &Path) -> Result<Vec<(PathBuf, RangeImage)>> {
    let bytes = super::input::read_file(conf_path)?;
    let text = std::str::from_utf8(super::input::strip_bom(&bytes)).map_err(|e| {
        Error::parse(
            conf_path,
            parse_err!("not a text file: invalid UTF-8 at byte {}", e.valid_up_to()),
        )
    })?;
    let entries = read(text).map_err(|e| Error::parse(conf_path, e))?;
    let dir = conf_path.parent().unwrap_or(Path::new(""));
    entries
        .into_iter()
        .map(|entry| {
            let path = super::input::resolve_inside(dir, &entry.file)
                .map_err(|why| Error::parse(conf_path, parse_err!("scan {why}")))?;
            match super::load(&path)? {
                Model::Range(mut scan) => {
                    scan.pose = Some(entry.pose);
                    Ok((path, scan))
                }
                other => Err(Error::unsupported(
                    &path,
                    format!(
                        "holds a {}, but {} lists range scans (a PLY with a range_grid element)",
                        other.kind(),
                        conf_path.display()
                    ),
                )),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::TriMesh;

    const SAMPLE: &str = "camera -0.0172 -0.0936 -0.734  -0.0461723 0.970603 -0.235889 0.0124573\n\
        bmesh a.ply 0 0 0 0 0 0 1\n\
        \n\
        # a comment\n\
        bmesh b.ply 1 2 3 0 0.70710678 0 0.70710678\r\n";

    #[test]
    fn parses_bmesh_lines_into_scan_to_world_poses() {
        let e = read(SAMPLE).unwrap();
        assert_eq!(e.len(), 2);
        assert_eq!(e[0].file, "a.ply");
        assert_eq!(
            e[0].pose.apply(Vec3::new(1.0, 2.0, 3.0)),
            Vec3::new(1.0, 2.0, 3.0)
        );
        assert_eq!(e[1].file, "b.ply");
        assert_eq!(e[1].pose.translation, Vec3::new(1.0, 2.0, 3.0));
        // q is +90° about y, which maps x to -z; the pose applies its
        // conjugate (x to +z), then translates.
        let p = e[1].pose.apply(Vec3::X);
        assert!((p - Vec3::new(1.0, 2.0, 4.0)).length() < 1e-6, "{p}");
        assert!((e[1].pose.rotation.length() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn quaternions_are_normalised() {
        let e = read("bmesh a.ply 0 0 0 0 0 0 2\n").unwrap();
        assert_eq!(e[0].pose.rotation, Quat::IDENTITY);
    }

    #[test]
    fn malformed_lines_are_errors_with_their_line_number() {
        let cases = [
            (
                "bmesh a.ply 0 0 0 0 0 1\n",
                "line 1: expected 'bmesh FILE tx ty tz qx qy qz qw', found 6 numbers",
            ),
            ("\nbmesh\n", "line 2: bmesh line has no file name"),
            (
                "bmesh a.ply 0 0 x 0 0 0 1\n",
                "line 1: 'x' is not a finite number",
            ),
            (
                "bmesh a.ply 0 0 nan 0 0 0 1\n",
                "'nan' is not a finite number",
            ),
            (
                "bmesh a.ply 0 0 0 0 0 0 0\n",
                "line 1: rotation quaternion (0 0 0 0) has zero length",
            ),
            (
                "bmesh a.ply 0 0 0 0 0 0 1\nbmesh b.ply 0 0 0 1e30 0 0 1\n",
                "line 2: rotation quaternion (1000000000000000000000000000000 0 0 1) cannot be normalised",
            ),
            (
                "bmesh a.ply 0 0 0 3e19 3e19 3e19 3e19\n",
                "line 1: rotation quaternion",
            ),
            (
                "bmesh a.ply 0 0 0 1e-30 0 0 0\n",
                "line 1: rotation quaternion (0.000000000000000000000000000001 0 0 0) has zero length",
            ),
            (
                "bmesh a.ply 0 0 2e18 0 0 0 1\n",
                "line 1: translation (0e0 0e0 2e18) is beyond the supported coordinate range",
            ),
            (
                "bmesh a.ply 0 0 0 0 0 0 inf\n",
                "line 1: 'inf' is not a finite number",
            ),
            (
                "camera 1 2 3\nscan a.ply\n",
                "line 2: unknown keyword 'scan'",
            ),
        ];
        for (text, needle) in cases {
            let err = read(text).unwrap_err().0;
            assert!(err.contains(needle), "{err:?} does not contain {needle:?}");
        }
    }

    #[test]
    fn load_scans_sets_poses_and_refuses_non_range_files() {
        let dir = tempfile::tempdir().unwrap();
        let scan = "ply\nformat ascii 1.0\nobj_info num_cols 2\nobj_info num_rows 1\n\
            element vertex 1\nproperty float x\nproperty float y\nproperty float z\n\
            element range_grid 2\nproperty list uchar int vertex_indices\nend_header\n\
            1 0 0\n0\n1 0\n";
        std::fs::write(dir.path().join("a.ply"), scan).unwrap();
        std::fs::write(dir.path().join("b.ply"), scan).unwrap();
        let conf = dir.path().join("scans.conf");
        std::fs::write(&conf, SAMPLE).unwrap();
        let scans = load_scans(&conf).unwrap();
        assert_eq!(scans.len(), 2);
        assert_eq!(scans[1].0, dir.path().join("b.ply"));
        let world = scans[1].1.to_point_cloud().positions;
        assert_eq!(world.len(), 1);
        assert!((world[0] - Vec3::new(1.0, 2.0, 4.0)).length() < 1e-6);

        let mesh = TriMesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]);
        crate::io::save_mesh(&dir.path().join("a.ply"), &mesh, Default::default()).unwrap();
        let err = load_scans(&conf).unwrap_err().to_string();
        assert!(err.contains("a.ply: holds a mesh"), "{err}");
        let err = load_scans(&dir.path().join("missing.conf"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("missing.conf"), "{err}");
    }

    /// Median distance from every `step`-th point to its nearest neighbour
    /// in `cloud` (brute force; fine for a few hundred queries).
    fn median_nn(points: &[Vec3], step: usize, cloud: &[Vec3]) -> f32 {
        let mut d: Vec<f32> = points
            .iter()
            .step_by(step)
            .map(|p| {
                cloud
                    .iter()
                    .map(|q| p.distance_squared(*q))
                    .fold(f32::INFINITY, f32::min)
                    .sqrt()
            })
            .collect();
        d.sort_by(f32::total_cmp);
        d[d.len() / 2]
    }

    /// The Stanford bunny scans, aligned by `bun.conf`, lie on the
    /// reconstruction; with the quaternion applied un-conjugated they don't.
    #[test]
    fn stanford_scans_align_with_the_reconstruction() {
        let data =
            std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data");
        let conf = data.join("range/stanford_bunny/bun.conf");
        if !conf.exists() {
            eprintln!("skipping: {} is absent", conf.display());
            return;
        }
        let scans = load_scans(&conf).unwrap();
        assert_eq!(scans.len(), 10);
        let reference = crate::io::load_mesh(&data.join("meshes/stanford_bunny.ply")).unwrap();
        let (_, bun045) = scans
            .iter()
            .find(|(p, _)| p.ends_with("bun045.ply"))
            .unwrap();
        let aligned = bun045.to_point_cloud().positions;
        let step = aligned.len() / 300;
        let good = median_nn(&aligned, step, &reference.positions);
        let mut wrong = bun045.clone();
        let pose = wrong.pose.as_mut().unwrap();
        pose.rotation = pose.rotation.conjugate();
        let bad = median_nn(
            &wrong.to_point_cloud().positions,
            step,
            &reference.positions,
        );
        eprintln!("bun045 median NN distance: aligned {good} m, un-conjugated {bad} m");
        // Reconstruction vertices are ~0.5-1 mm apart.
        assert!(
            good < 0.001,
            "aligned bun045 is {good} m from the reconstruction"
        );
        assert!(
            bad > 10.0 * good,
            "the wrong rotation should be far off ({bad} m)"
        );
    }
}
