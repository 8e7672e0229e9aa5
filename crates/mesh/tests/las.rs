//! LAS/LAZ reading: exact coordinates through the origin, colours, bounded
//! counts, and the shared Autzen LAZ (skipped when absent).

use std::io::Cursor;
use std::path::PathBuf;

use lodkit_mesh::Model;
use lodkit_mesh::io::{self, Format};

/// A LAS file written by the `las` crate: `points` of (integer x, y, z)
/// at scale 0.01 and offset `offset`, format 2 (with colour) or 0.
fn las_bytes(points: &[[i32; 3]], colors: Option<&[[u16; 3]]>, offset: f64) -> Vec<u8> {
    let mut builder = las::Builder::from((1, 2));
    builder.point_format = las::point::Format::new(if colors.is_some() { 2 } else { 0 }).unwrap();
    let t = las::Transform {
        scale: 0.01,
        offset,
    };
    builder.transforms = las::Vector { x: t, y: t, z: t };
    let header = builder.into_header().unwrap();
    let mut w = las::Writer::new(Cursor::new(Vec::new()), header).unwrap();
    {
        for (i, p) in points.iter().enumerate() {
            let f = |k: usize| p[k] as f64 * 0.01 + offset;
            let color = colors.map(|c| las::Color::new(c[i][0], c[i][1], c[i][2]));
            w.write_point(las::Point {
                x: f(0),
                y: f(1),
                z: f(2),
                color,
                ..Default::default()
            })
            .unwrap();
        }
    }
    w.into_inner().unwrap().into_inner()
}

#[test]
fn las_positions_plus_origin_are_the_stored_values() {
    // Far from zero, as airborne scans are: f32 alone would round to 0.06.
    let pts = [
        [63_600_176, 84_893_520, 40_626],
        [63_717_922, 84_949_790, 52_051],
        [63_650_001, 84_920_003, 45_000],
    ];
    let bytes = las_bytes(&pts, None, 0.0);
    let l = io::decode_located(Format::Las, &bytes, None).unwrap();
    let origin = l.origin.expect("LAS has an origin");
    let Model::Points(p) = &l.model else {
        panic!("a cloud")
    };
    assert_eq!(p.len(), 3);
    assert!(p.colors.is_none() && p.normals.is_none());
    for (got, want) in p.positions.iter().zip(&pts) {
        for k in 0..3 {
            let abs = got[k] as f64 + origin[k];
            let stored = want[k] as f64 * 0.01;
            assert!((abs - stored).abs() < 1e-3, "{abs} vs {stored}");
        }
    }
    // The origin lies on the file's grid, at the box's centre.
    for o in origin {
        let i = o / 0.01;
        assert!((i - i.round()).abs() < 1e-6, "{o}");
    }
    // Plain decode gives the same (relative) cloud.
    assert_eq!(io::decode(Format::Las, &bytes, None).unwrap(), l.model);
}

#[test]
fn colours_that_fit_in_eight_bits_are_kept_else_shifted() {
    let pts = [[0, 0, 0], [100, 0, 0]];
    let narrow = las_bytes(&pts, Some(&[[40, 236, 7], [255, 0, 1]]), 10.0);
    let Model::Points(p) = io::decode(Format::Las, &narrow, None).unwrap() else {
        panic!()
    };
    assert_eq!(p.colors.unwrap(), [[40, 236, 7, 255], [255, 0, 1, 255]]);
    let wide = las_bytes(&pts, Some(&[[65535, 256, 0], [0x8000, 255, 0x1234]]), 10.0);
    let Model::Points(p) = io::decode(Format::Las, &wide, None).unwrap() else {
        panic!()
    };
    assert_eq!(p.colors.unwrap(), [[255, 1, 0, 255], [0x80, 0, 0x12, 255]]);
}

