//! End-to-end tests of `lodkit serve`: the real binary on an ephemeral
//! loopback port, spoken to over raw TCP so that malformed requests can be
//! sent as they are.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdout, Command, Stdio};
use std::time::{Duration, Instant};

mod common;
use common::{lodkit, stderr};

/// What no answer may ever contain: the secret file beside the root.
const SECRET: &str = "TOPSECRET-beside-the-root";

/// A running server, killed when dropped; it also stops by itself after two
/// minutes (`--exit-after`) should the test process die first.
struct Server {
    child: Child,
    port: u16,
    _stdout: BufReader<ChildStdout>,
}

impl Server {
    fn start(roots: &[&Path]) -> Server {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_lodkit"));
        cmd.arg("serve")
            .args(roots)
            .args(["--port", "0", "--exit-after", "120"])
            .stdout(Stdio::piped())
            .stderr(Stdio::null());
        let mut child = cmd.spawn().expect("start lodkit serve");
        let mut stdout = BufReader::new(child.stdout.take().unwrap());
        let mut line = String::new();
        stdout.read_line(&mut line).expect("first line");
        assert!(line.starts_with("serving "), "{line}");
        let port = line
            .trim()
            .strip_suffix('/')
            .and_then(|l| l.rsplit_once(':'))
            .and_then(|(_, p)| p.parse().ok())
            .unwrap_or_else(|| panic!("no port in {line:?}"));
        assert!(line.contains("http://127.0.0.1:"), "{line}");
        Server {
            child,
            port,
            _stdout: stdout,
        }
    }

    /// Sends `request` as it is and reads the answer to the end (every
    /// request here says `Connection: close`, or is one hyper closes on).
    fn raw(&self, request: &[u8]) -> Reply {
        let mut s = TcpStream::connect(("127.0.0.1", self.port)).unwrap();
        s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
        // The server may answer and close before it has read everything
        // (oversized heads): a failed write is not the test's concern.
        let _ = s.write_all(request);
        let mut bytes = Vec::new();
        let _ = s.read_to_end(&mut bytes);
        Reply::parse(&bytes)
    }

    fn get(&self, path: &str, headers: &[(&str, &str)]) -> Reply {
        self.request("GET", path, headers)
    }

