//! Progressive decoding of a stream still arriving (§5.4 of Yemez &
//! Schmitt, as `decode.rs`), one chunk at a time: the state of
//! [`decode_prefix`](crate::decode_prefix) is kept between calls, so a
//! viewer that decodes after every network read reads each chunk once
//! instead of decoding the whole prefix again.
use crate::container::{HEADER_LEN, read_header};
use crate::decode::{DecodeOptions, Decoded, Progress};
use crate::error::Result;

/// A `.pop` stream decoded as its bytes arrive.
///
/// Call [`read`](Self::read) with the bytes received so far (each call's
/// bytes a longer prefix of the same stream); it decodes the whole chunks
/// that arrived since the last call. [`decoded`](Self::decoded) then gives
/// what [`decode_prefix`](crate::decode_prefix) would give for those bytes.
///
/// Cost: linear in the bytes over all calls (each chunk decoded once);
/// [`decoded`](Self::decoded) copies the decoded levels. Memory: the
/// decoded levels (the caller keeps the bytes).
#[derive(Debug, Clone)]
pub struct PrefixDecoder {
    opts: DecodeOptions,
    /// `None` until the header has arrived.
    progress: Option<Progress>,
    /// The first error: the stream stays failed.
    failed: Option<String>,
}

impl PrefixDecoder {
    /// A decoder stopping where `opts` say (as [`crate::decode_prefix`]).
    pub fn new(opts: &DecodeOptions) -> PrefixDecoder {
        PrefixDecoder {
            opts: *opts,
            progress: None,
            failed: None,
        }
    }

    /// Decodes the whole chunks of `bytes` (the stream from its first
    /// byte: a prefix at least as long as at the last call, of the same
    /// stream) that follow those read before; a chunk cut short by the end
    /// of `bytes` waits for a later call. Returns whether a chunk was
    /// decoded. Fewer bytes than the header: `Ok(false)`.
    ///
    /// Errors ([`Error::Stream`](crate::Error::Stream), as
    /// [`crate::decode_prefix`]): a bad header, a damaged chunk, chunks
    /// out of order. After an error every call returns it again.
    pub fn read(&mut self, bytes: &[u8]) -> Result<bool> {
        if let Some(e) = &self.failed {
            return crate::error::stream_err(e.clone());
        }
        let r = self.read_more(bytes);
        if let Err(crate::Error::Stream(e)) = &r {
            self.failed = Some(e.clone());
        }
        r
    }

    fn read_more(&mut self, bytes: &[u8]) -> Result<bool> {
        if self.progress.is_none() {
            if bytes.len() < HEADER_LEN {
                return Ok(false);
            }
            self.progress = Some(Progress::new(read_header(bytes)?, &self.opts));
        }
        let p = self.progress.as_mut().expect("set above");
        let before = p.d.bytes_read;
        p.read(bytes, true)?;
        Ok(p.d.bytes_read > before)
    }

    /// Levels whose chunks have all arrived (a level's attribute chunk,
    /// where the stream codes colours or normals, is part of it): the
    /// levels a viewer shows with their attributes.
    pub fn whole_levels(&self) -> usize {
        self.progress.as_ref().map_or(0, Progress::whole_levels)
    }

    /// Stream bytes the [`whole_levels`](Self::whole_levels) (and the
    /// precision layers read) take: [`bytes_read`](Self::bytes_read), less
    /// a last level chunk still waiting for its attribute chunk. Zero
    /// before the first whole level.
    pub fn whole_bytes(&self) -> usize {
        let Some(p) = &self.progress else { return 0 };
        let whole = p.whole_levels();
        if whole == p.d.levels.len() {
            if whole == 0 { 0 } else { p.d.bytes_read }
        } else if whole == 0 {
            0
        } else {
            // Level `whole`'s chunk follows level `whole - 1`'s attributes.
            p.d.bytes_per_level[whole - 1]
        }
    }

    /// Stream bytes decoded: the end of the last whole chunk read.
    pub fn bytes_read(&self) -> usize {
        self.progress.as_ref().map_or(0, |p| p.d.bytes_read)
    }

    /// What has been decoded, as [`crate::decode_prefix`] of the bytes of
    /// the last call returns it (the last level may lack its attributes:
    /// see [`whole_levels`](Self::whole_levels)). Errors when no level has
    /// arrived yet. Cost: a copy of the decoded levels.
    pub fn decoded(&self) -> Result<Decoded> {
        match &self.progress {
            Some(p) => p.snapshot(),
            None => crate::error::stream_err("the stream holds no level (no header yet)"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{EncodeOptions, decode_prefix, encode};
    use lodkit_mesh::Model;

    fn stream(normals: bool) -> Vec<u8> {
        let mesh = lodkit_mesh::shapes::icosphere(3);
        let opts = EncodeOptions {
            depth: Some(5),
            normals,
            ..EncodeOptions::DEFAULT
        };
        encode(&Model::Mesh(mesh), &opts).expect("encodes").bytes
    }

    #[test]
    fn every_prefix_read_piece_by_piece_equals_decode_prefix() {
        for normals in [false, true] {
            let bytes = stream(normals);
            let opts = DecodeOptions::default();
            let mut dec = PrefixDecoder::new(&opts);
            for cut in 0..=bytes.len() {
                dec.read(&bytes[..cut]).expect("a prefix is no error");
                let Ok(whole) = decode_prefix(&bytes[..cut], &opts) else {
                    assert!(dec.decoded().is_err(), "cut {cut}");
                    continue;
                };
                let got = dec.decoded().expect("levels");
                assert_eq!(got.bytes_read, whole.bytes_read, "cut {cut}");
                assert_eq!(got.levels, whole.levels, "cut {cut}");
                assert_eq!(got.q, whole.q, "cut {cut}");
                assert_eq!(got.precision, whole.precision);
                assert_eq!(got.normals, whole.normals);
                assert_eq!(got.cut.is_some(), whole.cut.is_some(), "cut {cut}");
                assert_eq!(dec.bytes_read(), whole.bytes_read);
                // A level is whole once its attributes are in.
                let with = whole.normals.as_ref().map_or(whole.levels.len(), Vec::len);
                assert_eq!(dec.whole_levels(), with, "cut {cut}");
                if with > 0 && with == whole.levels.len() {
                    assert_eq!(dec.whole_bytes(), whole.bytes_read, "cut {cut}");
                } else if with > 0 {
                    assert_eq!(
                        dec.whole_bytes(),
                        whole.bytes_per_level[with - 1],
                        "cut {cut}"
                    );
                }
            }
        }
    }

    #[test]
    fn big_pieces_read_as_one() {
        let bytes = stream(true);
        let opts = DecodeOptions::default();
        let mut dec = PrefixDecoder::new(&opts);
        assert!(dec.read(&bytes[..bytes.len() / 3]).unwrap());
        assert!(dec.read(&bytes).unwrap());
        assert!(!dec.read(&bytes).unwrap(), "nothing new");
        let d = dec.decoded().unwrap();
        let whole = crate::decode(&bytes, &opts).unwrap();
        assert_eq!(d.q, whole.q);
        assert_eq!(d.bytes_read, bytes.len());
    }

    #[test]
    fn damage_is_an_error_and_stays_one() {
        let mut bytes = stream(false);
        let at = bytes.len() / 2;
        bytes[at] ^= 0x55;
        let mut dec = PrefixDecoder::new(&DecodeOptions::default());
        assert!(dec.read(&bytes).is_err());
        assert!(dec.read(&bytes).is_err());
    }
}
