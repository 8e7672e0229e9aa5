// The `.mco` view-dependent cut in WebAssembly, under Node (V8) or in a
// Chromium page (--chromium: Debian's Chromium, headless, the page served
// on loopback), on the camera path of the native bench
// (crates/bench/examples/mco_view_cut.rs): cameras orbiting the root
// cube's centre at 1.2 x its diagonal, 60 degree field of view, a
// 1080-pixel square viewport; the cameras in path order within a round
// (as frames, through the handle's kept cut state), each camera's best of
// ROUNDS rounds, then the median and worst camera.
// Usage:
//   node web/bench-mco.mjs [--chromium] MODEL.mco TOLERANCE_PX [ROUNDS] [FRAMES]
// FRAMES (64) cameras on the orbit, as MCO_FRAMES for the native bench
// (240: the small steps of a viewer, where the kept cut is frame-coherent).
// with the wasm of scripts/build-web.sh (target/web-wasm/...), or another
// one in LODKIT_WASM. Use the tolerance the native bench printed for the
// same file and budget (its "tolerance (px)" column), so both time the
// same cuts; the triangle counts are printed to compare. Chromium's timer
// in a page is coarsened to 0.1 ms.
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..');
const args = process.argv.slice(2);
const inChromium = args[0] === '--chromium';
if (inChromium) args.shift();
const [file, tolArg, roundsArg, framesArg] = args;
if (!file || !tolArg) {
  console.error('usage: node web/bench-mco.mjs [--chromium] MODEL.mco TOLERANCE_PX [ROUNDS] [FRAMES]');
  process.exit(2);
}
const tol = Number(tolArg);
const rounds = Number(roundsArg || 5);
const frames = Number(framesArg || 64);
if (!(tol > 0) || !(rounds >= 1) || !(frames >= 1)) {
  console.error('bench-mco: TOLERANCE_PX must be > 0, ROUNDS and FRAMES >= 1');
  process.exit(2);
}
const wasmPath = process.env.LODKIT_WASM || path.join(root, 'target/web-wasm/wasm32-unknown-unknown/release/lodkit_wasm.wasm');
for (const f of [file, wasmPath]) {
  if (!fs.existsSync(f)) {
    console.error(`bench-mco: ${f}: no such file${f === wasmPath ? ' (run scripts/build-web.sh)' : ''}`);
    process.exit(1);
  }
}

// The whole measurement, self-contained: it runs as it is in Node and is
// handed to the Chromium page as source. `wasm` and `model` are bytes, or
// URLs to fetch them from.
async function orbitBench({ wasm, model, tol, rounds, frames }) {
  const bytesOf = async (x) => (typeof x === 'string' ? new Uint8Array(await (await fetch(x)).arrayBuffer()) : x);
  const w = (await WebAssembly.instantiate(await bytesOf(wasm), {})).instance.exports;
  const bytes = await bytesOf(model);
  const p = w.lk_alloc(bytes.length);
  new Uint8Array(w.memory.buffer, p, bytes.length).set(bytes);
  const t0 = performance.now();
  const h = w.lk_mco_open(p, bytes.length);
  const loadMs = performance.now() - t0;
  w.lk_free(p, bytes.length);
  if (h === 0) {
    return { error: new TextDecoder().decode(new Uint8Array(w.memory.buffer, w.lk_error_ptr(), w.lk_error_len())) };
  }
  const b = new Float32Array(w.memory.buffer, w.lk_mco_bounds(h), 6).slice();
  const c = [0, 1, 2].map((i) => Math.fround((b[i] + b[i + 3]) * 0.5));
  const r = Math.hypot(b[3] - b[0], b[4] - b[1], b[5] - b[2]);
  const cameras = [];
  for (let i = 0; i < frames; i++) {
    const a = (i / frames) * 2 * Math.PI;
    const d = [Math.cos(a), 0.35, Math.sin(a)];
    const l = Math.hypot(...d);
    const pos = d.map((x, k) => c[k] + (x / l) * r * 1.2);
    cameras.push({ pos, dir: [0, 1, 2].map((k) => c[k] - pos[k]) });
  }
  const cut = ({ pos, dir }) => {
    const e = w.lk_mco_extract_view(h, pos[0], pos[1], pos[2], dir[0], dir[1], dir[2], 0, 1, 0, 60, 1080, 1, tol);
    return [w.lk_mesh_index_count(h) / 3, e];
  };
  cameras.forEach(cut); // the first cut builds the model's view layout
  const best = cameras.map(() => Infinity);
  const tris = cameras.map(() => 0);
  let expanded = 0;
  for (let round = 0; round < rounds; round++) {
    cameras.forEach((cam, i) => {
      const t = performance.now();
      const [n, e] = cut(cam);
      best[i] = Math.min(best[i], performance.now() - t);
      if (round === 0) {
        tris[i] = n;
        expanded += e;
      }
    });
  }
  const sorted = [...best].sort((x, y) => x - y);
  return {
    full_triangles: w.lk_mco_full_triangles(h),
    load_ms: +loadMs.toFixed(1),
    triangles_min_mean_max: [Math.min(...tris), Math.round(tris.reduce((s, x) => s + x, 0) / tris.length), Math.max(...tris)],
    expanded_mean: Math.round(expanded / cameras.length),
    wasm_ms_median: +sorted[sorted.length >> 1].toFixed(3),
    wasm_ms_worst: +sorted[sorted.length - 1].toFixed(3),
  };
}

let result;
let engine;
if (inChromium) {
  const { staticServer, launch, openPage } = await import('./tests/lib.mjs');
  // The wasm as the site, the model's folder as /models/.
  const site = fs.mkdtempSync(path.join(process.env.TMPDIR || '/tmp', 'lodkit-bench-'));
  fs.copyFileSync(wasmPath, path.join(site, 'lodkit.wasm'));
  fs.writeFileSync(path.join(site, 'index.html'), '<!doctype html><title>bench</title>\n');
  const server = await staticServer(site, path.dirname(path.resolve(file)));
  const browser = await launch();
  try {
    const { page } = await openPage(browser.context);
    await page.goto(`${server.url}/index.html`);
    const url = `/models/${encodeURIComponent(path.basename(file))}`;
    result = await page.evaluate(orbitBench, { wasm: '/lodkit.wasm', model: url, tol, rounds, frames });
    engine = { chromium: await page.evaluate(() => navigator.userAgent.match(/Chrome\/[\d.]+/)?.[0] || navigator.userAgent) };
  } finally {
    await browser.close();
    await server.close();
    fs.rmSync(site, { recursive: true, force: true });
  }
} else {
  result = await orbitBench({ wasm: fs.readFileSync(wasmPath), model: fs.readFileSync(file), tol, rounds, frames });
  engine = { node: process.version };
}
if (result.error) {
  console.error(`bench-mco: ${file}: ${result.error}`);
  process.exit(1);
}
console.log(JSON.stringify({ file: path.basename(file), tolerance_px: tol, frames, ...result, ...engine }));