    fn request(&self, method: &str, path: &str, headers: &[(&str, &str)]) -> Reply {
        let mut req =
            format!("{method} {path} HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n");
        for (k, v) in headers {
            req.push_str(&format!("{k}: {v}\r\n"));
        }
        req.push_str("\r\n");
        self.raw(req.as_bytes())
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

#[derive(Debug)]
struct Reply {
    status: u16,
    headers: Vec<(String, String)>,
    body: Vec<u8>,
}

impl Reply {
    fn parse(bytes: &[u8]) -> Reply {
        let split = bytes
            .windows(4)
            .position(|w| w == b"\r\n\r\n")
            .unwrap_or_else(|| panic!("no head in {:?}", String::from_utf8_lossy(bytes)));
        let head = std::str::from_utf8(&bytes[..split]).unwrap();
        let mut lines = head.split("\r\n");
        let status = lines
            .next()
            .unwrap()
            .split(' ')
            .nth(1)
            .unwrap()
            .parse()
            .unwrap();
        let headers: Vec<(String, String)> = lines
            .filter_map(|l| l.split_once(':'))
            .map(|(k, v)| (k.trim().to_ascii_lowercase(), v.trim().to_string()))
            .collect();
        let mut body = bytes[split + 4..].to_vec();
        if headers
            .iter()
            .any(|(k, v)| k == "transfer-encoding" && v.contains("chunked"))
        {
            body = dechunk(&body);
        }
        Reply {
            status,
            headers,
            body,
        }
    }

    fn header(&self, name: &str) -> Option<&str> {
        self.headers
            .iter()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v.as_str())
    }

    fn text(&self) -> String {
        String::from_utf8_lossy(&self.body).into_owned()
    }
}

fn dechunk(mut b: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    loop {
        let eol = b.windows(2).position(|w| w == b"\r\n").expect("chunk size");
        let size_field = std::str::from_utf8(&b[..eol]).unwrap();
        let size = usize::from_str_radix(size_field.split(';').next().unwrap().trim(), 16).unwrap();
        b = &b[eol + 2..];
        if size == 0 {
            return out;
        }
        out.extend_from_slice(&b[..size]);
        b = &b[size + 2..];
    }
}

/// A root with a binary model, a nested one, a text report, a hidden file,
/// a symlink inside it and two symlinks out of it; the secret lies beside
/// the root.
struct Fixture {
    _dir: tempfile::TempDir,
    root: PathBuf,
    secret: PathBuf,
    model: Vec<u8>,
    report: String,
}

fn fixture() -> Fixture {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().join("out");
    std::fs::create_dir_all(root.join("lods")).unwrap();
    let secret = dir.path().join("secret.txt");
    std::fs::write(&secret, SECRET).unwrap();
    let model: Vec<u8> = (0..10_000u32).map(|i| (i * 7 % 251) as u8).collect();
    std::fs::write(root.join("bunny.pop"), &model).unwrap();
    std::fs::write(root.join("lods/bunny_lods.glb"), b"glTF\x02\0\0\0").unwrap();
    let report = "# Report\n\n".to_string() + &"| level | triangles |\n".repeat(100);
    std::fs::write(root.join("report.md"), &report).unwrap();
    std::fs::write(root.join(".hidden"), SECRET).unwrap();
    #[cfg(unix)]
    {
        use std::os::unix::fs::symlink;
        symlink(&secret, root.join("escape.ply")).unwrap();
        symlink("../secret.txt", root.join("relative_escape.ply")).unwrap();
        symlink(dir.path(), root.join("linkdir")).unwrap();
        symlink("bunny.pop", root.join("alias.pop")).unwrap();
    }
    Fixture {
        _dir: dir,
        root,
        secret,
        model,
        report,
    }
}

#[test]
fn listing_gives_every_model_below_the_root_sorted_and_nothing_outside_it() {
    let f = fixture();
    let s = Server::start(&[&f.root]);
    let r = s.get("/api/models", &[]);
    assert_eq!(r.status, 200);
    assert!(
        r.header("content-type")
            .unwrap()
            .starts_with("application/json")
    );
    let v: serde_json::Value = serde_json::from_slice(&r.body).unwrap();
    let names: Vec<&str> = v
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["name"].as_str().unwrap())
        .collect();
    let mut expected = vec!["bunny.pop", "lods/bunny_lods.glb", "report.md"];
    if cfg!(unix) {
        expected.insert(0, "alias.pop");
    }
    assert_eq!(names, expected);
    let pop = &v.as_array().unwrap()[names.iter().position(|n| *n == "bunny.pop").unwrap()];
    assert_eq!(pop["url"], "/models/bunny.pop");
    assert_eq!(pop["kind"], "pop");
    assert_eq!(pop["bytes"], 10_000);
    let glb = &v.as_array().unwrap()[names.iter().position(|n| n.ends_with(".glb")).unwrap()];
    assert_eq!(glb["kind"], "glb");
    assert_eq!(glb["url"], "/models/lods/bunny_lods.glb");

    let html = s.get("/models/", &[]);
    assert_eq!(html.status, 200);
    assert!(html.text().contains("href=\"/models/lods/bunny_lods.glb\""));
    assert!(!html.text().contains("escape"));

    // Every listed URL answers with the listed size.
    for e in v.as_array().unwrap() {
        let r = s.get(e["url"].as_str().unwrap(), &[]);
        assert_eq!(r.status, 200, "{e}");
        assert_eq!(r.body.len() as u64, e["bytes"].as_u64().unwrap(), "{e}");
    }
    // The viewer answers at the root.
    let index = s.get("/", &[]);
    assert_eq!(index.status, 200);
    assert!(
        index
            .header("content-type")
            .unwrap()
            .starts_with("text/html")
    );
}

