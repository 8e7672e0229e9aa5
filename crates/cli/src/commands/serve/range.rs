//! Range and conditional requests (RFC 9110 §13 and §14), for one
//! representation of `len` bytes with one entity tag.
//!
//! Policy, chosen to be predictable:
//! - A `Range` whose unit is not `bytes` (or that has no `=`) is ignored,
//!   as §14.2 requires for units a server does not know: 200, whole body.
//! - A `bytes=` range set that is malformed (`bytes=abc`, `bytes=5-2`,
//!   `bytes=`) or that no range of satisfies answers 416 with
//!   `Content-Range: bytes */len` (§15.5.17 allows 416 for invalid ranges).
//! - A single satisfiable range answers 206. Several ranges, when at least
//!   one is satisfiable, answer 200 with the whole body: no multipart.
//! - `If-Range` honours the range only on a strong match of our tag; a date
//!   never matches (we send no `Last-Modified`), so it gives 200.
//! - `If-None-Match` uses the weak comparison (§13.1.2): a match gives 304.

/// What to send for a request's `Range` header.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Plan {
    /// 200 with all `len` bytes.
    Whole,
    /// 206 with bytes `start..=end` (inclusive, `end < len`).
    Part { start: u64, end: u64 },
    /// 416 with `Content-Range: bytes */len`.
    Unsatisfiable,
}

/// The plan for `range` (the header's value, if any) on `len` bytes.
pub fn plan(range: Option<&[u8]>, len: u64) -> Plan {
    let Some(range) = range else {
        return Plan::Whole;
    };
    let Ok(range) = std::str::from_utf8(range) else {
        return Plan::Unsatisfiable;
    };
    let Some((unit, set)) = range.trim().split_once('=') else {
        return Plan::Whole;
    };
    if !unit.trim().eq_ignore_ascii_case("bytes") {
        return Plan::Whole;
    }
    let mut parts = Vec::new();
    for spec in set.split(',') {
        let spec = spec.trim_matches([' ', '\t']);
        if spec.is_empty() {
            continue; // empty list elements are allowed (§5.6.1)
        }
        match one_range(spec, len) {
            Some(p) => parts.push(p),
            None => return Plan::Unsatisfiable,
        }
    }
    let satisfiable: Vec<(u64, u64)> = parts.iter().flatten().copied().collect();
    match (parts.len(), satisfiable.as_slice()) {
        (_, []) => Plan::Unsatisfiable,
        (1, [(start, end)]) => Plan::Part {
            start: *start,
            end: *end,
        },
        _ => Plan::Whole,
    }
}

/// One `first-last`, `first-` or `-suffix`: `None` when malformed,
/// `Some(None)` when well formed but outside `len` bytes.
fn one_range(spec: &str, len: u64) -> Option<Option<(u64, u64)>> {
    let (first, last) = spec.split_once('-')?;
    if first.is_empty() {
        let suffix = digits(last)?;
        if suffix == 0 || len == 0 {
            return Some(None);
        }
        return Some(Some((len - suffix.min(len), len - 1)));
    }
    let first = digits(first)?;
    let last = if last.is_empty() {
        u64::MAX
    } else {
        digits(last)?
    };
    if last < first {
        return None;
    }
    if first >= len {
        return Some(None);
    }
    Some(Some((first, last.min(len - 1))))
}

/// A run of ASCII digits (saturating at `u64::MAX`); `None` for anything else.
fn digits(s: &str) -> Option<u64> {
    if s.is_empty() || !s.bytes().all(|c| c.is_ascii_digit()) {
        return None;
    }
    Some(s.bytes().fold(0u64, |n, c| {
        n.saturating_mul(10).saturating_add(u64::from(c - b'0'))
    }))
}

/// Whether an `If-None-Match` value matches `etag` (weak comparison; `*`
/// matches anything).
pub fn none_match(header: &[u8], etag: &str) -> bool {
    let Ok(header) = std::str::from_utf8(header) else {
        return false;
    };
    let ours = opaque(etag);
    header
        .split(',')
        .map(str::trim)
        .any(|t| t == "*" || opaque(t) == ours)
}

/// Whether an `If-Range` value lets the range through: a strong match of a
/// strong `etag`.
pub fn if_range_holds(header: &[u8], etag: &str) -> bool {
    !etag.starts_with("W/") && header.trim_ascii() == etag.as_bytes()
}

/// The opaque part of an entity tag (drops `W/`).
fn opaque(tag: &str) -> &str {
    tag.strip_prefix("W/").unwrap_or(tag)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(h: &str, len: u64) -> Plan {
        plan(Some(h.as_bytes()), len)
    }

    #[test]
    fn single_ranges_of_each_form() {
        assert_eq!(p("bytes=0-9", 100), Plan::Part { start: 0, end: 9 });
        assert_eq!(p("bytes=90-", 100), Plan::Part { start: 90, end: 99 });
        assert_eq!(p("bytes=-10", 100), Plan::Part { start: 90, end: 99 });
        assert_eq!(p("bytes=-1000", 100), Plan::Part { start: 0, end: 99 });
        assert_eq!(p("bytes=50-5000", 100), Plan::Part { start: 50, end: 99 });
        assert_eq!(p("BYTES = 1-1", 100), Plan::Part { start: 1, end: 1 });
        assert_eq!(
            p("bytes=0-99999999999999999999999", 100),
            Plan::Part { start: 0, end: 99 }
        );
    }

    #[test]
    fn out_of_bounds_and_malformed_ranges_are_unsatisfiable() {
        for h in [
            "bytes=100-",
            "bytes=100-200",
            "bytes=-0",
            "bytes=5-2",
            "bytes=abc",
            "bytes=",
            "bytes=1-2-3",
            "bytes=+1-2",
            "bytes= 1 - 2",
            "bytes=0x1-2",
            "bytes=0-1,x",
            "bytes=99999999999999999999999-",
        ] {
            assert_eq!(p(h, 100), Plan::Unsatisfiable, "{h}");
        }
        assert_eq!(p("bytes=0-0", 0), Plan::Unsatisfiable);
        assert_eq!(p("bytes=-5", 0), Plan::Unsatisfiable);
    }

    #[test]
    fn unknown_units_and_several_ranges_get_the_whole_body() {
        assert_eq!(plan(None, 100), Plan::Whole);
        assert_eq!(p("items=0-5", 100), Plan::Whole);
        assert_eq!(p("garbage", 100), Plan::Whole);
        assert_eq!(p("bytes=0-1,5-6", 100), Plan::Whole);
        assert_eq!(p("bytes=0-1,500-600", 100), Plan::Whole);
        assert_eq!(p("bytes=0-1,", 100), Plan::Part { start: 0, end: 1 });
        assert_eq!(p("bytes=200-300,400-", 100), Plan::Unsatisfiable);
    }

    #[test]
    fn conditional_headers() {
        let tag = "\"a-b-c\"";
        assert!(none_match(b"\"a-b-c\"", tag));
        assert!(none_match(b"W/\"a-b-c\"", tag));
        assert!(none_match(b"\"x\", \"a-b-c\"", tag));
        assert!(none_match(b"*", tag));
        assert!(!none_match(b"\"x\"", tag));
        assert!(if_range_holds(b"\"a-b-c\"", tag));
        assert!(!if_range_holds(b"W/\"a-b-c\"", tag));
        assert!(!if_range_holds(b"Tue, 01 Dec 2026 20:00:00 GMT", tag));
        assert!(!if_range_holds(tag.as_bytes(), "W/\"a-b-c\""));
    }
}
