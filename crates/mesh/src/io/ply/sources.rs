//! Bounds-checked value readers for the general PLY decoding path: one
//! binary source (either byte order) and one line-structured ASCII source,
//! behind the [`Source`] trait that `read.rs`'s element decoder drives.

use super::header::{Element, ScalarType};
use crate::error::ParseError;
use crate::parse_err;

/// Reads values one at a time. Errors are plain descriptions; the caller
/// adds the element and record.
pub(super) trait Source {
    /// Reads one value of type `ty`.
    fn scalar(&mut self, ty: ScalarType) -> Result<f64, String>;
    /// Reads a list count of type `count` and checks that `n` items of type
    /// `item` can still fit in the remaining data.
    fn list_len(&mut self, count: ScalarType, item: ScalarType) -> Result<usize, String>;
    /// Skips `n` values of type `ty`.
    fn skip(&mut self, n: usize, ty: ScalarType) -> Result<(), String>;
    /// Called before each record (ASCII: moves to the record's line).
    fn begin_record(&mut self) -> Result<(), String> {
        Ok(())
    }
    /// Called after each record (ASCII: the line must hold nothing more).
    fn end_record(&mut self) -> Result<(), String> {
        Ok(())
    }
    /// The file line the current record is on (ASCII only).
    fn line(&self) -> Option<usize> {
        None
    }
}

pub(super) struct BinarySource<'a> {
    pub(super) data: &'a [u8],
    pub(super) pos: usize,
    pub(super) big: bool,
}

impl<'a> BinarySource<'a> {
    pub(super) fn remaining(&self) -> usize {
        self.data.len().saturating_sub(self.pos)
    }

    /// The next `n` bytes, if that many remain; does not advance.
    pub(super) fn peek(&self, n: u64) -> Option<&'a [u8]> {
        let end = self.pos.checked_add(usize::try_from(n).ok()?)?;
        self.data.get(self.pos..end)
    }

    /// The next `records × stride` bytes of element `el`, advancing past them.
    pub(super) fn take_records(
        &mut self,
        el: &Element,
        stride: usize,
    ) -> Result<&'a [u8], ParseError> {
        let need = el.count.checked_mul(stride as u64);
        match need.and_then(|n| self.peek(n)) {
            Some(bytes) => {
                self.pos += bytes.len();
                Ok(bytes)
            }
            None => Err(parse_err!(
                "{} element needs {} × {stride} bytes but only {} remain (truncated file)",
                el.name,
                el.count,
                self.remaining()
            )),
        }
    }
}

/// Decodes the value of type `ty` at the start of `b` with the given byte
/// order; `None` if `b` is too short.
#[inline(always)]
pub(super) fn decode_scalar(b: &[u8], ty: ScalarType, big: bool) -> Option<f64> {
    macro_rules! num {
        ($t:ty, $n:literal) => {{
            let a = *b.first_chunk::<$n>()?;
            f64::from(if big {
                <$t>::from_be_bytes(a)
            } else {
                <$t>::from_le_bytes(a)
            })
        }};
    }
    Some(match ty {
        ScalarType::I8 => num!(i8, 1),
        ScalarType::U8 => num!(u8, 1),
        ScalarType::I16 => num!(i16, 2),
        ScalarType::U16 => num!(u16, 2),
        ScalarType::I32 => num!(i32, 4),
        ScalarType::U32 => num!(u32, 4),
        ScalarType::F32 => num!(f32, 4),
        ScalarType::F64 => num!(f64, 8),
    })
}

pub(super) const TRUNCATED: &str = "data ends early (truncated file)";

impl Source for BinarySource<'_> {
    fn scalar(&mut self, ty: ScalarType) -> Result<f64, String> {
        let v = self
            .data
            .get(self.pos..)
            .and_then(|b| decode_scalar(b, ty, self.big))
            .ok_or(TRUNCATED)?;
        self.pos += ty.size();
        Ok(v)
    }

    fn list_len(&mut self, count: ScalarType, item: ScalarType) -> Result<usize, String> {
        let n = self.scalar(count)?;
        if n < 0.0 {
            return Err(format!("has negative list length {n}"));
        }
        let n = n as u64;
        let fits = n
            .checked_mul(item.size() as u64)
            .is_some_and(|b| b <= self.remaining() as u64);
        if !fits {
            return Err(format!(
                "has a list of {n} items that runs past the end of the file"
            ));
        }
        Ok(n as usize)
    }

    fn skip(&mut self, n: usize, ty: ScalarType) -> Result<(), String> {
        let bytes = n.checked_mul(ty.size()).ok_or(TRUNCATED)?;
        if bytes > self.remaining() {
            return Err(TRUNCATED.into());
        }
        self.pos += bytes;
        Ok(())
    }
}

/// ASCII PLY is line-structured: each record is one line (blank lines
/// are skipped), and a record's values never continue onto the next line.
pub(super) struct AsciiSource<'a> {
    pub(super) data: &'a [u8],
    pub(super) pos: usize,
    /// End (exclusive, before the `\n`) of the current record's line.
    pub(super) line_end: usize,
    /// 1-based file line number of the line at `pos`.
    pub(super) line_no: usize,
}

