// wasm timings in Chromium beside the native ones, on the same files:
//   .pop decode + triangulate of the finest level (best of N, after warm-up)
//   .mco view-dependent cut at about BUDGET triangles (same camera as
//        crates/wasm/examples/native.rs `time-mco`)
//   page weight: the viewer's JS + wasm, gzip -9
// Usage: node web/tests/bench.mjs   (environment as viewer.test.mjs, plus
//   LODKIT_WEB_BENCH_POP  comma-separated .pop names under the models folder
//   LODKIT_WEB_BENCH_MCO  one .mco name, LODKIT_WEB_BENCH_BUDGET (100000)
//   LODKIT_WEB_NATIVE     the native example binary, to print its numbers too)

import fs from 'node:fs';
import path from 'node:path';
import { execFileSync } from 'node:child_process';
import { staticServer, launch, openPage, gzipSize } from './lib.mjs';

const site = path.resolve(process.env.LODKIT_WEB_SITE);
const models = path.resolve(process.env.LODKIT_WEB_MODELS);
const pops = (process.env.LODKIT_WEB_BENCH_POP || 'stanford_bunny.pop').split(',').filter(Boolean);
const mco = process.env.LODKIT_WEB_BENCH_MCO || 'stanford_bunny.mco';
const budget = Number(process.env.LODKIT_WEB_BENCH_BUDGET || 100000);
const nativeBin = process.env.LODKIT_WEB_NATIVE;
const rounds = Number(process.env.LODKIT_WEB_BENCH_ROUNDS || 10);

const server = await staticServer(site, models);
const browser = await launch();
const { page, errors } = await openPage(browser.context);
await page.goto(`${server.url}/lodkit/index.js`); // same origin, no viewer
const out = { machine: `${process.platform} ${process.arch}`, pop: [], mco: null, weight: null };

for (const name of pops) {
  const r = await page.evaluate(
    async ({ url, rounds }) => {
      const { wasmModule } = await import('/lodkit/wasm.js');
      const w = new WebAssembly.Instance(await wasmModule(), {}).exports;
      const bytes = new Uint8Array(await (await fetch(url)).arrayBuffer());
      let best = Infinity;
      let tris = 0;
      for (let i = 0; i < rounds + 2; i++) {
        const h = w.lk_pop_new();
        const at = w.lk_pop_push(h, bytes.length); // may grow (detach) memory
        new Uint8Array(w.memory.buffer, at, bytes.length).set(bytes);
        const t0 = performance.now();
        const levels = w.lk_pop_decode(h);
        tris = w.lk_pop_mesh(h, levels - 1);
        const t = performance.now() - t0;
        w.lk_close(h);
        if (i >= 2) best = Math.min(best, t); // two warm-up rounds: tier-up
      }
      return { bytes: bytes.length, triangles: tris, best_ms: best };
    },
    { url: `/models/${name}`, rounds },
  );
  r.file = name;
  if (nativeBin) {
    const n = JSON.parse(execFileSync(nativeBin, ['time', path.join(models, name), String(rounds)], { encoding: 'utf8' }));
    r.native_ms = n.best_ms;
    r.ratio = +(n.best_ms / r.best_ms).toFixed(3); // wasm throughput / native
  }
  out.pop.push(r);
  console.log(`pop ${name}: ${r.triangles} triangles, wasm ${r.best_ms.toFixed(2)} ms` + (nativeBin ? `, native ${r.native_ms.toFixed(2)} ms, wasm/native throughput ${r.ratio}` : ''));
}

