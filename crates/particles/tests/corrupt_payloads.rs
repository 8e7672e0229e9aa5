//! Damaged payloads behind valid checksums: what a fuzzer (which skips the
//! checksums) feeds the decoders. Every byte pattern must decode to a
//! stream or to an error — never a panic — and whatever decodes must
//! triangulate.
use lodkit_mesh::Model;
use lodkit_particles::{CHUNK_HEADER_LEN, HEADER_LEN};
use lodkit_particles::{
    DecodeOptions, EncodeOptions, Mode, TriangulateOptions, decode, encode, triangulate,
};
use rand_xoshiro::Xoshiro256PlusPlus;
use rand_xoshiro::rand_core::{Rng, SeedableRng};

/// Rewrites every chunk's checksum so damaged payloads pass the container.
fn reseal(bytes: &mut [u8]) {
    let mut pos = HEADER_LEN;
    while pos + CHUNK_HEADER_LEN <= bytes.len() {
        let len = u32::from_le_bytes(bytes[pos + 12..pos + 16].try_into().unwrap()) as usize;
        let end = pos + CHUNK_HEADER_LEN + len;
        if end > bytes.len() {
            break;
        }
        let mut h = crc32fast::Hasher::new();
        h.update(&bytes[pos..pos + 16]);
        h.update(&bytes[pos + CHUNK_HEADER_LEN..end]);
        let crc = h.finalize();
        bytes[pos + 16..pos + 20].copy_from_slice(&crc.to_le_bytes());
        pos = end;
    }
}

/// Byte offsets of every chunk payload.
fn payload_ranges(bytes: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut pos = HEADER_LEN;
    while pos + CHUNK_HEADER_LEN <= bytes.len() {
        let len = u32::from_le_bytes(bytes[pos + 12..pos + 16].try_into().unwrap()) as usize;
        out.push((pos + CHUNK_HEADER_LEN, pos + CHUNK_HEADER_LEN + len));
        pos += CHUNK_HEADER_LEN + len;
    }
    out
}

#[test]
fn damaged_payloads_with_valid_checksums_decode_or_fail_cleanly() {
    let model = Model::Mesh(lodkit_mesh::shapes::icosphere(3));
    let mut decoded = 0;
    let mut failed = 0;
    for mode in [Mode::Entropy, Mode::Baseline] {
        let opts = EncodeOptions {
            depth: Some(5),
            precision: 9,
            mode,
            ..EncodeOptions::DEFAULT
        };
        let clean = encode(&model, &opts).unwrap().bytes;
        let ranges = payload_ranges(&clean);
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(0x9E37_79B9_7F4A_7C15);
        let mut next = move || rng.next_u64();
        for trial in 0..300 {
            let mut bytes = clean.clone();
            let (lo, hi) = ranges[trial % ranges.len()];
            if hi == lo {
                continue;
            }
            // One to four damaged bytes in one payload, sometimes all of it.
            if trial % 17 == 0 {
                for b in &mut bytes[lo..hi] {
                    *b = next() as u8;
                }
            } else {
                for _ in 0..1 + next() % 4 {
                    let at = lo + (next() as usize) % (hi - lo);
                    bytes[at] ^= 1 + (next() % 255) as u8;
                }
            }
            reseal(&mut bytes);
            match decode(&bytes, &DecodeOptions::default()) {
                Ok(d) => {
                    decoded += 1;
                    for r in 0..d.levels.len() {
                        if let Ok(s) = d.surface(r as u8) {
                            let _ = triangulate(&s, &TriangulateOptions::DEFAULT);
                        }
                    }
                }
                Err(e) => {
                    failed += 1;
                    assert!(e.to_string().starts_with("invalid .pop stream"), "{e}");
                }
            }
        }
    }
    // Both outcomes occur: damage in a precision layer only moves vertices.
    assert!(
        decoded > 0 && failed > 0,
        "{decoded} decoded, {failed} failed"
    );
}
