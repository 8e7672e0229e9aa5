//! `lodkit bench simplify`: lodkit's HQMS simplifier next to
//! meshoptimizer's `meshopt_simplify`, on the same mesh and target, one
//! thread each, in one process.
//!
//! Per case: input / output triangles, the best wall time of each over a
//! few runs, the time ratio (lodkit / meshopt; ≤ 1 means lodkit is
//! faster), the same ratio of the best thread CPU times (on Linux; it does
//! not count time the core spent on other processes, so it stays
//! meaningful on a shared, loaded machine), peak extra memory per input vertex, and both outputs'
//! symmetric mean and max distance to the input from
//! [`lodkit_mesh::metrics::compare`].
//!
//! Memory is measured with [`crate::alloc::CountingAlloc`]: the binary that runs the bench
//! installs it as its global allocator, and meshoptimizer's temporary
//! allocations are routed through Rust's allocator with
//! `meshopt_setAllocator`, so both sides are counted the same way: the peak
//! of live bytes during the call minus the live bytes before it (the
//! output included, the loaded input not). Without the counting allocator
//! installed, memory columns are `None`.
//!
//! meshopt is called with `target_error = 1` (relative to the mesh extent:
//! no error bound, the triangle count decides) and no options, the same
//! contract as lodkit's `--target`.

use lodkit_mesh::TriMesh;
use lodkit_simplify::Target;

#[cfg(feature = "peers")]
pub use crate::meshopt_peer::meshopt_simplify;

/// This thread's time on a CPU so far (`CLOCK_THREAD_CPUTIME_ID`: exact
/// when read, where `/proc/thread-self/schedstat` lags by up to a
/// scheduler tick). The time a loaded machine gives to other processes is
/// not counted. `None` where the clock is missing.
pub fn thread_cpu_seconds() -> Option<f64> {
    #[cfg(unix)]
    {
        let mut ts = libc::timespec {
            tv_sec: 0,
            tv_nsec: 0,
        };
        // SAFETY: `ts` is a valid, writable timespec for the call.
        let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
        (rc == 0).then_some(ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9)
    }
    #[cfg(not(unix))]
    {
        None
    }
}

/// One row of the table.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Row {
    pub mesh: String,
    pub target: String,
    pub input_triangles: usize,
    pub input_vertices: usize,
    pub target_triangles: usize,
    pub lodkit_triangles: usize,
    pub meshopt_triangles: usize,
    /// Fresh workspace (every buffer allocated in the call).
    pub lodkit_ms: f64,
    /// Reused workspace.
    pub lodkit_reused_ms: f64,
    pub meshopt_ms: f64,
    /// lodkit time (fresh workspace) / meshopt time.
    pub time_ratio: f64,
    /// Best thread CPU time of each side (`None` where the platform does
    /// not say), and their ratio.
    pub lodkit_cpu_ms: Option<f64>,
    pub meshopt_cpu_ms: Option<f64>,
    pub cpu_ratio: Option<f64>,
    pub lodkit_bytes_per_vertex: Option<f64>,
    pub meshopt_bytes_per_vertex: Option<f64>,
    /// lodkit's exact workspace accounting (arrays' capacities at the peak).
    pub lodkit_workspace_bytes_per_vertex: f64,
    pub lodkit_mean: f64,
    pub lodkit_max: f64,
    pub meshopt_mean: f64,
    pub meshopt_max: f64,
    pub lodkit_estimated_error: f32,
}

/// How to run the cases.
#[derive(Debug, Clone, Copy)]
pub struct BenchConfig {
    /// Timed runs per side (the best is kept).
    pub runs: usize,
    /// Samples per kind for `compare`.
    pub samples: usize,
}

impl Default for BenchConfig {
    fn default() -> Self {
        BenchConfig {
            runs: 3,
            samples: 1_000_000,
        }
    }
}

/// The standard targets: 50%, 10%, 1% and 1,000 triangles (a half, a
/// tenth, a hundredth, and a fixed small budget).
pub fn standard_targets() -> Vec<(String, Target)> {
    vec![
        ("50%".into(), Target::Ratio(0.5)),
        ("10%".into(), Target::Ratio(0.1)),
        ("1%".into(), Target::Ratio(0.01)),
        ("1000".into(), Target::Faces(1000)),
    ]
}

/// Runs one mesh at one target. Errors: lodkit's simplifier refused the
/// mesh, `compare` failed, or this build has no peer ([`crate::PEERS`]
/// false: [`NO_PEERS`]).
#[cfg(not(feature = "peers"))]
pub fn run_case(
    _name: &str,
    _mesh: &TriMesh,
    _label: &str,
    _target: Target,
    _cfg: &BenchConfig,
) -> Result<Row, String> {
    Err(NO_PEERS.to_string())
}

/// Why [`run_case`] fails in a build without the `peers` feature.
pub const NO_PEERS: &str = "built without meshoptimizer (the `peers` feature): rebuild with `cargo build --release -p lodkit-bench --features peers`";

