// Reads lodkit's streamed files with the browser's decoders (the wasm
// build of crates/wasm, the same module the viewer's worker runs), under
// Node: the conformance suite's third reader beside the CLI and pylodkit.
//
// Usage: node tests/conformance/wasm_read.mjs WASM JOBS.json
// JOBS.json: [{ "file": "x.mco", "budgets": [2000, ...] },
//             { "file": "y.pop" }]
// Prints one JSON array, one object per job, in order:
//   .mco: { ok, vertices, colors, max_lod, full_triangles,
//           cuts: [{ budget, lod, triangles, digest }] }
//   .pop: { ok, levels, depth, triangles, vertices, colors, digest }
//   a file the decoder refuses: { ok: false, error }
// `digest` is crates/wasm's FNV-1a of the indices and positions, as the
// native example `native digest` prints it, so the two can be compared.
import fs from 'node:fs';

const [wasmPath, jobsPath] = process.argv.slice(2);
if (!wasmPath || !jobsPath) {
  console.error('usage: node wasm_read.mjs WASM JOBS.json');
  process.exit(2);
}
const w = (await WebAssembly.instantiate(fs.readFileSync(wasmPath), {})).instance.exports;
const jobs = JSON.parse(fs.readFileSync(jobsPath, 'utf8'));

const lastError = () =>
  new TextDecoder().decode(new Uint8Array(w.memory.buffer, w.lk_error_ptr(), w.lk_error_len()));
const hex = (d) => BigInt.asUintN(64, BigInt(d)).toString(16).padStart(16, '0');

// True when the handle's mesh carries colours that are not all one value.
function hasColors(h, vertices) {
  const p = w.lk_mesh_colors(h);
  if (!p || vertices === 0) return false;
  const c = new Uint8Array(w.memory.buffer, p, vertices * 4);
  for (let i = 4; i < c.length; i++) if (c[i] !== c[i % 4]) return true;
  return false;
}

function readMco(job, bytes) {
  const p = w.lk_alloc(bytes.length);
  new Uint8Array(w.memory.buffer, p, bytes.length).set(bytes);
  const h = w.lk_mco_open(p, bytes.length);
  w.lk_free(p, bytes.length);
  if (h === 0) return { ok: false, error: lastError() };
  const vertices = w.lk_mco_vertices(h);
  const out = {
    ok: vertices > 0,
    vertices,
    colors: hasColors(h, vertices),
    max_lod: w.lk_mco_max_lod(h),
    full_triangles: w.lk_mco_full_triangles(h),
    cuts: [],
  };
  for (const budget of job.budgets || []) {
    const lod = w.lk_mco_extract_triangles(h, budget);
    if (lod < 0) {
      out.ok = false;
      out.error = lastError();
      break;
    }
    out.cuts.push({ budget, lod, triangles: w.lk_mesh_index_count(h) / 3, digest: hex(w.lk_mesh_digest(h)) });
  }
  w.lk_close(h);
  return out;
}

function readPop(job, bytes) {
  const h = w.lk_pop_new();
  const at = w.lk_pop_push(h, bytes.length);
  new Uint8Array(w.memory.buffer, at, bytes.length).set(bytes);
  const levels = w.lk_pop_decode(h);
  if (levels <= 0) {
    const error = levels < 0 ? lastError() : 'no level decoded';
    w.lk_close(h);
    return { ok: false, error };
  }
  const depth = w.lk_pop_depth(h);
  const level = job.level ?? levels - 1;
  const triangles = w.lk_pop_mesh(h, level);
  if (triangles < 0) {
    const error = lastError();
    w.lk_close(h);
    return { ok: false, error };
  }
  const vertices = w.lk_mesh_vertex_count(h);
  const out = {
    ok: true,
    levels,
    depth,
    level,
    triangles,
    vertices,
    colors: hasColors(h, vertices),
    digest: hex(w.lk_mesh_digest(h)),
  };
  w.lk_close(h);
  return out;
}

const results = [];
for (const job of jobs) {
  let bytes;
  try {
    bytes = fs.readFileSync(job.file);
  } catch (e) {
    results.push({ ok: false, error: String(e) });
    continue;
  }
  try {
    results.push(job.file.endsWith('.mco') ? readMco(job, bytes) : readPop(job, bytes));
  } catch (e) {
    results.push({ ok: false, error: `trap: ${e}` });
  }
}
console.log(JSON.stringify(results));