#[test]
fn several_files_are_each_published_under_their_own_name() {
    let f = fixture();
    let a = f.root.join("bunny.pop");
    let b = f.root.join("lods/bunny_lods.glb");
    let s = Server::start(&[&a, &b]);
    let v: serde_json::Value = serde_json::from_slice(&s.get("/api/models", &[]).body).unwrap();
    let urls: Vec<&str> = v
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["url"].as_str().unwrap())
        .collect();
    assert_eq!(urls, ["/models/bunny.pop", "/models/bunny_lods.glb"]);
    assert_eq!(s.get("/models/bunny.pop", &[]).body, f.model);
    assert_eq!(s.get("/models/report.md", &[]).status, 404);
}

#[test]
fn ranges_answer_206_with_content_range_and_416_when_unsatisfiable_or_malformed() {
    let f = fixture();
    let s = Server::start(&[&f.root]);
    let whole = s.get("/models/bunny.pop", &[]);
    assert_eq!(whole.status, 200);
    assert_eq!(whole.header("accept-ranges"), Some("bytes"));
    assert_eq!(whole.body, f.model);

    for (range, start, end) in [
        ("bytes=0-9", 0, 9),
        ("bytes=9990-", 9990, 9999),
        ("bytes=-5", 9995, 9999),
        ("bytes=100-99999", 100, 9999),
        ("bytes=1234-1234", 1234, 1234),
    ] {
        let r = s.get("/models/bunny.pop", &[("Range", range)]);
        assert_eq!(r.status, 206, "{range}");
        let cr = format!("bytes {start}-{end}/10000");
        assert_eq!(r.header("content-range"), Some(cr.as_str()), "{range}");
        assert_eq!(r.body, &f.model[start..=end], "{range}");
        assert_eq!(
            r.header("content-length"),
            Some((end - start + 1).to_string().as_str())
        );
    }
    for range in [
        "bytes=10000-",
        "bytes=20000-30000",
        "bytes=-0",
        "bytes=5-2",
        "bytes=abc",
        "bytes=",
        "bytes=--1",
        "bytes=1-2-3",
    ] {
        let r = s.get("/models/bunny.pop", &[("Range", range)]);
        assert_eq!(r.status, 416, "{range}");
        assert_eq!(r.header("content-range"), Some("bytes */10000"), "{range}");
        assert!(r.body.is_empty(), "{range}");
    }
    // Unknown units are ignored; several ranges get the whole body.
    for range in ["items=0-5", "bytes=0-1,5-6"] {
        let r = s.get("/models/bunny.pop", &[("Range", range)]);
        assert_eq!(r.status, 200, "{range}");
        assert_eq!(r.body, f.model, "{range}");
    }
    // HEAD: the headers without the body.
    let head = s.request("HEAD", "/models/bunny.pop", &[("Range", "bytes=0-9")]);
    assert_eq!(head.status, 206);
    assert_eq!(head.header("content-length"), Some("10"));
    assert!(head.body.is_empty());
}

