//! Load on `lodkit serve`: C concurrent keep-alive clients × R range requests
//! each, on loopback, every answer checked byte for byte against the file.
//!
//! ```text
//! cargo build --release -p lodkit
//! target/release/lodkit build --out /tmp/x --samples 100000
//! cargo run --release -p lodkit --example serve_load -- target/release/lodkit /tmp/x [C] [R]
//! ```
//!
//! It starts the server itself on an ephemeral 127.0.0.1 port (nothing else
//! is ever contacted), asks `/api/models` for the model files, and sends
//! each client's requests (a seeded random file and range of 1 KiB–256 KiB)
//! over one connection. It prints the error count, p50/p99/max latency and
//! the server's peak resident memory (`VmHWM`), then stops the server. The
//! whole run is bounded: clients stop at [`DEADLINE`], the server stops by
//! itself after ten minutes should this program die.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// No client sends a request after this long.
const DEADLINE: Duration = Duration::from_secs(120);
/// Range lengths are drawn from 1 KiB up to this.
const MAX_RANGE: u64 = 256 * 1024;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 2 {
        eprintln!("usage: serve_load LODKIT_BIN DIR [CLIENTS=64] [REQUESTS=200]");
        std::process::exit(2);
    }
    let (bin, dir) = (&args[0], Path::new(&args[1]));
    let clients: usize = args.get(2).map_or(64, |s| s.parse().expect("CLIENTS"));
    let requests: usize = args.get(3).map_or(200, |s| s.parse().expect("REQUESTS"));

    let mut child = Command::new(bin)
        .args(["serve", &args[1], "--port", "0", "--exit-after", "600"])
        .stdout(Stdio::piped())
        .spawn()
        .expect("start lodkit serve");
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .expect("banner");
    let port: u16 = line
        .trim()
        .trim_end_matches('/')
        .rsplit_once(':')
        .and_then(|(_, p)| p.parse().ok())
        .unwrap_or_else(|| panic!("no port in {line:?}"));

    let files = Arc::new(models(port, dir));
    let total_bytes: usize = files.iter().map(|(_, _, b)| b.len()).sum();
    println!(
        "{} model files ({:.1} MB) from {}; {clients} clients x {requests} range requests",
        files.len(),
        total_bytes as f64 / 1e6,
        dir.display()
    );

    let start = Instant::now();
    let workers: Vec<_> = (0..clients)
        .map(|c| {
            let files = files.clone();
            std::thread::spawn(move || client(port, c as u64, requests, &files, start))
        })
        .collect();
    let mut latencies = Vec::with_capacity(clients * requests);
    let (mut errors, mut bytes) = (0usize, 0u64);
    for w in workers {
        let r = w.join().expect("client thread");
        latencies.extend(r.latencies);
        errors += r.errors;
        bytes += r.bytes;
    }
    let wall = start.elapsed();
    let peak_kib = peak_rss_kib(child.id());
    let _ = child.kill();
    let _ = child.wait();

    latencies.sort();
    let pct = |q: f64| {
        latencies
            .get(((latencies.len() as f64 * q) as usize).min(latencies.len().saturating_sub(1)))
            .map_or(f64::NAN, |d| d.as_secs_f64() * 1e3)
    };
    println!(
        "requests {} errors {errors} | latency p50 {:.2} ms p99 {:.2} ms max {:.2} ms | {:.0} req/s, {:.0} MB/s | server peak RSS {}",
        latencies.len(),
        pct(0.50),
        pct(0.99),
        latencies.last().map_or(f64::NAN, |d| d.as_secs_f64() * 1e3),
        latencies.len() as f64 / wall.as_secs_f64(),
        bytes as f64 / 1e6 / wall.as_secs_f64(),
        peak_kib.map_or("unknown".to_string(), |k| format!(
            "{:.1} MiB",
            k as f64 / 1024.0
        )),
    );
    if errors > 0 || latencies.len() != clients * requests {
        std::process::exit(1);
    }
}

