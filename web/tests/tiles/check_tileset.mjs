// Checks a 3D Tiles tileset as its clients read it:
//   node web/tests/tiles/check_tileset.mjs DIR/tileset.json [...]
// Walks tileset.json and every external tileset it names, and checks
//   - the JSON: asset.version 1.0 or 1.1 (3DTilesRendererJS throws without
//     one), a geometricError >= 0 on the tileset and every tile, no child's
//     above its parent's, a box/sphere/region bounding volume on every tile,
//     refine REPLACE or ADD, every content URI relative and inside the
//     tileset's folder (symlinks resolved), no external tileset named twice;
//   - every GLB content with the Khronos glTF-Validator: 0 errors, 0
//     warnings; its extensionsRequired within what both clients decode
//     (CesiumJS refuses others); NORMAL on every triangle primitive
//     (CesiumJS draws a primitive without normals unlit); its positions
//     (node transforms applied, y-up turned to the tileset's z-up) inside
//     its tile's bounding box or sphere.
// Prints one line per tileset (tiles, contents, bytes) and one per failure;
// exit 1 on any failure.

import fs from 'node:fs';
import path from 'node:path';
import validator from 'gltf-validator';

const KNOWN_GLTF_REQUIRED = new Set(['KHR_mesh_quantization', 'EXT_meshopt_compression', 'KHR_meshopt_compression', 'KHR_materials_unlit', 'KHR_texture_transform']);
const MAX_TILES = 1_000_000; // a bound on the walk
const MAX_JSON_BYTES = 64 << 20;

const files = process.argv.slice(2);
if (files.length === 0) {
  console.error('usage: check_tileset.mjs DIR/tileset.json [...]');
  process.exit(2);
}
let failures = 0;
const fail = (msg) => {
  failures++;
  console.error(`FAIL ${msg}`);
};


