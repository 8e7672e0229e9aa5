// The lodkit viewer: one page for the three LOD forms, 3D Tiles tilesets
// and plain meshes.
//   ?model=URL            the model to open (kind from its extension, or &kind=;
//                         a `.json` is a 3D Tiles tileset)
//   GET /api/models       the server's listing (lodkit serve), if there is one
// The HUD's figures are on window.lodkitViewer.state (the browser tests read
// them there).

import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { MeshoptDecoder } from 'three/addons/libs/meshopt_decoder.module.js';
import { TilesRenderer } from '3d-tiles-renderer';
// Not imported here: the .pop/.mco decoders (./lodkit/: loaders, worker,
// wasm) and the PLY reader, loaded when a page opens such a file (or may
// open any: `?idle`, a listing), so that a tileset's first frame does not
// share the link or the CPU with them.

// The LOD-chain switch uses a level's mean edge length as its error; an
// edge this many times the pixel tolerance on screen is still accepted
// (edges are longer than the geometric deviation they cause).
const CHAIN_EDGE_PER_PX = 4;

const $ = (id) => document.getElementById(id);
const view = $('view');
const renderer = new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio || 1);
renderer.setClearColor(0x20232a);
view.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.add(new THREE.HemisphereLight(0xffffff, 0x404050, 1.6));
const sun = new THREE.DirectionalLight(0xffffff, 1.8);
sun.position.set(1, 2, 1.5);
scene.add(sun);
const camera = new THREE.PerspectiveCamera(45, 1, 0.001, 1000);
scene.add(camera);
const controls = new OrbitControls(camera, renderer.domElement);
controls.addEventListener('change', () => requestRender());

const state = {
  kind: '',
  url: '',
  loaded: 0,
  total: 0,
  level: -1, // .pop level, chain level (LODk: 0 = the input, finest), .mco LOD number
  levels: 0, // .pop: levels decoded so far (0 .. levels - 1); chain: levels in the GLB
  lastLevel: -1, // the highest level number the file holds (the HUD's "in 0–N"; .pop: its depth)
  precision: -1,
  triangles: 0,
  decodeMs: 0,
  frameMs: 0,
  frames: 0,
  tolerance: 1,
  wireframe: false,
  firstDrawLoaded: -1, // bytes received when the model was first drawn
  firstDrawMs: -1,
  firstCutLoaded: -1, // .mco: file bytes read when a cut first had triangles
  models: 0, // .mco: models read so far (one per read that completed chunks)
  maxLod: 0,
  levelsShown: [], // .pop: {level, precision, triangles, bytesUsed, latencyMs}
  cuts: 0,
  digest: '',
  complete: false,
  error: '',
  // A tileset: tiles with content loaded (in the cache), drawn this frame,
  // failed; bytes fetched so far (tileset JSON and tile contents).
  tilesLoaded: 0,
  tilesVisible: 0,
  tilesFailed: 0,
  tilesetBytes: 0,
  settledFrames: 0,
  points: 0, // a tileset: points drawn this frame (POINTS tiles)
  firstFrameMs: -1, // a tileset: performance.now() of the first frame drawing tile content
  prefetched: 0, // a tileset: requests answered by the page's prefetch
};
const viewer = {
  state,
  scene,
  camera,
  renderer,
  controls,
  model: null,
  ready: null,
  render: () => renderNow(),
  /** Opens a model (what ?model= does). */
  open: (url, kind) => open(url, kind),
  /** Puts the camera at `position` looking at `target` and draws a frame. */
  setCamera(position, target) {
    camera.position.fromArray(position);
    controls.target.fromArray(target);
    controls.update();
    renderNow();
  },
  /** The model's surface point under the view at normalised device
   * coordinates `x`, `y` (each in -1..1; 0, 0 is the centre), or null. */
  pick(x, y) {
    const ray = new THREE.Raycaster();
    ray.setFromCamera(new THREE.Vector2(x, y), camera);
    const hit = viewer.model && ray.intersectObject(viewer.model, true)[0];
    return hit ? hit.point.toArray() : null;
  },
};
window.lodkitViewer = viewer;
let startCamera = null;

