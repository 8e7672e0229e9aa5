// PopLoader: a three.js loader for lodkit's progressive `.pop` streams.
//
// The stream is read from fetch's ReadableStream and handed, as it arrives,
// to a Web Worker running lodkit's own decoder (Rust compiled to wasm). The
// returned THREE.Mesh shows the first octree level as soon as its chunks
// are in, then each finer level, then the precision layers that refine the
// finest level's positions. Every refinement fires a 'level' event on the
// mesh; `mesh.userData.pop` holds the current figures.

import * as THREE from 'three';
import { DecoderWorker, newId } from './wasm.js';

/** Builds a BufferGeometry from a worker mesh ({positions, normals?, colors?, indices?}). */
export function geometryFromMesh(m) {
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(m.positions, 3));
  if (m.normals) g.setAttribute('normal', new THREE.BufferAttribute(m.normals, 3));
  if (m.colors) g.setAttribute('color', new THREE.BufferAttribute(m.colors, 4, true));
  if (m.indices) g.setIndex(new THREE.BufferAttribute(m.indices, 1));
  if (!m.normals && m.indices) g.computeVertexNormals();
  g.computeBoundingBox();
  g.computeBoundingSphere();
  return g;
}

export class PopLoader extends THREE.Loader {
  constructor(manager) {
    super(manager);
    this.decoder = new DecoderWorker();
  }

  /** Where lodkit.wasm is (default: beside this module). */
  setWasmPath(url) {
    this.decoder.wasmUrl = url;
    return this;
  }

  /**
   * Streams `url`. `onLoad(mesh)` runs once the first level is on the mesh
   * (later levels refine the same mesh: listen to its 'level' event or
   * await `mesh.userData.pop.done`). `onProgress({loaded, total, level,
   * triangles})` runs for each network read and each level.
   */
  load(url, onLoad, onProgress, onError) {
    const fullUrl = this.manager.resolveURL(this.path + url);
    const mesh = new THREE.Mesh(
      new THREE.BufferGeometry(),
      new THREE.MeshStandardMaterial({ color: 0xd8d0c0, roughness: 0.8, metalness: 0.0, side: THREE.DoubleSide }),
    );
    const state = {
      url: fullUrl,
      level: -1,
      depth: -1,
      precision: -1,
      levels: 0,
      triangles: 0,
      loaded: 0,
      total: 0,
      bytesUsed: 0,
      decodeMs: 0,
      triangulateMs: 0,
      digest: '',
      complete: false,
      // Per level refinement: {level, precision, bytesUsed, receivedAt (ms,
      // performance.now() when its last byte arrived), shownAt}.
      history: [],
    };
    mesh.userData.pop = state;
    let resolveDone, rejectDone;
    state.done = new Promise((res, rej) => {
      resolveDone = res;
      rejectDone = rej;
    });
    state.done.catch(() => {});
    const arrivals = []; // [cumulative bytes, time]
    const id = newId();
    let first = true;
    let failed = false;
    const fail = (err) => {
      if (failed) return;
      failed = true;
      this.decoder.off(id);
      rejectDone(err);
      if (onError) onError(err);
      else console.error(err);
      this.manager.itemError(fullUrl);
      this.manager.itemEnd(fullUrl);
    };
    this.manager.itemStart(fullUrl);
    this.decoder.on(id, (m) => {
      if (m.type === 'error') return fail(new Error(`${fullUrl}: ${m.message}`));
      if (m.type === 'pop-level') {
        const old = mesh.geometry;
        mesh.geometry = geometryFromMesh(m.mesh);
        old.dispose();
        const colours = !!m.mesh.colors;
        if (mesh.material.vertexColors !== colours) {
          mesh.material.vertexColors = colours;
          if (colours) mesh.material.color.set(0xffffff);
          mesh.material.needsUpdate = true;
        }
        const arrived = arrivals.find((a) => a[0] >= m.bytesUsed);
        Object.assign(state, {
          level: m.level,
          depth: m.depth,
          precision: m.precision,
          levels: m.levels,
          triangles: m.triangles,
          bytesUsed: m.bytesUsed,
          decodeMs: m.decodeMs,
          triangulateMs: m.triangulateMs,
        });
        state.history.push({
          level: m.level,
          precision: m.precision,
          bytesUsed: m.bytesUsed,
          triangles: m.triangles,
          receivedAt: arrived ? arrived[1] : performance.now(),
          startedAt: m.startedAt - performance.timeOrigin,
          postedAt: m.postedAt - performance.timeOrigin,
          meshAt: performance.now(),
          decodeMs: m.decodeMs,
          triangulateMs: m.triangulateMs,
          shownAt: null,
        });
        mesh.dispatchEvent({ type: 'level', level: m.level, precision: m.precision });
        if (onProgress) onProgress({ loaded: state.loaded, total: state.total, level: m.level, triangles: m.triangles });
        if (first) {
          first = false;
          onLoad(mesh);
        }
      } else if (m.type === 'pop-digest') {
        if (m.level === state.level && m.precision === state.precision) state.digest = m.digest;
        mesh.dispatchEvent({ type: 'digest', digest: m.digest });
      } else if (m.type === 'pop-done') {
        state.complete = true;
        this.decoder.off(id);
        if (first) return fail(new Error(`${fullUrl}: the stream holds no complete level`));
        resolveDone(mesh);
        this.manager.itemEnd(fullUrl);
      }
    });
    (async () => {
      // The stream starts while the worker starts: reads made before it is
      // ready are queued and sent in order.
      const workerReady = this.decoder.ready().then((w) => {
        w.postMessage({ type: 'pop-open', id });
        return w;
      });
      let worker = null;
      const queued = [];
      const send = (bytes, done) => {
        if (worker) worker.postMessage({ type: 'pop-data', id, bytes, done }, [bytes]);
        else queued.push([bytes, done]);
      };
      workerReady.then((w) => {
        worker = w;
        for (const [bytes, done] of queued.splice(0)) w.postMessage({ type: 'pop-data', id, bytes, done }, [bytes]);
      }, fail);
      const res = await fetch(fullUrl, { headers: this.requestHeader, credentials: this.withCredentials ? 'include' : 'same-origin' });
      if (!res.ok) throw new Error(`${fullUrl}: HTTP ${res.status}`);
      state.total = Number(res.headers.get('content-length')) || 0;
      const reader = res.body.getReader();
      for (;;) {
        const { done, value } = await reader.read();
        if (failed) {
          reader.cancel();
          return;
        }
        if (done) break;
        state.loaded += value.byteLength;
        arrivals.push([state.loaded, performance.now()]);
        // The reader's chunk may view a larger buffer: move a copy.
        send(value.slice().buffer, false);
        if (onProgress) onProgress({ loaded: state.loaded, total: state.total, level: state.level, triangles: state.triangles });
      }
      if (!state.total) state.total = state.loaded;
      send(new ArrayBuffer(0), true);
    })().catch(fail);
    return mesh;
  }

  /**
   * Starts the worker (and the wasm download) now, so that the first
   * stream's first level is not kept waiting for them.
   */
  preload() {
    this.decoder.ready();
    return this;
  }

  /** Frees the worker (meshes already made stay usable). */
  dispose() {
    this.decoder.terminate();
    return this;
  }
}
