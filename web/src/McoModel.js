// McoModel: a lodkit `.mco` continuous-LOD model as a THREE.Mesh.
//
// The model's whole vertex buffer goes to the GPU once; every cut is only a
// new index buffer. `update(camera, renderer)` asks the decoder worker for
// the view-dependent cut of the current view (nodes whose projected error
// exceeds `tolerance` pixels are refined) whenever the view changed; at most
// one cut is in flight, later views wait and only the newest is sent.

import * as THREE from 'three';
import { startWorker, newId } from './wasm.js';
import { geometryFromMesh } from './PopLoader.js';

const inv = new THREE.Matrix4();
const v = new THREE.Vector3();
const d = new THREE.Vector3();
const u = new THREE.Vector3();

export class McoModel extends THREE.Mesh {
  /**
   * Fetches and opens `url`. Options: `tolerance` (pixels, default 1),
   * `wasmUrl`, `onProgress({loaded, total})`, `initialTriangles` (the cut
   * shown before the first `update`, default 20000).
   */
  static async load(url, options = {}) {
    const res = await fetch(url);
    if (!res.ok) throw new Error(`${url}: HTTP ${res.status}`);
    const total = Number(res.headers.get('content-length')) || 0;
    const reader = res.body.getReader();
    const parts = [];
    let loaded = 0;
    for (;;) {
      const { done, value } = await reader.read();
      if (done) break;
      parts.push(value);
      loaded += value.byteLength;
      if (options.onProgress) options.onProgress({ loaded, total: total || loaded });
    }
    const bytes = new Uint8Array(loaded);
    let at = 0;
    for (const p of parts) {
      bytes.set(p, at);
      at += p.byteLength;
    }
    const m = new McoModel(options);
    await m._open(bytes.buffer, url);
    return m;
  }

  constructor(options = {}) {
    super(
      new THREE.BufferGeometry(),
      new THREE.MeshStandardMaterial({ color: 0xd8d0c0, roughness: 0.8, metalness: 0.0, side: THREE.DoubleSide }),
    );
    this.tolerance = options.tolerance ?? 1;
    this.wasmUrl = options.wasmUrl;
    this.initialTriangles = options.initialTriangles ?? 20000;
    this.workerId = newId();
    this.worker = null;
    this.seq = 0;
    this.inFlight = null; // seq of the cut being made
    this.pendingView = null;
    this.lastKey = '';
    this.waiters = new Map(); // seq -> resolve
    // The figures of the cut on screen.
    this.state = { lod: -1, expanded: -1, triangles: 0, cutMs: 0, digest: '', maxLod: 0, fullTriangles: 0, cuts: 0 };
  }

  async _open(buffer, url) {
    let ready;
    const opened = new Promise((res, rej) => (ready = { res, rej }));
    this.worker = await startWorker(this.wasmUrl, (m) => this._message(m, ready));
    this.worker.postMessage({ type: 'mco-open', id: this.workerId, bytes: buffer }, [buffer]);
    await opened.catch((e) => {
      throw new Error(`${url}: ${e.message}`);
    });
    await this.extractTriangles(this.initialTriangles);
  }

  _message(m, ready) {
    if (m.type === 'error') {
      if (ready && !this.state.maxLod) ready.rej(new Error(m.message));
      else console.error(`lodkit worker: ${m.message}`);
      return;
    }
    if (m.type === 'mco-model') {
      this.geometry.dispose();
      this.geometry = geometryFromMesh(m.mesh);
      if (m.mesh.colors) {
        this.material.vertexColors = true;
        this.material.color.set(0xffffff);
      }
      this.state.maxLod = m.maxLod;
      this.state.fullTriangles = m.fullTriangles;
      this.bounds = m.bounds;
      ready.res();
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
          this.pendingView = null;
          this._send(p);
        }
      }
    }
  }

  _send(msg) {
    const seq = ++this.seq;
    this.inFlight = seq;
    this.worker.postMessage({ ...msg, id: this.workerId, seq });
    return new Promise((res) => this.waiters.set(seq, res));
  }

  /** The cut closest to `triangles` triangles (resolves with `state`). */
  extractTriangles(triangles) {
    this.lastKey = '';
    return this._send({ type: 'mco-triangles', triangles });
  }

  /** The cut at LOD number `lod` (resolves with `state`). */
  extractLod(lod) {
    this.lastKey = '';
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
    if (this.inFlight !== null) {
      this.pendingView = msg;
      return null;
    }
    return this._send(msg);
  }

  /** Frees the worker and the GPU buffers. */
  dispose() {
    if (this.worker) {
      this.worker.postMessage({ type: 'close', id: this.workerId });
      this.worker.terminate();
    }
    this.worker = null;
    this.geometry.dispose();
    this.material.dispose();
  }
}