window.addEventListener('error', (e) => showError(e.message));
window.addEventListener('unhandledrejection', (e) => showError(String(e.reason && e.reason.message ? e.reason.message : e.reason)));

function showError(msg) {
  state.error = msg;
  $('error').textContent = msg;
  console.error(msg);
}

function resize() {
  const w = view.clientWidth || 800;
  const h = view.clientHeight || 600;
  renderer.setSize(w, h, false);
  camera.aspect = w / h;
  camera.updateProjectionMatrix();
  requestRender();
}
window.addEventListener('resize', resize);

let renderQueued = false;
function requestRender() {
  if (renderQueued) return;
  renderQueued = true;
  requestAnimationFrame(() => {
    renderQueued = false;
    renderNow();
  });
}

let onFrame = null; // per-kind work before each frame (cuts, level switch)
let onFirstShown = null; // the page's model on screen (its first frame drawn)
function firstShown() {
  const f = onFirstShown;
  onFirstShown = null;
  if (f) f();
}
let afterFrame = null;
function renderNow() {
  if (onFrame) onFrame();
  const t0 = performance.now();
  renderer.render(scene, camera);
  state.frameMs = performance.now() - t0;
  state.frames += 1;
  if (afterFrame) afterFrame();
  hud();
}

function fmtBytes(n) {
  if (n >= 1 << 20) return `${(n / (1 << 20)).toFixed(2)} MiB`;
  if (n >= 1 << 10) return `${(n / (1 << 10)).toFixed(1)} KiB`;
  return `${n} B`;
}

// One convention for every numbered level: "k in 0–N", k the number the
// file gives the level shown and N the highest number the file holds (so
// both ends count from 0). A .pop level and an .mco LOD number count up
// from the coarsest (0); a chain's LODk counts up from the finest (LOD0,
// the input), as its node names do; the note after it says which.
function levelLine(label, k, last, note) {
  return `${label.padEnd(9)} ${k} in 0–${last >= 0 ? last : '?'}  (${note})`;
}

function hud() {
  const lines = [
    `${state.kind || '-'}  ${state.url.split('/').pop()}`,
    state.kind === 'tileset' ? `bytes     ${fmtBytes(state.loaded)} downloaded` : `bytes     ${fmtBytes(state.loaded)} / ${fmtBytes(state.total)}`,
  ];
  if (state.kind === 'pop') lines.push(levelLine('level', state.level, state.lastLevel, `0 coarsest, ${state.precision} bits`));
  if (state.kind === 'mco') {
    // Before the first cut (or when the file cannot be read) there is none.
    if (state.level >= 0) lines.push(levelLine('LOD', state.level, state.maxLod, '0 coarsest'));
    else if (state.expanded >= 0) lines.push(`view cut  ${state.expanded} nodes refined`);
    else lines.push('cut       -');
  }
  if (state.kind === 'chain') lines.push(levelLine('level', state.level, state.lastLevel, `lod${state.level}, 0 finest`));
  if (state.kind === 'tileset') {
    lines.push(`tiles     ${state.tilesLoaded} loaded, ${state.tilesVisible} drawn${state.tilesFailed ? `, ${state.tilesFailed} failed` : ''}`);
    lines.push(`error     ${state.tolerance} px target`);
    if (state.points) lines.push(`points    ${state.points.toLocaleString('en')}`);
  }
  lines.push(`triangles ${state.triangles.toLocaleString('en')}`);
  lines.push(`decode    ${state.decodeMs.toFixed(1)} ms`);
  lines.push(`frame     ${state.frameMs.toFixed(1)} ms`);
  $('hud').textContent = lines.join('\n');
}

