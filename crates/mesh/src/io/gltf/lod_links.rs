//! Linking the levels of an LOD chain GLB: `MSFT_lod` on level 0's node
//! and `MSFT_screencoverage` in its extras (one-mesh and scene chains).

use gltf::json;

use super::write::{Builder, MSFT_LOD};
use crate::error::ParseError;
use crate::parse_err;

/// Refuses a screen coverage outside `[0, 1]` (or NaN) for level `name`.
pub(super) fn check_coverage(name: &str, coverage: f64) -> Result<(), ParseError> {
    if !(0.0..=1.0).contains(&coverage) {
        return Err(parse_err!(
            "GLB level '{name}': screen coverage {coverage} is outside [0, 1]"
        ));
    }
    Ok(())
}

/// Makes `nodes[0]` the `MSFT_lod` base of `nodes[1..]`: `MSFT_lod` used
/// (not required), `extras.MSFT_screencoverage` on the base (the
/// `coverage` values, checked by [`check_coverage`], made
/// non-increasing); returns the base node's extension object for
/// [`Builder::finish`]. One node: nothing to link.
pub(super) fn link_lods(
    b: &mut Builder,
    nodes: &[json::Index<json::Node>],
    coverage: &[f64],
) -> Result<Vec<(usize, serde_json::Value)>, ParseError> {
    if nodes.len() <= 1 {
        return Ok(Vec::new());
    }
    let mut last = 1.0f64;
    let coverage: Vec<f64> = coverage
        .iter()
        .map(|&c| {
            last = last.min(c);
            last
        })
        .collect();
    b.uses(MSFT_LOD, false);
    let ids: Vec<usize> = nodes[1..].iter().map(|n| n.value()).collect();
    let base = &mut b.root.nodes[nodes[0].value()];
    let mut extras: serde_json::Value =
        serde_json::from_str(base.extras.as_ref().map_or("{}", |r| r.get()))
            .map_err(|e| parse_err!("GLB: {e}"))?;
    extras["MSFT_screencoverage"] = serde_json::json!(coverage);
    base.extras =
        Some(serde_json::value::to_raw_value(&extras).map_err(|e| parse_err!("GLB: {e}"))?);
    Ok(vec![(nodes[0].value(), serde_json::json!({ "ids": ids }))])
}
