//! Fuzzes the calibration readers of `lodkit_mesh::io::cameras`: NeRF
//! `transforms.json`, the COLMAP text model (`cameras.txt`, NUL,
//! `images.txt`), and the PNG / JPEG decoder of `lodkit_mesh::image` with
//! its header-only size (what the pixel budget is charged from, which must
//! agree with the decoded size), chosen by the first byte.
//! Any bytes must give `Ok` or an error, never a panic, an abort or a
//! runaway allocation.
#![no_main]

use libfuzzer_sys::fuzz_target;
use lodkit_mesh::image::{decode_rgba, image_size};
use lodkit_mesh::io::cameras;

fuzz_target!(|data: &[u8]| {
    let Some((&kind, rest)) = data.split_first() else {
        return;
    };
    let decoded = |b: &[u8]| decode_rgba(b).map(|d| (d.width, d.height));
    match kind % 4 {
        0 => {
            let _ = cameras::parse_for_fuzzing(true, rest);
        }
        1 => {
            let _ = cameras::parse_for_fuzzing(false, rest);
        }
        2 => {
            let _ = decoded(rest);
        }
        _ => {
            if let (Ok(size), Ok(d)) = (image_size(rest), decoded(rest)) {
                assert_eq!(size, d, "the header size is not the decoded size");
            }
        }
    }
});
