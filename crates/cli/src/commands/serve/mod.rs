//! `lodkit serve`: the viewer and the models over HTTP/1.1.
//!
//! Stages, one file each: [`roots`] (what is published, URL path → file,
//! containment), [`range`] (Range / If-None-Match / If-Range decisions),
//! [`respond`] (routing and bodies). This file binds, accepts and stops.
//!
//! Limits that keep a hostile or broken client from hurting the server:
//! request heads are capped at [`MAX_HEAD_BYTES`] and [`MAX_HEADERS`]
//! (hyper answers 431 past them, 400 for garbage), a head must arrive within
//! [`HEAD_TIMEOUT`], and only GET and HEAD are served.

mod range;
mod respond;
mod roots;

use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use anyhow::{Context, Result};
use axum::Router;
use axum::http::{HeaderMap, StatusCode, Version, header};
use clap::Args;
use hyper_util::rt::{TokioIo, TokioTimer};
use hyper_util::server::graceful::GracefulShutdown;
use hyper_util::service::TowerToHyperService;
use tower_http::compression::CompressionLayer;

use crate::ui::Ui;

/// Bytes a request line plus headers may take (hyper's floor is 8 KiB).
const MAX_HEAD_BYTES: usize = 64 * 1024;
/// Header fields a request may carry.
const MAX_HEADERS: usize = 64;
/// Time a client has to send its request head (slow-loris bound).
const HEAD_TIMEOUT: Duration = Duration::from_secs(10);
/// Time open connections get to finish after Ctrl-C / SIGTERM.
const DRAIN_TIMEOUT: Duration = Duration::from_secs(3);
/// Text bodies smaller than this are sent as they are.
const MIN_COMPRESS_BYTES: u64 = 256;

#[derive(Args)]
pub struct ServeArgs {
    /// Directory or files to publish (default: the current directory).
    #[arg(value_name = "DIR|FILE")]
    pub roots: Vec<PathBuf>,
    /// TCP port; 0 picks a free one (printed on the first line).
    #[arg(long, default_value_t = 8080)]
    pub port: u16,
    /// Address to listen on. Anything but loopback exposes the files to the
    /// network.
    #[arg(long, value_name = "ADDR", default_value_t = IpAddr::V4(Ipv4Addr::LOCALHOST))]
    pub bind: IpAddr,
    /// Stop by itself after this many seconds (tests and benchmarks).
    #[arg(long, value_name = "SECS", hide = true)]
    pub exit_after: Option<u64>,
}

