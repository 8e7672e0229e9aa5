//! Fuzzes the image-set readers of `lodkit_particles::silhouette`: NeRF
//! `transforms.json`, the COLMAP text model (`cameras.txt`, NUL,
//! `images.txt`), the PNG / JPEG decoder and its header-only size (what
//! the pixel budget is charged from, which must agree with the decoded
//! size), chosen by the first byte.
//! Any bytes must give `Ok` or an error, never a panic, an abort or a
//! runaway allocation.
#![no_main]

use libfuzzer_sys::fuzz_target;
use lodkit_particles::silhouette::{calibration, images};

fuzz_target!(|data: &[u8]| {
    let Some((&kind, rest)) = data.split_first() else {
        return;
    };
    match kind % 4 {
        0 => {
            let _ = calibration::parse_for_fuzzing(true, rest);
        }
        1 => {
            let _ = calibration::parse_for_fuzzing(false, rest);
        }
        2 => {
            let _ = images::decode_for_fuzzing(rest);
        }
        _ => {
            if let (Ok(size), Ok(decoded)) =
                (images::image_size(rest), images::decode_for_fuzzing(rest))
            {
                assert_eq!(size, decoded, "the header size is not the decoded size");
            }
        }
    }
});