impl<'a> AsciiSource<'a> {
    pub(super) fn new(data: &'a [u8], first_line: usize) -> Self {
        AsciiSource {
            data,
            pos: 0,
            line_end: 0,
            line_no: first_line,
        }
    }

    /// The end of the line starting at `from` (before its `\n`).
    pub(super) fn end_of_line(&self, from: usize) -> usize {
        self.data[from..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(self.data.len(), |i| from + i)
    }

    /// The next whitespace-separated token of the current line.
    pub(super) fn token(&mut self) -> Result<&'a str, String> {
        let rest = self.data.get(self.pos..self.line_end).unwrap_or_default();
        let start = rest
            .iter()
            .position(|b| !b.is_ascii_whitespace())
            .ok_or("has too few values on its line")?;
        let len = rest[start..]
            .iter()
            .position(|b| b.is_ascii_whitespace())
            .unwrap_or(rest.len() - start);
        self.pos += start + len;
        let tok = &rest[start..start + len];
        std::str::from_utf8(tok).map_err(|_| "holds a value that is not text".to_string())
    }

    /// After the last element: only blank lines may remain.
    pub(super) fn finish(&mut self) -> Result<(), ParseError> {
        while self.pos < self.data.len() {
            let end = self.end_of_line(self.pos);
            if !self.data[self.pos..end].trim_ascii().is_empty() {
                return Err(parse_err!(
                    "line {}: more data lines than the header's element counts declare",
                    self.line_no
                ));
            }
            self.pos = end + 1;
            self.line_no += 1;
        }
        Ok(())
    }
}

impl Source for AsciiSource<'_> {
    fn scalar(&mut self, ty: ScalarType) -> Result<f64, String> {
        let tok = self.token()?;
        let shown = || tok.chars().take(40).collect::<String>();
        match ty {
            // Parse `float` directly as f32 so written values round-trip exactly.
            ScalarType::F32 => tok.parse::<f32>().map(f64::from),
            ScalarType::F64 => tok.parse::<f64>(),
            _ => {
                let v = match tok.parse::<i64>() {
                    Ok(i) => i as f64,
                    Err(_) => match tok.parse::<f64>() {
                        Ok(f) if f.fract() == 0.0 => f,
                        _ => return Err(format!("expected an integer, found '{}'", shown())),
                    },
                };
                let (lo, hi) = match ty {
                    ScalarType::I8 => (i8::MIN as f64, i8::MAX as f64),
                    ScalarType::U8 => (0.0, u8::MAX as f64),
                    ScalarType::I16 => (i16::MIN as f64, i16::MAX as f64),
                    ScalarType::U16 => (0.0, u16::MAX as f64),
                    ScalarType::I32 => (i32::MIN as f64, i32::MAX as f64),
                    _ => (0.0, u32::MAX as f64),
                };
                return if (lo..=hi).contains(&v) {
                    Ok(v)
                } else {
                    Err(format!(
                        "value {} is out of range for {}",
                        shown(),
                        ty.name()
                    ))
                };
            }
        }
        .map_err(|_| format!("expected a number, found '{}'", shown()))
    }

    fn list_len(&mut self, count: ScalarType, _item: ScalarType) -> Result<usize, String> {
        let n = self.scalar(count)?;
        if n < 0.0 {
            return Err(format!("has negative list length {n}"));
        }
        // Every item is a token plus a separator: at least 2 bytes.
        let remaining = self.line_end.saturating_sub(self.pos) as f64;
        if n * 2.0 > remaining + 1.0 {
            return Err(format!(
                "has a list of {n} items but its line holds fewer values"
            ));
        }
        Ok(n as usize)
    }

    fn skip(&mut self, n: usize, _ty: ScalarType) -> Result<(), String> {
        for _ in 0..n {
            self.token()?;
        }
        Ok(())
    }

    fn begin_record(&mut self) -> Result<(), String> {
        loop {
            if self.pos >= self.data.len() {
                return Err(
                    "is missing: the file has fewer data lines than the header declares".into(),
                );
            }
            let end = self.end_of_line(self.pos);
            if !self.data[self.pos..end].trim_ascii().is_empty() {
                self.line_end = end;
                return Ok(());
            }
            self.pos = end + 1;
            self.line_no += 1;
        }
    }

    fn end_record(&mut self) -> Result<(), String> {
        let rest = &self.data[self.pos.min(self.line_end)..self.line_end];
        if let Some(extra) = rest
            .split(|b| b.is_ascii_whitespace())
            .find(|t| !t.is_empty())
        {
            let shown: String = String::from_utf8_lossy(extra).chars().take(40).collect();
            return Err(format!(
                "has more values on its line than the header declares ('{shown}' is extra)"
            ));
        }
        self.pos = self.line_end + 1;
        self.line_no += 1;
        Ok(())
    }

    fn line(&self) -> Option<usize> {
        Some(self.line_no)
    }
}
