//! Stage 1 of reading a PLY file: the text header.
//!
//! [`parse`] turns the bytes up to and including the `end_header` line into a
//! [`Header`]: the body encoding, the elements in file order with their
//! properties, and the `obj_info` key/value pairs. It also checks that the
//! declared element counts can fit in the bytes that follow the header (see
//! [`Header::check_counts`]), which is what lets the decoder size its
//! allocations from those counts.

use crate::error::ParseError;
use crate::parse_err;

/// How the body after `end_header` is encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Encoding {
    Ascii,
    BinaryLittleEndian,
    BinaryBigEndian,
}

/// A PLY scalar type. The spec's names (`char`, `uchar`, …) and the sized
/// aliases (`int8`, `uint8`, …) both map here.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ScalarType {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl ScalarType {
    /// The type named `name` in a `property` line, or `None` if unknown.
    pub fn from_name(name: &str) -> Option<ScalarType> {
        Some(match name {
            "char" | "int8" => ScalarType::I8,
            "uchar" | "uint8" => ScalarType::U8,
            "short" | "int16" => ScalarType::I16,
            "ushort" | "uint16" => ScalarType::U16,
            "int" | "int32" => ScalarType::I32,
            "uint" | "uint32" => ScalarType::U32,
            "float" | "float32" => ScalarType::F32,
            "double" | "float64" => ScalarType::F64,
            _ => return None,
        })
    }

    /// The spec's name for the type (what the writer emits).
    pub fn name(self) -> &'static str {
        match self {
            ScalarType::I8 => "char",
            ScalarType::U8 => "uchar",
            ScalarType::I16 => "short",
            ScalarType::U16 => "ushort",
            ScalarType::I32 => "int",
            ScalarType::U32 => "uint",
            ScalarType::F32 => "float",
            ScalarType::F64 => "double",
        }
    }

    /// Size of one binary value in bytes.
    pub fn size(self) -> usize {
        match self {
            ScalarType::I8 | ScalarType::U8 => 1,
            ScalarType::I16 | ScalarType::U16 => 2,
            ScalarType::I32 | ScalarType::U32 | ScalarType::F32 => 4,
            ScalarType::F64 => 8,
        }
    }

    pub fn is_integer(self) -> bool {
        !matches!(self, ScalarType::F32 | ScalarType::F64)
    }
}

/// The shape of one property: a single scalar or a counted list.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PropertyKind {
    Scalar(ScalarType),
    /// `property list COUNT ITEM name`; `count` is always an integer type.
    List {
        count: ScalarType,
        item: ScalarType,
    },
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Property {
    pub name: String,
    pub kind: PropertyKind,
}

/// One `element NAME COUNT` block with its properties in record order.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Element {
    pub name: String,
    pub count: u64,
    pub properties: Vec<Property>,
}

impl Element {
    /// Index of the property called `name`, if any.
    pub fn property(&self, name: &str) -> Option<usize> {
        self.properties.iter().position(|p| p.name == name)
    }

    /// Bytes per binary record when the element has no list property (every
    /// record then has the same size), else `None`.
    pub fn fixed_stride(&self) -> Option<usize> {
        self.properties
            .iter()
            .try_fold(0usize, |acc, p| match p.kind {
                PropertyKind::Scalar(t) => acc.checked_add(t.size()),
                PropertyKind::List { .. } => None,
            })
    }

    /// Byte offset of property `index` inside a binary record, when every
    /// property before it is a scalar.
    pub fn offset_of(&self, index: usize) -> Option<usize> {
        self.properties
            .get(..index)?
            .iter()
            .try_fold(0usize, |acc, p| match p.kind {
                PropertyKind::Scalar(t) => acc.checked_add(t.size()),
                PropertyKind::List { .. } => None,
            })
    }

