// Writes a small, valid 3D Tiles 1.1 tileset of the shipped Stanford bunny
// from GLBs that lodkit writes, for the client tests until `lodkit tiles`
// makes them (scripts/ci-tiles.sh uses `lodkit tiles` when it has it).
//
//   node web/tests/make_fixture_tileset.mjs LODKIT OUT_DIR
//
// OUT_DIR/plain/tileset.json     plain GLBs (float positions, normals)
// OUT_DIR/meshopt/tileset.json   the same tiles with KHR_mesh_quantization +
//                                EXT_meshopt_compression, positions on one grid
//                                shared by every tile (meshoptimizer's encoder,
//                                from web/tests/tiles/node_modules; left out
//                                when that is not installed)
// OUT_DIR/points/tileset.json    a point cloud (40,000 points on a bumpy unit
//                                sphere, normals and colours): glTF POINTS tiles,
//                                ADD refinement (a root of every 8th point, then
//                                the rest by octant), `lodkit convert` of each
//
// The hierarchy (REPLACE refinement throughout):
//   root           the whole bunny simplified to 2 % (`lodkit simplify`)
//   └ 8 octants    the input's triangles split by centroid at the box centre,
//                  full resolution (`lodkit convert` of each piece)
//     └ the largest octant is an external tileset (ext/tileset.json):
//         its root is that piece simplified to a quarter (borders locked,
//         so it meets its neighbours), its two children the piece's halves.
// Each geometricError is the symmetric Hausdorff distance `lodkit compare`
// measures between a tile and the input it stands for (0 at full
// resolution); the tileset's is the bunny's box diagonal.
//
// Frames: glTF content is y-up; the tileset (bounding volumes) is z-up, so
// a content point (x, y, z) sits at (x, -z, y) in the tileset's frame.
// Same inputs give the same bytes.

import fs from 'node:fs';
import path from 'node:path';
import { execFileSync } from 'node:child_process';
import { fileURLToPath, pathToFileURL } from 'node:url';

const [lodkit, outArg] = process.argv.slice(2);
if (!lodkit || !outArg) {
  console.error('usage: make_fixture_tileset.mjs LODKIT OUT_DIR');
  process.exit(2);
}
const here = path.dirname(fileURLToPath(import.meta.url));
const root = path.resolve(here, '../..');
const meshoptFile = path.join(here, 'tiles/node_modules/meshoptimizer/index.js');
const meshopt = fs.existsSync(meshoptFile) ? pathToFileURL(meshoptFile).href : null;
const bunny = path.join(root, 'data/models/stanford_bunny.ply');
const out = path.resolve(outArg);
const tmp = `${out}.tmp`;
fs.rmSync(tmp, { recursive: true, force: true });
fs.mkdirSync(path.join(tmp, 'work'), { recursive: true });
const work = path.join(tmp, 'work');

const run = (...args) => execFileSync(lodkit, ['-q', ...args], { stdio: ['ignore', 'pipe', 'inherit'] }).toString();

// --- the GLB lodkit writes, read back: positions, normals, triangles ---
function readGlb(file) {
  const b = fs.readFileSync(file);
  if (b.readUInt32LE(0) !== 0x46546c67) throw new Error(`${file}: not a GLB`);
  const jsonLen = b.readUInt32LE(12);
  const json = JSON.parse(b.subarray(20, 20 + jsonLen).toString('utf8'));
  const binStart = 20 + jsonLen + 8;
  const view = (acc) => {
    const a = json.accessors[acc];
    const bv = json.bufferViews[a.bufferView];
    const off = binStart + (bv.byteOffset || 0) + (a.byteOffset || 0);
    const comps = { SCALAR: 1, VEC3: 3 }[a.type];
    const n = a.count * comps;
    const copy = (T, size) => new T(b.buffer.slice(b.byteOffset + off, b.byteOffset + off + n * size));
    if (a.componentType === 5126) return copy(Float32Array, 4);
    if (a.componentType === 5125) return copy(Uint32Array, 4);
    if (a.componentType === 5123) return Uint32Array.from(copy(Uint16Array, 2));
    throw new Error(`${file}: component type ${a.componentType}`);
  };
  const prim = json.meshes[0].primitives[0];
  return { pos: view(prim.attributes.POSITION), nrm: view(prim.attributes.NORMAL), idx: view(prim.indices) };
}

