// McoLoader: a three.js loader for lodkit's `.mco` continuous-LOD models,
// beside PopLoader: `load(url, onLoad, onProgress, onError)` /
// `loadAsync(url, onProgress)` give an McoModel (a THREE.Mesh re-cut per
// view by its `update(camera, renderer)`), and every model a loader makes
// is decoded by that loader's one Web Worker (lodkit's own decoder, Rust
// compiled to wasm, the module fetched and compiled once). `dispose()`
// frees the worker and the models it still holds.

import * as THREE from 'three';
import { DecoderWorker } from './wasm.js';
import { McoModel } from './McoModel.js';

export class McoLoader extends THREE.Loader {
  constructor(manager) {
    super(manager);
    this.decoder = new DecoderWorker();
    this.tolerance = 1; // pixels of projected error a cut leaves
    this.initialTriangles = 20000; // the cut shown before the first update
    this.models = new Set();
  }

  /** Where lodkit.wasm is (default: beside this module). */
  setWasmPath(url) {
    this.decoder.wasmUrl = url;
    return this;
  }

  /** The pixel tolerance of the models this loader makes (default 1). */
  setTolerance(px) {
    this.tolerance = px;
    return this;
  }

  /**
   * Streams `url`. `onLoad(model)` runs once the first chunk's coarse cut
   * is on the model (later chunks re-cut it: listen to its 'model' event or
   * await `model.done`). `onProgress({loaded, total})` runs for each
   * network read. Returns the model at once (empty until the first chunk).
   */
  load(url, onLoad, onProgress, onError) {
    const fullUrl = this.manager.resolveURL(this.path + url);
    const model = new McoModel({
      tolerance: this.tolerance,
      initialTriangles: this.initialTriangles,
      decoder: this.decoder,
    });
    this.models.add(model);
    model.addEventListener('dispose', () => this.models.delete(model));
    this.manager.itemStart(fullUrl);
    let ended = false;
    const end = () => {
      if (!ended) this.manager.itemEnd(fullUrl);
      ended = true;
    };
    const init = { headers: this.requestHeader, credentials: this.withCredentials ? 'include' : 'same-origin' };
    model._stream(fullUrl, onProgress, init).then(
      () => {
        if (onLoad) onLoad(model);
      },
      (err) => {
        if (onError) onError(err);
        else console.error(err);
        this.manager.itemError(fullUrl);
        end();
      },
    );
    model.done.then(end, () => {});
    return model;
  }

  /**
   * Starts the worker (and the wasm download) now, so that the first
   * model's first cut is not kept waiting for them.
   */
  preload() {
    this.decoder.ready();
    return this;
  }

  /** Frees the worker and every model this loader made that is still open. */
  dispose() {
    for (const m of [...this.models]) m.dispose();
    this.models.clear();
    this.decoder.terminate();
    return this;
  }
}