// Frames the camera on a bounding sphere (once per model); `elevation`
// (radians) looks down on it, as a tileset's terrain or room scan wants.
function frameSphere(sphere, elevation) {
  const r = sphere.radius || 1;
  const dist = r / Math.sin((camera.fov * Math.PI) / 360) * 1.1;
  controls.target.copy(sphere.center);
  const offset = elevation === undefined
    ? new THREE.Vector3(0, r * 0.15, dist)
    : new THREE.Vector3(0, dist * Math.sin(elevation), dist * Math.cos(elevation));
  camera.position.copy(sphere.center).add(offset);
  camera.near = dist / 100;
  camera.far = dist * 100;
  camera.updateProjectionMatrix();
  controls.update();
  requestRender();
}

function setWireframe(obj, on) {
  obj.traverse((o) => {
    if (o.material) for (const m of [o.material].flat()) m.wireframe = on;
  });
}

function kindOf(url, given) {
  if (given) return given;
  const ext = url.split('?')[0].split('.').pop().toLowerCase();
  return { pop: 'pop', mco: 'mco', glb: 'glb', gltf: 'glb', ply: 'ply', json: 'tileset' }[ext] || ext;
}

// Total size from a HEAD request, for the HUD while a whole-file loader runs.
async function headSize(url) {
  try {
    const r = await fetch(url, { method: 'HEAD' });
    return Number(r.headers.get('content-length')) || 0;
  } catch {
    return 0;
  }
}

// One loader (one worker) per kind for the page, made when the decoders
// are first wanted: a promise of {popLoader, mcoLoader, wasm}, resolved
// once their script is in. The wasm module (`wasm`, a promise) and the
// .pop worker start then, beside the model's own download (an .mco model
// starts its own worker).
let decoders = null;
function loadDecoders() {
  if (!decoders) {
    decoders = import('./lodkit/index.js').then((m) => {
      const popLoader = new m.PopLoader();
      const mcoLoader = new m.McoLoader();
      popLoader.preload();
      const wasm = m.wasmModule();
      wasm.catch(() => {}); // reported by the loader that needs it
      return { popLoader, mcoLoader, wasm };
    });
    // A failed download is tried again by the next model that wants it.
    decoders.catch(() => (decoders = null));
  }
  return decoders;
}

async function openPop(url) {
  const { popLoader: loader } = await loadDecoders();
  viewer.loader = loader;
  let framed = false;
  let pending = null; // the refinement waiting for its first frame
  return new Promise((resolve, reject) => {
    const mesh = loader.load(
      url,
      () => {},
      (p) => {
        state.loaded = p.loaded;
        state.total = p.total;
        hud();
      },
      (err) => reject(err),
    );
    viewer.model = mesh;
    scene.add(mesh);
    const s = mesh.userData.pop;
    mesh.addEventListener('level', () => {
      if (viewer.model !== mesh) return; // a stream the page has moved on from
      Object.assign(state, { level: s.level, levels: s.levels, lastLevel: s.depth >= 0 ? s.depth : s.levels - 1, precision: s.precision, triangles: s.triangles, decodeMs: s.decodeMs + s.triangulateMs });
      setWireframe(mesh, state.wireframe);
      pending = s.history[s.history.length - 1];
      if (!framed) {
        framed = true;
        frameSphere(mesh.geometry.boundingSphere);
      }
      renderNow();
      firstShown();
    });
    afterFrame = () => {
      if (!pending) return;
      // The level is on screen once the GPU has drawn this frame.
      const f0 = performance.now();
      renderer.getContext().finish();
      const now = performance.now();
      pending.finishMs = now - f0;
      pending.frameMs = state.frameMs;
      pending.shownAt = now;
      state.levelsShown.push({
        level: pending.level,
        precision: pending.precision,
        triangles: pending.triangles,
        bytesUsed: pending.bytesUsed,
        // From the read holding the level's last byte to this frame drawn,
        // and its parts: to the worker taking the bytes up, the worker
        // (decode, triangulate, copy out), the message to the page, the
        // upload and draw.
        latencyMs: now - pending.receivedAt,
        queueMs: pending.startedAt - pending.receivedAt,
        workerMs: pending.postedAt - pending.startedAt,
        decodeMs: pending.decodeMs,
        triangulateMs: pending.triangulateMs,
        postMs: pending.meshAt - pending.postedAt,
        drawMs: now - pending.meshAt,
      });
      if (state.firstDrawLoaded < 0 && pending.triangles > 0) {
        state.firstDrawLoaded = s.loaded;
        state.firstDrawMs = now;
      }
      pending = null;
    };
    mesh.addEventListener('digest', () => {
      if (viewer.model === mesh) state.digest = s.digest;
    });
    s.done.then(() => {
      state.digest = s.digest;
      state.complete = true;
      state.loaded = s.loaded;
      state.total = s.total;
      hud();
      resolve();
    }, reject);
  });
}

