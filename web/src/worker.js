// The decoder worker: lodkit's own Rust decoders (lodkit-wasm) run here, off
// the main thread. It imports nothing: the page compiles the wasm module
// once (wasm.js) and posts the compiled module in the 'init' message.
//
// Messages in (each carries `id`, the stream or model it is about):
//   {type:'init', module}                       compiled WebAssembly.Module
//   {type:'pop-open', id}
//   {type:'pop-data', id, bytes, done}          bytes: ArrayBuffer (moved)
//   {type:'pop-level', id, level}               re-send a decoded level
//   {type:'mco-open', id, bytes}                the whole .mco file
//   {type:'mco-stream', id}                     a .mco that will arrive in pieces
//   {type:'mco-data', id, bytes, done}          its next bytes (ArrayBuffer, moved)
//   {type:'mco-view', id, seq, camera, tolerance}
//   {type:'mco-triangles', id, seq, triangles}
//   {type:'mco-lod', id, seq, lod}
//   {type:'close', id}
// Messages out:
//   {type:'pop-level', id, level, depth, precision, levels, bytesUsed,
//    triangles, decodeMs, triangulateMs, startedAt, postedAt, mesh}
//   {type:'pop-digest', id, level, precision, digest}   right after each level
//   {type:'pop-done', id, levels, bytesUsed}
//   {type:'mco-model', id, maxLod, fullTriangles, bounds, complete, bytes, mesh}
//     (a streamed file: once per read that completed chunks, each a model
//     of every chunk so far; `bytes`: the file bytes received by then)
//   {type:'mco-cut', id, seq, lod, expanded, triangles, ms, digest, indices}
//   {type:'error', id, message}
// A `mesh` is {positions: Float32Array, normals?: Float32Array,
// colors?: Uint8Array, indices?: Uint32Array}, its buffers transferred.

let wasm = null; // the instance's exports
const streams = new Map(); // id -> {h, decodedTo, levels, sentLevel, precision}
const models = new Map(); // id -> handle
// Streamed .mco files: id -> {h, received, head: Uint8Array[] (bytes kept
// until the version is known), whole: Uint8Array[] | null (a version-1
// file, read whole at the end)}.
const mcoStreams = new Map();

function errorText() {
  const p = wasm.lk_error_ptr();
  const n = wasm.lk_error_len();
  return new TextDecoder().decode(new Uint8Array(wasm.memory.buffer, p, n).slice());
}

// Copies the handle's mesh out of wasm memory (views are made after the
// call: memory growth detaches older views).
function meshOf(h, withVertices, withIndices) {
  const out = {};
  const buf = wasm.memory.buffer;
  if (withVertices) {
    const n = wasm.lk_mesh_vertex_count(h);
    out.positions = new Float32Array(buf, wasm.lk_mesh_positions(h), n * 3).slice();
    const pn = wasm.lk_mesh_normals(h);
    if (pn) out.normals = new Float32Array(buf, pn, n * 3).slice();
    const pc = wasm.lk_mesh_colors(h);
    if (pc) out.colors = new Uint8Array(buf, pc, n * 4).slice();
  }
  if (withIndices) {
    const n = wasm.lk_mesh_index_count(h);
    out.indices = new Uint32Array(buf, wasm.lk_mesh_indices(h), n).slice();
  }
  return out;
}

function transfers(mesh) {
  return Object.values(mesh).map((a) => a.buffer);
}

function popDecode(id, s, done) {
  // Decodes the chunks that arrived (each once); the levels are copied out
  // only when a whole new chunk run made more of the stream usable.
  const t0 = performance.now();
  const usable = wasm.lk_pop_usable(s.h);
  if (usable < 0) throw new Error(errorText());
  if (usable <= s.decodedTo) {
    if (done) postMessage({ type: 'pop-done', id, levels: s.levels, bytesUsed: s.decodedTo });
    return;
  }
  s.decodedTo = usable;
  const levels = wasm.lk_pop_decode(s.h);
  const decodeMs = performance.now() - t0;
  if (levels < 0) throw new Error(errorText());
  s.levels = levels;
  if (levels === 0) return;
  const precision = wasm.lk_pop_precision(s.h);
  const finest = levels - 1;
  // A new level, or finer positions for the finest one (precision layers).
  if (finest > s.sentLevel || (finest === s.sentLevel && precision > s.precision)) {
    sendLevel(id, s, finest, levels, precision, decodeMs, t0);
  }
  if (done) {
    postMessage({ type: 'pop-done', id, levels, bytesUsed: wasm.lk_pop_bytes_used(s.h) });
  }
}

