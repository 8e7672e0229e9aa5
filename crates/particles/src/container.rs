//! The `.pop` container: a versioned header, then one chunk per octree
//! level (structure, then attributes) and per precision layer, each with
//! its length and a CRC-32, so a reader can stop after any chunk and
//! detects truncation and corruption. Byte layout: `docs/formats/pop.md`.
//!
//! Every count is checked against the bytes that remain before anything is
//! allocated; nothing here panics on hostile input.
use glam::Vec3;

use crate::error::{Result, stream_err};
use crate::octree::{Frame, MAX_DEPTH, QBITS};

/// First eight bytes of every `.pop` file.
pub const MAGIC: [u8; 8] = *b"LKPOP\r\n\x1a";
/// Container version this crate writes and reads.
pub const VERSION: u16 = 5;
/// Header size in bytes.
pub const HEADER_LEN: usize = 40;
/// Chunk header size in bytes.
pub const CHUNK_HEADER_LEN: usize = 20;

/// How chunk payloads are coded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// §7.1/§7.2 raw bits, as the paper.
    Baseline,
    /// Context-adaptive range coding (beyond the paper).
    Entropy,
}

impl Mode {
    /// Its name in reports and on the command line (`baseline`, `entropy`).
    pub fn name(self) -> &'static str {
        match self {
            Mode::Baseline => "baseline",
            Mode::Entropy => "entropy",
        }
    }
}

/// The stream header.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Header {
    /// How the payloads are coded.
    pub mode: Mode,
    /// Octree resolution `R`.
    pub depth: u8,
    /// Highest precision `N` the stream carries (`R ≤ N ≤ 16`).
    pub precision: u8,
    /// Whether each level has an attribute chunk with colours.
    pub colours: bool,
    /// Whether the attribute chunks carry normals.
    pub normals: bool,
    /// The cube the octree divides (its lower corner and side, in model units).
    pub frame: Frame,
    /// Number of particles (ON leaves at level `R`).
    pub particles: u32,
}

/// What a chunk carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ChunkKind {
    /// Octree level `index` (§7.1): `count` nodes.
    Level,
    /// Attributes of level `index` (§5.5): `count` kept nodes.
    Attributes,
    /// Precision bit `index` (§7.2, `R < index ≤ N`): `count` particles.
    Precision,
}

/// One chunk, borrowed from the stream.
#[derive(Debug, Clone, Copy)]
pub struct Chunk<'a> {
    /// What the chunk carries.
    pub kind: ChunkKind,
    /// Its level or precision layer.
    pub index: u8,
    /// Nodes, kept nodes or particles it codes (see [`ChunkKind`]).
    pub count: u32,
    /// Level chunks: cubes eliminated by thinning at this level (Table 1,
    /// informative); 0 elsewhere.
    pub aux: u32,
    /// The coded payload (checksum verified).
    pub payload: &'a [u8],
    /// Offset of the chunk's end in the stream (bytes so far).
    pub end: usize,
}

/// CRC-32 (IEEE 802.3, as zlib and PNG) of the concatenation of `parts`.
pub(crate) fn crc32(parts: &[&[u8]]) -> u32 {
    let mut h = crc32fast::Hasher::new();
    for part in parts {
        h.update(part);
    }
    h.finalize()
}

/// Appends the header.
pub fn write_header(h: &Header, out: &mut Vec<u8>) {
    let start = out.len();
    out.extend_from_slice(&MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.push(match h.mode {
        Mode::Baseline => 0,
        Mode::Entropy => 1,
    });
    out.push(h.depth);
    out.push(h.precision);
    out.push(u8::from(h.colours) | (u8::from(h.normals) << 1));
    out.extend_from_slice(&[0, 0]);
    for v in h.frame.origin.to_array() {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&h.frame.size.to_le_bytes());
    out.extend_from_slice(&h.particles.to_le_bytes());
    let crc = crc32(&[&out[start..]]);
    out.extend_from_slice(&crc.to_le_bytes());
}

fn u32_at(b: &[u8], i: usize) -> u32 {
    u32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]])
}

fn f32_at(b: &[u8], i: usize) -> f32 {
    f32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]])
}