// A subset of the triangles as a binary PLY with normals (vertices compacted).
function writePly(file, mesh, tris) {
  const remap = new Map();
  const verts = [];
  const faces = new Uint32Array(tris.length * 3);
  tris.forEach((t, i) => {
    for (let k = 0; k < 3; k++) {
      const v = mesh.idx[3 * t + k];
      if (!remap.has(v)) {
        remap.set(v, verts.length);
        verts.push(v);
      }
      faces[3 * i + k] = remap.get(v);
    }
  });
  const header = `ply\nformat binary_little_endian 1.0\nelement vertex ${verts.length}\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nelement face ${tris.length}\nproperty list uchar int vertex_indices\nend_header\n`;
  const body = Buffer.alloc(verts.length * 24 + tris.length * 13);
  let o = 0;
  for (const v of verts) {
    for (let k = 0; k < 3; k++, o += 4) body.writeFloatLE(mesh.pos[3 * v + k], o);
    for (let k = 0; k < 3; k++, o += 4) body.writeFloatLE(mesh.nrm[3 * v + k], o);
  }
  for (let i = 0; i < tris.length; i++) {
    body.writeUInt8(3, o++);
    for (let k = 0; k < 3; k++, o += 4) body.writeInt32LE(faces[3 * i + k], o);
  }
  fs.writeFileSync(file, Buffer.concat([Buffer.from(header), body]));
}

// Box of some triangles' vertices (glTF frame).
function bounds(mesh, tris) {
  const lo = [Infinity, Infinity, Infinity];
  const hi = [-Infinity, -Infinity, -Infinity];
  for (const t of tris) {
    for (let k = 0; k < 3; k++) {
      const v = mesh.idx[3 * t + k];
      for (let c = 0; c < 3; c++) {
        lo[c] = Math.min(lo[c], mesh.pos[3 * v + c]);
        hi[c] = Math.max(hi[c], mesh.pos[3 * v + c]);
      }
    }
  }
  return { lo, hi };
}

// A 3D Tiles box in the z-up tileset frame from a y-up glTF box: (x, y, z) -> (x, -z, y).
const r6 = (x) => Math.round(x * 1e6) / 1e6;
function box({ lo, hi }) {
  const c = [0, 1, 2].map((i) => (lo[i] + hi[i]) / 2);
  const h = [0, 1, 2].map((i) => (hi[i] - lo[i]) / 2 + 1e-5);
  return { box: [c[0], -c[2], c[1], h[0], 0, 0, 0, h[2], 0, 0, 0, h[1]].map(r6) };
}

// The union of two boxes: a tile's volume holds its own content (a
// simplified level's vertices can move past the input's box) and its
// children's.
function union(a, b) {
  return { lo: a.lo.map((v, i) => Math.min(v, b.lo[i])), hi: a.hi.map((v, i) => Math.max(v, b.hi[i])) };
}
const glbBounds = (file) => {
  const m = readGlb(file);
  return bounds(m, Array.from({ length: m.idx.length / 3 }, (_, t) => t));
};

