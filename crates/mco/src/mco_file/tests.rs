//! Version 1 read back, and the loader's errors.

use super::v1::{HEADER_BYTES, encode};
use super::*;
use crate::pipeline::{Options, build_from_mesh};
use glam::Vec3;
use rand_xoshiro::Xoshiro256PlusPlus;
use rand_xoshiro::rand_core::{Rng, SeedableRng};

fn model() -> McoModel {
    build_from_mesh(
        &lodkit_mesh::shapes::icosphere(3),
        &Options {
            resolution: Some(12),
        },
    )
    .unwrap()
}

#[test]
fn round_trip_is_exact_and_deterministic() {
    let m = model();
    let bytes = encode(&m);
    assert_eq!(bytes, encode(&m));
    let back = decode(&bytes).unwrap();
    assert_eq!(back, m);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.mco");
    std::fs::write(&path, &bytes).unwrap();
    assert_eq!(load(&path).unwrap(), m);
}

#[test]
fn truncated_and_corrupted_files_are_clear_errors() {
    let bytes = encode(&model());
    for cut in [0, 7, 8, 40, HEADER_BYTES, bytes.len() / 2, bytes.len() - 1] {
        let e = decode(&bytes[..cut]).unwrap_err();
        assert!(!e.contains('\n'));
        assert!(
            e.contains("shorter") || e.contains("size mismatch") || e.contains("signature"),
            "{cut}: {e}"
        );
    }
    let mut flipped = bytes.clone();
    let at = bytes.len() / 3;
    flipped[at] ^= 0x10;
    assert!(decode(&flipped).unwrap_err().contains("checksum"));
    let mut version = bytes.clone();
    version[8] = 9;
    assert!(decode(&version).unwrap_err().contains("version 9"));
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.mco");
    std::fs::write(&path, &bytes[..100]).unwrap();
    let msg = load(&path).unwrap_err().to_string();
    assert!(msg.starts_with(&path.display().to_string()), "{msg}");
}

/// Mutations with a re-computed checksum reach the semantic checks:
/// none may panic, and every accepted model must extract safely.
#[test]
fn mutated_files_never_panic() {
    let m = model();
    let bytes = encode(&m);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(0x2545_f491_4f6c_dd1d);
    let mut next = || rng.next_u64();
    let mut idx = Vec::new();
    for _ in 0..3000 {
        let mut b = bytes.clone();
        let body = b.len() - 4;
        for _ in 0..1 + next() % 4 {
            let at = (next() as usize) % body;
            b[at] = next() as u8;
        }
        let crc = crc32fast::hash(&b[..body]);
        b[body..].copy_from_slice(&crc.to_le_bytes());
        if let Ok(back) = decode(&b) {
            for k in [0, 1, back.max_lod() / 2, back.max_lod()] {
                back.extract_lod(k, &mut idx);
            }
            back.extract_triangles(100, &mut idx);
            let cam = crate::Camera::looking_at(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO);
            back.extract_view(&cam, 1.0, &mut idx);
        }
    }
}