{
  const r = await page.evaluate(
    async ({ url, budget, rounds }) => {
      const { wasmModule } = await import('/lodkit/wasm.js');
      const w = new WebAssembly.Instance(await wasmModule(), {}).exports;
      const bytes = new Uint8Array(await (await fetch(url)).arrayBuffer());
      const p = w.lk_alloc(bytes.length);
      new Uint8Array(w.memory.buffer, p, bytes.length).set(bytes);
      const t0 = performance.now();
      const h = w.lk_mco_open(p, bytes.length);
      const loadMs = performance.now() - t0;
      w.lk_free(p, bytes.length);
      const b = new Float32Array(w.memory.buffer, w.lk_mco_bounds(h), 6).slice();
      // The camera of native.rs camera_for(lo, hi, 1.5).
      const c = [0, 1, 2].map((i) => (b[i] + b[i + 3]) / 2);
      const size = Math.max(b[3] - b[0], b[4] - b[1], b[5] - b[2]);
      const len = Math.hypot(0, 0.15, 1);
      const pos = [c[0], c[1] + (0.15 / len) * size * 1.5, c[2] + (1 / len) * size * 1.5];
      const dir = [c[0] - pos[0], c[1] - pos[1], c[2] - pos[2]];
      const cut = (tol) => {
        w.lk_mco_extract_view(h, pos[0], pos[1], pos[2], dir[0], dir[1], dir[2], 0, 1, 0, 45, 1080, 16 / 9, tol);
        return w.lk_mesh_index_count(h) / 3;
      };
      let lo = 0.01;
      let hi = 1000;
      for (let i = 0; i < 30; i++) {
        const m = Math.fround(Math.sqrt(lo * hi));
        if (cut(m) > budget) lo = m;
        else hi = m;
      }
      let best = Infinity;
      let tris = 0;
      for (let i = 0; i < rounds + 2; i++) {
        const t = performance.now();
        tris = cut(hi);
        if (i >= 2) best = Math.min(best, performance.now() - t);
      }
      return { full_triangles: w.lk_mco_full_triangles(h), tolerance_px: hi, triangles: tris, best_ms: best, load_ms: loadMs };
    },
    { url: `/models/${mco}`, budget, rounds: rounds * 2 },
  );
  r.file = mco;
  if (nativeBin) {
    const n = JSON.parse(execFileSync(nativeBin, ['time-mco', path.join(models, mco), String(budget), String(rounds * 2)], { encoding: 'utf8' }));
    r.native_ms = n.best_ms;
    r.native_triangles = n.triangles;
  }
  out.mco = r;
  console.log(`mco ${mco}: view cut ${r.triangles} of ${r.full_triangles} triangles at ${r.tolerance_px.toFixed(3)} px, wasm ${r.best_ms.toFixed(2)} ms` + (nativeBin ? `, native ${r.native_ms.toFixed(2)} ms (${r.native_triangles} triangles)` : '') + `; load ${r.load_ms.toFixed(0)} ms`);
}

{
  const files = ['index.html', 'viewer.js', 'lodkit/index.js', 'lodkit/PopLoader.js', 'lodkit/McoModel.js', 'lodkit/wasm.js', 'lodkit/worker.js'];
  const three = ['three/build/three.module.js', 'three/build/three.core.js', 'three/examples/jsm/controls/OrbitControls.js', 'three/examples/jsm/loaders/GLTFLoader.js', 'three/examples/jsm/loaders/PLYLoader.js', 'three/examples/jsm/utils/BufferGeometryUtils.js', 'three/examples/jsm/utils/SkeletonUtils.js'];
  const sum = (list) => list.reduce((s, f) => s + gzipSize(path.join(site, f)), 0);
  const raw = (list) => list.reduce((s, f) => s + fs.statSync(path.join(site, f)).size, 0);
  out.weight = {
    lodkit_js_gzip: sum(files),
    wasm_gzip: gzipSize(path.join(site, 'lodkit/lodkit.wasm')),
    wasm_raw: fs.statSync(path.join(site, 'lodkit/lodkit.wasm')).size,
    three_gzip: sum(three),
    three_raw: raw(three),
  };
  out.weight.total_gzip = out.weight.lodkit_js_gzip + out.weight.wasm_gzip + out.weight.three_gzip;
  console.log(`page weight (gzip -9): viewer + loaders ${out.weight.lodkit_js_gzip} B, wasm ${out.weight.wasm_gzip} B (raw ${out.weight.wasm_raw}), three.js ${out.weight.three_gzip} B; total ${out.weight.total_gzip} B`);
}

if (errors.length) console.log(`console errors: ${JSON.stringify(errors)}`);
await browser.close();
await server.close();
const dir = process.env.LODKIT_WEB_OUT || path.join(process.cwd(), 'target/web-test');
fs.mkdirSync(dir, { recursive: true });
fs.writeFileSync(path.join(dir, 'bench.json'), JSON.stringify(out, null, 2));
