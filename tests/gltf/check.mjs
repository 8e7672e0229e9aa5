// Real glTF loaders on the GLBs lodkit writes (run by scripts/check-gltf.sh).
//
//   node check.mjs validate FILE.glb...      Khronos glTF-Validator: 0 errors,
//                                            0 warnings, no UNUSED_OBJECT info
//                                            on a TEXCOORD attribute
//   node check.mjs chain FILE.glb LEVELS     Babylon.js (NullEngine) loads the
//                                            MSFT_lod chain: LEVELS levels, coarsest
//                                            first, names NAME_LODk, all at level
//                                            0's place; MSFT_screencoverage strictly
//                                            decreasing; three.js GLTFLoader (no
//                                            MSFT_lod) shows level 0 alone
//   node check.mjs scenechain FILE.glb LEVELS  the same for a scene chain (one
//                                            root node NAME_LODk per level over
//                                            that level's meshes): Babylon.js
//                                            loads LEVELS MSFT_lod levels and ends
//                                            showing meshes under NAME_LOD0 only;
//                                            three.js shows level 0's meshes alone
//   node check.mjs load FILE.glb...          three.js GLTFLoader loads each file
//
// Exit 1 with one line per failure.
import { readFileSync } from "node:fs";
import validator from "gltf-validator";

const failures = [];
const fail = (msg) => {
  failures.push(msg);
  console.error(`FAIL ${msg}`);
};

async function validate(files) {
  for (const file of files) {
    const bytes = new Uint8Array(readFileSync(file));
    const report = await validator.validateBytes(bytes, {
      uri: file,
      maxIssues: 1000,
      // Buffers are all inside the GLB; nothing external to fetch.
      externalResourceFunction: () => Promise.reject(new Error("no external resources")),
    });
    const { numErrors, numWarnings, messages } = report.issues;
    const uvUnused = messages.filter(
      (m) => m.code === "UNUSED_OBJECT" && /TEXCOORD/.test(m.pointer ?? ""),
    );
    const line = `${file}: ${numErrors} errors, ${numWarnings} warnings, ${report.issues.numInfos} infos, ${report.issues.numHints} hints`;
    if (numErrors || numWarnings || uvUnused.length) {
      fail(line);
      for (const m of messages.filter((m) => m.severity <= 1 || m.code === "UNUSED_OBJECT")) {
        console.error(`  ${m.code} ${m.pointer ?? ""}: ${m.message}`);
      }
    } else {
      console.log(`ok ${line}`);
    }
  }
}

async function threeScene(file) {
  const THREE = await import("three");
  const { GLTFLoader } = await import("three/examples/jsm/loaders/GLTFLoader.js");
  const { MeshoptDecoder } = await import("three/examples/jsm/libs/meshopt_decoder.module.js");
  const loader = new GLTFLoader();
  loader.setMeshoptDecoder(MeshoptDecoder);
  // Node has no image decoder: textures resolve to an empty THREE.Texture
  // through GLTFLoader's own plugin hook (materials, samplers and texture
  // slots are still parsed by three.js; glTF-Validator checks the images'
  // bytes against their MIME types).
  const textures = { count: 0 };
  loader.register(() => ({
    name: "lodkit_node_textures",
    loadTexture() {
      textures.count++;
      return Promise.resolve(new THREE.Texture());
    },
  }));
  const buf = readFileSync(file);
  const ab = buf.buffer.slice(buf.byteOffset, buf.byteOffset + buf.byteLength);
  const gltf = await new Promise((resolve, reject) => loader.parse(ab, "", resolve, reject));
  const objects = [];
  gltf.scene.updateMatrixWorld(true);
  gltf.scene.traverse((o) => {
    if (o.isMesh || o.isPoints) {
      const box = new THREE.Box3().setFromObject(o);
      const g = o.geometry;
      const n = g.index ? g.index.count : g.attributes.position.count;
      const ancestors = [];
      for (let p = o.parent; p; p = p.parent) ancestors.push(p.name);
      objects.push({ name: o.name, kind: o.isMesh ? "mesh" : "points", elements: n, box, ancestors });
    }
  });
  return objects;
}