/// Parses and checks a stream's header (magic, version, depth and
/// precision in range): the first [`HEADER_LEN`] bytes.
///
/// Errors: [`Error::Stream`](crate::Error::Stream) naming what is wrong,
/// for fewer bytes than the header or any field out of range.
pub fn read_header(bytes: &[u8]) -> Result<Header> {
    if bytes.len() < MAGIC.len() || bytes[..MAGIC.len()] != MAGIC {
        return stream_err("not a .pop stream (bad magic)");
    }
    if bytes.len() < HEADER_LEN {
        return stream_err(format!(
            "header truncated ({} of {HEADER_LEN} bytes)",
            bytes.len()
        ));
    }
    let version = u16::from_le_bytes([bytes[8], bytes[9]]);
    if version != VERSION {
        return stream_err(format!(
            "version {version} is not supported (this reader knows {VERSION})"
        ));
    }
    if !cfg!(fuzzing) && crc32(&[&bytes[..36]]) != u32_at(bytes, 36) {
        return stream_err("header checksum mismatch");
    }
    let mode = match bytes[10] {
        0 => Mode::Baseline,
        1 => Mode::Entropy,
        m => return stream_err(format!("unknown coding mode {m}")),
    };
    let depth = bytes[11];
    let precision = bytes[12];
    if !(1..=MAX_DEPTH).contains(&depth) {
        return stream_err(format!("depth {depth} outside 1..={MAX_DEPTH}"));
    }
    if precision < depth || u32::from(precision) > QBITS {
        return stream_err(format!("precision {precision} outside {depth}..={QBITS}"));
    }
    let flags = bytes[13];
    if flags > 3 || bytes[14] != 0 || bytes[15] != 0 {
        return stream_err("unknown header flags");
    }
    let origin = Vec3::new(f32_at(bytes, 16), f32_at(bytes, 20), f32_at(bytes, 24));
    let size = f32_at(bytes, 28);
    if !origin.is_finite() || !size.is_finite() || size <= 0.0 {
        return stream_err("header frame is not finite and positive");
    }
    Ok(Header {
        mode,
        depth,
        precision,
        colours: flags & 1 != 0,
        normals: flags & 2 != 0,
        frame: Frame { origin, size },
        particles: u32_at(bytes, 32),
    })
}

/// Appends one chunk.
pub fn write_chunk(
    kind: ChunkKind,
    index: u8,
    count: u32,
    aux: u32,
    payload: &[u8],
    out: &mut Vec<u8>,
) {
    let mut head = [0u8; 16];
    head[0] = match kind {
        ChunkKind::Level => 0,
        ChunkKind::Attributes => 1,
        ChunkKind::Precision => 2,
    };
    head[1] = index;
    head[4..8].copy_from_slice(&count.to_le_bytes());
    head[8..12].copy_from_slice(&aux.to_le_bytes());
    head[12..16].copy_from_slice(&(payload.len() as u32).to_le_bytes());
    let crc = crc32(&[&head, payload]);
    out.extend_from_slice(&head);
    out.extend_from_slice(&crc.to_le_bytes());
    out.extend_from_slice(payload);
}

/// Iterates the chunks after the header; yields an error (then stops) on a
/// truncated or corrupted chunk.
pub struct ChunkReader<'a> {
    bytes: &'a [u8],
    pos: usize,
    number: usize,
    failed: bool,
    cut: bool,
}

impl<'a> ChunkReader<'a> {
    /// Chunks of a stream whose header has been read ([`read_header`]): each
    /// chunk's kind, index, counts and checksum-verified payload, in stream
    /// order; an error (then the end) at a damaged or cut chunk
    /// ([`ChunkReader::was_cut`] tells the two apart). Reads no byte twice.
    pub fn new(bytes: &'a [u8]) -> Self {
        ChunkReader {
            bytes,
            pos: HEADER_LEN.min(bytes.len()),
            number: 0,
            failed: false,
            cut: false,
        }
    }

    /// [`ChunkReader::new`] starting at byte `pos` of `bytes` (the end of a
    /// chunk read before), `number` chunks into the stream (for messages):
    /// a stream arriving in pieces is read on from where it stopped.
    pub(crate) fn resume(bytes: &'a [u8], pos: usize, number: usize) -> Self {
        ChunkReader {
            bytes,
            pos: pos.max(HEADER_LEN).min(bytes.len()),
            number,
            failed: false,
            cut: false,
        }
    }

    /// Offset of the next chunk: after the last one yielded (the header's
    /// end before the first).
    pub fn position(&self) -> usize {
        self.pos
    }

    /// Whether the error yielded was the end of the bytes cutting a chunk
    /// short (its header or its payload), as in a stream still arriving,
    /// rather than damage.
    pub fn was_cut(&self) -> bool {
        self.cut
    }
}

