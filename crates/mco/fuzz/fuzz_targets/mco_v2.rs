//! Fuzzes the `.mco` version-2 reader (`McoModel::from_bytes`,
//! `McoModel::from_prefix`, `McoStream`): whole files,
//! prefixes and the streaming reader fed in pieces. Any bytes must give
//! `Ok` or an error, never a panic, an abort or a runaway allocation; a
//! model that decodes (whole or a prefix) must extract at any LOD number,
//! budget and view without panicking.
//! Run: `cargo +nightly fuzz run mco_v2 corpus/mco_v2` in this directory.
//! Seeds: any `.mco` written by `lodkit mco build` (version 2). Half the
//! inputs (first byte odd) get the header's and every chunk's checksum
//! fixed up before decoding, so mutations reach the structural checks
//! instead of all failing a CRC; the second byte picks the piece size fed
//! to the stream.
#![no_main]

use libfuzzer_sys::fuzz_target;
use lodkit_mco::{McoModel, McoStream};

/// Bytes of the version-2 header and of a chunk head (`docs/formats/mco.md`).
const HEADER_BYTES: usize = 104;
const CHUNK_HEAD_BYTES: usize = 12;

fn fix_checksums(b: &mut [u8]) {
    if b.len() < HEADER_BYTES {
        return;
    }
    let crc = crc32fast::hash(&b[..HEADER_BYTES - 4]);
    b[HEADER_BYTES - 4..HEADER_BYTES].copy_from_slice(&crc.to_le_bytes());
    let mut at = HEADER_BYTES;
    while at + CHUNK_HEAD_BYTES <= b.len() {
        let len = u32::from_le_bytes(b[at..at + 4].try_into().unwrap()) as usize;
        let Some(end) = (at + CHUNK_HEAD_BYTES)
            .checked_add(len)
            .filter(|&e| e <= b.len())
        else {
            break;
        };
        let crc = crc32fast::hash(&b[at + CHUNK_HEAD_BYTES..end]);
        b[at + 4..at + 8].copy_from_slice(&crc.to_le_bytes());
        at = end;
    }
}

fn exercise(m: &McoModel) {
    let mut idx = Vec::new();
    for k in [0, 1, m.max_lod() / 2, m.max_lod(), usize::MAX] {
        m.extract_lod(k, &mut idx);
        m.extract_lod_traversal(k, &mut idx);
    }
    m.extract_triangles(1000, &mut idx);
    let cam = lodkit_mco::Camera::looking_at([0.0, 0.0, 5.0].into(), [0.0; 3].into());
    m.extract_view(&cam, 1.0, &mut idx);
    // A viewer's kept cut: frame-coherent state carried across cameras
    // (the incremental closure and the re-emission from the last frame),
    // each cut equal to a fresh one.
    let mut kept = lodkit_mco::ViewCut::new();
    for (i, tol) in [(0u8, 1.0f32), (1, 1.0), (2, 0.25), (3, 4.0)] {
        let a = f32::from(i) * 0.7;
        let cam = lodkit_mco::Camera::looking_at(
            [5.0 * a.sin(), 0.5, 5.0 * a.cos()].into(),
            [0.0; 3].into(),
        );
        let cut = kept.update(m, &cam, tol).to_vec();
        m.extract_view(&cam, tol, &mut idx);
        assert_eq!(cut, idx, "a kept cut differs from a fresh one");
    }
}

fuzz_target!(|data: &[u8]| {
    let mut bytes = data.to_vec();
    let piece = bytes.get(1).map_or(64, |&b| 1 + b as usize * 16);
    if bytes.len() > 8 && bytes[0] & 1 == 1 {
        bytes[..8].copy_from_slice(b"LODKMCO\0");
        fix_checksums(&mut bytes);
    }
    if let Ok(m) = McoModel::from_bytes(&bytes) {
        exercise(&m);
    }
    if let Ok(p) = McoModel::from_prefix(&bytes) {
        exercise(&p.model);
    }
    let mut s = McoStream::new();
    for part in bytes.chunks(piece) {
        match s.push(part) {
            Ok(true) => {
                if let Some(m) = s.model() {
                    exercise(&m);
                }
            }
            Ok(false) => {}
            Err(_) => break,
        }
    }
});