/// `(url, name, bytes)` of every model file the server lists.
fn models(port: u16, dir: &Path) -> Vec<(String, String, Vec<u8>)> {
    let mut s = TcpStream::connect(("127.0.0.1", port)).expect("connect");
    s.write_all(b"GET /api/models HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n")
        .unwrap();
    let mut all = Vec::new();
    s.read_to_end(&mut all).unwrap();
    let text = String::from_utf8(all).unwrap();
    let body = text.split_once("\r\n\r\n").expect("answer").1;
    // The listing is flat JSON objects; pick the fields without a JSON crate.
    let mut out = Vec::new();
    for obj in body.split('}') {
        let field = |k: &str| {
            let at = obj.find(&format!("\"{k}\":\""))? + k.len() + 4;
            Some(obj[at..].split('"').next()?.to_string())
        };
        let (Some(name), Some(url), Some(kind)) = (field("name"), field("url"), field("kind"))
        else {
            continue;
        };
        if matches!(kind.as_str(), "pop" | "mco" | "glb" | "ply") {
            let bytes = std::fs::read(dir.join(&name)).expect("read a listed file");
            if !bytes.is_empty() {
                out.push((url, name, bytes));
            }
        }
    }
    assert!(!out.is_empty(), "no models listed under {}", dir.display());
    out
}

struct ClientResult {
    latencies: Vec<Duration>,
    errors: usize,
    bytes: u64,
}

/// One keep-alive connection; a failed exchange counts as an error and the
/// client reconnects.
fn client(
    port: u16,
    seed: u64,
    requests: usize,
    files: &[(String, String, Vec<u8>)],
    start: Instant,
) -> ClientResult {
    let mut rng = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut next = move || {
        // xorshift64*
        rng ^= rng >> 12;
        rng ^= rng << 25;
        rng ^= rng >> 27;
        rng.wrapping_mul(0x2545_F491_4F6C_DD1D)
    };
    let mut r = ClientResult {
        latencies: Vec::with_capacity(requests),
        errors: 0,
        bytes: 0,
    };
    let mut conn: Option<(TcpStream, BufReader<TcpStream>)> = None;
    for _ in 0..requests {
        if start.elapsed() > DEADLINE {
            break;
        }
        let (url, _, data) = &files[(next() % files.len() as u64) as usize];
        let len = data.len() as u64;
        let want = (1024 + next() % MAX_RANGE).min(len);
        let first = next() % (len - want + 1);
        let last = first + want - 1;
        let t = Instant::now();
        let ok = (|| -> std::io::Result<bool> {
            if conn.is_none() {
                let s = TcpStream::connect(("127.0.0.1", port))?;
                s.set_nodelay(true)?;
                s.set_read_timeout(Some(Duration::from_secs(30)))?;
                conn = Some((s.try_clone()?, BufReader::new(s)));
            }
            let (w, rd) = conn.as_mut().unwrap();
            write!(
                w,
                "GET {url} HTTP/1.1\r\nHost: 127.0.0.1\r\nRange: bytes={first}-{last}\r\n\r\n"
            )?;
            let mut line = String::new();
            rd.read_line(&mut line)?;
            let mut good = line.starts_with("HTTP/1.1 206");
            let mut length = None;
            let mut range_ok = false;
            loop {
                line.clear();
                if rd.read_line(&mut line)? == 0 {
                    return Ok(false);
                }
                if line == "\r\n" {
                    break;
                }
                let l = line.to_ascii_lowercase();
                if let Some(v) = l.strip_prefix("content-length:") {
                    length = v.trim().parse::<usize>().ok();
                } else if let Some(v) = l.strip_prefix("content-range:") {
                    range_ok = v.trim() == format!("bytes {first}-{last}/{len}");
                }
            }
            let Some(n) = length else { return Ok(false) };
            let mut body = vec![0; n];
            rd.read_exact(&mut body)?;
            r.bytes += n as u64;
            good &= range_ok && body == data[first as usize..=last as usize];
            Ok(good)
        })()
        .unwrap_or(false);
        r.latencies.push(t.elapsed());
        if !ok {
            r.errors += 1;
            conn = None;
        }
    }
    r
}

/// The peak resident set of a process, in KiB (Linux `/proc`).
fn peak_rss_kib(pid: u32) -> Option<u64> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}
