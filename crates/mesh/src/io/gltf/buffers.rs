//! Where a buffer's bytes come from: the GLB `BIN` chunk, a base64 `data:`
//! URI, or a file relative to the glTF's directory (see the module docs of
//! `io::gltf` for what is refused).

use std::borrow::Cow;
use std::path::Path;

use crate::error::ParseError;
use crate::error::clip;
use crate::parse_err;

/// as glTF data URIs use it.
pub(super) fn decode_base64(s: &str) -> Result<Vec<u8>, String> {
    use base64::Engine as _;
    use base64::engine::{DecodePaddingMode, GeneralPurpose, GeneralPurposeConfig};
    const ENGINE: GeneralPurpose = GeneralPurpose::new(
        &base64::alphabet::STANDARD,
        GeneralPurposeConfig::new().with_decode_padding_mode(DecodePaddingMode::Indifferent),
    );
    ENGINE.decode(s).map_err(|e| e.to_string())
}

/// Decodes `%XX` escapes in a relative URI.
pub(super) fn percent_decode(s: &str) -> Result<String, ParseError> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let hex = b
                .get(i + 1..i + 3)
                .and_then(|h| std::str::from_utf8(h).ok())
                .and_then(|h| u8::from_str_radix(h, 16).ok())
                .ok_or_else(|| parse_err!("buffer URI '{}' has a bad %-escape", clip(s, 48)))?;
            out.push(hex);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).map_err(|_| parse_err!("buffer URI '{}' is not UTF-8", clip(s, 48)))
}

/// The bytes of buffer `buffer` (see the module docs for what is accepted).
pub(super) fn load_buffer<'a>(
    buffer: gltf::Buffer<'_>,
    bin: Option<&'a [u8]>,
    base_dir: Option<&Path>,
) -> Result<Cow<'a, [u8]>, ParseError> {
    let i = buffer.index();
    let uri = match buffer.source() {
        gltf::buffer::Source::Bin => {
            // Only the first buffer may stand for the BIN chunk (glTF 2.0
            // §4.4.3.3): another buffer without a uri has no bytes.
            if i != 0 {
                return Err(parse_err!(
                    "buffer {i} has no uri: only buffer 0 may be the GLB BIN chunk"
                ));
            }
            return bin
                .map(Cow::Borrowed)
                .ok_or_else(|| parse_err!("buffer {i} has no uri and there is no GLB BIN chunk"));
        }
        gltf::buffer::Source::Uri(u) => u,
    };
    if let Some(rest) = uri.strip_prefix("data:") {
        let (meta, data) = rest
            .split_once(',')
            .ok_or_else(|| parse_err!("buffer {i}: data URI has no ','"))?;
        if !meta.ends_with(";base64") {
            return Err(parse_err!(
                "buffer {i}: data URI is not base64 ('{}')",
                clip(meta, 48)
            ));
        }
        return decode_base64(data)
            .map(Cow::Owned)
            .map_err(|e| parse_err!("buffer {i}: data URI is not valid base64: {e}"));
    }
    // Decode first, so that `%2F`, `%2E%2E` or `file%3A` cannot slip past
    // the path rule; then the one rule for paths named inside a file.
    let rel = percent_decode(uri)?;
    let dir = base_dir.ok_or_else(|| {
        parse_err!(
            "buffer {i}: external file '{}' but no directory to resolve it against",
            clip(&rel, 48)
        )
    })?;
    let path = crate::io::input::resolve_inside(dir, &rel)
        .map_err(|why| parse_err!("buffer {i}: URI {why}"))?;
    crate::io::input::read_file(&path)
        .map(Cow::Owned)
        .map_err(|e| parse_err!("buffer {i}: {e}"))
}
