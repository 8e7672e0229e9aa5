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
//     (CesiumJS draws a primitive without normals unlit).
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

for (const file of files) await checkTileset(path.resolve(file));
process.exit(failures ? 1 : 0);

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
          if (realContent) await checkContent(realContent, name, stats);
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

async function checkContent(file, name, stats) {
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
}