// One tile as a GLB with KHR_mesh_quantization + EXT_meshopt_compression:
// positions (x, y, z, pad) uint16 on the shared grid `origin + q * step`,
// normals octahedral int8, indices uint32.
function packGlb(enc, mesh, origin, step) {
  const n = mesh.pos.length / 3;
  const m = mesh.idx.length;
  const q = new Uint16Array(n * 4);
  const lo = [65535, 65535, 65535];
  const hi = [0, 0, 0];
  for (let v = 0; v < n; v++) {
    for (let c = 0; c < 3; c++) {
      const x = Math.min(65535, Math.max(0, Math.round((mesh.pos[3 * v + c] - origin[c]) / step)));
      q[4 * v + c] = x;
      lo[c] = Math.min(lo[c], x);
      hi[c] = Math.max(hi[c], x);
    }
  }
  const nrm = new Float32Array(n * 4);
  for (let v = 0; v < n; v++) for (let c = 0; c < 3; c++) nrm[4 * v + c] = mesh.nrm[3 * v + c];
  const views = [
    { raw: new Uint8Array(q.buffer), count: n, stride: 8, mode: 'ATTRIBUTES', target: 34962 },
    { raw: enc.encodeFilterOct(nrm, n, 4, 8), count: n, stride: 4, mode: 'ATTRIBUTES', target: 34962, filter: 'OCTAHEDRAL' },
    { raw: new Uint8Array(Uint32Array.from(mesh.idx).buffer), count: m, stride: 4, mode: 'TRIANGLES', target: 34963 },
  ];
  const pad4 = (x) => (x + 3) & ~3;
  let binLen = 0;
  let fallbackLen = 0;
  const chunks = [];
  const bufferViews = views.map((v) => {
    const data = enc.encodeGltfBuffer(v.raw, v.count, v.stride, v.mode, 0);
    const ext = { buffer: 0, byteOffset: binLen, byteLength: data.length, byteStride: v.stride, count: v.count, mode: v.mode };
    if (v.filter) ext.filter = v.filter;
    chunks.push({ at: binLen, data });
    binLen = pad4(binLen + data.length);
    const bv = { buffer: 1, byteOffset: fallbackLen, byteLength: v.raw.length, target: v.target, extensions: { EXT_meshopt_compression: ext } };
    if (v.mode === 'ATTRIBUTES') bv.byteStride = v.stride;
    fallbackLen = pad4(fallbackLen + v.raw.length);
    return bv;
  });
  const json = {
    asset: { version: '2.0', generator: 'lodkit web/tests/make_fixture_tileset.mjs' },
    extensionsUsed: ['KHR_mesh_quantization', 'EXT_meshopt_compression'],
    extensionsRequired: ['KHR_mesh_quantization', 'EXT_meshopt_compression'],
    buffers: [{ byteLength: binLen }, { byteLength: fallbackLen, extensions: { EXT_meshopt_compression: { fallback: true } } }],
    bufferViews,
    accessors: [
      { bufferView: 0, componentType: 5123, count: n, type: 'VEC3', min: lo, max: hi },
      { bufferView: 1, componentType: 5120, normalized: true, count: n, type: 'VEC3' },
      { bufferView: 2, componentType: 5125, count: m, type: 'SCALAR' },
    ],
    meshes: [{ primitives: [{ attributes: { POSITION: 0, NORMAL: 1 }, indices: 2 }] }],
    nodes: [{ mesh: 0, translation: origin, scale: [step, step, step] }],
    scenes: [{ nodes: [0] }],
    scene: 0,
  };
  let jsonBytes = Buffer.from(JSON.stringify(json));
  jsonBytes = Buffer.concat([jsonBytes, Buffer.alloc(pad4(jsonBytes.length) - jsonBytes.length, 0x20)]);
  const bin = Buffer.alloc(binLen);
  for (const c of chunks) bin.set(c.data, c.at);
  const header = Buffer.alloc(12);
  header.writeUInt32LE(0x46546c67, 0);
  header.writeUInt32LE(2, 4);
  header.writeUInt32LE(12 + 8 + jsonBytes.length + 8 + bin.length, 8);
  const chunk = (type, body) => {
    const h = Buffer.alloc(8);
    h.writeUInt32LE(body.length, 0);
    h.writeUInt32LE(type, 4);
    return Buffer.concat([h, body]);
  };
  return Buffer.concat([header, chunk(0x4e4f534a, jsonBytes), chunk(0x004e4942, bin)]);
}

function centroid(mesh, t, c) {
  let s = 0;
  for (let k = 0; k < 3; k++) s += mesh.pos[3 * mesh.idx[3 * t + k] + c];
  return s / 3;
}

// Symmetric Hausdorff distance lodkit measures between two meshes.
function hausdorff(a, b) {
  const r = JSON.parse(execFileSync(lodkit, ['-q', 'compare', a, b, '--samples', '20000', '--json']).toString());
  return r6(Math.max(r.a_to_b.max, r.b_to_a.max) * 1.0001 + 1e-6);
}

// --- the tiles ---
run('convert', bunny, path.join(work, 'full.glb'));
const mesh = readGlb(path.join(work, 'full.glb'));
const all = Array.from({ length: mesh.idx.length / 3 }, (_, t) => t);
const whole = bounds(mesh, all);
const mid = [0, 1, 2].map((i) => (whole.lo[i] + whole.hi[i]) / 2);