async function load(files) {
  for (const file of files) {
    try {
      const objects = await threeScene(file);
      if (objects.length === 0) {
        fail(`${file}: three.js loaded no mesh or points`);
      } else {
        console.log(`ok ${file}: three.js GLTFLoader: ${objects.map((o) => `${o.name} (${o.kind}, ${o.elements})`).join(", ")}`);
      }
    } catch (e) {
      fail(`${file}: three.js GLTFLoader: ${e?.message ?? e}`);
    }
  }
}

async function babylonChain(file) {
  const BABYLON = await import("@babylonjs/core");
  await import("@babylonjs/loaders/glTF/index.js");
  // Babylon fetches its meshopt decoder from a CDN with a <script> tag;
  // in Node it gets the same meshoptimizer decoder from the three package.
  const { MeshoptDecoder } = await import("three/examples/jsm/libs/meshopt_decoder.module.js");
  await MeshoptDecoder.ready;
  BABYLON.MeshoptCompression._Default = {
    decodeGltfBufferAsync: async (source, count, stride, mode, filter) => {
      const out = new Uint8Array(count * stride);
      MeshoptDecoder.decodeGltfBuffer(out, count, stride, source, mode, filter);
      return out;
    },
    dispose() {},
  };
  const engine = new BABYLON.NullEngine();
  const scene = new BABYLON.Scene(engine);
  // Each mesh as it loads (MSFT_lod: coarsest first, each replaced by the
  // next), and how many LOD levels the extension reports loaded.
  const meshes = [];
  let lodsLoaded = 0;
  const done = new Promise((resolve) => {
    const obs = BABYLON.SceneLoader.OnPluginActivatedObservable.add((plugin) => {
      BABYLON.SceneLoader.OnPluginActivatedObservable.remove(obs);
      plugin.onMeshLoadedObservable.add((m) => {
        if (m.name !== "__root__") meshes.push({ name: m.name });
      });
      plugin.onExtensionLoadedObservable.add((ext) => {
        if (ext.name === "MSFT_lod") ext.onNodeLODsLoadedObservable.add(() => lodsLoaded++);
      });
      plugin.onCompleteObservable.add(() => resolve());
    });
  });
  const bytes = new Uint8Array(readFileSync(file));
  await BABYLON.SceneLoader.ImportMeshAsync("", "", bytes, scene, null, ".glb");
  await done;
  const shown = scene.meshes.filter((m) => m.isEnabled() && m.getTotalIndices() > 0);
  const enabled = shown.map((m) => m.name);
  // The names of each shown mesh's ancestors (for scene chains).
  const lineage = shown.map((m) => {
    const names = [];
    for (let p = m.parent; p; p = p.parent) names.push(p.name);
    return names;
  });
  engine.dispose();
  return { meshes, lodsLoaded, enabled, lineage };
}

// The JSON chunk of a GLB.
function glbJson(file) {
  const b = readFileSync(file);
  const len = b.readUInt32LE(12);
  return JSON.parse(b.subarray(20, 20 + len).toString("utf8"));
}

// MSFT_screencoverage on level 0's node: one value per level, in [0, 1],
// strictly decreasing, so that a switch by coverage reaches every level.
function coverages(file, levels) {
  const j = glbJson(file);
  const base = j.nodes[j.scenes[j.scene ?? 0].nodes[0]];
  const c = base?.extras?.MSFT_screencoverage;
  if (!Array.isArray(c) || c.length !== levels) {
    fail(`${file}: MSFT_screencoverage ${JSON.stringify(c)}: expected ${levels} values`);
    return;
  }
  const bad = c.findIndex((x, k) => !(x >= 0 && x <= 1) || (k > 0 && !(x < c[k - 1])));
  if (bad >= 0) {
    fail(`${file}: MSFT_screencoverage ${JSON.stringify(c)}: value ${bad} is not in [0, 1] below the one before, so a switch by coverage never shows level ${bad}`);
  } else {
    console.log(`ok ${file}: MSFT_screencoverage strictly decreasing: ${c.join(", ")}`);
  }
}

