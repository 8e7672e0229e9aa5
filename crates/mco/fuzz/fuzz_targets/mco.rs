//! Fuzzes `model_file::decode`: any bytes must give `Ok` or an error, never
//! a panic, an abort or a runaway allocation; a model that decodes must
//! extract at any LOD number and any budget without panicking.
//! Run: `cargo +nightly fuzz run mco` in this directory. Seeds: any `.mco`
//! written by `lodkit mco build` (the checksum makes blind mutations fail
//! early; libFuzzer's CMP tracing gets past it).
#![no_main]

use libfuzzer_sys::fuzz_target;
use lodkit_mco::model_file::decode;

fuzz_target!(|data: &[u8]| {
    if let Ok(m) = decode(data) {
        let mut idx = Vec::new();
        for k in [0, 1, m.max_lod() / 2, m.max_lod(), usize::MAX] {
            m.extract_lod(k, &mut idx);
        }
        m.extract_triangles(1000, &mut idx);
        let cam = lodkit_mco::Camera::looking_at([0.0, 0.0, 5.0].into(), [0.0; 3].into());
        m.extract_view(&cam, 1.0, &mut idx);
    }
});