// `startedAt`: when the worker took up the bytes that completed the level.
function sendLevel(id, s, level, levels, precision, decodeMs, startedAt) {
  const t1 = performance.now();
  const triangles = wasm.lk_pop_mesh(s.h, level);
  const triangulateMs = performance.now() - t1;
  if (triangles < 0) throw new Error(errorText());
  const mesh = meshOf(s.h, true, true);
  s.sentLevel = level;
  s.precision = precision;
  const now = performance.now();
  postMessage(
    {
      type: 'pop-level',
      id,
      level,
      depth: wasm.lk_pop_depth(s.h),
      precision,
      levels,
      bytesUsed: wasm.lk_pop_bytes_used(s.h),
      triangles,
      decodeMs,
      triangulateMs,
      // Absolute times (ms since the epoch): the worker took the bytes up,
      // and the level left it.
      startedAt: performance.timeOrigin + (startedAt ?? t1),
      postedAt: performance.timeOrigin + now,
      mesh,
    },
    transfers(mesh),
  );
  // The digest (for tests comparing buffers with the CLI's) after the
  // level is on its way: it is not on the path to the screen.
  const digest = BigInt.asUintN(64, wasm.lk_mesh_digest(s.h)).toString(16).padStart(16, '0');
  postMessage({ type: 'pop-digest', id, level, precision, digest });
}

function copyIn(bytes) {
  const p = wasm.lk_alloc(bytes.length);
  new Uint8Array(wasm.memory.buffer, p, bytes.length).set(bytes);
  return p;
}

function concat(parts) {
  const n = parts.reduce((s, p) => s + p.length, 0);
  const out = new Uint8Array(n);
  let at = 0;
  for (const p of parts) {
    out.set(p, at);
    at += p.length;
  }
  return out;
}

// Posts the model of handle `h`: its whole vertex buffer (a streamed
// file's grows with each chunk) and its figures.
function postModel(id, h, bytes) {
  wasm.lk_mco_vertices(h);
  const mesh = meshOf(h, true, false);
  const b = new Float32Array(wasm.memory.buffer, wasm.lk_mco_bounds(h), 6).slice();
  postMessage(
    {
      type: 'mco-model',
      id,
      maxLod: wasm.lk_mco_max_lod(h),
      fullTriangles: wasm.lk_mco_full_triangles(h),
      bounds: Array.from(b),
      complete: wasm.lk_mco_complete(h) === 1,
      bytes,
      mesh,
    },
    transfers(mesh),
  );
}

function mcoPush(s, bytes) {
  const p = copyIn(bytes);
  const r = wasm.lk_mco_stream_push(s.h, p, bytes.length);
  wasm.lk_free(p, bytes.length);
  if (r < 0) throw new Error(errorText());
  return r === 1;
}

function mcoData(m) {
  const s = mcoStreams.get(m.id);
  const bytes = new Uint8Array(m.bytes);
  s.received += bytes.length;
  let grew = false;
  if (s.whole) {
    s.whole.push(bytes);
  } else if (s.head) {
    // The version is in the first 12 bytes: version 1 has no chunks and is
    // read whole; version 2 streams.
    s.head.push(bytes);
    const head = concat(s.head);
    if (head.length >= 12 || m.done) {
      s.head = null;
      const p = copyIn(head.subarray(0, 12));
      const version = wasm.lk_mco_file_version(p, Math.min(head.length, 12));
      wasm.lk_free(p, 12);
      if (version === 1) s.whole = [head];
      else grew = mcoPush(s, head);
    }
  } else if (bytes.length > 0) {
    grew = mcoPush(s, bytes);
  }
  if (m.done && s.whole) {
    const all = concat(s.whole);
    const p = copyIn(all);
    const h = wasm.lk_mco_open(p, all.length);
    wasm.lk_free(p, all.length);
    if (h === 0) throw new Error(errorText());
    wasm.lk_close(s.h);
    s.h = h;
    models.set(m.id, h);
    grew = true;
  }
  if (grew) postModel(m.id, s.h, s.received);
  if (m.done && wasm.lk_mco_complete(s.h) !== 1) {
    throw new Error(`the file ends inside a chunk (${s.received} bytes)`);
  }
}

