//! Fuzzes the image-set readers of `lodkit_particles::silhouette`: NeRF
//! `transforms.json`, the COLMAP text model (`cameras.txt`, NUL,
//! `images.txt`) and the PNG / JPEG decoder, chosen by the first byte.
//! Any bytes must give `Ok` or an error, never a panic, an abort or a
//! runaway allocation.
#![no_main]

use libfuzzer_sys::fuzz_target;
use lodkit_particles::silhouette::{calibration, images};

fuzz_target!(|data: &[u8]| {
    let Some((&kind, rest)) = data.split_first() else {
        return;
    };
    match kind % 3 {
        0 => {
            let _ = calibration::parse_for_fuzzing(true, rest);
        }
        1 => {
            let _ = calibration::parse_for_fuzzing(false, rest);
        }
        _ => {
            let _ = images::decode_for_fuzzing(rest);
        }
    }
});
