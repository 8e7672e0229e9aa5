// Browser tests of 3D Tiles tilesets in the two clients, in Chromium:
//   - lodkit's viewer (3DTilesRendererJS + three.js, meshopt decoder):
//     the tileset loads with no console error, tiles load, the model is on
//     screen; a coarser error target draws fewer triangles than a finer one.
//   - CesiumJS (`Cesium3DTileset.fromUrl`, no ion, no globe; maximum
//     screen-space error 1 px, so it refines past the root): loads with no
//     console error, tiles load, the model is on screen.
// Both pages must request nothing but the loopback servers.
// Screenshots and results.json go to LODKIT_WEB_OUT.
//
//   node web/tests/tiles.test.mjs MODELS_DIR REL/tileset.json [REL2/tileset.json ...]
//
// Environment (scripts/ci-tiles.sh sets it):
//   LODKIT_WEB_SITE   the built viewer (scripts/build-web.sh)
//   LODKIT_WEB_OUT    where screenshots and results go
//   LODKIT_CESIUM     CesiumJS's Build/Cesium folder (default: web/tests/tiles/node_modules/cesium/Build/Cesium)
//   LODKIT_WEB_BASE   a running server (lodkit serve) to test the viewer on
//                     instead of the built-in one; MODELS_DIR under /models/
//   LODKIT_TILES_CLIENTS  which clients: `viewer,cesium` (default), `viewer`, `cesium`

import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { staticServer, launch, openPage, coverage, assert } from './lib.mjs';

const here = path.dirname(fileURLToPath(import.meta.url));
const [modelsArg, ...tilesets] = process.argv.slice(2);
if (!modelsArg || tilesets.length === 0) {
  console.error('usage: tiles.test.mjs MODELS_DIR REL/tileset.json [...]');
  process.exit(2);
}
const site = process.env.LODKIT_WEB_SITE;
if (!site) throw new Error('LODKIT_WEB_SITE is not set (run scripts/ci-tiles.sh)');
const outDir = path.resolve(process.env.LODKIT_WEB_OUT || 'target/web-test/tiles');
fs.mkdirSync(outDir, { recursive: true });
const cesium = path.resolve(process.env.LODKIT_CESIUM || path.join(here, 'tiles/node_modules/cesium/Build/Cesium'));

// The model on screen: a closed model framed in the view covers 15-20 %;
// a flat scan from the default framing far less (the RGB-D mug scene, a
// depth map in its camera's frame seen from behind: 1.0-1.5 %; the Autzen
// terrain from 36 degrees up: about 4 %), a blank canvas 0.
const MIN_COVERAGE = 0.005;
const TIMEOUT = 120000;

const server = await staticServer(path.resolve(site), path.resolve(modelsArg), {
  '/cesium/': cesium,
  '/cesium-test/': path.join(here, 'tiles'),
});
const viewerBase = process.env.LODKIT_WEB_BASE || server.url;
const browser = await launch();
const results = { viewerBase, checks: [] };
let failures = 0;

async function check(name, fn) {
  const t0 = Date.now();
  try {
    const r = await fn();
    results.checks.push({ name, ok: true, ms: Date.now() - t0, ...r });
    console.log(`ok   ${name} ${JSON.stringify(r)}`);
  } catch (e) {
    failures++;
    results.checks.push({ name, ok: false, ms: Date.now() - t0, error: String(e.stack || e) });
    console.log(`FAIL ${name}: ${e.stack || e}`);
  }
}

// Console errors but the viewer's listing probe (404 on a static server),
// and any request that leaves the loopback servers (CesiumJS must fetch
// nothing from the internet: no ion, imagery or terrain).
async function page() {
  const { page: p } = await openPage(browser.context);
  const errors = [];
  p.on('request', (r) => {
    const u = new URL(r.url());
    if (!['data:', 'blob:'].includes(u.protocol) && u.hostname !== '127.0.0.1') errors.push(`request outside loopback: ${r.url()}`);
  });
  p.on('console', (m) => {
    if (m.type() !== 'error') return;
    const url = m.location().url || '';
    if (/status of 404/.test(m.text()) && /\/api\/models$/.test(url)) return;
    errors.push(m.text());
  });
  p.on('pageerror', (e) => errors.push(String(e)));
  return { p, errors };
}