async function checkTileset(top) {
  const rootDir = fs.realpathSync(path.dirname(top));
  const stats = { tilesets: 0, tiles: 0, contents: 0, bytes: 0, triangles: 0, points: 0 };
  const seen = new Set();
  const pending = [{ file: top, parentError: Infinity, where: path.basename(top) }];
  while (pending.length) {
    const { file, parentError, where } = pending.shift();
    const real = inside(rootDir, file, where);
    if (!real) continue;
    if (seen.has(real)) {
      fail(`${where}: external tileset named twice (a loop?)`);
      continue;
    }
    seen.add(real);
    stats.tilesets++;
    const size = fs.statSync(real).size;
    if (size > MAX_JSON_BYTES) {
      fail(`${where}: ${size} bytes of JSON`);
      continue;
    }
    stats.bytes += size;
    let ts;
    try {
      ts = JSON.parse(fs.readFileSync(real, 'utf8'));
    } catch (e) {
      fail(`${where}: ${e.message}`);
      continue;
    }
    const version = ts.asset && ts.asset.version;
    if (version !== '1.0' && version !== '1.1') fail(`${where}: asset.version ${JSON.stringify(version)}, not "1.0" or "1.1"`);
    if (!(ts.geometricError >= 0)) fail(`${where}: tileset geometricError ${ts.geometricError}`);
    for (const ext of ts.extensionsRequired || []) fail(`${where}: extensionsRequired ${ext} (CesiumJS refuses unknown ones)`);
    if (!ts.root) {
      fail(`${where}: no root tile`);
      continue;
    }
    const stack = [{ tile: ts.root, ptr: 'root', parentError: Math.min(parentError, ts.geometricError) }];
    while (stack.length) {
      const { tile, ptr, parentError: pe } = stack.pop();
      if (++stats.tiles > MAX_TILES) {
        fail(`${where}: more than ${MAX_TILES} tiles`);
        return;
      }
      const at = `${where} ${ptr}`;
      if (!(tile.geometricError >= 0)) fail(`${at}: geometricError ${tile.geometricError}`);
      else if (tile.geometricError > pe * (1 + 1e-9)) fail(`${at}: geometricError ${tile.geometricError} above its parent's ${pe}`);
      const bv = tile.boundingVolume || {};
      const okBv = (Array.isArray(bv.box) && bv.box.length === 12) || (Array.isArray(bv.sphere) && bv.sphere.length === 4) || (Array.isArray(bv.region) && bv.region.length === 6);
      if (!okBv || ![bv.box, bv.sphere, bv.region].flat().filter((x) => x !== undefined).every(Number.isFinite)) fail(`${at}: bounding volume ${JSON.stringify(bv)}`);
      if (tile.refine !== undefined && tile.refine !== 'REPLACE' && tile.refine !== 'ADD') fail(`${at}: refine ${JSON.stringify(tile.refine)}`);
      if (ptr === 'root' && tile.refine === undefined && where === path.basename(top)) fail(`${at}: the root tile has no refine`);
      const contents = tile.contents || (tile.content ? [tile.content] : []);
      for (const c of contents) {
        const uri = c.uri || c.url;
        if (typeof uri !== 'string' || /^[a-z][a-z0-9+.-]*:/i.test(uri) || uri.startsWith('/')) {
          fail(`${at}: content URI ${JSON.stringify(uri)} is not a relative path`);
          continue;
        }
        const target = path.resolve(path.dirname(real), decodeURIComponent(uri.split(/[?#]/)[0]));
        const name = path.relative(rootDir, target);
        if (/\.json$/i.test(uri)) {
          pending.push({ file: target, parentError: tile.geometricError, where: name });
        } else {
          const realContent = inside(rootDir, target, `${at} content ${uri}`);
          if (realContent) await checkContent(realContent, name, stats, bv);
        }
      }
      (tile.children || []).forEach((child, i) => stack.push({ tile: child, ptr: `${ptr}.children[${i}]`, parentError: tile.geometricError }));
    }
  }
  console.log(`${path.relative(process.cwd(), top)}: ${stats.tilesets} tileset files, ${stats.tiles} tiles, ${stats.contents} contents, ${stats.triangles} triangles, ${stats.points} points, ${stats.bytes} bytes`);
}

// The real path of `file` when it exists inside `rootDir`; else a failure.
function inside(rootDir, file, where) {
  let real;
  try {
    real = fs.realpathSync(file);
  } catch {
    fail(`${where}: ${file} does not exist`);
    return null;
  }
  if (!real.startsWith(rootDir + path.sep)) {
    fail(`${where}: ${file} is outside the tileset's folder ${rootDir}`);
    return null;
  }
  return real;
}

async function checkContent(file, name, stats, bv) {
  const bytes = new Uint8Array(fs.readFileSync(file));
  stats.contents++;
  stats.bytes += bytes.length;
  if (!/\.glb$/i.test(file)) {
    fail(`${name}: content is not a GLB`);
    return;
  }
  const report = await validator.validateBytes(bytes, {
    uri: name,
    maxIssues: 100,
    externalResourceFunction: () => Promise.reject(new Error('a tile holds its own buffers and images')),
  });
  const { numErrors, numWarnings, messages } = report.issues;
  if (numErrors || numWarnings) {
    fail(`${name}: glTF-Validator: ${numErrors} errors, ${numWarnings} warnings`);
    for (const m of messages.filter((m) => m.severity <= 1).slice(0, 10)) console.error(`  ${m.code} ${m.pointer ?? ''}: ${m.message}`);
  }
  const info = report.info || {};
  for (const ext of info.extensionsRequired || []) {
    if (!KNOWN_GLTF_REQUIRED.has(ext)) fail(`${name}: requires ${ext}, which the clients do not decode`);
  }
  stats.triangles += info.totalTriangleCount || 0;
  // NORMAL on triangle primitives, from the GLB's JSON chunk.
  const dv = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  if (bytes.length < 20 || dv.getUint32(0, true) !== 0x46546c67) return; // the validator has said why
  const len = dv.getUint32(12, true);
  let json;
  try {
    json = JSON.parse(new TextDecoder().decode(bytes.subarray(20, 20 + len)));
  } catch {
    return;
  }
  (json.meshes || []).forEach((m, i) =>
    (m.primitives || []).forEach((p, j) => {
      const mode = p.mode === undefined ? 4 : p.mode;
      if (mode >= 4 && !(p.attributes && p.attributes.NORMAL !== undefined)) fail(`${name}: meshes[${i}].primitives[${j}] has triangles and no NORMAL`);
      const position = p.attributes && json.accessors && json.accessors[p.attributes.POSITION];
      if (mode === 0 && position) stats.points += position.count || 0;
    }),
  );
  const outside = contentOutside(json, bv);
  if (outside) fail(`${name}: content reaches past its tile's bounding volume: ${outside}`);
}

// --- content against its tile's bounding volume ---
// Both are in the tile's frame: the glTF scene (its node transforms
// applied to each POSITION accessor's min/max box) turned from y-up to
// z-up, (x, y, z) -> (x, -z, y). Both clients cull a tile by its volume,
// so content outside it vanishes or pops; a content in the wrong frame
// (left y-up, say) is caught here. Returns a description, or null.
const EPS = 1e-4; // of the volume's size

function mat(node) {
  if (Array.isArray(node.matrix) && node.matrix.length === 16) return node.matrix.slice();
  const [tx, ty, tz] = node.translation || [0, 0, 0];
  const [qx, qy, qz, qw] = node.rotation || [0, 0, 0, 1];
  const [sx, sy, sz] = node.scale || [1, 1, 1];
  // Column-major T * R * S.
  return [
    (1 - 2 * (qy * qy + qz * qz)) * sx, 2 * (qx * qy + qz * qw) * sx, 2 * (qx * qz - qy * qw) * sx, 0,
    2 * (qx * qy - qz * qw) * sy, (1 - 2 * (qx * qx + qz * qz)) * sy, 2 * (qy * qz + qx * qw) * sy, 0,
    2 * (qx * qz + qy * qw) * sz, 2 * (qy * qz - qx * qw) * sz, (1 - 2 * (qx * qx + qy * qy)) * sz, 0,
    tx, ty, tz, 1,
  ];
}
function mul(a, b) {
  const o = new Array(16).fill(0);
  for (let c = 0; c < 4; c++) for (let r = 0; r < 4; r++) for (let k = 0; k < 4; k++) o[c * 4 + r] += a[k * 4 + r] * b[c * 4 + k];
  return o;
}
const apply = (m, [x, y, z]) => [0, 1, 2].map((r) => m[r] * x + m[4 + r] * y + m[8 + r] * z + m[12 + r]);
// The largest value of a normalized integer component type.
const NORM = { 5120: 127, 5121: 255, 5122: 32767, 5123: 65535 };

function contentOutside(json, bv) {
  const corners = [];
  const visit = (i, parent, depth) => {
    const node = (json.nodes || [])[i];
    if (!node || depth > 64) return;
    const m = mul(parent, mat(node));
    const mesh = node.mesh !== undefined && (json.meshes || [])[node.mesh];
    for (const p of (mesh && mesh.primitives) || []) {
      const a = json.accessors && json.accessors[p.attributes && p.attributes.POSITION];
      if (!a || !a.min || !a.max) continue;
      const k = a.normalized ? NORM[a.componentType] || 1 : 1;
      const lo = a.min.map((v) => v / k);
      const hi = a.max.map((v) => v / k);
      for (let c = 0; c < 8; c++) corners.push(apply(m, [c & 1 ? hi[0] : lo[0], c & 2 ? hi[1] : lo[1], c & 4 ? hi[2] : lo[2]]));
    }
    for (const c of node.children || []) visit(c, m, depth + 1);
  };
  const identity = [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1];
  const scene = (json.scenes || [])[json.scene || 0];
  for (const n of (scene && scene.nodes) || []) visit(n, identity, 0);
  if (corners.length === 0) return null;
  const zUp = corners.map(([x, y, z]) => [x, -z, y]);
  if (Array.isArray(bv.box) && bv.box.length === 12) {
    const c = bv.box.slice(0, 3);
    const axes = [bv.box.slice(3, 6), bv.box.slice(6, 9), bv.box.slice(9, 12)];
    for (const p of zUp) {
      const d = p.map((v, i) => v - c[i]);
      for (const [i, ax] of axes.entries()) {
        const len2 = ax[0] * ax[0] + ax[1] * ax[1] + ax[2] * ax[2];
        // The point's coordinate along this half-axis, in half-axis lengths.
        const t = len2 > 0 ? (d[0] * ax[0] + d[1] * ax[1] + d[2] * ax[2]) / len2 : 0;
        const size = Math.sqrt(len2) + Math.hypot(...axes.map((a) => Math.hypot(...a)));
        if (Math.abs(t) * Math.sqrt(len2) > Math.sqrt(len2) + EPS * size) return `point ${p.map((v) => v.toPrecision(6)).join(', ')} (z-up) is ${(Math.abs(t)).toFixed(4)} half-axes from the box centre along axis ${i}`;
      }
    }
  } else if (Array.isArray(bv.sphere) && bv.sphere.length === 4) {
    const [cx, cy, cz, r] = bv.sphere;
    for (const p of zUp) {
      const dist = Math.hypot(p[0] - cx, p[1] - cy, p[2] - cz);
      if (dist > r * (1 + EPS) + EPS) return `point ${p.map((v) => v.toPrecision(6)).join(', ')} (z-up) is ${dist} from the sphere's centre, radius ${r}`;
    }
  }
  // A region is in geographic coordinates: the tile's transform would be
  // needed to compare; not checked.
  return null;
}

for (const file of files) await checkTileset(path.resolve(file));
process.exit(failures ? 1 : 0);
