// The `.mco` decoder of the browser (lodkit.wasm) under Node, without a
// browser: each file opens whole and streamed (in 4 KiB pieces, as a
// download arrives), both give the same cut at full resolution, a budget
// cut and a view cut are not empty, and a file built from a coloured input
// has its colours. Run by scripts/ci-web.sh on the bunny's `.mco` and on a
// coloured point cloud's (the sheet below, written by this script with
// --write-sheet), whose root cube holds triangles.
// Usage:
//   node web/tests/mco-decode.mjs --write-sheet OUT.ply
//   node web/tests/mco-decode.mjs FILE.mco[:colors] ...
// with the wasm of scripts/build-web.sh, or another one in LODKIT_WASM.
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
const args = process.argv.slice(2);

if (args[0] === '--write-sheet') {
  // A wavy coloured sheet of 61 × 61 points, as ASCII PLY (no normals: the
  // build estimates them).
  const n = 60;
  const lines = [];
  for (let j = 0; j <= n; j++) {
    for (let i = 0; i <= n; i++) {
      const x = i / n;
      const y = j / n;
      const z = 0.1 * Math.sin(6 * x) * Math.cos(4 * y);
      lines.push(`${x.toFixed(6)} ${y.toFixed(6)} ${z.toFixed(6)} ${Math.round(x * 255)} ${Math.round(y * 255)} 90`);
    }
  }
  const head = ['ply', 'format ascii 1.0', `element vertex ${lines.length}`, 'property float x', 'property float y', 'property float z', 'property uchar red', 'property uchar green', 'property uchar blue', 'end_header'];
  fs.writeFileSync(args[1], `${head.concat(lines).join('\n')}\n`);
  process.exit(0);
}

const wasmPath = process.env.LODKIT_WASM || path.join(root, 'target/web-wasm/wasm32-unknown-unknown/release/lodkit_wasm.wasm');
const w = (await WebAssembly.instantiate(fs.readFileSync(wasmPath), {})).instance.exports;
const error = () => new TextDecoder().decode(new Uint8Array(w.memory.buffer, w.lk_error_ptr(), w.lk_error_len()));
const put = (bytes) => {
  const p = w.lk_alloc(bytes.length);
  new Uint8Array(w.memory.buffer, p, bytes.length).set(bytes);
  return p;
};
const indices = (h) => new Uint32Array(w.memory.buffer, w.lk_mesh_indices(h), w.lk_mesh_index_count(h)).slice();
const same = (a, b) => a.length === b.length && a.every((x, i) => x === b[i]);

let failures = 0;
for (const arg of args) {
  const [file, want] = arg.split(':');
  const name = path.basename(file);
  try {
    const bytes = new Uint8Array(fs.readFileSync(file));
    const p = put(bytes);
    const h = w.lk_mco_open(p, bytes.length);
    w.lk_free(p, bytes.length);
    if (h === 0) throw new Error(`open: ${error()}`);
    const vertices = w.lk_mco_vertices(h);
    if (!(vertices > 0)) throw new Error(`${vertices} vertices`);
    const colors = w.lk_mesh_colors(h) !== 0;
    if (want === 'colors' && !colors) throw new Error('colours lost');
    const maxLod = w.lk_mco_max_lod(h);
    w.lk_mco_extract_lod(h, maxLod);
    const whole = indices(h);
    if (whole.length === 0) throw new Error('empty cut at full resolution');
    const budget = w.lk_mco_extract_triangles(h, Math.max(1, Math.floor(whole.length / 6)));
    const budgetTris = w.lk_mesh_index_count(h) / 3;
    if (!(budget >= 0 && budgetTris > 0)) throw new Error(`budget cut: LOD ${budget}, ${budgetTris} triangles`);
    const b = new Float32Array(w.memory.buffer, w.lk_mco_bounds(h), 6).slice();
    const c = [0, 1, 2].map((i) => (b[i] + b[i + 3]) / 2);
    const r = Math.hypot(b[3] - b[0], b[4] - b[1], b[5] - b[2]);
    const expanded = w.lk_mco_extract_view(h, c[0] + 0.3 * r, c[1] + 0.4 * r, c[2] + 1.1 * r, -0.3, -0.4, -1.1, 0, 1, 0, 60, 1080, 1, 1);
    if (!(expanded > 0 && w.lk_mesh_index_count(h) > 0)) throw new Error(`view cut: ${expanded} nodes refined`);
    // Streamed in pieces: the last model cuts as the whole file.
    const s = w.lk_mco_stream_new();
    for (let at = 0; at < bytes.length; at += 4096) {
      const piece = bytes.subarray(at, Math.min(at + 4096, bytes.length));
      const q = put(piece);
      const got = w.lk_mco_stream_push(s, q, piece.length);
      w.lk_free(q, piece.length);
      if (got < 0) throw new Error(`stream at byte ${at}: ${error()}`);
    }
    if (w.lk_mco_complete(s) !== 1) throw new Error('stream incomplete');
    w.lk_mco_extract_lod(s, maxLod);
    const streamed = indices(s);
    w.lk_close(s);
    w.lk_close(h);
    if (!same(streamed, whole)) throw new Error('the streamed model cuts otherwise than the whole file');
    console.log(`ok   ${name}: ${vertices} vertices${colors ? ', coloured' : ''}, ${whole.length / 3} triangles at LOD ${maxLod}, ${budgetTris} at a budget, view cut ${expanded} nodes refined`);
  } catch (e) {
    failures++;
    console.log(`FAIL ${name}: ${e.message}`);
  }
}
process.exit(failures ? 1 : 0);