// Renders until the viewer's tileset has settled (nothing in flight,
// something drawn) for a few frames in a row; returns its state.
async function settle(p) {
  const deadline = Date.now() + TIMEOUT;
  for (;;) {
    const s = await p.evaluate(() => {
      window.lodkitViewer.render();
      const st = window.lodkitViewer.state;
      return { settledFrames: st.settledFrames, error: st.error };
    });
    if (s.error) throw new Error(`viewer error: ${s.error}`);
    if (s.settledFrames >= 5) break;
    if (Date.now() > deadline) throw new Error('the tileset did not settle');
    await p.waitForTimeout(50);
  }
  return p.evaluate(() => ({ ...window.lodkitViewer.state, hud: document.getElementById('hud').textContent }));
}

async function setErrorTarget(p, px) {
  await p.evaluate((v) => {
    const el = document.getElementById('tolerance');
    el.value = String(v);
    el.dispatchEvent(new Event('input'));
  }, px);
  return settle(p);
}

const clients = (process.env.LODKIT_TILES_CLIENTS || 'viewer,cesium').split(',');
const slug = (rel) => rel.replace(/\/?tileset\.json$/, '').replace(/[^A-Za-z0-9]+/g, '_') || 'root';

for (const rel of tilesets) {
  const url = `/models/${rel.split('/').map(encodeURIComponent).join('/')}`;

  if (clients.includes('viewer')) await check(`3DTilesRendererJS viewer: ${rel}`, async () => {
    const { p, errors } = await page();
    await p.goto(`${viewerBase}/?model=${encodeURIComponent(url)}`);
    await p.waitForFunction(() => window.lodkitViewer && (window.lodkitViewer.state.complete || window.lodkitViewer.state.error), null, { timeout: TIMEOUT });
    const fine = await setErrorTarget(p, 0.25);
    const covFine = await coverage(p);
    await p.screenshot({ path: path.join(outDir, `viewer-${slug(rel)}-fine.png`) });
    const coarse = await setErrorTarget(p, 32);
    const covCoarse = await coverage(p);
    await p.screenshot({ path: path.join(outDir, `viewer-${slug(rel)}-coarse.png`) });
    await p.close();
    assert(errors.length === 0, `console errors: ${JSON.stringify(errors)}`);
    assert(fine.kind === 'tileset', `opened as ${fine.kind}`);
    assert(fine.tilesLoaded > 0 && fine.tilesFailed === 0, `${fine.tilesLoaded} tiles loaded, ${fine.tilesFailed} failed`);
    assert(fine.tilesetBytes > 0, 'no bytes counted');
    assert(covFine > MIN_COVERAGE, `only ${(covFine * 100).toFixed(2)} % of the canvas shows the model (error target 0.25 px)`);
    // The coarse cut of a point cloud is a sparse subsample of 1-pixel points.
    assert(covCoarse > MIN_COVERAGE / 10, `only ${(covCoarse * 100).toFixed(2)} % of the canvas shows the model (error target 32 px)`);
    // Triangles, or points for a point cloud's tiles.
    const drawn = (st) => st.triangles + st.points;
    assert(drawn(coarse) < drawn(fine), `${drawn(coarse)} triangles and points at 32 px, ${drawn(fine)} at 0.25 px`);
    assert(/tiles\s+\d+ loaded, \d+ drawn/.test(fine.hud) && /triangles/.test(fine.hud) && /downloaded/.test(fine.hud), `HUD: ${fine.hud}`);
    return {
      fine: { tilesLoaded: fine.tilesLoaded, tilesDrawn: fine.tilesVisible, triangles: fine.triangles, points: fine.points, bytes: fine.tilesetBytes, coverage: +covFine.toFixed(3) },
      coarse: { tilesDrawn: coarse.tilesVisible, triangles: coarse.triangles, points: coarse.points, coverage: +covCoarse.toFixed(3) },
    };
  });

  if (clients.includes('cesium')) await check(`CesiumJS: ${rel}`, async () => {
    const { p, errors } = await page();
    await p.goto(`${server.url}/cesium-test/cesium.html?tileset=${encodeURIComponent(url)}&sse=1`);
    await p.waitForFunction(() => window.cesiumTest && (window.cesiumTest.error || (window.cesiumTest.allLoaded && window.cesiumTest.tilesLoaded > 0)), null, { timeout: TIMEOUT });
    // A few frames after the last tile.
    const frames = await p.evaluate(() => window.cesiumTest.frames);
    await p.waitForFunction((n) => window.cesiumTest.frames > n + 3, frames, { timeout: TIMEOUT });
    const s = await p.evaluate(() => ({ error: window.cesiumTest.error, tilesLoaded: window.cesiumTest.tilesLoaded, tilesFailed: window.cesiumTest.tilesFailed }));
    const cov = await p.evaluate(() => {
      const src = window.cesiumTest.widget.scene.canvas;
      const c = document.createElement('canvas');
      c.width = src.width;
      c.height = src.height;
      const g = c.getContext('2d');
      g.drawImage(src, 0, 0);
      const px = g.getImageData(0, 0, c.width, c.height).data;
      let diff = 0;
      for (let i = 0; i < px.length; i += 4) {
        if (Math.abs(px[i] - 0x20) + Math.abs(px[i + 1] - 0x23) + Math.abs(px[i + 2] - 0x2a) > 12) diff++;
      }
      return diff / (c.width * c.height);
    });
    await p.screenshot({ path: path.join(outDir, `cesium-${slug(rel)}.png`) });
    await p.close();
    assert(!s.error, `CesiumJS: ${s.error}`);
    assert(errors.length === 0, `console errors: ${JSON.stringify(errors)}`);
    assert(s.tilesLoaded > 0 && s.tilesFailed === 0, `${s.tilesLoaded} tiles loaded, ${s.tilesFailed} failed`);
    assert(cov > MIN_COVERAGE, `only ${(cov * 100).toFixed(2)} % of the canvas shows the model`);
    return { tilesLoaded: s.tilesLoaded, coverage: +cov.toFixed(3) };
  });
}

