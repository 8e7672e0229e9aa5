//! Fuzzes `McoModel::from_bytes`: any bytes must give `Ok` or an error, never
//! a panic, an abort or a runaway allocation; a model that decodes must
//! extract at any LOD number and any budget without panicking.
//! Run: `cargo +nightly fuzz run mco corpus/mco` in this directory. Seeds:
//! any `.mco` written by `lodkit mco build`. Half the inputs (first byte
//! odd) get their checksum fixed up before decoding, so mutations reach
//! the structural checks instead of all failing the CRC.
#![no_main]

use libfuzzer_sys::fuzz_target;
use lodkit_mco::McoModel;

fuzz_target!(|data: &[u8]| {
    let mut bytes = data.to_vec();
    if bytes.len() > 4 && bytes[0] & 1 == 1 {
        bytes[0] = b'L';
        let body = bytes.len() - 4;
        let crc = crc32fast::hash(&bytes[..body]);
        bytes[body..].copy_from_slice(&crc.to_le_bytes());
    }
    if let Ok(m) = McoModel::from_bytes(&bytes) {
        let mut idx = Vec::new();
        for k in [0, 1, m.max_lod() / 2, m.max_lod(), usize::MAX] {
            m.extract_lod(k, &mut idx);
            m.extract_lod_traversal(k, &mut idx);
        }
        m.extract_triangles(1000, &mut idx);
        let cam = lodkit_mco::Camera::looking_at([0.0, 0.0, 5.0].into(), [0.0; 3].into());
        m.extract_view(&cam, 1.0, &mut idx);
    }
});