async function chain(file, levels) {
  coverages(file, levels);
  // Babylon: MSFT_lod levels arrive coarsest first, each replacing the last.
  try {
    const { meshes, lodsLoaded, enabled } = await babylonChain(file);
    const names = meshes.map((m) => m.name);
    if (lodsLoaded !== levels || meshes.length !== levels) {
      fail(`${file}: Babylon.js loaded ${lodsLoaded} MSFT_lod levels and ${meshes.length} meshes, expected ${levels} (${names.join(", ")})`);
    }
    meshes.forEach((m, k) => {
      const want = `_LOD${levels - 1 - k}`;
      if (!m.name.endsWith(want)) fail(`${file}: Babylon.js LOD ${k} is ${m.name}, expected *${want}`);
    });
    if (enabled.length !== 1 || !enabled[0].endsWith("_LOD0")) {
      fail(`${file}: Babylon.js ends showing ${enabled.join(", ")}, expected level 0 alone`);
    }
    console.log(`ok ${file}: Babylon.js MSFT_lod loaded ${lodsLoaded} levels: ${names.join(" -> ")}, then shows ${enabled.join(", ")}`);
  } catch (e) {
    fail(`${file}: Babylon.js: ${e?.stack ?? e}`);
  }
  // three.js: no MSFT_lod, so level 0 alone.
  try {
    const objects = await threeScene(file);
    if (objects.length !== 1 || !objects[0].name.endsWith("_LOD0")) {
      fail(`${file}: three.js shows ${objects.map((o) => o.name).join(", ")}, expected level 0 alone`);
    } else {
      console.log(`ok ${file}: three.js GLTFLoader shows ${objects[0].name} alone (${objects[0].elements / 3} triangles)`);
    }
  } catch (e) {
    fail(`${file}: three.js GLTFLoader: ${e?.message ?? e}`);
  }
}

async function sceneChain(file, levels) {
  coverages(file, levels);
  const under0 = (names) => names.some((n) => n.endsWith("_LOD0"));
  try {
    const { meshes, lodsLoaded, enabled, lineage } = await babylonChain(file);
    if (lodsLoaded !== levels) {
      fail(`${file}: Babylon.js loaded ${lodsLoaded} MSFT_lod levels, expected ${levels}`);
    }
    if (enabled.length === 0 || !lineage.every(under0)) {
      fail(`${file}: Babylon.js ends showing ${enabled.join(", ")}, expected level 0's meshes alone`);
    }
    console.log(`ok ${file}: Babylon.js MSFT_lod loaded ${lodsLoaded} levels (${meshes.length} meshes), then shows ${enabled.length} meshes under *_LOD0`);
  } catch (e) {
    fail(`${file}: Babylon.js: ${e?.stack ?? e}`);
  }
  try {
    const objects = await threeScene(file);
    if (objects.length === 0 || !objects.every((o) => under0(o.ancestors))) {
      fail(`${file}: three.js shows ${objects.map((o) => `${o.name} under ${o.ancestors.join("/")}`).join(", ")}, expected level 0 alone`);
    } else {
      console.log(`ok ${file}: three.js GLTFLoader shows level 0 alone (${objects.length} meshes)`);
    }
  } catch (e) {
    fail(`${file}: three.js GLTFLoader: ${e?.message ?? e}`);
  }
}

const [cmd, ...args] = process.argv.slice(2);
if (cmd === "validate") await validate(args);
else if (cmd === "load") await load(args);
else if (cmd === "chain") await chain(args[0], Number(args[1]));
else if (cmd === "scenechain") await sceneChain(args[0], Number(args[1]));
else {
  console.error("usage: node check.mjs validate|load FILE... | chain|scenechain FILE LEVELS");
  process.exit(2);
}
process.exit(failures.length ? 1 : 0);
