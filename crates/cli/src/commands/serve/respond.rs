//! The answers: routing, model files (ranges, entity tags), viewer assets,
//! the listing.
//!
//! URL scheme:
//! - `GET /` and `GET /<asset>`: the viewer built into the binary.
//! - `GET /api/models`: the listing as JSON, `[{name, url, kind, bytes}]`
//!   sorted by name.
//! - `GET /models/`: the same listing as a plain HTML page.
//! - `GET /models/<name>`: a model's bytes, with ranges and entity tags.
//!
//! Only `GET` and `HEAD` are answered (405 otherwise).

use std::collections::HashMap;
use std::io::SeekFrom;
use std::path::Path;
use std::sync::Arc;

use axum::body::Body;
use axum::extract::{Request, State};
use axum::http::{HeaderMap, HeaderValue, Method, StatusCode, header};
use axum::response::Response;
use tokio::io::{AsyncReadExt, AsyncSeekExt};

use super::range::{self, Plan};
use super::roots::{Entry, MODELS_PREFIX, Roots, kind_of};

/// Read size of the file streams: large enough that a multi-megabyte model
/// takes few reads, small enough that 64 clients hold little memory.
const CHUNK: usize = 64 * 1024;

/// What every request sees.
pub struct Shared {
    pub roots: Roots,
    /// Entity tag of each viewer asset, computed once (the bytes are static).
    asset_tags: HashMap<&'static str, String>,
}

impl Shared {
    pub fn new(roots: Roots) -> Self {
        let asset_tags = crate::viewer_assets::list()
            .filter_map(|p| {
                let (bytes, _) = crate::viewer_assets::get(p)?;
                Some((p, format!("W/\"{:016x}\"", fnv1a(bytes))))
            })
            .collect();
        Shared { roots, asset_tags }
    }
}

/// Every request lands here.
pub async fn route(State(shared): State<Arc<Shared>>, req: Request) -> Response {
    let method = req.method().clone();
    if method != Method::GET && method != Method::HEAD {
        let mut r = status(StatusCode::METHOD_NOT_ALLOWED, "only GET and HEAD\n");
        r.headers_mut()
            .insert(header::ALLOW, HeaderValue::from_static("GET, HEAD"));
        return r;
    }
    let head = method == Method::HEAD;
    let path = req.uri().path();
    if path == "/api/models" || path == "/models" || path == MODELS_PREFIX {
        let json = path == "/api/models";
        // Walking the roots touches the file system: keep it off the reactor.
        let walker = shared.clone();
        let entries = tokio::task::spawn_blocking(move || walker.roots.list())
            .await
            .unwrap_or_default();
        return if json {
            listing_json(&entries, head)
        } else {
            listing_html(&entries, head)
        };
    }
    if let Some(raw) = path.strip_prefix(MODELS_PREFIX) {
        let headers = req.headers();
        // Resolving touches the file system: keep it off the reactor.
        let roots_shared = shared.clone();
        let raw = raw.to_string();
        let file = tokio::task::spawn_blocking(move || roots_shared.roots.resolve(&raw))
            .await
            .ok()
            .flatten();
        return match file {
            Some(f) => model(&f, headers, head).await,
            None => not_found(),
        };
    }
    asset(&shared, path, req.headers(), head)
}

