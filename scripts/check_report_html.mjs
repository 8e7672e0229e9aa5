// Opens a build's report.html in headless Chromium (Debian's, driven by
// playwright-core from web/node_modules) and checks what a reader sees:
// no console or page error, no request leaving the page (it must work
// offline), every <img> loaded and showing the model (enough pixels that
// are not the white background), and the charts drawn.
// Usage: node scripts/check_report_html.mjs OUT/report.html
import { createRequire } from 'node:module';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { pathToFileURL } from 'node:url';

const require = createRequire(path.join(process.cwd(), 'web', 'package.json'));
const { chromium } = require('playwright-core');

const file = process.argv[2];
if (!file || !fs.existsSync(file)) {
  console.error(`usage: node scripts/check_report_html.mjs REPORT.html (got ${file})`);
  process.exit(2);
}
const userDataDir = fs.mkdtempSync(path.join(os.tmpdir(), 'lodkit-report-'));
const context = await chromium.launchPersistentContext(userDataDir, {
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
  headless: true,
  args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking',
    '--disable-component-update', '--disable-sync', '--no-first-run'],
});
const problems = [];
try {
  const page = await context.newPage();
  page.on('console', (m) => { if (m.type() === 'error') problems.push(`console: ${m.text()}`); });
  page.on('pageerror', (e) => problems.push(`page error: ${e.message}`));
  const url = pathToFileURL(path.resolve(file)).href;
  page.on('request', (r) => {
    if (r.url() !== url && !r.url().startsWith('data:')) problems.push(`request leaves the page: ${r.url()}`);
  });
  await page.goto(url, { waitUntil: 'load' });
  const result = await page.evaluate(async () => {
    const imgs = [...document.images];
    await Promise.all(imgs.map((i) => (i.complete ? null : new Promise((r) => { i.onload = i.onerror = r; }))));
    return {
      svgs: document.querySelectorAll('svg').length,
      tables: document.querySelectorAll('table').length,
      images: imgs.map((img) => {
        const c = document.createElement('canvas');
        c.width = img.naturalWidth;
        c.height = img.naturalHeight;
        let drawn = 0;
        if (c.width > 0) {
          const g = c.getContext('2d');
          g.drawImage(img, 0, 0);
          const d = g.getImageData(0, 0, c.width, c.height).data;
          for (let p = 0; p < d.length; p += 4) if (d[p] < 250 || d[p + 1] < 250 || d[p + 2] < 250) drawn++;
        }
        return { alt: img.alt, data: img.src.startsWith('data:image/png;base64,'), w: img.naturalWidth, drawn };
      }),
    };
  });
  if (result.images.length === 0) problems.push('no image');
  for (const i of result.images) {
    if (!i.data) problems.push(`${i.alt}: not an embedded PNG`);
    if (i.w === 0) problems.push(`${i.alt}: did not load`);
    else if (i.drawn < 500) problems.push(`${i.alt}: shows almost nothing (${i.drawn} pixels)`);
  }
  if (result.svgs < 3) problems.push(`only ${result.svgs} inline SVGs (two charts and a colour bar expected)`);
  console.log(`${file}: ${result.images.length} images (fewest drawn pixels ${Math.min(...result.images.map((i) => i.drawn))}), ${result.svgs} SVGs, ${result.tables} tables`);
} finally {
  await context.close();
  fs.rmSync(userDataDir, { recursive: true, force: true });
}
if (problems.length) {
  for (const p of problems) console.error(`FAIL ${p}`);
  process.exit(1);
}
console.log('report.html: OK in headless Chromium');
