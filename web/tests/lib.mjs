// Shared pieces of the browser tests: a small static server (Node's http,
// loopback, ephemeral port), Debian's Chromium driven by playwright-core,
// and pixel checks of the canvas.

import http from 'node:http';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import zlib from 'node:zlib';
import { chromium } from 'playwright-core';

export const MIME = {
  '.html': 'text/html; charset=utf-8',
  '.js': 'text/javascript; charset=utf-8',
  '.mjs': 'text/javascript; charset=utf-8',
  '.json': 'application/json',
  '.wasm': 'application/wasm',
  '.glb': 'model/gltf-binary',
  '.ply': 'application/octet-stream',
  '.pop': 'application/octet-stream',
  '.mco': 'application/octet-stream',
  '.css': 'text/css; charset=utf-8',
  '.png': 'image/png',
  '.jpg': 'image/jpeg',
  '.svg': 'image/svg+xml',
  '.xml': 'application/xml',
};

/**
 * Serves `site` (the built viewer) at `/` and `models` at `/models/` on
 * 127.0.0.1 with an ephemeral port; `mounts` maps more URL prefixes
 * (`/cesium/`) to folders. No listing API: the viewer must work without
 * one. Returns {url, close()}.
 */
export async function staticServer(site, models, mounts = {}) {
  const prefixes = Object.entries({ ...mounts, '/models/': models });
  const server = http.createServer((req, res) => {
    const u = new URL(req.url, 'http://x');
    let rel = decodeURIComponent(u.pathname);
    let base = site;
    const mount = prefixes.find(([p]) => rel.startsWith(p));
    if (mount) {
      base = mount[1];
      rel = rel.slice(mount[0].length - 1);
    }
    if (rel.endsWith('/')) rel += 'index.html';
    const file = path.join(base, path.normalize(rel));
    if (!file.startsWith(base + path.sep) || !fs.existsSync(file) || !fs.statSync(file).isFile()) {
      res.writeHead(404, { 'content-type': 'text/plain' });
      res.end('not found\n');
      return;
    }
    const bytes = fs.readFileSync(file);
    res.writeHead(200, {
      'content-type': MIME[path.extname(file)] || 'application/octet-stream',
      'content-length': bytes.length,
      'cache-control': 'no-cache',
    });
    res.end(req.method === 'HEAD' ? undefined : bytes);
  });
  await new Promise((r) => server.listen(0, '127.0.0.1', r));
  // Stops by itself if the test runner dies without closing it.
  server.unref();
  const { port } = server.address();
  return { url: `http://127.0.0.1:${port}`, close: () => new Promise((r) => server.close(r)) };
}

export const CHROMIUM_ARGS = [
  '--headless',
  '--no-sandbox',
  '--disable-gpu',
  '--disable-background-networking',
  '--disable-component-update',
  '--disable-sync',
  '--no-first-run',
  // WebGL through SwiftShader (software) when there is no GPU.
  '--use-angle=swiftshader',
  '--enable-unsafe-swiftshader',
];

/** Debian's Chromium, headless, with a fresh profile. */
export async function launch() {
  const userDataDir = fs.mkdtempSync(path.join(os.tmpdir(), 'lodkit-chromium-'));
  const context = await chromium.launchPersistentContext(userDataDir, {
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    headless: true,
    args: CHROMIUM_ARGS,
    viewport: { width: 800, height: 600 },
    deviceScaleFactor: 1,
  });
  return {
    context,
    async close() {
      await context.close();
      fs.rmSync(userDataDir, { recursive: true, force: true });
    },
  };
}

/**
 * Opens a page that records console errors and page errors in `errors`.
 */
export async function openPage(context) {
  const page = await context.newPage();
  const errors = [];
  page.on('console', (m) => {
    if (m.type() === 'error') errors.push(m.text());
  });
  page.on('pageerror', (e) => errors.push(String(e)));
  return { page, errors };
}

/** Fraction of the canvas's pixels that differ from the background colour. */
export async function coverage(page) {
  return page.evaluate(() => {
    const c = document.querySelector('#view canvas');
    const gl = c.getContext('webgl2') || c.getContext('webgl');
    const w = gl.drawingBufferWidth;
    const h = gl.drawingBufferHeight;
    const px = new Uint8Array(w * h * 4);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
    // The clear colour 0x20232a.
    let diff = 0;
    for (let i = 0; i < px.length; i += 4) {
      if (Math.abs(px[i] - 0x20) + Math.abs(px[i + 1] - 0x23) + Math.abs(px[i + 2] - 0x2a) > 12) diff++;
    }
    return diff / (w * h);
  });
}

/** Reads JSON figures printed by a native command. */
export function gzipSize(file) {
  return zlib.gzipSync(fs.readFileSync(file), { level: 9 }).length;
}

export function assert(cond, msg) {
  if (!cond) throw new Error(`assertion failed: ${msg}`);
}