/// Runs one mesh at one target. Errors: lodkit's simplifier refused the
/// mesh, or `compare` failed.
#[cfg(feature = "peers")]
pub fn run_case(
    name: &str,
    mesh: &TriMesh,
    label: &str,
    target: Target,
    cfg: &BenchConfig,
) -> Result<Row, String> {
    use std::time::{Duration, Instant};

    use lodkit_mesh::metrics::{CompareOptions, compare};
    use lodkit_simplify::{Options, Simplifier};

    use crate::alloc::measure_peak;

    crate::meshopt_peer::route_meshopt_allocations();
    let goal = target.faces(mesh.faces.len());
    let opts = Options {
        target,
        ..Options::DEFAULT
    };
    let bytes: Vec<u8> = mesh
        .positions
        .iter()
        .flat_map(|p| p.to_array())
        .flat_map(f32::to_le_bytes)
        .collect();

    // Memory: one measured call each (outside the timed runs).
    let mut ws = Simplifier::new();
    let (lk, lk_peak) = measure_peak(|| Simplifier::new().simplify(mesh, &opts));
    let lk = lk.map_err(|e| e.to_string())?;
    let (mo, mo_peak) = measure_peak(|| meshopt_simplify(mesh, &bytes, goal));

    // Time: best of `runs`, alternating sides. lodkit is timed both with a
    // fresh workspace (allocating everything, as meshopt does each call:
    // this is the ratio) and with a reused one (its intended use in a
    // pipeline).
    let mut lk_best = Duration::MAX;
    let mut lk_reused = Duration::MAX;
    let mut mo_best = Duration::MAX;
    let (mut lk_cpu, mut mo_cpu) = (f64::INFINITY, f64::INFINITY);
    for _ in 0..cfg.runs.max(1) {
        let t = Instant::now();
        let c = thread_cpu_seconds();
        let r = Simplifier::new()
            .simplify(mesh, &opts)
            .map_err(|e| e.to_string())?;
        lk_cpu = lk_cpu.min(thread_cpu_seconds().unwrap_or(f64::NAN) - c.unwrap_or(f64::NAN));
        lk_best = lk_best.min(t.elapsed());
        drop(std::hint::black_box(r));
        let t = Instant::now();
        let r = ws.simplify(mesh, &opts).map_err(|e| e.to_string())?;
        lk_reused = lk_reused.min(t.elapsed());
        drop(std::hint::black_box(r));
        let t = Instant::now();
        let c = thread_cpu_seconds();
        let r = meshopt_simplify(mesh, &bytes, goal);
        mo_cpu = mo_cpu.min(thread_cpu_seconds().unwrap_or(f64::NAN) - c.unwrap_or(f64::NAN));
        mo_best = mo_best.min(t.elapsed());
        drop(std::hint::black_box(r));
    }
    let workspace = ws.peak_bytes();

    let mo_mesh = TriMesh::new(
        mesh.positions.clone(),
        mo.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
    );
    let copts = CompareOptions {
        samples: Some(cfg.samples),
        ..CompareOptions::default()
    };
    let lk_cmp = compare(mesh, &lk.mesh, &copts).map_err(|e| e.to_string())?;
    let mo_cmp = compare(mesh, &mo_mesh, &copts).map_err(|e| e.to_string())?;
    let nv = mesh.positions.len().max(1) as f64;
    Ok(Row {
        mesh: name.to_string(),
        target: label.to_string(),
        input_triangles: mesh.faces.len(),
        input_vertices: mesh.positions.len(),
        target_triangles: goal,
        lodkit_triangles: lk.mesh.faces.len(),
        meshopt_triangles: mo_mesh.faces.len(),
        lodkit_ms: lk_best.as_secs_f64() * 1e3,
        lodkit_reused_ms: lk_reused.as_secs_f64() * 1e3,
        meshopt_ms: mo_best.as_secs_f64() * 1e3,
        time_ratio: lk_best.as_secs_f64() / mo_best.as_secs_f64().max(1e-9),
        lodkit_cpu_ms: lk_cpu.is_finite().then_some(lk_cpu * 1e3),
        meshopt_cpu_ms: mo_cpu.is_finite().then_some(mo_cpu * 1e3),
        cpu_ratio: (lk_cpu.is_finite() && mo_cpu.is_finite() && mo_cpu > 0.0)
            .then_some(lk_cpu / mo_cpu),
        lodkit_bytes_per_vertex: lk_peak.map(|b| b as f64 / nv),
        meshopt_bytes_per_vertex: mo_peak.map(|b| b as f64 / nv),
        lodkit_workspace_bytes_per_vertex: workspace as f64 / nv,
        lodkit_mean: lk_cmp.symmetric.mean,
        lodkit_max: lk_cmp.symmetric.max,
        meshopt_mean: mo_cmp.symmetric.mean,
        meshopt_max: mo_cmp.symmetric.max,
        lodkit_estimated_error: lk.report.estimated_error,
    })
}

/// The table as aligned text.
pub fn format_table(rows: &[Row]) -> String {
    let mut s = String::new();
    s.push_str(&format!(
        "{:<16} {:>6} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>6} {:>6} {:>7} {:>7} {:>10} {:>10} {:>10} {:>10}\n",
        "mesh", "target", "in tris", "lk tris", "mo tris", "lk ms", "lk re ms", "mo ms", "ratio",
        "cpu r", "lk B/v", "mo B/v", "lk mean", "mo mean", "lk max", "mo max"
    ));
    let b = |x: Option<f64>| x.map_or("n/a".to_string(), |v| format!("{v:.1}"));
    for r in rows {
        s.push_str(&format!(
            "{:<16} {:>6} {:>9} {:>9} {:>9} {:>9.2} {:>9.2} {:>9.2} {:>6.2} {:>6} {:>7} {:>7} {:>10.3e} {:>10.3e} {:>10.3e} {:>10.3e}\n",
            r.mesh,
            r.target,
            r.input_triangles,
            r.lodkit_triangles,
            r.meshopt_triangles,
            r.lodkit_ms,
            r.lodkit_reused_ms,
            r.meshopt_ms,
            r.time_ratio,
            r.cpu_ratio.map_or("n/a".to_string(), |x| format!("{x:.2}")),
            b(r.lodkit_bytes_per_vertex),
            b(r.meshopt_bytes_per_vertex),
            r.lodkit_mean,
            r.meshopt_mean,
            r.lodkit_max,
            r.meshopt_max,
        ));
    }
    s
}