    /// The fewest bytes one record can take in `encoding`: a binary record
    /// holds every scalar and at least each list's count; an ASCII record
    /// holds at least one token per scalar or list, and a token plus its
    /// separator is at least 2 bytes.
    pub fn min_record_bytes(&self, encoding: Encoding) -> u64 {
        self.properties
            .iter()
            .map(|p| match (encoding, p.kind) {
                (Encoding::Ascii, _) => 2,
                (_, PropertyKind::Scalar(t)) => t.size() as u64,
                (_, PropertyKind::List { count, .. }) => count.size() as u64,
            })
            .sum()
    }
}

/// Everything the header says about the file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Header {
    pub encoding: Encoding,
    /// Elements in file order (the body stores them in this order).
    pub elements: Vec<Element>,
    /// `obj_info KEY VALUE…` lines, split at the first whitespace.
    pub obj_info: Vec<(String, String)>,
    /// Byte offset of the first body byte (just after `end_header`'s newline).
    pub body_start: usize,
}

impl Header {
    /// The element called `name`, if any.
    pub fn element(&self, name: &str) -> Option<&Element> {
        self.elements.iter().find(|e| e.name == name)
    }

    /// The value of `obj_info KEY VALUE`, for the first line with that key.
    pub fn obj_info(&self, key: &str) -> Option<&str> {
        self.obj_info
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }

    /// Checks that every element's records, at their smallest possible size,
    /// fit in the `body_len` bytes after the header (an ASCII file may omit
    /// the separator after its last token, hence one byte of slack).
    ///
    /// After this succeeds, `count × min_record_bytes` of every element is
    /// bounded by the file size, so allocating `count` entries is safe.
    pub fn check_counts(&self, body_len: usize) -> Result<(), ParseError> {
        let available = body_len as u64 + u64::from(self.encoding == Encoding::Ascii);
        let mut needed: u64 = 0;
        for e in &self.elements {
            let per = e.min_record_bytes(self.encoding);
            let bytes = e.count.checked_mul(per);
            match bytes.and_then(|b| needed.checked_add(b)) {
                Some(total) if total <= available => needed = total,
                _ => {
                    let shown = bytes.map_or_else(|| "more than 2^64".into(), |b| b.to_string());
                    return Err(parse_err!(
                        "header declares {} {} elements (≥ {shown} bytes) but only {body_len} bytes follow the header",
                        e.count,
                        e.name
                    ));
                }
            }
        }
        Ok(())
    }
}