const tiles = path.join(work, 'tiles');
fs.mkdirSync(path.join(tiles, 'ext'), { recursive: true });
run('simplify', bunny, '-o', path.join(tiles, 'root.glb'), '--ratio', '0.02');
const rootError = hausdorff(bunny, path.join(tiles, 'root.glb'));

const octants = Array.from({ length: 8 }, () => []);
for (const t of all) {
  let o = 0;
  for (let c = 0; c < 3; c++) if (centroid(mesh, t, c) >= mid[c]) o |= 1 << c;
  octants[o].push(t);
}
const pieces = octants.map((tris, o) => ({ o, tris })).filter((p) => p.tris.length > 0);
const largest = pieces.reduce((a, p) => (p.tris.length > a.tris.length ? p : a));
const children = [];
for (const p of pieces) {
  const name = `octant${p.o}`;
  const ply = path.join(work, `${name}.ply`);
  writePly(ply, mesh, p.tris);
  if (p !== largest) {
    run('convert', ply, path.join(tiles, `${name}.glb`));
    children.push({ boundingVolume: box(bounds(mesh, p.tris)), geometricError: 0, content: { uri: `${name}.glb` } });
    continue;
  }
  // The external tileset: the piece at a quarter, refined into its halves.
  const coarse = path.join(tiles, 'ext', `${name}_quarter.glb`);
  run('simplify', ply, '-o', coarse, '--ratio', '0.25', '--lock-border');
  const extError = hausdorff(ply, coarse);
  const b = bounds(mesh, p.tris);
  const axis = [0, 1, 2].reduce((a, c) => (b.hi[c] - b.lo[c] > b.hi[a] - b.lo[a] ? c : a), 0);
  const cut = (b.lo[axis] + b.hi[axis]) / 2;
  const halves = [p.tris.filter((t) => centroid(mesh, t, axis) < cut), p.tris.filter((t) => centroid(mesh, t, axis) >= cut)];
  const extChildren = halves.map((h, i) => {
    const hp = path.join(work, `${name}_half${i}.ply`);
    writePly(hp, mesh, h);
    run('convert', hp, path.join(tiles, 'ext', `${name}_half${i}.glb`));
    return { boundingVolume: box(bounds(mesh, h)), geometricError: 0, content: { uri: `${name}_half${i}.glb` } };
  });
  const ext = {
    asset: { version: '1.1', generator: 'lodkit web/tests/make_fixture_tileset.mjs' },
    geometricError: extError,
    root: { boundingVolume: box(union(b, glbBounds(coarse))), geometricError: extError, refine: 'REPLACE', content: { uri: `${name}_quarter.glb` }, children: extChildren },
  };
  fs.writeFileSync(path.join(tiles, 'ext', 'tileset.json'), JSON.stringify(ext, null, 1) + '\n');
  children.push({ boundingVolume: box(union(b, glbBounds(coarse))), geometricError: extError, content: { uri: 'ext/tileset.json' } });
}
const tileset = {
  asset: { version: '1.1', generator: 'lodkit web/tests/make_fixture_tileset.mjs', tilesetVersion: 'fixture' },
  geometricError: r6(Math.hypot(...[0, 1, 2].map((i) => whole.hi[i] - whole.lo[i]))),
  root: { boundingVolume: box(union(whole, glbBounds(path.join(tiles, 'root.glb')))), geometricError: rootError, refine: 'REPLACE', content: { uri: 'root.glb' }, children },
};
fs.writeFileSync(path.join(tiles, 'tileset.json'), JSON.stringify(tileset, null, 1) + '\n');
fs.renameSync(tiles, path.join(tmp, 'plain'));