async function openMco(url) {
  // Resolves at the file's first chunk: the coarse cut shows while the rest
  // streams in, and each chunk re-cuts it with finer LOD numbers.
  const { mcoLoader } = await loadDecoders();
  const model = await mcoLoader.setTolerance(state.tolerance).loadAsync(url, (p) => {
    state.loaded = p.loaded;
    state.total = p.total;
    hud();
  });
  viewer.model = model;
  scene.add(model);
  const b = model.bounds;
  const box = new THREE.Box3(new THREE.Vector3(b[0], b[1], b[2]), new THREE.Vector3(b[3], b[4], b[5]));
  viewer.bounds = box;
  // Framed on the first chunks' vertices: coarse, but spread as the
  // model's (the bounding cube is larger than the surface).
  frameSphere(model.geometry.boundingSphere);
  firstShown();
  const sync = () => {
    const m = model.state;
    Object.assign(state, { level: m.lod, expanded: m.expanded, triangles: m.triangles, decodeMs: m.cutMs, cuts: m.cuts, digest: m.digest, maxLod: m.maxLod, fileBytes: m.bytes });
  };
  model.addEventListener('cut', () => {
    sync();
    if (state.firstCutLoaded < 0 && model.state.triangles > 0) state.firstCutLoaded = model.state.bytes;
    setWireframe(model, state.wireframe);
    requestRender();
  });
  model.addEventListener('model', () => {
    state.models = model.state.models;
    requestRender();
  });
  sync();
  if (model.state.triangles > 0) state.firstCutLoaded = model.state.bytes;
  onFrame = () => {
    model.tolerance = state.tolerance;
    model.update(camera, renderer);
  };
  requestRender();
  await model.done;
  sync();
  state.complete = true;
  requestRender();
}

function triangleCount(g) {
  return (g.index ? g.index.count : g.attributes.position.count) / 3;
}

function surfaceArea(g) {
  const p = g.attributes.position;
  const idx = g.index;
  const n = triangleCount(g);
  const a = new THREE.Vector3(), b = new THREE.Vector3(), c = new THREE.Vector3();
  let area = 0;
  for (let t = 0; t < n; t++) {
    const i = idx ? idx.getX(3 * t) : 3 * t, j = idx ? idx.getX(3 * t + 1) : 3 * t + 1, k = idx ? idx.getX(3 * t + 2) : 3 * t + 2;
    a.fromBufferAttribute(p, i);
    b.fromBufferAttribute(p, j).sub(a);
    c.fromBufferAttribute(p, k).sub(a);
    area += b.cross(c).length() / 2;
  }
  return area;
}