/// Text for `lodkit serve --help`.
pub const AFTER_HELP: &str = "\
URLs:
  /                  the viewer
  /api/models        the models as JSON: [{name, url, kind, bytes}] sorted by name
                     (a folder with a tileset.json is a 3D Tiles tileset: kind
                     \"tileset\", opened by the viewer through 3DTilesRendererJS)
  /models/           the same list as an HTML page
  /models/NAME       a model's bytes (NAME as listed; ranges, ETag, If-None-Match)

One DIR is published at /models/ (recursively, hidden files left out); with
several roots each is published under its base name (/models/bunny.pop,
/models/out/lods/...). Nothing outside the roots is ever served, symlinks
included. Single byte ranges answer 206; several ranges answer 200 with the
whole file; a malformed or unsatisfiable bytes range answers 416. Text
(HTML, JS, CSS, JSON, SVG, Markdown) and the viewer's WebAssembly are
compressed as Accept-Encoding asks; model bytes never are.

Examples:
  lodkit build --out out/ && lodkit serve out/
  lodkit serve scan.pop scan.mco --port 0
  lodkit serve out/ --bind 0.0.0.0 --port 8000";

/// Serves until Ctrl-C or SIGTERM.
///
/// Errors (exit 1): a root that does not exist, an address that cannot be
/// bound. The first stdout line is `serving ROOTS at http://ADDR:PORT/`.
pub fn run(ui: &Ui, args: &ServeArgs) -> Result<()> {
    let given = if args.roots.is_empty() {
        vec![PathBuf::from(".")]
    } else {
        args.roots.clone()
    };
    let roots = roots::Roots::new(&given)?;
    let addr = SocketAddr::new(args.bind, args.port);
    let listener =
        std::net::TcpListener::bind(addr).with_context(|| format!("cannot listen on {addr}"))?;
    listener.set_nonblocking(true)?;
    let local = listener.local_addr()?;
    if !args.bind.is_loopback() {
        ui.status(format!(
            "warning: listening on {}: anyone who can reach this machine can read {}",
            args.bind,
            roots.shown()
        ));
    }

    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .context("cannot start the async runtime")?;
    let shown = roots.shown().to_string();
    let app = app(Arc::new(respond::Shared::new(roots)));
    runtime.block_on(async move {
        let listener = tokio::net::TcpListener::from_std(listener)?;
        {
            use std::io::Write;
            let mut out = std::io::stdout().lock();
            writeln!(out, "serving {shown} at http://{local}/")?;
            out.flush()?;
        }
        accept_loop(listener, app, args.exit_after).await;
        ui.status("stopped");
        Ok(())
    })
}

/// The router with its compression layer.
fn app(shared: Arc<respond::Shared>) -> Router {
    Router::new()
        .fallback(respond::route)
        .with_state(shared)
        .layer(CompressionLayer::new().compress_when(compress_when))
}

/// Compress whole text and wasm bodies only: never a 206 (its `Content-Range`
/// addresses the identity bytes) and never a model format.
fn compress_when(
    status: StatusCode,
    _: Version,
    headers: &HeaderMap,
    _: &axum::http::Extensions,
) -> bool {
    let text = headers
        .get(header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .is_some_and(respond::compressible);
    let big = headers
        .get(header::CONTENT_LENGTH)
        .and_then(|v| v.to_str().ok()?.parse::<u64>().ok())
        .is_none_or(|n| n >= MIN_COMPRESS_BYTES);
    status == StatusCode::OK && text && big && !headers.contains_key(header::CONTENT_RANGE)
}

async fn accept_loop(listener: tokio::net::TcpListener, app: Router, exit_after: Option<u64>) {
    let mut http = hyper::server::conn::http1::Builder::new();
    http.timer(TokioTimer::new())
        .header_read_timeout(HEAD_TIMEOUT)
        .max_buf_size(MAX_HEAD_BYTES)
        .max_headers(MAX_HEADERS);
    let graceful = GracefulShutdown::new();
    let stop = stop_signal(exit_after);
    tokio::pin!(stop);
    loop {
        tokio::select! {
            accepted = listener.accept() => match accepted {
                Ok((stream, _)) => {
                    let _ = stream.set_nodelay(true);
                    let conn = http.serve_connection(
                        TokioIo::new(stream),
                        TowerToHyperService::new(app.clone()),
                    );
                    let conn = graceful.watch(conn);
                    // A client that resets or sends garbage ends only its
                    // own connection (hyper has already answered 4xx).
                    tokio::spawn(async move {
                        let _ = conn.await;
                    });
                }
                // Out of descriptors or a connection reset before accept:
                // wait a little instead of spinning, keep serving.
                Err(_) => tokio::time::sleep(Duration::from_millis(50)).await,
            },
            () = &mut stop => break,
        }
    }
    drop(listener);
    let _ = tokio::time::timeout(DRAIN_TIMEOUT, graceful.shutdown()).await;
}

/// Resolves on Ctrl-C (SIGINT), SIGTERM, or after `exit_after` seconds.
///
/// The signal handlers are installed here, when called, not when the
/// future is first polled: the accept loop may serve its first requests
/// before it polls this future, and a signal arriving in that window would
/// end the process by the default action instead of a clean stop.
fn stop_signal(exit_after: Option<u64>) -> impl std::future::Future<Output = ()> {
    #[cfg(unix)]
    let (mut int, mut term) = {
        use tokio::signal::unix::{SignalKind, signal};
        (
            signal(SignalKind::interrupt()).ok(),
            signal(SignalKind::terminate()).ok(),
        )
    };
    async move {
        #[cfg(unix)]
        let (ctrl_c, term) = (
            async {
                match int.as_mut() {
                    Some(s) => {
                        s.recv().await;
                    }
                    None => std::future::pending::<()>().await,
                }
            },
            async {
                match term.as_mut() {
                    Some(s) => {
                        s.recv().await;
                    }
                    None => std::future::pending::<()>().await,
                }
            },
        );
        #[cfg(not(unix))]
        let (ctrl_c, term) = (
            async {
                let _ = tokio::signal::ctrl_c().await;
            },
            std::future::pending::<()>(),
        );
        let timer = async {
            match exit_after {
                Some(s) => tokio::time::sleep(Duration::from_secs(s)).await,
                None => std::future::pending::<()>().await,
            }
        };
        tokio::select! {
            () = ctrl_c => {},
            () = term => {},
            () = timer => {},
        }
    }
}