// --- a point cloud: POINTS tiles, ADD refinement ---
{
  const n = 40000;
  const pts = [];
  for (let i = 0; i < n; i++) {
    const z = 1 - (2 * (i + 0.5)) / n;
    const r = Math.sqrt(1 - z * z);
    const a = i * 2.399963229728653;
    const x = r * Math.cos(a);
    const y = r * Math.sin(a);
    const s = 1 + 0.08 * Math.sin(5 * x) * Math.sin(4 * y) * Math.sin(3 * z);
    pts.push({ p: [x * s, y * s, z * s], n: [x, y, z], c: [x, y, z].map((v) => Math.round(40 + (200 * (v + 1)) / 2)) });
  }
  const dir = path.join(tmp, 'points');
  fs.mkdirSync(dir);
  const cloudTile = (name, list) => {
    const ply = path.join(work, `${name}.ply`);
    const lines = list.map((q) => `${q.p.map((v) => v.toFixed(6)).join(' ')} ${q.n.map((v) => v.toFixed(6)).join(' ')} ${q.c.join(' ')}`);
    fs.writeFileSync(ply, `ply\nformat ascii 1.0\nelement vertex ${list.length}\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n${lines.join('\n')}\n`);
    run('convert', ply, path.join(dir, `${name}.glb`));
    const lo = [0, 1, 2].map((c) => Math.min(...list.map((q) => q.p[c])));
    const hi = [0, 1, 2].map((c) => Math.max(...list.map((q) => q.p[c])));
    return { boundingVolume: box({ lo, hi }), content: { uri: `${name}.glb` } };
  };
  const rootTile = cloudTile('root', pts.filter((_, i) => i % 8 === 0));
  const rest = pts.filter((_, i) => i % 8 !== 0);
  const kids = [];
  for (let o = 0; o < 8; o++) {
    const part = rest.filter((q) => [0, 1, 2].every((c) => (q.p[c] >= 0) === Boolean(o & (1 << c))));
    if (part.length) kids.push({ ...cloudTile(`octant${o}`, part), geometricError: 0 });
  }
  // The root's points are about 8x sparser: its error is their spacing.
  const spacing = r6(Math.sqrt((4 * Math.PI) / (n / 8)));
  const cloud = {
    asset: { version: '1.1', generator: 'lodkit web/tests/make_fixture_tileset.mjs', tilesetVersion: 'fixture' },
    geometricError: 2,
    root: { ...rootTile, geometricError: spacing, refine: 'ADD', children: kids },
  };
  fs.writeFileSync(path.join(dir, 'tileset.json'), JSON.stringify(cloud, null, 1) + '\n');
}

// --- the compressed variant: the same tiles quantised on ONE grid ---
// Positions as uint16 on a grid shared by every tile of the tileset (a node
// transform maps them back to metres), so that vertices on a border
// between tiles stay equal; quantising each tile on its own grid (as
// gltfpack -cc does per file) opens pinholes along tile borders in both
// clients. Normals octahedral (int8, meshopt's OCTAHEDRAL filter); every
// buffer view EXT_meshopt_compression (codec version 0), with a fallback
// buffer of the decoded size and no bytes.
if (meshopt) {
  const { MeshoptEncoder } = await import(meshopt);
  await MeshoptEncoder.ready;
  const plain = path.join(tmp, 'plain');
  const packed = path.join(tmp, 'meshopt');
  const files = walk(plain);
  const glbs = files.filter((f) => f.endsWith('.glb'));
  let grid = null;
  for (const rel of glbs) {
    const b = glbBounds(path.join(plain, rel));
    grid = grid ? union(grid, b) : b;
  }
  const origin = grid.lo;
  const step = Math.max(...[0, 1, 2].map((i) => grid.hi[i] - grid.lo[i])) / 65535;
  for (const rel of files) {
    const to = path.join(packed, rel);
    fs.mkdirSync(path.dirname(to), { recursive: true });
    if (rel.endsWith('.glb')) fs.writeFileSync(to, packGlb(MeshoptEncoder, readGlb(path.join(plain, rel)), origin, step));
    else fs.copyFileSync(path.join(plain, rel), to);
  }
}
fs.rmSync(work, { recursive: true, force: true });
fs.rmSync(out, { recursive: true, force: true });
fs.renameSync(tmp, out);
const count = walk(path.join(out, 'plain')).filter((f) => f.endsWith('.glb')).length;
console.log(`fixture tileset: ${count} tiles, root error ${rootError}, in ${out}/plain${meshopt ? `, ${out}/meshopt` : ''} and ${out}/points`);

function walk(dir, rel = '') {
  const outList = [];
  for (const e of fs.readdirSync(path.join(dir, rel), { withFileTypes: true }).sort((a, b) => (a.name < b.name ? -1 : 1))) {
    const r = path.join(rel, e.name);
    if (e.isDirectory()) outList.push(...walk(dir, r));
    else outList.push(r);
  }
  return outList;
}