#[test]
fn etag_gives_304_on_if_none_match_and_gates_if_range() {
    let f = fixture();
    let s = Server::start(&[&f.root]);
    let first = s.get("/models/bunny.pop", &[]);
    let etag = first.header("etag").expect("etag").to_string();
    assert!(
        etag.starts_with('"') && etag.ends_with('"'),
        "strong: {etag}"
    );
    assert_eq!(
        s.get("/models/bunny.pop", &[]).header("etag"),
        Some(etag.as_str())
    );

    let r = s.get("/models/bunny.pop", &[("If-None-Match", &etag)]);
    assert_eq!(r.status, 304);
    assert!(r.body.is_empty());
    assert_eq!(r.header("etag"), Some(etag.as_str()));
    let list = format!("\"nope\", {etag}");
    assert_eq!(
        s.get("/models/bunny.pop", &[("If-None-Match", &list)])
            .status,
        304
    );
    assert_eq!(
        s.get("/models/bunny.pop", &[("If-None-Match", "*")]).status,
        304
    );
    assert_eq!(
        s.get("/models/bunny.pop", &[("If-None-Match", "\"nope\"")])
            .status,
        200
    );

    let r = s.get(
        "/models/bunny.pop",
        &[("Range", "bytes=0-3"), ("If-Range", &etag)],
    );
    assert_eq!(r.status, 206);
    assert_eq!(r.body, &f.model[..4]);
    let r = s.get(
        "/models/bunny.pop",
        &[("Range", "bytes=0-3"), ("If-Range", "\"old\"")],
    );
    assert_eq!(r.status, 200);
    assert_eq!(r.body, f.model);

    // A changed file gets a new tag.
    std::thread::sleep(Duration::from_millis(20));
    std::fs::write(f.root.join("bunny.pop"), b"changed").unwrap();
    let r = s.get("/models/bunny.pop", &[("If-None-Match", &etag)]);
    assert_eq!(r.status, 200);
    assert_eq!(r.body, b"changed");

    // Viewer assets are tagged too.
    let index = s.get("/", &[]);
    let tag = index.header("etag").expect("asset etag").to_string();
    assert_eq!(s.get("/", &[("If-None-Match", &tag)]).status, 304);
}

#[test]
fn text_is_compressed_as_asked_and_models_never_are() {
    let f = fixture();
    let s = Server::start(&[&f.root]);
    let gz = s.get("/models/report.md", &[("Accept-Encoding", "gzip")]);
    assert_eq!(gz.status, 200);
    assert_eq!(gz.header("content-encoding"), Some("gzip"));
    assert_eq!(&gz.body[..2], &[0x1f, 0x8b]);
    assert!(gz.body.len() < f.report.len() / 4);
    let br = s.get("/models/report.md", &[("Accept-Encoding", "br")]);
    assert_eq!(br.header("content-encoding"), Some("br"));
    assert!(br.body.len() < f.report.len() / 4);
    let plain = s.get("/models/report.md", &[]);
    assert_eq!(plain.header("content-encoding"), None);
    assert_eq!(plain.text(), f.report);
    let json = s.get("/api/models", &[("Accept-Encoding", "gzip, br")]);
    assert!(json.header("content-encoding").is_some());

    // Model bytes go out as they are, whole or in part.
    for headers in [
        vec![("Accept-Encoding", "gzip, deflate, br, zstd")],
        vec![("Accept-Encoding", "gzip"), ("Range", "bytes=10-19")],
    ] {
        let r = s.get("/models/bunny.pop", &headers);
        assert_eq!(r.header("content-encoding"), None, "{headers:?}");
        let expect = if r.status == 206 {
            &f.model[10..20]
        } else {
            &f.model[..]
        };
        assert_eq!(r.body, expect, "{headers:?}");
    }
    let r = s.get(
        "/models/lods/bunny_lods.glb",
        &[("Accept-Encoding", "gzip")],
    );
    assert_eq!(r.header("content-encoding"), None);
    // A range of a text file addresses its identity bytes.
    let r = s.get(
        "/models/report.md",
        &[("Accept-Encoding", "gzip"), ("Range", "bytes=0-7")],
    );
    assert_eq!(r.status, 206);
    assert_eq!(r.header("content-encoding"), None);
    assert_eq!(r.body, b"# Report");
}