async function openGlb(url) {
  const gltf = await new GLTFLoader().loadAsync(url, (p) => {
    state.loaded = p.loaded;
    state.total = p.total || state.total;
    hud();
  });
  const root = gltf.scene;
  // An MSFT_lod chain (lodkit's chain GLB): the scene holds the base
  // level only; its coarser levels are nodes the extension names. Load
  // them beside the base so the switch below sees every level.
  const nodes = gltf.parser.json.nodes || [];
  for (const n of nodes) {
    const ids = n.extensions && n.extensions.MSFT_lod && n.extensions.MSFT_lod.ids;
    if (!Array.isArray(ids)) continue;
    for (const id of ids) root.add(await gltf.parser.getDependency('node', id));
  }
  scene.add(root);
  viewer.model = root;
  const meshes = [];
  root.traverse((o) => {
    if (o.isMesh) meshes.push(o);
  });
  const chain = meshes
    .map((m) => ({ mesh: m, n: /_lod(\d+)(?!\d)/i.exec(m.name || (m.parent && m.parent.name) || '') }))
    .filter((e) => e.n);
  const box = new THREE.Box3().setFromObject(root);
  const sphere = box.getBoundingSphere(new THREE.Sphere());
  if (chain.length >= 2 && chain.length === meshes.length) {
    state.kind = 'chain';
    // Finest first; each level's error is its mean edge length.
    const levels = chain
      .map((e) => {
        const g = e.mesh.geometry;
        const tris = triangleCount(g);
        return { mesh: e.mesh, number: Number(e.n[1]), tris, edge: Math.sqrt((4 * surfaceArea(g)) / Math.sqrt(3) / Math.max(tris, 1)) };
      })
      .sort((x, y) => y.tris - x.tris);
    viewer.chain = levels;
    state.levels = levels.length;
    state.lastLevel = Math.max(...levels.map((l) => l.number));
    onFrame = () => {
      const d = Math.max(camera.position.distanceTo(sphere.center) - sphere.radius, sphere.radius * 0.05);
      const pxPerUnit = renderer.domElement.height / (2 * d * Math.tan((camera.fov * Math.PI) / 360) / (camera.zoom || 1));
      // The coarsest level whose edges stay under the tolerance on screen.
      let pick = levels[0];
      for (const l of levels) if (l.edge * pxPerUnit <= state.tolerance * CHAIN_EDGE_PER_PX) pick = l;
      for (const l of levels) l.mesh.visible = l === pick;
      state.level = pick.number;
      state.triangles = pick.tris;
    };
  } else {
    state.kind = 'glb';
    state.triangles = meshes.reduce((s, m) => s + triangleCount(m.geometry), 0);
  }
  setWireframe(root, state.wireframe);
  frameSphere(sphere);
  state.complete = true;
}

async function openPly(url) {
  const { PLYLoader } = await import('three/addons/loaders/PLYLoader.js');
  const g = await new PLYLoader().loadAsync(url, (p) => {
    state.loaded = p.loaded;
    state.total = p.total || state.total;
    hud();
  });
  if (!g.attributes.normal) g.computeVertexNormals();
  const colours = !!g.attributes.color;
  const mat = new THREE.MeshStandardMaterial({ color: colours ? 0xffffff : 0xd8d0c0, vertexColors: colours, roughness: 0.8 });
  const mesh = new THREE.Mesh(g, mat);
  scene.add(mesh);
  viewer.model = mesh;
  state.triangles = triangleCount(g);
  g.computeBoundingSphere();
  frameSphere(g.boundingSphere);
  setWireframe(mesh, state.wireframe);
  state.complete = true;
}

// `fetch(u, options)`, answered by the page's prefetch of `u` when there
// is one not yet used (a GET with no options but the renderer's abort
// signal: the prefetch was made the same way).
function fetchOnce(u, options) {
  const early = window.lodkitPrefetch;
  const href = new URL(u, location.href).href;
  const plain = !options || Object.keys(options).every((k) => k === 'signal');
  if (early && plain && early.has(href)) {
    const r = early.get(href);
    early.delete(href);
    state.prefetched += 1;
    return r.catch(() => fetch(u, options));
  }
  return fetch(u, options);
}

