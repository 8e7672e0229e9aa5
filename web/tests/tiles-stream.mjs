// How a tileset streams into lodkit's viewer (3DTilesRendererJS + three.js)
// in Chromium over an emulated link (default 50 Mbit/s, 20 ms latency):
//   - first frame: time from navigation start (the page's time origin) to
//     the first frame that draws tile content, and from the request of the
//     tileset's JSON; the bytes fetched by then, per request, split into
//     the viewer's own files (page, script, decoders) and the tileset's
//     (tileset JSON and tile contents). Judged against the targets: first
//     frame within 1 s of navigation start, from at most 256 KB (256,000
//     bytes) of tileset bytes, and none of the .pop/.mco decoders fetched
//     (printed PASS/FAIL; the exit status does not depend on them: timings
//     on a shared machine are not assertions);
//   - the overview settled at the viewer's error target (1 px);
//   - a close-up, in a fresh page that opens with the camera at a
//     twentieth of the model's radius from the surface point under the
//     overview's centre (`?camera=`): once settled, the bytes it fetched
//     against the bytes of the tiles its final view draws, and against
//     the whole tileset on disk.
// Bytes are as received (Content-Encoding applied by the server counts
// compressed). Prints one JSON object (and writes it to
// LODKIT_WEB_OUT/stream.json), then the first-frame summary.
// A benchmark, not a test: it asserts nothing but that the tileset loads.
//
//   node web/tests/tiles-stream.mjs MODELS_DIR REL/tileset.json [--mbps N] [--latency-ms N]
//        [--runs N] [--first-frame-only]
//
// --runs N: the first frame measured in N fresh browsers (medians reported;
// the overview and close-up run once). --first-frame-only: skip them.
// Environment: LODKIT_WEB_SITE (the built viewer, scripts/build-web.sh),
// LODKIT_WEB_OUT (default target/web-test/stream), LODKIT_WEB_BASE (a
// running server to measure instead of the built-in static one, MODELS_DIR
// under its /models/: `lodkit serve MODELS_DIR`, which compresses text and
// wasm; the static server sends every file as it is).

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
const runs = opt('--runs', 1);
const flag = (name) => {
  const i = args.indexOf(name);
  if (i >= 0) args.splice(i, 1);
  return i >= 0;
};
const firstFrameOnly = flag('--first-frame-only');
const [modelsArg, rel] = args;
if (!modelsArg || !rel || args.length > 2 || !Number.isInteger(runs) || runs < 1) {
  console.error('usage: tiles-stream.mjs MODELS_DIR REL/tileset.json [--mbps N] [--latency-ms N] [--runs N] [--first-frame-only]');
  process.exit(2);
}
// The targets of the first frame.
const FIRST_FRAME_MS = 1000;
const FIRST_FRAME_TILESET_BYTES = 256000;
const site = process.env.LODKIT_WEB_SITE;
if (!site && !process.env.LODKIT_WEB_BASE) {
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
// A close-up that has not settled by then reports its bytes so far
// (`settled: false`): LODKIT_CLOSE_UP_MS, default 300 s.
const CLOSE_UP_LIMIT = Number(process.env.LODKIT_CLOSE_UP_MS || 300000);

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

const server = process.env.LODKIT_WEB_BASE
  ? { url: process.env.LODKIT_WEB_BASE.replace(/\/$/, ''), close: async () => {} }
  : await staticServer(path.resolve(site), models);
const url = `/models/${rel.split('/').map(encodeURIComponent).join('/')}`;

// One page in a fresh browser (no cache) over the emulated link; every
// response's body bytes by URL, and at the first frame that draws tile
// content the bytes received by then, per request.
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
  const bodyBytes = new Map(); // URL -> body bytes (decoded)
  const received = new Map(); // request id -> {url, bytes (as received), head}
  const rec = (id) => {
    if (!received.has(id)) received.set(id, { url: '', bytes: 0, head: 0 });
    return received.get(id);
  };
  cdp.on('Network.responseReceived', (e) => {
    urls.set(e.requestId, e.response.url);
    rec(e.requestId).url = e.response.url;
  });
  cdp.on('Network.dataReceived', (e) => {
    const u = urls.get(e.requestId);
    if (!u) return;
    bodyBytes.set(u, (bodyBytes.get(u) || 0) + e.dataLength);
    // Bytes on the wire; Chromium may report 0 here and the total at
    // loadingFinished instead.
    rec(e.requestId).bytes += e.encodedDataLength || 0;
  });
  // (May come before responseReceived.)
  cdp.on('Network.responseReceivedExtraInfo', (e) => {
    if (e.headersText) rec(e.requestId).head = e.headersText.length;
  });
  cdp.on('Network.loadingFinished', (e) => {
    const r = received.get(e.requestId);
    // That total includes the response head: keep the body's share.
    if (r && r.bytes === 0) r.bytes = Math.max(0, e.encodedDataLength - r.head);
  });
  const prefix = `${server.url}/models/`;
  const sum = (keep) => [...bodyBytes].filter(([u]) => keep(u.startsWith(prefix))).reduce((n, [, b]) => n + b, 0);
  // Each request's bytes when the first frame is drawn, snapshot as the
  // page reports it (before refinement adds its tiles).
  let atFirst = null;
  await page.exposeFunction('__lodkitFirstFrameSeen', () => {
    atFirst = [...received.values()].filter((r) => r.url).map((r) => ({ url: r.url, bytes: r.bytes || bodyBytes.get(r.url) || 0 }));
  });
  // The first frame that draws tile content, timed in the page
  // (milliseconds since navigation start: performance.now()'s origin), by
  // the first animation frame that sees it drawn (so at most a frame late).
  await page.addInitScript(() => {
    const poll = () => {
      const v = window.lodkitViewer;
      if (v && v.state && v.state.kind === 'tileset' && v.state.triangles + v.state.points > 0) {
        const ms = performance.now();
        window.__lodkitFirstFrameSeen();
        // From the request of the tileset's JSON, too (the viewer's own
        // code comes first).
        const json = performance.getEntriesByType('resource').find((r) => /\/models\/.*\.json(\?|$)/.test(r.name));
        window.__firstFrame = { ms, fromTilesetMs: json ? ms - json.startTime : null, viewerMs: v.state.firstFrameMs };
        return;
      }
      requestAnimationFrame(poll);
    };
    requestAnimationFrame(poll);
  });
  await page.goto(`${server.url}/?model=${encodeURIComponent(url)}${query}`);
  await page.waitForFunction(() => window.__firstFrame || (window.lodkitViewer && window.lodkitViewer.state.error), null, { timeout: TIMEOUT });
  const first = await page.evaluate(() => ({ ...window.__firstFrame, error: window.lodkitViewer.state.error, prefetched: window.lodkitViewer.state.prefetched || 0 }));
  if (first.error) {
    console.error(`${rel}: ${first.error}`);
    process.exit(1);
  }
  const local = (u) => u.slice(server.url.length);
  // Requests that had received bytes by then (one just started is not counted).
  const requests = (atFirst || []).filter((r) => r.url.startsWith(server.url) && r.bytes > 0);
  const part = (tiles) => {
    const rs = requests.filter((r) => r.url.startsWith(prefix) === tiles);
    return { bytes: rs.reduce((n, r) => n + r.bytes, 0), requests: Object.fromEntries(rs.map((r) => [local(r.url), r.bytes])) };
  };
  const viewerPart = part(false);
  const tilesPart = part(true);
  first.viewerBytes = viewerPart.bytes;
  first.tilesetBytes = tilesPart.bytes;
  first.requests = { viewer: viewerPart.requests, tileset: tilesPart.requests };
  return { browser, page, errors, bodyBytes, tilesetBytes: () => sum((m) => m), first };
}