#[test]
fn a_lying_point_count_or_a_cut_file_is_a_one_line_error() {
    let pts: Vec<[i32; 3]> = (0..50).map(|i| [i, 2 * i, 3 * i]).collect();
    let good = las_bytes(&pts, None, 0.0);
    let mut cases: Vec<(String, Vec<u8>)> = Vec::new();
    // Legacy point count (u32 at 107) claims a billion points.
    let mut lying = good.clone();
    lying[107..111].copy_from_slice(&1_000_000_000u32.to_le_bytes());
    cases.push(("count".into(), lying));
    cases.push(("cut".into(), good[..good.len() - 7].to_vec()));
    cases.push(("header".into(), good[..200].to_vec()));
    let mut sig = good.clone();
    sig[0] = b'X';
    cases.push(("signature".into(), sig));
    let mut scale = good.clone();
    scale[131..139].copy_from_slice(&0f64.to_le_bytes()); // x scale
    cases.push(("scale".into(), scale));
    for (what, bytes) in cases {
        let e = io::decode(Format::Las, &bytes, None).unwrap_err().0;
        assert!(!e.contains('\n') && !e.is_empty(), "{what}: {e}");
    }
    // Every truncation and a sweep of byte flips: errors or clouds, no panic.
    for cut in (0..good.len()).step_by(17) {
        let _ = io::decode(Format::Las, &good[..cut], None);
    }
    for at in 0..good.len().min(400) {
        let mut b = good.clone();
        b[at] ^= 0xA5;
        let _ = io::decode(Format::Las, &b, None);
    }
}

fn shared_data() -> Option<PathBuf> {
    let p = std::env::var_os("LODKIT_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data"));
    p.is_dir().then_some(p)
}

#[test]
fn autzen_laz_reads_exactly_with_its_colours() {
    let Some(data) = shared_data() else {
        eprintln!("skipped: ../shared/data is absent");
        return;
    };
    let path = data.join("points/autzen_trim.laz");
    if !path.exists() {
        eprintln!("skipped: {} is absent", path.display());
        return;
    }
    let l = io::load_located(&path).unwrap();
    let origin = l.origin.unwrap();
    let Model::Points(p) = &l.model else {
        panic!("a cloud")
    };
    assert_eq!(p.len(), 110_000);
    let colors = p.colors.as_ref().expect("colours kept");
    // 16-bit values 40–236: kept as they are.
    let (lo, hi) = colors
        .iter()
        .flat_map(|c| &c[..3])
        .fold((255u8, 0u8), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    assert_eq!((lo, hi), (40, 236));
    // Bounds of README.md, to the centimetre: positions + origin.
    let mut min = [f64::MAX; 3];
    let mut max = [f64::MIN; 3];
    for q in &p.positions {
        for k in 0..3 {
            let v = q[k] as f64 + origin[k];
            min[k] = min[k].min(v);
            max[k] = max[k].max(v);
        }
    }
    let want_min = [636_001.76, 848_935.20, 406.26];
    let want_max = [637_179.22, 849_497.90, 520.51];
    for k in 0..3 {
        assert!((min[k] - want_min[k]).abs() < 0.01, "min {k}: {}", min[k]);
        assert!((max[k] - want_max[k]).abs() < 0.01, "max {k}: {}", max[k]);
    }
    // Every point within 0.01 ft of the stored integer × scale.
    let mut r = las::Reader::from_path(&path).unwrap();
    let all = r.read_all().unwrap();
    for ((q, (x, y)), z) in p.positions.iter().zip(all.x().zip(all.y())).zip(all.z()) {
        let want = [x, y, z];
        for k in 0..3 {
            let got = q[k] as f64 + origin[k];
            assert!((got - want[k]).abs() < 0.01, "{got} vs {}", want[k]);
        }
    }
    // A cut or flipped LAZ: one-line errors (or a cloud), never a panic.
    let bytes = std::fs::read(&path).unwrap();
    for cut in [
        0,
        100,
        226,
        227,
        1500,
        2000,
        5000,
        bytes.len() / 2,
        bytes.len() - 1,
    ] {
        if let Err(e) = io::decode(Format::Las, &bytes[..cut], None) {
            assert!(!e.0.contains('\n'), "{e}");
        }
    }
    for at in (0..2400)
        .step_by(29)
        .chain([bytes.len() - 3, bytes.len() / 3])
    {
        let mut b = bytes.clone();
        b[at] ^= 0x5A;
        if let Err(e) = io::decode(Format::Las, &b, None) {
            assert!(!e.0.contains('\n'), "{e}");
        }
    }
    let crs = l.crs.expect("the header names its CRS");
    assert!(
        crs.contains("Lambert_Conformal_Conic") && crs.contains("foot"),
        "{crs}"
    );
}