function mcoCut(id, seq, h, lod, expanded, ms) {
  const mesh = meshOf(h, false, true);
  const digest = BigInt.asUintN(64, wasm.lk_mesh_digest(h)).toString(16).padStart(16, '0');
  postMessage(
    {
      type: 'mco-cut',
      id,
      seq,
      lod,
      expanded,
      triangles: mesh.indices.length / 3,
      ms,
      digest,
      indices: mesh.indices,
    },
    [mesh.indices.buffer],
  );
}

function handle(m) {
  switch (m.type) {
    case 'init': {
      const instance = new WebAssembly.Instance(m.module, {});
      wasm = instance.exports;
      // Compile the decoder's code paths before the first stream needs them.
      wasm.lk_warm_up();
      return;
    }
    case 'pop-open':
      streams.set(m.id, { h: wasm.lk_pop_new(), decodedTo: 0, levels: 0, sentLevel: -1, precision: -1 });
      return;
    case 'pop-data': {
      const s = streams.get(m.id);
      const bytes = new Uint8Array(m.bytes);
      if (bytes.length > 0) {
        const p = wasm.lk_pop_push(s.h, bytes.length);
        new Uint8Array(wasm.memory.buffer, p, bytes.length).set(bytes);
      }
      popDecode(m.id, s, m.done);
      return;
    }
    case 'pop-level': {
      const s = streams.get(m.id);
      sendLevel(m.id, s, m.level, wasm.lk_pop_decode(s.h), wasm.lk_pop_precision(s.h), 0);
      return;
    }
    case 'mco-open': {
      const bytes = new Uint8Array(m.bytes);
      const p = copyIn(bytes);
      const h = wasm.lk_mco_open(p, bytes.length);
      wasm.lk_free(p, bytes.length);
      if (h === 0) throw new Error(errorText());
      models.set(m.id, h);
      postModel(m.id, h, bytes.length);
      return;
    }
    case 'mco-stream': {
      const h = wasm.lk_mco_stream_new();
      mcoStreams.set(m.id, { h, received: 0, head: [], whole: null });
      models.set(m.id, h);
      return;
    }
    case 'mco-data':
      mcoData(m);
      return;
    case 'mco-view': {
      const h = models.get(m.id);
      const c = m.camera;
      const t0 = performance.now();
      const expanded = wasm.lk_mco_extract_view(
        h,
        c.position[0], c.position[1], c.position[2],
        c.direction[0], c.direction[1], c.direction[2],
        c.up[0], c.up[1], c.up[2],
        c.vfov, c.viewportHeight, c.aspect,
        m.tolerance,
      );
      mcoCut(m.id, m.seq, h, -1, expanded, performance.now() - t0);
      return;
    }
    case 'mco-triangles': {
      const h = models.get(m.id);
      const t0 = performance.now();
      const lod = wasm.lk_mco_extract_triangles(h, m.triangles);
      mcoCut(m.id, m.seq, h, lod, -1, performance.now() - t0);
      return;
    }
    case 'mco-lod': {
      const h = models.get(m.id);
      const t0 = performance.now();
      const lod = wasm.lk_mco_extract_lod(h, m.lod);
      mcoCut(m.id, m.seq, h, lod, -1, performance.now() - t0);
      return;
    }
    case 'close': {
      const s = streams.get(m.id);
      if (s) wasm.lk_close(s.h);
      streams.delete(m.id);
      const h = models.get(m.id);
      if (h) wasm.lk_close(h);
      models.delete(m.id);
      mcoStreams.delete(m.id);
      return;
    }
    default:
      throw new Error(`unknown message ${m.type}`);
  }
}

self.onmessage = (e) => {
  try {
    handle(e.data);
  } catch (err) {
    postMessage({ type: 'error', id: e.data.id, message: String(err && err.message ? err.message : err) });
  }
};
