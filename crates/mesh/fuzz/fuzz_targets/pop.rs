//! Fuzzes the `.pop` reader (`lodkit_particles::decode`): any bytes must
//! give `Ok` or an error, never a panic, an abort or a runaway allocation;
//! whatever decodes is also triangulated level by level.
#![no_main]

use libfuzzer_sys::fuzz_target;
use lodkit_particles::{DecodeOptions, TriangulateOptions, decode, triangulate};

fuzz_target!(|data: &[u8]| {
    if let Ok(d) = decode(data, &DecodeOptions::default()) {
        for r in 0..d.levels.len() {
            if let Ok(s) = d.surface(r as u8) {
                let _ = triangulate(&s, &TriangulateOptions::DEFAULT);
            }
        }
    }
});
