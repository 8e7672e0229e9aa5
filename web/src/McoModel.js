// McoModel: a lodkit `.mco` continuous-LOD model as a THREE.Mesh.
//
// The model's whole vertex buffer goes to the GPU once per chunk read (once
// in all for a complete file); every cut is only a new index buffer. `update(camera, renderer)` asks the decoder worker for
// the view-dependent cut of the current view (nodes whose projected error
// exceeds `tolerance` pixels are refined) whenever the view changed; at most
// one cut is in flight, later views wait and only the newest is sent.
// The file streams: a coarse cut shows once its first chunk is in, and each
// later chunk (finer LOD numbers) re-cuts the model as it arrives.

import * as THREE from 'three';
import { startWorker, newId } from './wasm.js';
import { geometryFromMesh } from './PopLoader.js';

const inv = new THREE.Matrix4();
const v = new THREE.Vector3();
const d = new THREE.Vector3();
const u = new THREE.Vector3();

export class McoModel extends THREE.Mesh {
  /**
   * Streams `url` and resolves as soon as its first chunk is in, with a
   * coarse cut on the mesh: a version-2 `.mco` is LOD-ordered, so each
   * further chunk lets the model serve finer LOD numbers, and the model
   * re-cuts itself as they arrive (a 'model' event for each; `await
   * model.done` waits for the whole file). A version-1 file is shown once
   * whole. Options: `tolerance` (pixels, default 1), `wasmUrl`,
   * `onProgress({loaded, total})`, `initialTriangles` (the cut shown before
   * the first `update`, default 20000). `McoLoader` makes models that
   * share its one worker.
   */
  static async load(url, options = {}) {
    const m = new McoModel(options);
    await m._stream(url, options.onProgress);
    return m;
  }

  constructor(options = {}) {
    // Front faces only: every cut is wound counter-clockwise seen from
    // outside, so a back face is the inside of the surface seen past an
    // open rim (the bunny's underside): drawn double-sided, those showed as
    // dark and light speckles, lit with flipped normals, around the holes.
    super(
      new THREE.BufferGeometry(),
      new THREE.MeshStandardMaterial({ color: 0xd8d0c0, roughness: 0.8, metalness: 0.0, side: THREE.FrontSide }),
    );
    this.isMcoModel = true;
    this.tolerance = options.tolerance ?? 1;
    this.wasmUrl = options.wasmUrl;
    // A DecoderWorker shared with other models (`McoLoader`'s); none: the
    // model starts its own worker and ends it in `dispose`.
    this.decoder = options.decoder || null;
    this.initialTriangles = options.initialTriangles ?? 20000;
    this.workerId = newId();
    this.worker = null;
    this.seq = 0;
    this.inFlight = null; // seq of the cut being made
    this.pendingView = null;
    this.pendingResolvers = [];
    this.lastView = null; // the last view cut asked for (re-sent when the model grows)
    this.lastKey = '';
    this.waiters = new Map(); // seq -> resolve
    // The figures of the cut on screen; `bytes`/`complete`: of the file.
    this.state = { lod: -1, expanded: -1, triangles: 0, cutMs: 0, digest: '', maxLod: 0, fullTriangles: 0, cuts: 0, models: 0, bytes: 0, complete: false };
    this.done = new Promise((res, rej) => (this._done = { res, rej }));
    this.done.catch(() => {});
  }

  // The worker, with this model's messages routed to `_message`.
  _connect() {
    if (this.decoder) {
      this.decoder.on(this.workerId, (m) => this._message(m));
      return this.decoder.ready();
    }
    return startWorker(this.wasmUrl, (m) => this._message(m));
  }

  async _stream(url, onProgress, init = {}) {
    let first;
    const opened = new Promise((res, rej) => (first = { res, rej }));
    const fail = (e) => {
      const err = new Error(`${url}: ${e.message}`);
      first.rej(err);
      this._done.rej(err);
    };
    this._ready = first;
    this._fail = fail;
    // The worker starts while the first bytes are on their way.
    const workerReady = this._connect().then((w) => {
      this.worker = w;
      w.postMessage({ type: 'mco-stream', id: this.workerId });
      return w;
    });
    (async () => {
      const res = await fetch(url, init);
      if (!res.ok) throw new Error(`HTTP ${res.status}`);
      const total = Number(res.headers.get('content-length')) || 0;
      const reader = res.body.getReader();
      const w = await workerReady;
      let loaded = 0;
      for (;;) {
        const { done, value } = await reader.read();
        if (done) break;
        loaded += value.byteLength;
        // The reader's chunk may view a larger buffer: move a copy.
        const bytes = value.slice().buffer;
        w.postMessage({ type: 'mco-data', id: this.workerId, bytes, done: false }, [bytes]);
        if (onProgress) onProgress({ loaded, total: total || loaded });
      }
      w.postMessage({ type: 'mco-data', id: this.workerId, bytes: new ArrayBuffer(0), done: true });
    })().catch(fail);
    await opened;
  }

  /** Opens a whole file held in `buffer` (moved to the worker). */
  async _open(buffer, url) {
    let first;
    const opened = new Promise((res, rej) => (first = { res, rej }));
    this._ready = first;
    this._fail = (e) => {
      first.rej(new Error(`${url}: ${e.message}`));
      this._done.rej(e);
    };
    this.worker = await this._connect();
    this.worker.postMessage({ type: 'mco-open', id: this.workerId, bytes: buffer }, [buffer]);
    await opened;
  }