#[test]
fn the_viewers_wasm_is_compressed_as_asked() {
    let f = fixture();
    let s = Server::start(&[&f.root]);
    let plain = s.get("/lodkit/lodkit.wasm", &[]);
    if plain.status == 404 {
        eprintln!("skipped: this binary was built without the viewer (LODKIT_VIEWER=skip)");
        return;
    }
    assert_eq!(plain.status, 200);
    assert_eq!(plain.header("content-type"), Some("application/wasm"));
    assert_eq!(plain.header("content-encoding"), None);
    assert!(plain.body.starts_with(b"\0asm"));
    let gz = s.get("/lodkit/lodkit.wasm", &[("Accept-Encoding", "gzip")]);
    assert_eq!(gz.status, 200);
    assert_eq!(gz.header("content-encoding"), Some("gzip"));
    assert_eq!(gz.header("content-type"), Some("application/wasm"));
    assert!(
        gz.body.len() < plain.body.len() * 3 / 4,
        "{} gzipped bytes of {}",
        gz.body.len(),
        plain.body.len()
    );
    let mut back = Vec::new();
    flate2::read::GzDecoder::new(&gz.body[..])
        .read_to_end(&mut back)
        .unwrap();
    assert!(
        back == plain.body,
        "the gzipped wasm inflates to other bytes"
    );
    let br = s.get("/lodkit/lodkit.wasm", &[("Accept-Encoding", "br")]);
    assert_eq!(br.header("content-encoding"), Some("br"));
    assert!(br.body.len() < plain.body.len() * 3 / 4);
}

#[test]
fn no_escape_attempt_reads_a_byte_from_outside_the_root() {
    let f = fixture();
    let s = Server::start(&[&f.root]);
    let abs = f.secret.display().to_string();
    let abs_encoded = abs.replace('/', "%2f");
    let paths = [
        "/models/../secret.txt".to_string(),
        "/models/%2e%2e/secret.txt".into(),
        "/models/%2E%2E/secret.txt".into(),
        "/models/.%2e/secret.txt".into(),
        "/models/%2e%2e%2fsecret.txt".into(),
        "/models/..%2Fsecret.txt".into(),
        "/models/..%5csecret.txt".into(),
        "/models/%2e%2e%5csecret.txt".into(),
        "/models/..\\secret.txt".into(),
        "/models/lods/../../secret.txt".into(),
        "/models/lods/%2e%2e/%2e%2e/secret.txt".into(),
        "/models/%252e%252e/secret.txt".into(),
        "/models/escape.ply".into(),
        "/models/relative_escape.ply".into(),
        "/models/linkdir/secret.txt".into(),
        "/models/linkdir/".into(),
        "/models/linkdir".into(),
        "/models/.hidden".into(),
        "/models/bunny.pop%00".into(),
        "/models/bunny.pop%00.txt".into(),
        format!("/models/{abs}"),
        format!("/models/{abs_encoded}"),
        format!("/models/%2f{}", abs_encoded.trim_start_matches("%2f")),
        "/models//etc/passwd".into(),
        "/models/%2fetc%2fpasswd".into(),
        "/../secret.txt".into(),
        "/%2e%2e/secret.txt".into(),
        "/%2e%2e/%2e%2e/%2e%2e/etc/passwd".into(),
        "/models/C:%5cWindows%5cwin.ini".into(),
    ];
    for p in &paths {
        let r = s.get(p, &[]);
        assert!(matches!(r.status, 400 | 403 | 404), "{p}: {}", r.status);
        assert!(!r.text().contains(SECRET), "{p} leaked the secret");
        assert!(!r.text().contains("root:"), "{p} leaked /etc/passwd");
    }
    // Absolute-form request targets, raw.
    for target in [
        "http://127.0.0.1/models/../secret.txt",
        "http://127.0.0.1/models/%2e%2e/secret.txt",
    ] {
        let req = format!("GET {target} HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n");
        let r = s.raw(req.as_bytes());
        assert!(
            matches!(r.status, 400 | 403 | 404),
            "{target}: {}",
            r.status
        );
        assert!(!r.text().contains(SECRET));
    }
    // A symlink that stays inside the root is served.
    assert_eq!(s.get("/models/alias.pop", &[]).body, f.model);
}

