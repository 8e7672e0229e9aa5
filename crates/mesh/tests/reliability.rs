//! The readers' and writers' reliability rules, one test per rule: what reaches the
//! terminal is escaped, text readers skip a byte-order mark, lodkit reads
//! back what it writes (or refuses to write it), and the corpus files made
//! for these rules fail with the expected reason.

use std::path::{Path, PathBuf};

use glam::Vec3;
use lodkit_mesh::io::{self, Format, WriteOptions};
use lodkit_mesh::{Model, PointCloud, TriMesh};

fn corpus(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/malformed")
        .join(name)
}

/// The corpus files of the malformed-input probe classes, with what their one-line
/// error must say.
#[test]
fn probe_corpus_files_fail_for_the_right_reason() {
    let expected: &[(&str, &[&str])] = &[
        (
            "ply_ascii_values_across_lines.ply",
            &["line 10", "vertex 0"],
        ),
        (
            "ply_ascii_too_few_values.ply",
            &["line 11", "vertex 1", "too few"],
        ),
        (
            "ply_ascii_too_many_values.ply",
            &["line 11", "vertex 1", "'7' is extra"],
        ),
        (
            "ply_ascii_vertex_count_too_small.ply",
            &["line 12", "face 0"],
        ),
        (
            "ply_ascii_vertex_count_too_large.ply",
            &["line 13", "vertex 3"],
        ),
        ("ply_ascii_extra_lines.ply", &["line 14", "more data lines"]),
        (
            "ply_face_two_indices.ply",
            &["line 13", "face 0", "at least 3"],
        ),
        ("ply_face_two_indices_binary.ply", &["face 0", "at least 3"]),
        ("ply_header_control_chars.ply", &["\\x1b[31mevil\\x07"]),
        (
            "gltf_buffer_uri_percent_absolute.gltf",
            &["/etc/passwd", "absolute"],
        ),
        (
            "gltf_buffer_uri_parent_dir.gltf",
            &["proc/self/environ", "'..'"],
        ),
        ("gltf_buffer_uri_percent_parent_dir.gltf", &["'..'"]),
        ("gltf_buffer_uri_file_scheme.gltf", &["file:", "URI"]),
        (
            "gltf_buffer_uri_percent_file_scheme.gltf",
            &["file:", "URI"],
        ),
        ("gltf_buffer_uri_device.gltf", &["/dev/zero", "absolute"]),
        (
            "glb_instancing_expands_past_limit.glb",
            &["expand 1026 stored vertices to 4206600", "over the limit"],
        ),
        (
            "obj_coordinate_beyond_range.obj",
            &["vertex 1 (1e30", "±1e18"],
        ),
        ("ply_coordinate_beyond_range.ply", &["vertex 2", "±1e18"]),
        (
            "ply_coordinate_beyond_range_binary.ply",
            &["vertex 2", "±1e18"],
        ),
        ("stl_binary_coordinate_beyond_range.stl", &["±1e18"]),
        ("stl_ascii_coordinate_beyond_range.stl", &["(1e20", "±1e18"]),
        (
            "xyz_coordinate_beyond_range.xyz",
            &["point 1 (1e19", "±1e18"],
        ),
        ("pts_coordinate_beyond_range.pts", &["point 1", "±1e18"]),
        (
            "gltf_coordinate_beyond_range.gltf",
            &["vertex 1 (1e30", "±1e18"],
        ),
        (
            "gltf_node_scale_beyond_range.gltf",
            &["vertex 1 (1e20", "±1e18"],
        ),
        (
            "conf_quaternion_overflows.conf",
            &["line 3", "cannot be normalised"],
        ),
        (
            "conf_quaternion_huge_component.conf",
            &["line 3", "cannot be normalised"],
        ),
        ("conf_quaternion_zero.conf", &["line 3", "zero length"]),
        (
            "conf_quaternion_nan.conf",
            &["line 3", "'nan' is not a finite number"],
        ),
        (
            "conf_quaternion_inf.conf",
            &["line 3", "'1e39' is not a finite number"],
        ),
        (
            "conf_translation_beyond_range.conf",
            &["line 3", "translation"],
        ),
    ];
    let mut failures = Vec::new();
    for (name, needles) in expected {
        let path = corpus(name);
        let loaded = if name.ends_with(".conf") {
            io::conf::load_scans(&path).map(|_| Model::Points(PointCloud::default()))
        } else {
            io::load(&path)
        };
        let msg = match loaded {
            Ok(m) => {
                failures.push(format!("{name}: accepted as a {}", m.kind()));
                continue;
            }
            Err(e) => e.to_string(),
        };
        let raw_control = msg.chars().any(|c| c.is_control());
        if raw_control || !msg.contains(name) || needles.iter().any(|n| !msg.contains(n)) {
            failures.push(format!("{name}: {msg:?} should contain {needles:?}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A file name with terminal control bytes is escaped in the message.
#[test]
fn file_names_are_escaped_in_errors() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("evil\x1b]0;title\x07\nname.ply");
    let msg = io::load(&path).unwrap_err().to_string();
    assert!(!msg.chars().any(|c| c.is_control()), "{msg:?}");
    assert!(msg.contains("evil\\x1b]0;title\\x07\\x0aname.ply"), "{msg}");
    std::fs::write(&path, b"ply\nformat ascii 1.0\n\x1bevil\nend_header\n").unwrap();
    let msg = io::load(&path).unwrap_err().to_string();
    assert!(!msg.chars().any(|c| c.is_control()), "{msg:?}");
}

const BOM: &[u8] = b"\xEF\xBB\xBF";

fn with_bom(bytes: &[u8]) -> Vec<u8> {
    [BOM, bytes].concat()
}

/// Every text reader reads a file with a UTF-8 byte-order mark exactly as
/// the same file without it.
#[test]
fn a_byte_order_mark_changes_nothing() {
    let tri = TriMesh {
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
        faces: vec![[0, 1, 2]],
        ..Default::default()
    };
    let ascii = WriteOptions { ascii: true };
    let mut cases = vec![
        (
            Format::Obj,
            io::encode(Format::Obj, &Model::Mesh(tri.clone()), ascii).unwrap(),
        ),
        (
            Format::Ply,
            io::encode(Format::Ply, &Model::Mesh(tri.clone()), ascii).unwrap(),
        ),
        (
            Format::Stl,
            io::encode(Format::Stl, &Model::Mesh(tri.clone()), ascii).unwrap(),
        ),
        (
            Format::Ply,
            io::encode(Format::Ply, &Model::Mesh(tri.clone()), Default::default()).unwrap(),
        ),
        (Format::Xyz, b"0 0 0\n1 0 0\n".to_vec()),
        (Format::Pts, b"2\n0 0 0\n1 0 0\n".to_vec()),
    ];
    // A BOM before the first `v` used to swallow vertex 1 and shift faces.
    cases.push((
        Format::Obj,
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\n".to_vec(),
    ));
    for (f, bytes) in cases {
        let plain = io::decode(f, &bytes, None).unwrap();
        let marked = io::decode(f, &with_bom(&bytes), None)
            .unwrap_or_else(|e| panic!("{f:?} with a BOM: {e}"));
        assert_eq!(plain, marked, "{f:?}");
    }
    // `.conf`
    let conf = "bmesh a.ply 1 2 3 0 0 0 1\n";
    let plain = io::conf::read(conf).unwrap();
    let marked = io::conf::read(&format!("\u{feff}{conf}")).unwrap();
    assert_eq!(plain, marked);
}

/// lodkit reads back everything it writes, or refuses to write it: every
/// writable format, binary and ASCII, on the degenerate models.
#[test]
fn every_written_file_reads_back_or_is_refused() {
    let mesh = |positions: Vec<Vec3>, faces: Vec<[u32; 3]>| {
        Model::Mesh(TriMesh {
            positions,
            faces,
            ..Default::default()
        })
    };
    let cases = [
        ("empty mesh", mesh(vec![], vec![])),
        (
            "vertices, no faces",
            mesh(vec![Vec3::ZERO, Vec3::X], vec![]),
        ),
        (
            "one degenerate face",
            mesh(vec![Vec3::ONE; 3], vec![[0, 1, 2]]),
        ),
        (
            "zero-area mesh",
            mesh(
                vec![Vec3::ZERO, Vec3::X, Vec3::X * 2.0, Vec3::X * 3.0],
                vec![[0, 1, 2], [1, 2, 3]],
            ),
        ),
        ("empty point cloud", Model::Points(PointCloud::default())),
        (
            "range image without a sample",
            Model::Range(lodkit_mesh::RangeImage {
                cols: 2,
                rows: 1,
                points: vec![Vec3::ZERO; 2],
                valid: vec![false; 2],
                colors: None,
                pose: None,
            }),
        ),
        (
            "tiny mesh (1e-30)",
            mesh(
                vec![Vec3::ZERO, Vec3::X * 1e-30, Vec3::Y * 1e-30],
                vec![[0, 1, 2]],
            ),
        ),
        (
            "mesh beyond the coordinate bound",
            mesh(vec![Vec3::ZERO, Vec3::X * 1e19, Vec3::Y], vec![[0, 1, 2]]),
        ),
        (
            "denormal coordinates",
            mesh(
                vec![Vec3::ZERO, Vec3::X * 1e-40, Vec3::Y * 1e-40],
                vec![[0, 1, 2]],
            ),
        ),
    ];
    let formats = [
        Format::Ply,
        Format::Obj,
        Format::Stl,
        Format::Glb,
        Format::Xyz,
        Format::Pts,
    ];
    let mut failures = Vec::new();
    for (what, model) in &cases {
        for f in formats {
            for ascii in [false, true] {
                let Ok(bytes) = io::encode(f, model, WriteOptions { ascii }) else {
                    continue; // refused to write: allowed
                };
                if let Err(e) = io::decode(f, &bytes, None) {
                    failures.push(format!(
                        "{what} as {f:?} (ascii {ascii}): written, then {e}"
                    ));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[cfg(unix)]
mod unix {
    use super::*;
    use std::os::unix::fs::PermissionsExt as _;

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn write_atomic_keeps_permissions_and_never_follows_a_symlink() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("m.ply");
        std::fs::write(&out, b"old").unwrap();
        std::fs::set_permissions(&out, std::fs::Permissions::from_mode(0o640)).unwrap();
        io::write_atomic(&out, b"new").unwrap();
        assert_eq!(std::fs::read(&out).unwrap(), b"new");
        let mode = std::fs::metadata(&out).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode, 0o640);

        // The old fixed temp name, planted as a symlink, is not written through.
        let victim = dir.path().join("victim");
        std::fs::write(&victim, b"keep me").unwrap();
        let planted = dir
            .path()
            .join(format!(".n.ply.{}.tmp", std::process::id()));
        std::os::unix::fs::symlink(&victim, &planted).unwrap();
        // A symlink at the output is replaced, not written through.
        let link = dir.path().join("n.ply");
        std::os::unix::fs::symlink(&victim, &link).unwrap();
        io::write_atomic(&link, b"new").unwrap();
        assert_eq!(std::fs::read(&victim).unwrap(), b"keep me");
        assert!(!std::fs::symlink_metadata(&link).unwrap().is_symlink());
        assert_eq!(std::fs::read(&link).unwrap(), b"new");
        std::fs::remove_file(&planted).unwrap();
        assert_eq!(names(dir.path()), ["m.ply", "n.ply", "victim"]);

        // A failed write (the output is a directory) leaves nothing behind.
        let sub = dir.path().join("sub.ply");
        std::fs::create_dir(&sub).unwrap();
        std::fs::write(sub.join("x"), b"").unwrap();
        assert!(io::write_atomic(&sub, b"new").is_err());
        assert_eq!(names(dir.path()), ["m.ply", "n.ply", "sub.ply", "victim"]);
    }

    fn tiny_range_scan(dir: &Path, name: &str) {
        let ply = "ply\nformat ascii 1.0\nobj_info num_cols 1\nobj_info num_rows 1\n\
                   element vertex 1\nproperty float x\nproperty float y\nproperty float z\n\
                   element range_grid 1\nproperty list uchar int vertex_indices\nend_header\n\
                   0 0 0\n1 0\n";
        std::fs::write(dir.join(name), ply).unwrap();
    }

    /// `.conf` scan names follow the same rule as glTF URIs, and are read
    /// through the same door (no FIFO, no device).
    #[test]
    fn conf_scan_paths_stay_inside_the_folder_and_are_regular_files() {
        let dir = tempfile::tempdir().unwrap();
        tiny_range_scan(dir.path(), "ok.ply");
        let conf = dir.path().join("s.conf");
        std::fs::write(&conf, "\u{feff}bmesh ok.ply 0 0 0 0 0 0 1\n").unwrap();
        let scans = io::conf::load_scans(&conf).unwrap();
        assert_eq!(scans.len(), 1);
        for (line, needle) in [
            ("bmesh /dev/zero 0 0 0 0 0 0 1", "absolute"),
            ("bmesh ../ok.ply 0 0 0 0 0 0 1", "'..'"),
            ("bmesh file:ok.ply 0 0 0 0 0 0 1", "URI"),
        ] {
            std::fs::write(&conf, format!("{line}\n")).unwrap();
            let e = io::conf::load_scans(&conf).unwrap_err().to_string();
            assert!(e.contains("s.conf") && e.contains(needle), "{line}: {e}");
        }
        let fifo = dir.path().join("pipe.ply");
        if std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .is_ok_and(|s| s.success())
        {
            std::fs::write(&conf, "bmesh pipe.ply 0 0 0 0 0 0 1\n").unwrap();
            let e = io::conf::load_scans(&conf).unwrap_err().to_string();
            assert!(
                e.contains("pipe.ply") && e.contains("not a regular file"),
                "{e}"
            );
            // The `.conf` itself as a FIFO.
            let e = io::conf::load_scans(&fifo).unwrap_err().to_string();
            assert!(e.contains("not a regular file"), "{e}");
        }
    }

    /// An external glTF buffer that is a FIFO is refused, not waited on.
    #[test]
    fn a_gltf_buffer_that_is_a_fifo_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let src = std::fs::read_to_string(corpus("gltf_missing_buffer_file.gltf")).unwrap();
        let gltf = dir.path().join("m.gltf");
        std::fs::write(&gltf, src.replace("no_such_buffer.bin", "fifo.bin")).unwrap();
        let ok = std::process::Command::new("mkfifo")
            .arg(dir.path().join("fifo.bin"))
            .status()
            .is_ok_and(|s| s.success());
        if ok {
            let e = io::load(&gltf).unwrap_err().to_string();
            assert!(
                e.contains("m.gltf") && e.contains("not a regular file"),
                "{e}"
            );
        }
    }
}