  _message(m) {
    if (m.type === 'error') {
      if (!this.state.complete) this._fail(new Error(m.message));
      else console.error(`lodkit worker: ${m.message}`);
      return;
    }
    if (m.type === 'mco-model') {
      // The vertex buffer of every chunk so far: the cut on screen indexes
      // into its first vertices, which a longer prefix keeps as they are.
      const index = this.geometry.index;
      this.geometry.dispose();
      this.geometry = geometryFromMesh(m.mesh);
      if (index) this.geometry.setIndex(index);
      if (m.mesh.colors && !this.material.vertexColors) {
        this.material.vertexColors = true;
        this.material.color.set(0xffffff);
        this.material.needsUpdate = true;
      }
      Object.assign(this.state, { maxLod: m.maxLod, fullTriangles: m.fullTriangles, bytes: m.bytes, complete: m.complete });
      this.state.models += 1;
      this.bounds = m.bounds;
      // Re-cut with the finer LOD numbers: the last view, or the budget.
      const cut = this.lastView ? this._send(this.lastView, true) : this.extractTriangles(this.initialTriangles);
      if (this.state.models === 1) cut.then(() => this._ready.res());
      if (m.complete) cut.then(() => this._done.res(this));
      this.dispatchEvent({ type: 'model', maxLod: m.maxLod, bytes: m.bytes, complete: m.complete });
      return;
    }
    if (m.type === 'mco-cut') {
      this.geometry.setIndex(new THREE.BufferAttribute(m.indices, 1));
      Object.assign(this.state, {
        lod: m.lod,
        expanded: m.expanded,
        triangles: m.triangles,
        cutMs: m.ms,
        digest: m.digest,
      });
      this.state.cuts += 1;
      this.dispatchEvent({ type: 'cut', triangles: m.triangles });
      const w = this.waiters.get(m.seq);
      if (w) {
        this.waiters.delete(m.seq);
        w(this.state);
      }
      if (m.seq === this.inFlight) {
        this.inFlight = null;
        if (this.pendingView) {
          const p = this.pendingView;
          const waiting = this.pendingResolvers.splice(0);
          this.pendingView = null;
          const sent = this._send(p);
          for (const r of waiting) sent.then(r);
        }
      }
    }
  }

  // Sends a cut request; `queue`: wait behind a cut in flight (a view).
  _send(msg, queue = false) {
    if (queue && this.inFlight !== null) {
      this.pendingView = msg;
      // Resolved by the cut of the newest view (which may replace this one).
      return new Promise((res) => this.pendingResolvers.push(res));
    }
    const seq = ++this.seq;
    this.inFlight = seq;
    this.worker.postMessage({ ...msg, id: this.workerId, seq });
    return new Promise((res) => this.waiters.set(seq, res));
  }

  /** The cut closest to `triangles` triangles (resolves with `state`). */
  extractTriangles(triangles) {
    this.lastKey = '';
    this.lastView = null;
    return this._send({ type: 'mco-triangles', triangles });
  }

  /** The cut at LOD number `lod` (resolves with `state`). */
  extractLod(lod) {
    this.lastKey = '';
    this.lastView = null;
    return this._send({ type: 'mco-lod', lod });
  }

  /**
   * Re-cuts the model for `camera` (a PerspectiveCamera) as `renderer`
   * draws it, if the view or the tolerance changed since the last cut.
   * Returns a promise of the new state, or null when nothing changed.
   */
  update(camera, renderer) {
    if (!this.worker) return null;
    this.updateMatrixWorld();
    camera.updateMatrixWorld();
    inv.copy(this.matrixWorld).invert();
    camera.getWorldPosition(v).applyMatrix4(inv);
    camera.getWorldDirection(d).transformDirection(inv);
    u.copy(camera.up).transformDirection(inv);
    const zoom = camera.zoom || 1;
    const vfov = (2 * Math.atan(Math.tan((camera.fov * Math.PI) / 360) / zoom) * 180) / Math.PI;
    const height = renderer.domElement.height;
    const cam = {
      position: v.toArray(),
      direction: d.toArray(),
      up: u.toArray(),
      vfov,
      viewportHeight: height,
      aspect: camera.aspect,
    };
    const key = [...cam.position, ...cam.direction, ...cam.up, vfov, height, cam.aspect, this.tolerance]
      .map((x) => x.toPrecision(5))
      .join(',');
    if (key === this.lastKey) return null;
    this.lastKey = key;
    const msg = { type: 'mco-view', camera: cam, tolerance: this.tolerance };
    this.lastView = msg;
    if (this.inFlight !== null) {
      this.pendingView = msg;
      return null;
    }
    return this._send(msg);
  }

  /** Frees the model's decoder state, its own worker and the GPU buffers. */
  dispose() {
    if (this.worker) {
      this.worker.postMessage({ type: 'close', id: this.workerId });
      if (this.decoder) this.decoder.off(this.workerId);
      else this.worker.terminate();
    }
    this.worker = null;
    this.geometry.dispose();
    this.material.dispose();
    this.dispatchEvent({ type: 'dispose' });
  }
}
