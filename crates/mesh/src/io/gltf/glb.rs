//! The GLB container (glTF 2.0 §4.4): a 12-byte header, a JSON chunk, an
//! optional BIN chunk; every length is little-endian u32 and is checked
//! against the bytes present before it is used.

use crate::error::ParseError;
use crate::parse_err;

pub(super) const GLB_MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: &[u8; 4] = b"JSON";
const CHUNK_BIN: &[u8; 4] = b"BIN\0";

pub(super) fn u32_at(b: &[u8], o: usize) -> u32 {
    u32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]])
}

/// Splits a GLB into its JSON chunk and its first BIN chunk, checking every
/// length against the bytes present.
pub(super) fn split_glb(bytes: &[u8]) -> Result<(&[u8], Option<&[u8]>), ParseError> {
    if bytes.len() < 12 {
        return Err(parse_err!(
            "GLB truncated: {} bytes, the header alone is 12",
            bytes.len()
        ));
    }
    let version = u32_at(bytes, 4);
    if version != 2 {
        return Err(parse_err!("GLB version {version} (only 2 is supported)"));
    }
    let length = u32_at(bytes, 8) as usize;
    if length < 12 || length > bytes.len() {
        return Err(parse_err!(
            "GLB header says {length} bytes but the file has {}",
            bytes.len()
        ));
    }
    let body = &bytes[..length];
    let mut at = 12usize;
    let mut json_chunk = None;
    let mut bin = None;
    while at < body.len() {
        if body.len() - at < 8 {
            return Err(parse_err!("GLB chunk header at byte {at} is truncated"));
        }
        let len = u32_at(body, at) as usize;
        let ty = &body[at + 4..at + 8];
        let start = at + 8;
        if len > body.len() - start {
            return Err(parse_err!(
                "GLB chunk at byte {at} says {len} bytes but only {} remain",
                body.len() - start
            ));
        }
        let data = &body[start..start + len];
        match (json_chunk.is_none(), ty) {
            (true, t) if t == CHUNK_JSON => json_chunk = Some(data),
            (true, _) => return Err(ParseError::new("GLB's first chunk is not JSON")),
            (false, t) if t == CHUNK_BIN && bin.is_none() => bin = Some(data),
            _ => {} // unknown chunk types are ignored, as the spec asks
        }
        at = start + len;
    }
    let json_chunk = json_chunk.ok_or_else(|| ParseError::new("GLB has no JSON chunk"))?;
    Ok((json_chunk, bin))
}

/// Joins a JSON chunk (padded here with spaces to 4 bytes) and a BIN chunk
/// (already 4-byte aligned, zero-padded by the writer) into one GLB.
pub(super) fn join_glb(mut js: Vec<u8>, bin: &[u8]) -> Result<Vec<u8>, ParseError> {
    while !js.len().is_multiple_of(4) {
        js.push(b' ');
    }
    let bin_len = bin.len();
    let total = 12 + 8 + js.len() + 8 + bin_len;
    let total32 = u32::try_from(total)
        .map_err(|_| parse_err!("GLB: {total} bytes, over the 4 GiB GLB limit"))?;
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(GLB_MAGIC);
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&total32.to_le_bytes());
    out.extend_from_slice(&(js.len() as u32).to_le_bytes());
    out.extend_from_slice(CHUNK_JSON);
    out.extend_from_slice(&js);
    out.extend_from_slice(&(bin_len as u32).to_le_bytes());
    out.extend_from_slice(CHUNK_BIN);
    out.extend_from_slice(bin);
    Ok(out)
}