impl<'a> Iterator for ChunkReader<'a> {
    type Item = Result<Chunk<'a>>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.failed || self.pos >= self.bytes.len() {
            return None;
        }
        let n = self.number;
        self.number += 1;
        let rest = &self.bytes[self.pos..];
        let fail = |this: &mut Self, msg: String| {
            this.failed = true;
            Some(stream_err(msg))
        };
        if rest.len() < CHUNK_HEADER_LEN {
            self.cut = true;
            return fail(
                self,
                format!(
                    "chunk {n} truncated in its header ({} bytes left)",
                    rest.len()
                ),
            );
        }
        let kind = match rest[0] {
            0 => ChunkKind::Level,
            1 => ChunkKind::Attributes,
            2 => ChunkKind::Precision,
            k => return fail(self, format!("chunk {n} has unknown kind {k}")),
        };
        let len = u32_at(rest, 12) as usize;
        if rest.len() - CHUNK_HEADER_LEN < len {
            self.cut = true;
            return fail(
                self,
                format!(
                    "chunk {n} truncated: {len} payload bytes declared, {} present",
                    rest.len() - CHUNK_HEADER_LEN
                ),
            );
        }
        let payload = &rest[CHUNK_HEADER_LEN..CHUNK_HEADER_LEN + len];
        // Fuzzing builds skip the checksum so libFuzzer reaches the payload
        // decoders instead of stopping at the CRC.
        if !cfg!(fuzzing) && crc32(&[&rest[..16], payload]) != u32_at(rest, 16) {
            return fail(self, format!("chunk {n} checksum mismatch (corrupted)"));
        }
        if rest[2] != 0 || rest[3] != 0 {
            return fail(self, format!("chunk {n} has unknown flags"));
        }
        self.pos += CHUNK_HEADER_LEN + len;
        Some(Ok(Chunk {
            kind,
            index: rest[1],
            count: u32_at(rest, 4),
            aux: u32_at(rest, 8),
            payload,
            end: self.pos,
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc32_matches_the_check_value() {
        assert_eq!(crc32(&[b"123456789"]), 0xcbf4_3926);
        assert_eq!(crc32(&[b"1234", b"56789"]), 0xcbf4_3926);
        // Long enough for the eight-byte steps, split off their grid.
        let long: Vec<u8> = (0..1000u32).map(|i| (i * 7 + 3) as u8).collect();
        // The reflected polynomial 0xedb88320, a bit at a time: the
        // container's checksum since version 1.
        let bytewise = !long.iter().fold(!0u32, |c, &b| {
            (0..8).fold(c ^ u32::from(b), |c, _| {
                (c >> 1) ^ (0xedb8_8320 & (c & 1).wrapping_neg())
            })
        });
        assert_eq!(crc32(&[&long]), bytewise);
        assert_eq!(crc32(&[&long[..13], &long[13..]]), bytewise);
    }

    #[test]
    fn header_round_trips_and_rejects_damage() {
        let h = Header {
            mode: Mode::Entropy,
            depth: 7,
            precision: 12,
            colours: true,
            normals: false,
            frame: Frame {
                origin: Vec3::new(-1.0, 0.5, 2.0),
                size: 3.0,
            },
            particles: 1234,
        };
        let mut b = Vec::new();
        write_header(&h, &mut b);
        assert_eq!(b.len(), HEADER_LEN);
        assert_eq!(read_header(&b).unwrap(), h);
        for i in 8..HEADER_LEN {
            let mut d = b.clone();
            d[i] ^= 0x10;
            assert!(read_header(&d).is_err(), "byte {i}");
        }
        assert!(read_header(&b[..20]).is_err());
        assert!(read_header(b"PLY").is_err());
    }

    #[test]
    fn chunks_stop_cleanly_on_truncation() {
        let mut b = vec![0u8; HEADER_LEN];
        write_chunk(ChunkKind::Level, 0, 1, 0, &[1, 2, 3], &mut b);
        write_chunk(ChunkKind::Level, 1, 5, 7, &[9; 10], &mut b);
        let all: Vec<_> = ChunkReader::new(&b).collect();
        assert_eq!(all.len(), 2);
        assert!(all.iter().all(|c| c.is_ok()));
        for cut in HEADER_LEN + 1..b.len() {
            let got: Vec<_> = ChunkReader::new(&b[..cut]).collect();
            let ok = got.iter().filter(|c| c.is_ok()).count();
            let boundary = cut == HEADER_LEN + CHUNK_HEADER_LEN + 3;
            assert_eq!(got.last().unwrap().is_err(), !boundary, "cut {cut}");
            assert!(ok <= 1);
        }
    }
}