// Milliseconds until five settled frames; `null` when the tileset has not
// settled after TIMEOUT (the close-up then reports what it fetched so far).
async function settle(page, limit = TIMEOUT) {
  const deadline = Date.now() + limit;
  const t0 = Date.now();
  for (;;) {
    const s = await page.evaluate(() => {
      window.lodkitViewer.render();
      return window.lodkitViewer.state.settledFrames;
    });
    if (s >= 5) return Date.now() - t0;
    if (Date.now() > deadline) return null;
    await page.waitForTimeout(50);
  }
}
const drawnState = (page) => page.evaluate(() => ({ triangles: window.lodkitViewer.state.triangles, tiles: window.lodkitViewer.state.tilesVisible }));

// The first frame, `runs` times, each in a fresh browser; the first run
// goes on to the overview and the close-up.
const firsts = [];
const consoleErrors = [];
let a = null;
for (let i = 0; i < runs; i++) {
  const r = await openStreamed('');
  firsts.push(r.first);
  consoleErrors.push(...r.errors);
  if (i === 0 && !firstFrameOnly) a = r;
  else await r.browser.close();
}
const median = (xs) => {
  const v = [...xs].sort((x, y) => x - y);
  return v.length % 2 ? v[(v.length - 1) / 2] : (v[v.length / 2 - 1] + v[v.length / 2]) / 2;
};
const firstFrame = {
  runs,
  ms: Math.round(median(firsts.map((f) => f.ms))),
  fromTilesetMs: Math.round(median(firsts.map((f) => f.fromTilesetMs))),
  viewerBytes: median(firsts.map((f) => f.viewerBytes)),
  tilesetBytes: median(firsts.map((f) => f.tilesetBytes)),
  // Per run; viewerMs: the viewer's own time of the frame (when its draw
  // calls were issued, before the frame reached the screen); prefetched:
  // tileset requests the page's early fetch answered.
  each: firsts.map((f) => ({ ms: Math.round(f.ms), viewerMs: f.viewerMs > 0 ? Math.round(f.viewerMs) : null, fromTilesetMs: Math.round(f.fromTilesetMs), viewerBytes: f.viewerBytes, tilesetBytes: f.tilesetBytes, prefetched: f.prefetched })),
  // The first run's requests before its first frame: path -> bytes.
  requests: firsts[0].requests,
};
// The .pop/.mco decoders (the viewer's lodkit/ folder) are no part of a
// tileset's first frame.
const decoderRequests = firsts.flatMap((f) => Object.keys(f.requests.viewer).filter((u) => u.startsWith('/lodkit/')));
firstFrame.pass = {
  ms: firstFrame.ms <= FIRST_FRAME_MS,
  tilesetBytes: firstFrame.tilesetBytes <= FIRST_FRAME_TILESET_BYTES,
  noDecoders: decoderRequests.length === 0,
};