#[test]
fn malformed_requests_get_a_4xx_and_the_server_keeps_answering() {
    let f = fixture();
    let s = Server::start(&[&f.root]);
    let huge_header = format!(
        "GET /api/models HTTP/1.1\r\nHost: x\r\nX-Big: {}\r\n\r\n",
        "a".repeat(200_000)
    );
    let many_headers = format!(
        "GET /api/models HTTP/1.1\r\nHost: x\r\n{}\r\n",
        (0..500)
            .map(|i| format!("X-H{i}: v\r\n"))
            .collect::<String>()
    );
    let long_uri = format!(
        "GET /models/{} HTTP/1.1\r\nHost: x\r\n\r\n",
        "a".repeat(100_000)
    );
    let cases: Vec<(&str, Vec<u8>)> = vec![
        ("garbage line", b"HELLO THERE\r\n\r\n".to_vec()),
        (
            "binary",
            vec![0xff, 0x00, 0x13, 0x37, b'\r', b'\n', b'\r', b'\n'],
        ),
        ("bad version", b"GET / HTTP/9.9\r\nHost: x\r\n\r\n".to_vec()),
        (
            "NUL in path",
            b"GET /models/a\0b HTTP/1.1\r\nHost: x\r\n\r\n".to_vec(),
        ),
        (
            "space in path",
            b"GET /models/a b HTTP/1.1\r\nHost: x\r\n\r\n".to_vec(),
        ),
        ("bad header", b"GET / HTTP/1.1\r\nHost x\r\n\r\n".to_vec()),
        ("huge header", huge_header.into_bytes()),
        ("many headers", many_headers.into_bytes()),
        ("long uri", long_uri.into_bytes()),
        (
            "bad content-length",
            b"GET / HTTP/1.1\r\nHost: x\r\nContent-Length: -5\r\n\r\n".to_vec(),
        ),
    ];
    for (what, req) in &cases {
        let r = s.raw(req);
        assert!((400..500).contains(&r.status), "{what}: {}", r.status);
    }
    for (method, code) in [("POST", 405), ("PUT", 405), ("DELETE", 405)] {
        let r = s.request(method, "/models/bunny.pop", &[]);
        assert_eq!(r.status, code, "{method}");
    }
    for range in [
        "bytes=\u{7f}",
        "bytes=\u{e9}",
        "bytes=99999999999999999999999-",
    ] {
        let r = s.get("/models/bunny.pop", &[("Range", range)]);
        assert!((400..500).contains(&r.status), "{range:?}: {}", r.status);
    }
    assert_eq!(s.get("/models/%zz", &[]).status, 404);
    assert_eq!(s.get("/models/%", &[]).status, 404);
    assert_eq!(s.get("/nothing-here.js", &[]).status, 404);
    // A client that sends half a head and goes away.
    {
        let mut c = TcpStream::connect(("127.0.0.1", s.port)).unwrap();
        c.write_all(b"GET /models/bunny.pop HTTP/1.1\r\nHo")
            .unwrap();
    }
    let r = s.get("/models/bunny.pop", &[]);
    assert_eq!(r.status, 200);
    assert_eq!(r.body, f.model);
}

#[test]
fn keep_alive_connections_serve_many_requests() {
    let f = fixture();
    let s = Server::start(&[&f.root]);
    let mut c = TcpStream::connect(("127.0.0.1", s.port)).unwrap();
    c.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
    let mut reader = BufReader::new(c.try_clone().unwrap());
    for i in 0..50u64 {
        let req = format!(
            "GET /models/bunny.pop HTTP/1.1\r\nHost: x\r\nRange: bytes={i}-{}\r\n\r\n",
            i + 99
        );
        c.write_all(req.as_bytes()).unwrap();
        let mut len = None;
        let mut line = String::new();
        reader.read_line(&mut line).unwrap();
        assert!(line.starts_with("HTTP/1.1 206"), "{line}");
        loop {
            line.clear();
            reader.read_line(&mut line).unwrap();
            if line == "\r\n" {
                break;
            }
            if let Some(v) = line.to_ascii_lowercase().strip_prefix("content-length:") {
                len = Some(v.trim().parse::<usize>().unwrap());
            }
        }
        let mut body = vec![0; len.unwrap()];
        reader.read_exact(&mut body).unwrap();
        assert_eq!(body, &f.model[i as usize..i as usize + 100]);
    }
}

