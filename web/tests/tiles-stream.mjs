// How a tileset streams into lodkit's viewer (3DTilesRendererJS + three.js)
// in Chromium over an emulated link (default 50 Mbit/s, 20 ms latency):
//   - first frame: time from navigation start to the first frame that
//     draws tile content, and the tileset bytes (tileset JSON and tile
//     contents) fetched by then;
//   - the overview settled at the viewer's error target (1 px);
//   - a close-up, in a fresh page that opens with the camera at a
//     twentieth of the model's radius from the surface point under the
//     overview's centre (`?camera=`): once settled, the bytes it fetched
//     against the bytes of the tiles its final view draws, and against
//     the whole tileset on disk.
// Prints one JSON object (and writes it to LODKIT_WEB_OUT/stream.json).
// A benchmark, not a test: it asserts nothing but that the tileset loads.
//
//   node web/tests/tiles-stream.mjs MODELS_DIR REL/tileset.json [--mbps N] [--latency-ms N]
//
// Environment: LODKIT_WEB_SITE (the built viewer, scripts/build-web.sh),
// LODKIT_WEB_OUT (default target/web-test/stream).

import fs from 'node:fs';
import path from 'node:path';
import { staticServer, launch } from './lib.mjs';

const args = process.argv.slice(2);
const opt = (name, dflt) => {
  const i = args.indexOf(name);
  if (i < 0) return dflt;
  const v = Number(args[i + 1]);
  args.splice(i, 2);
  if (!(v >= 0)) {
    console.error(`${name}: want a number, got ${JSON.stringify(String(args[i + 1]))}`);
    process.exit(2);
  }
  return v;
};
const mbps = opt('--mbps', 50);
const latencyMs = opt('--latency-ms', 20);
const [modelsArg, rel] = args;
if (!modelsArg || !rel) {
  console.error('usage: tiles-stream.mjs MODELS_DIR REL/tileset.json [--mbps N] [--latency-ms N]');
  process.exit(2);
}
const site = process.env.LODKIT_WEB_SITE;
if (!site) {
  console.error('LODKIT_WEB_SITE is not set (the viewer built by scripts/build-web.sh)');
  process.exit(2);
}
const models = path.resolve(modelsArg);
const tilesetFile = path.join(models, rel);
if (!fs.existsSync(tilesetFile)) {
  console.error(`${tilesetFile}: no such file`);
  process.exit(1);
}
const outDir = path.resolve(process.env.LODKIT_WEB_OUT || 'target/web-test/stream');
fs.mkdirSync(outDir, { recursive: true });
const TIMEOUT = 600000;

// Bytes of the whole tileset on disk: every file under its folder.
function folderBytes(dir) {
  let n = 0;
  for (const e of fs.readdirSync(dir, { withFileTypes: true })) {
    const p = path.join(dir, e.name);
    if (e.isDirectory()) n += folderBytes(p);
    else if (e.isFile()) n += fs.statSync(p).size;
  }
  return n;
}

const server = await staticServer(path.resolve(site), models);
const url = `/models/${rel.split('/').map(encodeURIComponent).join('/')}`;

// One page in a fresh browser (no cache) over the emulated link; every
// response's body bytes by URL.
async function openStreamed(query) {
  const browser = await launch();
  const page = await browser.context.newPage();
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  page.on('console', (m) => {
    if (m.type() === 'error' && !/\/api\/models/.test(m.location().url || '')) errors.push(m.text());
  });
  const cdp = await browser.context.newCDPSession(page);
  await cdp.send('Network.enable');
  await cdp.send('Network.setCacheDisabled', { cacheDisabled: true });
  await cdp.send('Network.emulateNetworkConditions', {
    offline: false,
    latency: latencyMs,
    downloadThroughput: (mbps * 1e6) / 8,
    uploadThroughput: (mbps * 1e6) / 8,
  });
  const urls = new Map();
  const bodyBytes = new Map();
  cdp.on('Network.responseReceived', (e) => urls.set(e.requestId, e.response.url));
  cdp.on('Network.dataReceived', (e) => {
    const u = urls.get(e.requestId);
    if (u) bodyBytes.set(u, (bodyBytes.get(u) || 0) + e.dataLength);
  });
  const prefix = `${server.url}/models/`;
  const sum = (keep) => [...bodyBytes].filter(([u]) => keep(u.startsWith(prefix))).reduce((n, [, b]) => n + b, 0);
  // The first frame that draws tile content, timed in the page
  // (milliseconds since navigation start).
  await page.addInitScript(() => {
    const poll = () => {
      const v = window.lodkitViewer;
      if (v && v.state && v.state.kind === 'tileset' && v.state.triangles + v.state.points > 0) {
        // From the request of the tileset's JSON, too (the viewer's own
        // code and decoders come first).
        const json = performance.getEntriesByType('resource').find((r) => /\/models\/.*\.json(\?|$)/.test(r.name));
        const ms = performance.now();
        window.__firstFrame = { ms, fromTilesetMs: json ? ms - json.startTime : null };
        return;
      }
      requestAnimationFrame(poll);
    };
    requestAnimationFrame(poll);
  });
  await page.goto(`${server.url}/?model=${encodeURIComponent(url)}${query}`);
  await page.waitForFunction(() => window.__firstFrame || (window.lodkitViewer && window.lodkitViewer.state.error), null, { timeout: TIMEOUT });
  const first = await page.evaluate(() => ({ ...window.__firstFrame, error: window.lodkitViewer.state.error }));
  if (first.error) {
    console.error(`${rel}: ${first.error}`);
    process.exit(1);
  }
  first.tilesetBytes = sum((m) => m);
  first.viewerBytes = sum((m) => !m);
  return { browser, page, errors, bodyBytes, tilesetBytes: () => sum((m) => m), first };
}