let overview = null;
let closeUp = null;
const total = folderBytes(path.dirname(tilesetFile));
if (a) {
  // The overview.
  const overviewMs = await settle(a.page);
  if (overviewMs === null) throw new Error('the overview did not settle');
  overview = { ...(await drawnState(a.page)), settleMs: overviewMs, tilesetBytes: a.tilesetBytes() };
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
  consoleErrors.push(...b.errors);
  const closeMs = await settle(b.page, CLOSE_UP_LIMIT);
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
  closeUp = {
    ...close,
    firstFrameMs: Math.round(b.first.ms),
    settled: closeMs !== null,
    settleMs: closeMs ?? CLOSE_UP_LIMIT,
    fetchedBytes: fetched,
    drawnTileBytes: drawnBytes,
    fetchedOverDrawn: +(fetched / Math.max(drawnBytes, 1)).toFixed(2),
    fetchedShareOfTileset: +(fetched / total).toFixed(4),
  };
}
await server.close();

const out = {
  tileset: rel,
  link: { mbps, latencyMs },
  firstFrame,
  overview,
  closeUp,
  tilesetBytesOnDisk: total,
  consoleErrors,
};
fs.writeFileSync(path.join(outDir, 'stream.json'), JSON.stringify(out, null, 2));
console.log(JSON.stringify(out, null, 2));
const verdict = (ok) => (ok ? 'PASS' : 'FAIL');
const kb = (n) => `${(n / 1000).toFixed(1)} KB`;
const of = runs > 1 ? ` (median of ${runs}: ${firsts.map((f) => Math.round(f.ms)).join(', ')} ms)` : '';
console.log(`first frame ${firstFrame.ms} ms after navigation start${of}, ${firstFrame.fromTilesetMs} ms after the tileset request: ${verdict(firstFrame.pass.ms)} (target ${FIRST_FRAME_MS} ms)`);
console.log(`fetched before it: tileset ${kb(firstFrame.tilesetBytes)} in ${Object.keys(firstFrame.requests.tileset).length} requests: ${verdict(firstFrame.pass.tilesetBytes)} (target ${kb(FIRST_FRAME_TILESET_BYTES)}); viewer ${kb(firstFrame.viewerBytes)} in ${Object.keys(firstFrame.requests.viewer).length} requests`);
console.log(`.pop/.mco decoders before it: ${decoderRequests.length ? [...new Set(decoderRequests)].join(' ') : 'none'}: ${verdict(firstFrame.pass.noDecoders)}`);
process.exit(consoleErrors.length ? 1 : 0);