#[cfg(unix)]
#[test]
fn sigterm_and_ctrl_c_stop_the_server_cleanly() {
    let f = fixture();
    for signal in ["-TERM", "-INT"] {
        let mut s = Server::start(&[&f.root]);
        assert_eq!(s.get("/api/models", &[]).status, 200);
        let ok = Command::new("kill")
            .args([signal, &s.child.id().to_string()])
            .status()
            .unwrap();
        assert!(ok.success());
        let deadline = Instant::now() + Duration::from_secs(10);
        let status = loop {
            if let Some(st) = s.child.try_wait().unwrap() {
                break st;
            }
            assert!(
                Instant::now() < deadline,
                "still running 10 s after {signal}"
            );
            std::thread::sleep(Duration::from_millis(20));
        };
        assert!(status.success(), "{signal}: {status:?}");
    }
}

#[test]
fn a_missing_root_is_one_line_and_exit_1_bad_options_exit_2() {
    let o = lodkit(&["serve", "/no/such/dir", "--port", "0"]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("/no/such/dir"), "{err}");
    for bad in [
        &["serve", ".", "--port", "abc"][..],
        &["serve", ".", "--port", "70000"],
        &["serve", ".", "--bind", "not-an-address"],
    ] {
        let o = lodkit(bad);
        assert_eq!(o.status.code(), Some(2), "{bad:?}: {}", stderr(&o));
    }
}

#[test]
fn a_port_in_use_is_one_line_and_exit_1() {
    let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let port = taken.local_addr().unwrap().port().to_string();
    let o = lodkit(&["serve", ".", "--port", &port, "--exit-after", "5"]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(err.contains(&port), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
}

/// A build folder's tileset (`lodkit tiles`, as `build` writes it under
/// `tiles/`): listed once with kind `tileset` (what the viewer opens via
/// `?model=`), its external tilesets and tiles as parts of it, each URL
/// answering with its file.
#[test]
fn tilesets_are_listed_as_models_the_viewer_opens() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().join("out");
    let bunny = common::bunny();
    let o = lodkit(&[
        "-q",
        "tiles",
        &bunny,
        "--out",
        root.join("tiles").to_str().unwrap(),
        "--leaf-triangles",
        "2048",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = Server::start(&[&root]);
    let v: serde_json::Value = serde_json::from_slice(&s.get("/api/models", &[]).body).unwrap();
    let entries = v.as_array().unwrap();
    let sets: Vec<&serde_json::Value> = entries.iter().filter(|e| e["kind"] == "tileset").collect();
    assert_eq!(sets.len(), 1, "{v}");
    assert_eq!(sets[0]["name"], "tiles/tileset.json");
    assert_eq!(sets[0]["url"], "/models/tiles/tileset.json");
    // External tilesets (tiles/tiles/D-X-Y-Z.json) are parts, not models.
    assert!(
        entries
            .iter()
            .filter(|e| e["name"].as_str().unwrap().starts_with("tiles/tiles/"))
            .all(|e| e["kind"] != "tileset"),
        "{v}"
    );
    let tileset = s.get("/models/tiles/tileset.json", &[]);
    assert_eq!(tileset.status, 200);
    let json: serde_json::Value = serde_json::from_slice(&tileset.body).unwrap();
    let uri = json["root"]["content"]["uri"].as_str().unwrap();
    let tile = s.get(&format!("/models/tiles/{uri}"), &[]);
    assert_eq!(tile.status, 200);
    assert!(tile.body.starts_with(b"glTF"));
}
