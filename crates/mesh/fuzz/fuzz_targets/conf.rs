//! Fuzzes the `.conf` parser (`io::conf::read`): any text must give `Ok`
//! (every entry with a unit quaternion and a translation within the
//! coordinate bound) or a `ParseError`, never a panic. Only the parser:
//! no scan file is ever opened.
#![no_main]

use libfuzzer_sys::fuzz_target;
use lodkit_mesh::io::{MAX_COORDINATE, conf};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(entries) = conf::read(text) {
        for e in entries {
            let q = e.pose.rotation;
            assert!(q.is_finite() && (q.length() - 1.0).abs() < 1e-3, "{q:?}");
            assert!(e.pose.translation.abs().max_element() <= MAX_COORDINATE);
        }
    }
});