// A 3D Tiles tileset (tileset.json, external tilesets, GLB contents plain
// or with EXT_meshopt_compression + KHR_mesh_quantization) streamed by
// 3DTilesRendererJS: tiles are fetched and swapped as the camera moves,
// until each drawn tile's screen-space error is within the slider's target
// (`errorTarget`, pixels). The tileset's frame is z-up; the scene is y-up,
// so the tiles' group turns by -90° about x.
async function openTileset(url) {
  const tiles = new TilesRenderer(url);
  const gltf = new GLTFLoader(tiles.manager);
  gltf.setMeshoptDecoder(MeshoptDecoder);
  tiles.manager.addHandler(/\.(gltf|glb)$/i, gltf);
  // Counts the bytes of every fetch (JSON and contents) for the HUD; the
  // page's prefetch (index.html) answers the first requests.
  tiles.registerPlugin({
    name: 'LODKIT_BYTE_COUNT',
    fetchData: async (u, options) => {
      const r = await fetchOnce(u, options);
      if (!r.ok) return r;
      const body = await r.arrayBuffer();
      state.tilesetBytes += body.byteLength;
      state.loaded = state.tilesetBytes;
      return new Response(body, { status: r.status, statusText: r.statusText, headers: r.headers });
    },
  });
  tiles.group.rotation.x = -Math.PI / 2;
  // The first frame draws what the root alone shows (one small download,
  // not a link shared by every tile the view wants); refinement to the
  // error target starts once it is on screen.
  let firstDrawn = false;
  tiles.errorTarget = Infinity;
  tiles.setCamera(camera);
  tiles.setResolutionFromRenderer(camera, renderer);
  viewer.tiles = tiles;
  viewer.model = tiles.group;
  viewer.model.isTileset = true;
  scene.add(tiles.group);
  // The root tileset's request goes out now, not at the next frame, and
  // the tiles' shaders compile while it is read.
  tiles.update();
  warmShaders(true);
  const update = () => requestRender();
  for (const ev of ['needs-update', 'needs-render', 'load-model', 'tiles-load-end']) tiles.addEventListener(ev, update);
  tiles.addEventListener('load-model', ({ scene: s }) => setWireframe(s, state.wireframe));
  onFrame = () => {
    tiles.errorTarget = firstDrawn ? state.tolerance : Infinity;
    camera.updateMatrixWorld();
    tiles.setResolutionFromRenderer(camera, renderer);
    tiles.update();
  };
  afterFrame = () => {
    const s = tiles.stats;
    state.tilesLoaded = s.loaded;
    state.tilesVisible = s.visible;
    state.tilesFailed = s.failed;
    state.triangles = renderer.info.render.triangles;
    state.points = renderer.info.render.points;
    // Settled: nothing queued, downloading or parsing and something drawn
    // (`settledFrames` counts such frames in a row).
    if (!firstDrawn && s.visible > 0 && state.triangles + state.points > 0) {
      firstDrawn = true;
      state.firstFrameMs = performance.now();
      firstShown();
      requestRender();
      return;
    }
    const settled = firstDrawn && s.queued + s.downloading + s.parsing === 0 && s.visible > 0;
    state.settledFrames = settled ? state.settledFrames + 1 : 0;
    if (settled) state.complete = true;
    else requestRender();
  };
  await new Promise((resolve, reject) => {
    tiles.addEventListener('load-root-tileset', () => {
      tiles.group.updateMatrixWorld(true);
      const sphere = new THREE.Sphere();
      tiles.getBoundingSphere(sphere);
      sphere.applyMatrix4(tiles.group.matrixWorld);
      viewer.bounds = sphere;
      frameSphere(sphere, Math.PI / 5);
      if (startCamera) viewer.setCamera(startCamera.slice(0, 3), startCamera.slice(3));
      resolve();
    });
    tiles.addEventListener('load-error', ({ tile, error, url: u }) => {
      if (tile) return; // a tile: 3DTilesRendererJS logs it and counts it in stats.failed
      const msg = String(error && error.message ? error.message : error);
      reject(new Error(msg.includes(u) ? msg : `${u}: ${msg}`));
    });
    requestRender();
  });
  // The first tiles: resolved once something is drawn and nothing is in flight.
  await new Promise((resolve) => {
    const poll = () => (state.complete || state.error ? resolve() : setTimeout(poll, 50));
    poll();
  });
}

