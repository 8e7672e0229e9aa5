//! Fuzzes the `.pop` reader (`lodkit_particles::decode_prefix` and
//! `decode`): any bytes must give `Ok` or an error, never a panic, an abort
//! or a runaway allocation; whatever decodes is also triangulated level by
//! level.
#![no_main]

use libfuzzer_sys::fuzz_target;
use lodkit_particles::{DecodeOptions, TriangulateOptions, decode, decode_prefix};

fuzz_target!(|data: &[u8]| {
    let _ = decode(data, &DecodeOptions::default());
    if let Ok(d) = decode_prefix(data, &DecodeOptions::default()) {
        for r in 0..=d.finest_level() {
            let _ = d.triangulate(r, &TriangulateOptions::DEFAULT);
        }
    }
});