/// A model file: whole, one range, 304 or 416.
async fn model(path: &Path, headers: &HeaderMap, head: bool) -> Response {
    let Ok(mut file) = tokio::fs::File::open(path).await else {
        return not_found();
    };
    let Ok(meta) = file.metadata().await else {
        return not_found();
    };
    if !meta.is_file() {
        return not_found();
    }
    let len = meta.len();
    let mime = model_mime(path);
    let etag = file_tag(&meta, compressible(mime));

    let mut r = Response::new(Body::empty());
    let h = r.headers_mut();
    h.insert(header::CONTENT_TYPE, HeaderValue::from_static(mime));
    h.insert(header::ACCEPT_RANGES, HeaderValue::from_static("bytes"));
    h.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-cache"));
    h.insert(
        header::X_CONTENT_TYPE_OPTIONS,
        HeaderValue::from_static("nosniff"),
    );
    if let Ok(v) = HeaderValue::from_str(&etag) {
        h.insert(header::ETAG, v);
    }

    if headers
        .get(header::IF_NONE_MATCH)
        .is_some_and(|v| range::none_match(v.as_bytes(), &etag))
    {
        *r.status_mut() = StatusCode::NOT_MODIFIED;
        return r;
    }
    let range_header = headers
        .get(header::RANGE)
        .filter(|_| {
            headers
                .get(header::IF_RANGE)
                .is_none_or(|v| range::if_range_holds(v.as_bytes(), &etag))
        })
        .map(HeaderValue::as_bytes);
    let (start, count) = match range::plan(range_header, len) {
        Plan::Whole => (0, len),
        Plan::Part { start, end } => {
            *r.status_mut() = StatusCode::PARTIAL_CONTENT;
            let cr = format!("bytes {start}-{end}/{len}");
            r.headers_mut()
                .insert(header::CONTENT_RANGE, HeaderValue::from_str(&cr).unwrap());
            (start, end - start + 1)
        }
        Plan::Unsatisfiable => {
            *r.status_mut() = StatusCode::RANGE_NOT_SATISFIABLE;
            let cr = format!("bytes */{len}");
            r.headers_mut()
                .insert(header::CONTENT_RANGE, HeaderValue::from_str(&cr).unwrap());
            return r;
        }
    };
    r.headers_mut()
        .insert(header::CONTENT_LENGTH, HeaderValue::from(count));
    if head || count == 0 {
        return r;
    }
    if start > 0 && file.seek(SeekFrom::Start(start)).await.is_err() {
        return status(StatusCode::INTERNAL_SERVER_ERROR, "seek failed\n");
    }
    let stream = tokio_util::io::ReaderStream::with_capacity(file.take(count), CHUNK);
    *r.body_mut() = Body::from_stream(stream);
    r
}

/// A viewer file, `/` being `index.html`.
fn asset(shared: &Shared, path: &str, headers: &HeaderMap, head: bool) -> Response {
    let name = match path.trim_start_matches('/') {
        "" => "index.html",
        p => p,
    };
    // The asset table is keyed without the leading slash; accept a table
    // keyed with it too, so either convention of the generated module works.
    let found = crate::viewer_assets::get(name)
        .map(|a| (name, a))
        .or_else(|| crate::viewer_assets::get(path).map(|a| (path, a)));
    let Some((key, (bytes, mime))) = found else {
        return not_found();
    };
    let mut r = Response::new(Body::empty());
    let h = r.headers_mut();
    h.insert(header::CONTENT_TYPE, HeaderValue::from_static(mime));
    h.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-cache"));
    h.insert(
        header::X_CONTENT_TYPE_OPTIONS,
        HeaderValue::from_static("nosniff"),
    );
    if let Some(tag) = shared.asset_tags.get(key) {
        h.insert(header::ETAG, HeaderValue::from_str(tag).unwrap());
        if headers
            .get(header::IF_NONE_MATCH)
            .is_some_and(|v| range::none_match(v.as_bytes(), tag))
        {
            *r.status_mut() = StatusCode::NOT_MODIFIED;
            return r;
        }
    }
    r.headers_mut()
        .insert(header::CONTENT_LENGTH, HeaderValue::from(bytes.len()));
    if !head {
        *r.body_mut() = Body::from(bytes);
    }
    r
}

fn listing_json(entries: &[Entry], head: bool) -> Response {
    let body = serde_json::to_vec(entries).unwrap_or_else(|_| b"[]".to_vec());
    text_response("application/json", body, head)
}

fn listing_html(entries: &[Entry], head: bool) -> Response {
    let mut page = String::from(
        "<!doctype html>\n<meta charset=\"utf-8\">\n<title>lodkit models</title>\n\
         <h1>Models</h1>\n<p><a href=\"/\">viewer</a> · <a href=\"/api/models\">JSON</a></p>\n\
         <table>\n<tr><th>name</th><th>kind</th><th>bytes</th></tr>\n",
    );
    for e in entries {
        page.push_str(&format!(
            "<tr><td><a href=\"{}\">{}</a></td><td>{}</td><td>{}</td></tr>\n",
            html_escape(&e.url),
            html_escape(&e.name),
            e.kind,
            e.bytes
        ));
    }
    page.push_str("</table>\n");
    text_response("text/html; charset=utf-8", page.into_bytes(), head)
}

