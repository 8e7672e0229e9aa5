//! The browser viewer's files, built into the binary by `build.rs` (from
//! `web/` and the `lodkit-wasm` crate) for `lodkit serve`.
//!
//! Paths are relative to the viewer's root, `/`-separated, with no leading
//! slash (`index.html`, `lodkit/lodkit.wasm`, `three/build/three.module.js`):
//! the server maps `GET /<path>` to `get(path)` and `GET /` to
//! `get("index.html")`. When the viewer could not be built, `index.html` is
//! a page saying how to build it and nothing else is there.

include!(concat!(env!("OUT_DIR"), "/viewer_assets.rs"));

/// Shown in place of the viewer when the build had no npm or wasm target.
const NOT_BUILT: &[u8] = b"<!doctype html>\n<meta charset=\"utf-8\">\n<title>lodkit</title>\n\
<h1>The lodkit viewer is not built into this binary</h1>\n\
<p>Building it needs <code>npm</code> (Node.js) and the Rust target <code>wasm32-unknown-unknown</code> \
(<code>rustup target add wasm32-unknown-unknown</code>). Install them, then rebuild: \
<code>cargo build --release -p lodkit</code> (unset <code>LODKIT_VIEWER=skip</code> if it is set). \
<code>scripts/build-web.sh</code> shows what the build does.</p>\n\
<p>The models are listed at <a href=\"/models/\">/models/</a> and <a href=\"/api/models\">/api/models</a>.</p>\n";

/// MIME type of a viewer file, from its extension.
fn mime(path: &str) -> &'static str {
    match path.rsplit('.').next() {
        Some("html") => "text/html; charset=utf-8",
        Some("js" | "mjs") => "text/javascript; charset=utf-8",
        Some("wasm") => "application/wasm",
        Some("json") => "application/json",
        Some("css") => "text/css; charset=utf-8",
        _ => "application/octet-stream",
    }
}

/// The bytes and MIME type of the viewer file at `path` (relative to the
/// viewer's root, no leading slash: `index.html`), if there is one.
pub fn get(path: &str) -> Option<(&'static [u8], &'static str)> {
    if let Some((p, bytes)) = ASSETS.iter().find(|(p, _)| *p == path) {
        return Some((bytes, mime(p)));
    }
    (path == "index.html" && ASSETS.is_empty()).then_some((NOT_BUILT, mime(path)))
}

/// The paths `get` answers, sorted.
pub fn list() -> impl Iterator<Item = &'static str> {
    let fallback = ASSETS.is_empty().then_some("index.html");
    ASSETS.iter().map(|(p, _)| *p).chain(fallback)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn index_is_always_there() {
        let (bytes, mime) = get("index.html").expect("a page either way");
        assert!(mime.starts_with("text/html"));
        assert!(bytes.starts_with(b"<!doctype html>"));
        assert!(list().any(|p| p == "index.html"));
    }

    #[test]
    fn every_listed_path_is_served_with_a_type() {
        for p in list() {
            let (_, m) = get(p).expect("listed paths are served");
            assert!(!m.is_empty());
        }
        assert!(get("../Cargo.toml").is_none());
        assert!(get("").is_none());
    }

    #[test]
    fn a_built_viewer_has_its_decoders() {
        if ASSETS.is_empty() {
            return; // built without npm or with LODKIT_VIEWER=skip
        }
        let (wasm, m) = get("lodkit/lodkit.wasm").expect("the decoders");
        assert_eq!(m, "application/wasm");
        assert!(wasm.starts_with(b"\0asm"));
        assert!(get("three/build/three.module.js").is_some());
        // Tilesets: 3DTilesRendererJS and the meshopt decoder it is given.
        assert!(get("3d-tiles-renderer/build/index.three.js").is_some());
        assert!(get("three/examples/jsm/libs/meshopt_decoder.module.js").is_some());
    }
}