// Through a server with a listing (lodkit serve): the viewer's menu offers
// each tileset once and none of the files inside it.
if (process.env.LODKIT_WEB_BASE) {
  await check('viewer menu: tilesets listed, their tiles not', async () => {
    const { p } = await page();
    await p.goto(`${viewerBase}/?idle`);
    await p.waitForFunction(() => window.lodkitViewer && window.lodkitViewer.ready);
    await p.evaluate(() => window.lodkitViewer.ready);
    const options = await p.evaluate(() => [...document.querySelectorAll('#models option')].map((o) => o.value));
    await p.close();
    for (const rel of tilesets) assert(options.includes(`/models/${rel}`), `no menu entry for ${rel}: ${JSON.stringify(options)}`);
    const folders = tilesets.map((rel) => `/models/${rel.replace(/[^/]*$/, '')}`);
    const inside = options.filter((o) => folders.some((f) => o.startsWith(f)) && !o.endsWith('/tileset.json'));
    assert(inside.length === 0, `tile files in the menu: ${JSON.stringify(inside.slice(0, 5))}`);
    return { entries: options.length };
  });
}

await check('viewer: a missing tileset is one error line naming it', async () => {
  const { p } = await page();
  const url = '/models/no-such-folder/tileset.json';
  await p.goto(`${viewerBase}/?model=${encodeURIComponent(url)}`);
  await p.waitForFunction(() => window.lodkitViewer && window.lodkitViewer.state.error, null, { timeout: TIMEOUT });
  const shown = await p.evaluate(() => document.getElementById('error').textContent);
  await p.close();
  assert(shown.includes('no-such-folder/tileset.json') && !shown.includes('\n'), `error line: ${JSON.stringify(shown)}`);
  return { error: shown };
});

await browser.close();
await server.close();
fs.writeFileSync(path.join(outDir, 'results.json'), JSON.stringify(results, null, 2));
console.log(`${results.checks.length - failures} of ${results.checks.length} tileset checks passed`);
process.exit(failures ? 1 : 0);
