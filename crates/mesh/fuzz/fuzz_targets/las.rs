//! Fuzzes `io::decode(Format::Las, ..)`: any bytes must give `Ok` or a
//! `ParseError`, never a panic, an abort or a runaway allocation.
#![no_main]

use libfuzzer_sys::fuzz_target;
use lodkit_mesh::io::{Format, decode};

fuzz_target!(|data: &[u8]| {
    let _ = decode(Format::Las, data, None);
});
