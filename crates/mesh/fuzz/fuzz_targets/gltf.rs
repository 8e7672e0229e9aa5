//! Fuzzes `io::decode(Format::Glb, ..)`: any bytes must give `Ok` or a
//! `ParseError`, never a panic, an abort or a runaway allocation.
#![no_main]

use libfuzzer_sys::fuzz_target;
use lodkit_mesh::io::{Format, decode};

fuzz_target!(|data: &[u8]| {
    let _ = decode(Format::Glb, data, None);
    // Format::Gltf and Format::Glb take the same path (magic decides); no
    // base directory, so external buffers are refused, never read from disk.
});