/// Parses the header at the start of `bytes`.
///
/// Accepts `\n` or `\r\n` line ends, `comment` and `obj_info` lines anywhere,
/// blank lines, and the type aliases of [`ScalarType::from_name`]. Fails with
/// a one-line message on a missing `ply` magic, an unknown or missing
/// `format`, an unknown keyword or type, a `property` before any `element`,
/// a duplicate element or property name, a non-integer list count type, or
/// a missing `end_header`. Does not look at the body.
pub fn parse(bytes: &[u8]) -> Result<Header, ParseError> {
    if bytes.is_empty() {
        return Err(ParseError::new("empty file"));
    }
    let mut lines = Lines {
        bytes,
        pos: 0,
        line_no: 0,
    };
    match lines.next() {
        Some((_, magic)) if magic.trim_ascii() == b"ply" => {}
        _ => return Err(ParseError::new("not a PLY file (no 'ply' magic line)")),
    }
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut obj_info = Vec::new();
    loop {
        let Some((line_no, raw)) = lines.next() else {
            return Err(ParseError::new(
                "header has no end_header line (file truncated or not a PLY file)",
            ));
        };
        let Ok(line) = std::str::from_utf8(raw) else {
            // Comments may carry any bytes; everything else must be text.
            if raw.starts_with(b"comment") {
                continue;
            }
            return Err(parse_err!("header line {line_no} is not text"));
        };
        let mut words = line.split_ascii_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        match keyword {
            "comment" => {}
            "obj_info" => {
                let rest = line.trim_start().strip_prefix("obj_info").unwrap_or("");
                let rest = rest.trim();
                let (key, value) = rest
                    .split_once(|c: char| c.is_ascii_whitespace())
                    .unwrap_or((rest, ""));
                obj_info.push((key.to_string(), value.trim().to_string()));
            }
            "format" => {
                if encoding.is_some() {
                    return Err(parse_err!("header line {line_no}: second format line"));
                }
                let name = words.next().unwrap_or("");
                encoding = Some(match name {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::BinaryLittleEndian,
                    "binary_big_endian" => Encoding::BinaryBigEndian,
                    _ => {
                        return Err(parse_err!(
                            "header line {line_no}: unknown format '{name}' (expected ascii, binary_little_endian or binary_big_endian)"
                        ));
                    }
                });
                match words.next() {
                    Some("1.0" | "1") => {}
                    Some(v) => {
                        return Err(parse_err!(
                            "header line {line_no}: unsupported PLY version '{v}' (expected 1.0)"
                        ));
                    }
                    None => {
                        return Err(parse_err!(
                            "header line {line_no}: format line has no version"
                        ));
                    }
                }
            }
            "element" => {
                let (Some(name), Some(count)) = (words.next(), words.next()) else {
                    return Err(parse_err!(
                        "header line {line_no}: expected 'element NAME COUNT'"
                    ));
                };
                let count: u64 = count.parse().map_err(|_| {
                    parse_err!("header line {line_no}: element {name} has invalid count '{count}'")
                })?;
                if elements.iter().any(|e| e.name == name) {
                    return Err(parse_err!(
                        "header line {line_no}: element {name} is declared twice"
                    ));
                }
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    properties: Vec::new(),
                });
            }
            "property" => {
                let Some(element) = elements.last_mut() else {
                    return Err(parse_err!(
                        "header line {line_no}: property before any element"
                    ));
                };
                let ty = |word: Option<&str>| -> Result<ScalarType, ParseError> {
                    let word = word.ok_or_else(|| {
                        parse_err!("header line {line_no}: incomplete property line")
                    })?;
                    ScalarType::from_name(word).ok_or_else(|| {
                        parse_err!("header line {line_no}: unknown property type '{word}'")
                    })
                };
                let first = words.next();
                let kind = if first == Some("list") {
                    let count = ty(words.next())?;
                    let item = ty(words.next())?;
                    if !count.is_integer() {
                        return Err(parse_err!(
                            "header line {line_no}: list count type '{}' is not an integer type",
                            count.name()
                        ));
                    }
                    PropertyKind::List { count, item }
                } else {
                    PropertyKind::Scalar(ty(first)?)
                };
                let Some(name) = words.next() else {
                    return Err(parse_err!(
                        "header line {line_no}: property line has no name"
                    ));
                };
                if element.property(name).is_some() {
                    return Err(parse_err!(
                        "header line {line_no}: element {} has two properties named {name}",
                        element.name
                    ));
                }
                element.properties.push(Property {
                    name: name.to_string(),
                    kind,
                });
            }
            "end_header" => break,
            other => {
                let shown: String = other.chars().take(40).collect();
                return Err(parse_err!(
                    "header line {line_no}: unknown keyword '{shown}'"
                ));
            }
        }
    }
    let encoding = encoding.ok_or_else(|| ParseError::new("header has no format line"))?;
    Ok(Header {
        encoding,
        elements,
        obj_info,
        body_start: lines.pos,
    })
}

/// Iterates over `\n`-terminated header lines (a trailing `\r` is dropped),
/// yielding 1-based line numbers. A final line without `\n` is still yielded.
struct Lines<'a> {
    bytes: &'a [u8],
    pos: usize,
    line_no: usize,
}

impl<'a> Iterator for Lines<'a> {
    type Item = (usize, &'a [u8]);

    fn next(&mut self) -> Option<Self::Item> {
        let rest = self.bytes.get(self.pos..).filter(|r| !r.is_empty())?;
        let (line, consumed) = match rest.iter().position(|&b| b == b'\n') {
            Some(i) => (&rest[..i], i + 1),
            None => (rest, rest.len()),
        };
        self.pos += consumed;
        self.line_no += 1;
        Some((self.line_no, line.strip_suffix(b"\r").unwrap_or(line)))
    }
}