// Takes the open model off the scene (its worker and buffers freed).
function close() {
  const m = viewer.model;
  if (!m) return;
  scene.remove(m);
  if (m.isTileset) {
    viewer.tiles.dispose();
    viewer.tiles = null;
  } else if (m.isMcoModel) m.dispose();
  else
    m.traverse((o) => {
      if (o.geometry) o.geometry.dispose();
    });
  viewer.model = null;
}

async function open(url, kind) {
  close();
  onFrame = null;
  afterFrame = null;
  // Every figure is about the model being opened, none about the last one.
  Object.assign(state, {
    url,
    kind: kindOf(url, kind),
    loaded: 0,
    total: 0,
    level: -1,
    levels: 0,
    lastLevel: -1,
    precision: -1,
    triangles: 0,
    firstDrawLoaded: -1,
    firstDrawMs: -1,
    firstCutLoaded: -1,
    models: 0,
    maxLod: 0,
    levelsShown: [],
    cuts: 0,
    digest: '',
    complete: false,
    error: '',
    tilesLoaded: 0,
    tilesVisible: 0,
    tilesFailed: 0,
    tilesetBytes: 0,
    settledFrames: 0,
    points: 0,
    firstFrameMs: -1,
    prefetched: 0,
  });
  const t0 = performance.now();
  if (state.kind !== 'tileset')
    headSize(url).then((n) => {
      if (!state.total) state.total = n;
    });
  const openers = { pop: openPop, mco: openMco, glb: openGlb, ply: openPly, tileset: openTileset };
  const opener = openers[state.kind];
  if (!opener) throw new Error(`${url}: cannot show a .${state.kind} file`);
  await opener(url);
  if (state.kind !== 'pop') state.decodeMs = state.decodeMs || performance.now() - t0;
  if (state.firstDrawLoaded < 0) {
    state.firstDrawLoaded = state.loaded;
    state.firstDrawMs = performance.now();
  }
  renderNow();
}

async function listModels() {
  try {
    const r = await fetch('/api/models');
    if (!r.ok || !(r.headers.get('content-type') || '').includes('json')) return [];
    const list = await r.json();
    if (!Array.isArray(list)) return [];
    // A tileset is one entry: the files in its folder (tiles, external
    // tilesets) are opened through it, not one by one.
    const folders = list.filter((m) => m.kind === 'tileset').map((m) => m.name.replace(/[^/]*$/, ''));
    return list.filter((m) => m.kind === 'tileset' || !folders.some((f) => m.name.startsWith(f)));
  } catch {
    return [];
  }
}

function controlsUi() {
  $('tolerance').addEventListener('input', (e) => {
    state.tolerance = Number(e.target.value);
    $('tolerance-value').textContent = `${state.tolerance} px`;
    requestRender();
  });
  $('wireframe').addEventListener('change', (e) => {
    state.wireframe = e.target.checked;
    if (viewer.model) setWireframe(viewer.model, state.wireframe);
    requestRender();
  });
}

