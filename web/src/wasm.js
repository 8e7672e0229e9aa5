// The wasm module is fetched and compiled once per URL and shared by every
// loader and model: each worker gets the compiled module in its 'init'
// message and instantiates it (no second download, no second compile).

const modules = new Map();

/** Default location of lodkit.wasm: beside this file. */
export const DEFAULT_WASM_URL = new URL('./lodkit.wasm', import.meta.url).href;

/** The compiled lodkit-wasm module at `url` (a promise, cached). */
export function wasmModule(url = DEFAULT_WASM_URL) {
  const key = String(url);
  if (!modules.has(key)) {
    const p = (async () => {
      const res = await fetch(key);
      if (!res.ok) throw new Error(`${key}: HTTP ${res.status}`);
      // compileStreaming needs the application/wasm type; a server that
      // sends another still works through the buffered path.
      if ((res.headers.get('content-type') || '').startsWith('application/wasm')) {
        return WebAssembly.compileStreaming(res);
      }
      return WebAssembly.compile(await res.arrayBuffer());
    })();
    p.catch(() => modules.delete(key));
    modules.set(key, p);
  }
  return modules.get(key);
}

let nextId = 1;

/**
 * A decoder worker with the lodkit module instantiated in it. `onMessage`
 * receives every message the worker posts; `post(msg, transfer)` sends one.
 */
export async function startWorker(wasmUrl, onMessage) {
  const module = await wasmModule(wasmUrl);
  const worker = new Worker(new URL('./worker.js', import.meta.url), { type: 'module' });
  worker.onmessage = (e) => onMessage(e.data);
  worker.onerror = (e) => onMessage({ type: 'error', message: e.message || 'worker failed' });
  worker.postMessage({ type: 'init', module });
  return worker;
}

/**
 * One decoder worker shared by a loader's streams or models (PopLoader's,
 * McoLoader's): `ready()` starts it on first use (a promise of the
 * worker), `on(id, handler)` / `off(id)` route its messages by stream or
 * model id, `terminate()` ends it (a later `ready()` starts a new one).
 */
export class DecoderWorker {
  constructor() {
    this.wasmUrl = undefined; // default: lodkit.wasm beside this module
    this.worker = null;
    this.started = null;
    this.handlers = new Map();
  }

  ready() {
    if (!this.started) {
      this.started = startWorker(this.wasmUrl, (m) => {
        const h = this.handlers.get(m.id);
        if (h) h(m);
        else if (m.type === 'error') console.error(`lodkit worker: ${m.message}`);
      }).then((w) => (this.worker = w));
    }
    return this.started;
  }

  on(id, handler) {
    this.handlers.set(id, handler);
  }

  off(id) {
    this.handlers.delete(id);
  }

  terminate() {
    if (this.worker) this.worker.terminate();
    this.worker = null;
    this.started = null;
    this.handlers.clear();
  }
}

/** A fresh id for a stream or model inside a worker. */
export function newId() {
  return nextId++;
}
