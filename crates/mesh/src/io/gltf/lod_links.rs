//! Linking the levels of an LOD chain GLB: `MSFT_lod` on level 0's node
//! and `MSFT_screencoverage` in its extras (one-mesh and scene chains).

use gltf::json;

use crate::error::ParseError;
use crate::parse_err;

/// The viewport height (pixels) [`error_coverage`] is set for: a level is
/// shown from the coverage at which its error projects to
/// [`COVERAGE_PIXELS`] on a screen this many lines high.
pub const COVERAGE_LINES: f64 = 1080.0;
/// The error (pixels) [`error_coverage`] allows on a [`COVERAGE_LINES`]
/// screen.
pub const COVERAGE_PIXELS: f64 = 1.0;

/// The screen coverage (projected area ÷ viewport area) below which an
/// error of `error` object units on an object of diagonal `diagonal`
/// projects to at most [`COVERAGE_PIXELS`] on a [`COVERAGE_LINES`] screen:
/// the object spans `h` lines when its diagonal does, its error is
/// `error × h / diagonal` pixels, so `h ≤ px × diagonal / error`, and the
/// coverage is `(h / lines)²`, at most 1. A zero, negative or NaN error or
/// diagonal: 1.
pub fn error_coverage(error: f64, diagonal: f64) -> f64 {
    if error.is_nan() || diagonal.is_nan() || error <= 0.0 || diagonal <= 0.0 {
        return 1.0;
    }
    let h = COVERAGE_PIXELS * diagonal / error / COVERAGE_LINES;
    (h * h).min(1.0)
}

/// Refuses a screen coverage outside `[0, 1]` (or NaN) for level `name`.
pub(super) fn check_coverage(name: &str, coverage: f64) -> Result<(), ParseError> {
    if !(0.0..=1.0).contains(&coverage) {
        return Err(parse_err!(
            "GLB level '{name}': screen coverage {coverage} is outside [0, 1]"
        ));
    }
    Ok(())
}

/// The `MSFT_screencoverage` values of a chain whose levels have
/// `triangles` (finest first) and ask for `coverage` (each level's smallest
/// screen coverage, checked by [`check_coverage`]): **strictly
/// decreasing**, so that a switch by coverage reaches every level. Level
/// `k`'s value is the smaller of what it asks and the previous level's
/// value times the triangle ratio of the next level to this one
/// (`triangles[k + 1] / triangles[k]`; level 0 starts from 1, the last
/// level uses its own ratio to the level before): a coarser level takes
/// over no later than where it keeps the triangles per unit of screen
/// area the finer one had, so levels asking for full coverage (an error
/// below a pixel) still get their share of the range. Values are rounded
/// down to 4 significant digits and a value that would not fall is put
/// one unit of its 4th digit under the one before; only a level asked to
/// stop at 0 before the last one can tie (it and what follows are then
/// never shown by coverage). A ratio is capped at 0.999, so levels with as
/// many triangles as the one before still get a sliver.
pub fn screen_coverages(coverage: &[f64], triangles: &[usize]) -> Vec<f64> {
    let n = coverage.len().min(triangles.len());
    let ratio = |a: usize, b: usize| {
        if a == 0 {
            0.999
        } else {
            (b as f64 / a as f64).min(0.999)
        }
    };
    let mut out: Vec<f64> = Vec::with_capacity(n);
    for k in 0..n {
        let r = if n < 2 {
            1.0
        } else if k + 1 < n {
            ratio(triangles[k], triangles[k + 1])
        } else {
            ratio(triangles[k - 1], triangles[k])
        };
        let prev = out.last().copied().unwrap_or(1.0);
        let mut c = floor_4_digits(coverage[k].min(prev * r));
        if k > 0 && c >= prev && prev > 0.0 {
            c = below_4_digits(prev);
        }
        out.push(c);
    }
    out
}

/// `10^(3 - e)` for the decimal exponent `e` of `x` in `(0, 1]`: the scale
/// at which `x` has 4 significant digits before the point.
fn digits_scale(x: f64) -> f64 {
    10f64.powi(3 - x.log10().floor() as i32)
}

/// `x` in `[0, 1]` rounded down to 4 significant digits (values already
/// at 4 digits are kept: the product is nudged up by 1e-9 of itself).
fn floor_4_digits(x: f64) -> f64 {
    if x <= 0.0 || !x.is_finite() {
        return x.max(0.0);
    }
    let s = digits_scale(x);
    if !s.is_finite() {
        return x; // below about 1e-300: nothing to round
    }
    (x * s * (1.0 + 1e-9)).floor() / s
}

/// The 4-significant-digit value one unit of its 4th digit under `x` (a
/// value with 4 digits, in `(0, 1]`).
fn below_4_digits(x: f64) -> f64 {
    let s = digits_scale(x);
    if !s.is_finite() {
        return 0.0;
    }
    ((x * s).round() - 1.0) / s
}

/// The glTF extension that links the levels of a chain.
pub(super) const MSFT_LOD: &str = "MSFT_lod";

/// Makes `nodes[0]` of `root` the `MSFT_lod` base of `nodes[1..]`:
/// `extras.MSFT_screencoverage` on the base (the [`screen_coverages`] of
/// `coverage`, checked by [`check_coverage`], and the levels'
/// `triangles`); returns the base node's extension object for the
/// writer's `finish`, which the caller marks [`MSFT_LOD`] used (not
/// required). One node: nothing to link (empty).
pub(super) fn link_lods(
    root: &mut json::Root,
    nodes: &[json::Index<json::Node>],
    coverage: &[f64],
    triangles: &[usize],
) -> Result<Vec<(usize, serde_json::Value)>, ParseError> {
    if nodes.len() <= 1 {
        return Ok(Vec::new());
    }
    let coverage = screen_coverages(coverage, triangles);
    let ids: Vec<usize> = nodes[1..].iter().map(|n| n.value()).collect();
    let base = &mut root.nodes[nodes[0].value()];
    let mut extras: serde_json::Value =
        serde_json::from_str(base.extras.as_ref().map_or("{}", |r| r.get()))
            .map_err(|e| parse_err!("GLB: {e}"))?;
    extras["MSFT_screencoverage"] = serde_json::json!(coverage);
    base.extras =
        Some(serde_json::value::to_raw_value(&extras).map_err(|e| parse_err!("GLB: {e}"))?);
    Ok(vec![(nodes[0].value(), serde_json::json!({ "ids": ids }))])
}