// Draws a triangle in each material the first model will use before it
// arrives, so that the model is not kept off the screen by shader
// compilation (a software GL such as SwiftShader also compiles its draw
// routines on the first draw, per vertex format). The .pop/.mco loaders'
// material: plain and with vertex colours, both sides or front only, float
// attributes; waits for the GPU. A tileset's (`tiles`): GLTFLoader's
// default material on lodkit's tiles (KHR_mesh_quantization: 16-bit
// positions, 8-bit normals), compiled without blocking, then drawn without
// waiting, while the page reads the tileset.
function warmShaders(tiles = false) {
  const warm = new THREE.Scene();
  warm.add(...scene.children.filter((o) => o.isLight).map((l) => l.clone()));
  const cam = new THREE.PerspectiveCamera(45, 1, 0.1, 10);
  const variants = tiles
    ? [[THREE.FrontSide, false]]
    : [[THREE.DoubleSide, false], [THREE.DoubleSide, true], [THREE.FrontSide, false], [THREE.FrontSide, true]];
  for (const [side, vertexColors] of variants) {
    const g = new THREE.BufferGeometry();
    if (tiles) {
      g.setAttribute('position', new THREE.Uint16BufferAttribute([0, 0, 0, 1, 0, 0, 0, 1, 0], 3));
      g.setAttribute('normal', new THREE.Int8BufferAttribute([0, 0, 127, 0, 0, 127, 0, 0, 127], 3, true));
      g.setIndex(new THREE.Uint16BufferAttribute([0, 1, 2], 1));
    } else {
      g.setAttribute('position', new THREE.Float32BufferAttribute([0, 0, 0, 1, 0, 0, 0, 1, 0], 3));
      g.setAttribute('normal', new THREE.Float32BufferAttribute([0, 0, 1, 0, 0, 1, 0, 0, 1], 3));
    }
    if (vertexColors) g.setAttribute('color', new THREE.Uint8BufferAttribute([255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255], 4, true));
    const material = tiles
      ? new THREE.MeshStandardMaterial({ color: 0xffffff, metalness: 1, roughness: 1 })
      : new THREE.MeshStandardMaterial({ roughness: 0.8, metalness: 0.0, side, vertexColors });
    const mesh = new THREE.Mesh(g, material);
    mesh.position.z = -2;
    warm.add(mesh);
  }
  const done = () => {
    for (const m of warm.children) if (m.isMesh) m.geometry.dispose();
  };
  if (!tiles) {
    renderer.render(warm, cam);
    renderer.getContext().finish();
    done();
    return;
  }
  renderer.compileAsync(warm, cam).then(() => {
    // Not over a frame that already shows tiles.
    if (state.triangles + state.points === 0) renderer.render(warm, cam);
    done();
    requestRender();
  });
}

// The server's listing in the menu, `url` selected.
function fillMenu(models, url) {
  if (!models.length) return;
  const sel = $('models');
  for (const m of models) {
    const o = document.createElement('option');
    o.value = m.url;
    o.textContent = `${m.name} (${m.kind}, ${fmtBytes(m.bytes)})`;
    sel.appendChild(o);
  }
  $('models-row').hidden = false;
  sel.value = url;
  sel.addEventListener('change', () => {
    location.search = `?model=${encodeURIComponent(sel.value)}`;
  });
}

async function main() {
  resize();
  controlsUi();
  const params = new URLSearchParams(location.search);
  // ?camera=EX,EY,EZ,TX,TY,TZ: a tileset's first view, eye and target in
  // the scene's frame (y up), instead of the framing of the whole model.
  const cam = (params.get('camera') || '').split(',').map(Number);
  if (cam.length === 6 && cam.every(Number.isFinite)) startCamera = cam;
  let url = params.get('model');
  const idle = params.has('idle');
  // ?idle: open nothing (a test opens its model itself).
  const kind = url && !idle ? kindOf(url, params.get('kind')) : '';
  // The decoders and their shaders, where this page streams a .pop or
  // .mco or may open any model (a page that opens another kind never
  // loads them).
  const streams = kind === '' || kind === 'pop' || kind === 'mco';
  const decoding = streams ? loadDecoders() : null;
  if (streams) warmShaders();
  // A named model opens at once; the listing (a long one for a folder of
  // tiles) is fetched once the model is on screen or has failed, so that
  // it shares neither the link nor the page's time with the first frame.
  const listing = url && !idle ? new Promise((resolve) => (onFirstShown = resolve)).then(listModels) : listModels();
  if (url) {
    listing.then((models) => fillMenu(models, url));
  } else {
    const models = await listing;
    if (models.length) url = (models.find((m) => m.kind === 'pop') || models[0]).url;
    fillMenu(models, url);
  }
  if (idle) {
    await listing;
    // Ready means ready to stream: the decoders are in.
    await (await decoding).wasm;
    return;
  }
  if (!url) {
    $('error').textContent = 'No model: open ?model=URL (a .pop, .mco, .glb, .ply or a 3D Tiles tileset.json).';
    return;
  }
  try {
    await open(url, params.get('kind'));
  } finally {
    firstShown();
  }
}

viewer.ready = main().catch((e) => showError(String(e && e.message ? e.message : e)));