async function settle(page) {
  const deadline = Date.now() + TIMEOUT;
  const t0 = Date.now();
  for (;;) {
    const s = await page.evaluate(() => {
      window.lodkitViewer.render();
      return window.lodkitViewer.state.settledFrames;
    });
    if (s >= 5) return Date.now() - t0;
    if (Date.now() > deadline) throw new Error('the tileset did not settle');
    await page.waitForTimeout(50);
  }
}
const drawnState = (page) => page.evaluate(() => ({ triangles: window.lodkitViewer.state.triangles, tiles: window.lodkitViewer.state.tilesVisible }));

// The overview.
const a = await openStreamed('');
const overviewMs = await settle(a.page);
const overview = { ...(await drawnState(a.page)), settleMs: overviewMs, tilesetBytes: a.tilesetBytes() };
// The close-up's camera: the surface point under the centre, seen from a
// twentieth of the bounding sphere's radius back along the view.
const camera = await a.page.evaluate(() => {
  const v = window.lodkitViewer;
  const hit = v.pick(0, 0);
  if (!hit) return null;
  const eye = v.camera.position.toArray();
  const d = Math.hypot(eye[0] - hit[0], eye[1] - hit[1], eye[2] - hit[2]);
  const k = v.bounds.radius / 20 / d;
  return [...hit.map((h, i) => h + (eye[i] - h) * k), ...hit];
});
await a.browser.close();
if (!camera) {
  console.error(`${rel}: no surface under the overview's centre`);
  process.exit(1);
}

// The close-up, from a cold start.
const b = await openStreamed(`&camera=${camera.map((x) => x.toPrecision(9)).join(',')}`);
const closeMs = await settle(b.page);
const drawn = await b.page.evaluate(() => {
  const t = window.lodkitViewer.tiles;
  return [...t.visibleTiles]
    .filter((tile) => tile.content && tile.content.uri)
    .map((tile) => new URL(tile.content.uri, `${tile.internal.basePath}/`).toString());
});
const drawnBytes = drawn.reduce((n, u) => n + (b.bodyBytes.get(u) || 0), 0);
const close = await drawnState(b.page);
const fetched = b.tilesetBytes();
await b.browser.close();
await server.close();
const total = folderBytes(path.dirname(tilesetFile));

const out = {
  tileset: rel,
  link: { mbps, latencyMs },
  firstFrame: { ms: Math.round(a.first.ms), fromTilesetMs: Math.round(a.first.fromTilesetMs), tilesetBytes: a.first.tilesetBytes, viewerBytes: a.first.viewerBytes },
  overview,
  closeUp: {
    ...close,
    firstFrameMs: Math.round(b.first.ms),
    settleMs: closeMs,
    fetchedBytes: fetched,
    drawnTileBytes: drawnBytes,
    fetchedOverDrawn: +(fetched / Math.max(drawnBytes, 1)).toFixed(2),
    fetchedShareOfTileset: +(fetched / total).toFixed(4),
  },
  tilesetBytesOnDisk: total,
  consoleErrors: [...a.errors, ...b.errors],
};
fs.writeFileSync(path.join(outDir, 'stream.json'), JSON.stringify(out, null, 2));
console.log(JSON.stringify(out, null, 2));
process.exit(out.consoleErrors.length ? 1 : 0);
