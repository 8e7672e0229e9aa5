// Load test of `lodkit serve` on loopback: C concurrent clients, each
// making N range requests (keep-alive) for random 64 KiB ranges of a model;
// prints errors, p50/p99 latency and the server's peak RSS (VmHWM).
// Usage: node web/tests/serve-load.mjs LODKIT MODELS_DIR FILE [CLIENTS] [REQUESTS]
//   e.g. node web/tests/serve-load.mjs target/release/lodkit target/web-test/models stanford_bunny.mco 64 200

import http from 'node:http';
import fs from 'node:fs';
import net from 'node:net';
import path from 'node:path';
import { spawn } from 'node:child_process';

const [lodkit, dir, file, clientsArg, requestsArg] = process.argv.slice(2);
if (!lodkit || !dir || !file) {
  console.error('usage: node web/tests/serve-load.mjs LODKIT MODELS_DIR FILE [CLIENTS] [REQUESTS]');
  process.exit(2);
}
const clients = Number(clientsArg || 64);
const requests = Number(requestsArg || 200);
const size = fs.statSync(path.join(dir, file)).size;
const span = Math.min(65536, size);

const port = await new Promise((res) => {
  const s = net.createServer().listen(0, '127.0.0.1', () => {
    const p = s.address().port;
    s.close(() => res(p));
  });
});
const server = spawn(lodkit, ['serve', dir, '--port', String(port)], { stdio: ['ignore', 'ignore', 'inherit'] });
const base = `http://127.0.0.1:${port}`;
for (let i = 0; ; i++) {
  const up = await new Promise((res) => http.get(`${base}/`, (r) => (r.resume(), res(true))).on('error', () => res(false)));
  if (up) break;
  if (i > 200) throw new Error('lodkit serve did not start');
  await new Promise((r) => setTimeout(r, 50));
}
const url = new URL(`${base}/models/${file}`);
const listing = await new Promise((res) => http.get(`${base}/api/models`, (r) => {
  let s = '';
  r.on('data', (d) => (s += d)).on('end', () => res(s));
}));
const entry = JSON.parse(listing).find((m) => m.name === file || m.url.endsWith(`/${file}`));
if (entry) url.pathname = entry.url;

let peakRss = 0;
const rss = () => {
  try {
    const m = /VmHWM:\s+(\d+) kB/.exec(fs.readFileSync(`/proc/${server.pid}/status`, 'utf8'));
    if (m) peakRss = Math.max(peakRss, Number(m[1]) * 1024);
  } catch {}
};
const sampler = setInterval(rss, 20);

let seed = 12345;
const rand = () => ((seed = (seed * 1103515245 + 12345) >>> 0) / 2 ** 32);
const latencies = [];
let errors = 0;
async function client() {
  const agent = new http.Agent({ keepAlive: true, maxSockets: 1 });
  for (let i = 0; i < requests; i++) {
    const start = Math.floor(rand() * (size - span + 1));
    const t0 = process.hrtime.bigint();
    const ok = await new Promise((res) => {
      const req = http.get(url, { agent, headers: { Range: `bytes=${start}-${start + span - 1}` } }, (r) => {
        let n = 0;
        r.on('data', (d) => (n += d.length));
        r.on('end', () => res(r.statusCode === 206 && n === span && r.headers['content-range'] === `bytes ${start}-${start + span - 1}/${size}`));
        r.on('error', () => res(false));
      });
      req.on('error', () => res(false));
    });
    latencies.push(Number(process.hrtime.bigint() - t0) / 1e6);
    if (!ok) errors++;
  }
  agent.destroy();
}
const t0 = Date.now();
await Promise.all(Array.from({ length: clients }, client));
const wall = (Date.now() - t0) / 1000;
clearInterval(sampler);
rss();
server.kill();
latencies.sort((a, b) => a - b);
const q = (f) => latencies[Math.min(latencies.length - 1, Math.floor(f * latencies.length))];
const out = {
  clients,
  requests_per_client: requests,
  range_bytes: span,
  total: latencies.length,
  errors,
  p50_ms: +q(0.5).toFixed(2),
  p99_ms: +q(0.99).toFixed(2),
  requests_per_s: Math.round(latencies.length / wall),
  peak_rss_mib: +(peakRss / 2 ** 20).toFixed(1),
};
console.log(`serve load: ${clients} clients x ${requests} range requests of ${span} B: ${out.errors} errors, p50 ${out.p50_ms} ms, p99 ${out.p99_ms} ms, ${out.requests_per_s} req/s, peak RSS ${out.peak_rss_mib} MiB`);
console.log(JSON.stringify(out));
process.exit(errors ? 1 : 0);