fn text_response(mime: &'static str, body: Vec<u8>, head: bool) -> Response {
    let mut r = Response::new(Body::empty());
    let h = r.headers_mut();
    h.insert(header::CONTENT_TYPE, HeaderValue::from_static(mime));
    h.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-cache"));
    h.insert(header::CONTENT_LENGTH, HeaderValue::from(body.len()));
    if !head {
        *r.body_mut() = Body::from(body);
    }
    r
}

fn not_found() -> Response {
    status(StatusCode::NOT_FOUND, "not found\n")
}

fn status(code: StatusCode, msg: &'static str) -> Response {
    let mut r = Response::new(Body::from(msg));
    *r.status_mut() = code;
    r.headers_mut().insert(
        header::CONTENT_TYPE,
        HeaderValue::from_static("text/plain; charset=utf-8"),
    );
    r
}

/// Whether responses of this content type are worth compressing: text,
/// and WebAssembly (the viewer's decoders, which gzip to about a third).
/// Model formats are sent as they are so that ranges address their bytes.
pub fn compressible(mime: &str) -> bool {
    let essence = mime.split(';').next().unwrap_or("").trim();
    essence.starts_with("text/")
        || matches!(
            essence,
            "application/json" | "application/javascript" | "application/wasm" | "image/svg+xml"
        )
}

/// Content type of a model-directory file from its extension. Model
/// formats get non-text types (never compressed); the reports that `lodkit
/// build` writes beside them (`.json`, `.md`, `.svg`, `.html`) get theirs.
fn model_mime(path: &Path) -> &'static str {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
    match kind_of(name) {
        "glb" => return "model/gltf-binary",
        "gltf" => return "model/gltf+json",
        "obj" => return "model/obj",
        "stl" => return "model/stl",
        "pop" | "mco" | "ply" | "xyz" => return "application/octet-stream",
        _ => {}
    }
    let ext = name.rsplit_once('.').map(|(_, e)| e.to_ascii_lowercase());
    match ext.as_deref() {
        Some("json") => "application/json",
        Some("md") => "text/markdown; charset=utf-8",
        Some("svg") => "image/svg+xml",
        Some("html" | "htm") => "text/html; charset=utf-8",
        Some("txt" | "log" | "csv") => "text/plain; charset=utf-8",
        Some("png") => "image/png",
        Some("jpg" | "jpeg") => "image/jpeg",
        _ => "application/octet-stream",
    }
}

/// Entity tag of a file from its size, modification time and inode. Strong
/// for bytes sent as they are; weak when the body may be compressed, since
/// the compressed body is a different sequence of bytes (RFC 9110 §8.8.1).
fn file_tag(meta: &std::fs::Metadata, weak: bool) -> String {
    let mtime = meta
        .modified()
        .ok()
        .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
        .map_or(0, |d| d.as_nanos());
    #[cfg(unix)]
    let ino = std::os::unix::fs::MetadataExt::ino(meta);
    #[cfg(not(unix))]
    let ino = 0u64;
    let tag = format!("\"{:x}-{:x}-{:x}\"", meta.len(), mtime, ino);
    if weak { format!("W/{tag}") } else { tag }
}

/// FNV-1a, 64 bits: a content tag for the static assets.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

fn html_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn models_are_not_compressible_reports_are() {
        for m in [
            "x.pop", "x.mco", "x.glb", "x.ply", "x.obj", "x.stl", "x.bin",
        ] {
            assert!(!compressible(model_mime(Path::new(m))), "{m}");
        }
        for m in ["lods.json", "report.md", "lod_error.svg", "index.html"] {
            assert!(compressible(model_mime(Path::new(m))), "{m}");
        }
        // The viewer's decoders (served from the built-in assets).
        assert!(compressible("application/wasm"));
    }
}
