#!/usr/bin/env node
// Issue 49: the lighting tool on a big scene. Renders SCENE once (deep file and cache kept in
// OUT), starts `bounce light` from them, opens the page in the browser test's headless Chromium
// (software WebGL: SwiftShader), and measures the seconds from navigation to a usable page
// (spreadsheet, 3D view and records loaded: window.bounce.ready), the records' transfer, and the
// 3D view's frames per second while the orbit camera is dragged with every record shown (frames
// counted as WebGL clears, one per three.js render).
//
//   node bench/tool-open.mjs [SCENE] [RES] [OUT]   (default bench/scenes/sponza.json 640x360 out/tool-open)
import { spawn, execFileSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..');
const [scene = path.join(root, 'bench/scenes/sponza.json'), res = '640x360', out = path.join(root, 'out/tool-open')] = process.argv.slice(2);
const bin = process.env.BOUNCE_BINARY || path.join(root, 'build/bounce');
fs.mkdirSync(out, { recursive: true });
const deep = path.join(out, 'scene.deep.exr'), cache = path.join(out, 'scene.bic');
if (!fs.existsSync(cache)) {
  execFileSync(bin, ['render', scene, '-o', path.join(out, 'scene.exr'), '--res', res, '--gi', 'cache', '--deep-out', deep,
    '--cache-out', cache, '-q'], { stdio: 'inherit' });
}
const tool = spawn(bin, ['light', scene, '--port', '0', '--out', path.join(out, 'session'), '--threads', '2', '--deep-in', deep,
  '--cache-in', cache, '--set', `camera.resolution=[${res.replace('x', ',')}]`], { stdio: ['ignore', 'pipe', 'inherit'] });
const url = await new Promise((resolve) => tool.stdout.on('data', (d) => { const m = /http:\S+/.exec(String(d)); if (m) resolve(m[0]); }));
const browser = await chromium.launch({ executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
  args: ['--no-sandbox', '--enable-unsafe-swiftshader', '--use-angle=swiftshader'] });
try {
  const page = await browser.newPage({ viewport: { width: 1400, height: 900 } });
  await page.addInitScript(() => {
    window.clears = 0;
    for (const C of [WebGLRenderingContext, WebGL2RenderingContext]) {
      const clear = C.prototype.clear;
      C.prototype.clear = function (...a) { window.clears++; return clear.apply(this, a); };
    }
  });
  let recordBytes = 0, recordSeconds = 0;
  const asked = new Map();
  page.on('request', (r) => { if (r.url().includes('/api/records')) asked.set(r, Date.now()); });
  page.on('requestfinished', async (r) => {
    if (!asked.has(r)) return;
    recordSeconds = (Date.now() - asked.get(r)) / 1000;
    recordBytes = (await r.sizes()).responseBodySize;
  });
  if (process.env.TRACE) page.on('requestfinished', async (r) => { const t = r.timing(); console.error(r.url().replace(/\?.*/, ''), (t.responseEnd / 1000).toFixed(2), 's', (await r.sizes()).responseBodySize); });
  const t0 = Date.now();
  await page.goto(url, { timeout: 120000 });
  await page.waitForFunction(() => window.bounce && window.bounce.ready, null, { timeout: 300000 });
  const usable = (Date.now() - t0) / 1000;
  const count = await page.textContent('#record-count');
  if (process.env.HIDE_RECORDS) await page.uncheck('#show-records');
  const box = await page.locator('#view canvas').boundingBox();
  const cx = box.x + box.width / 2, cy = box.y + box.height / 2;
  await page.mouse.move(cx, cy);
  await page.mouse.down();
  const c0 = await page.evaluate(() => window.clears), s0 = Date.now();
  for (let i = 0; Date.now() - s0 < 4000; i++) {
    await page.mouse.move(cx + 150 * Math.sin(i / 20), cy + 60 * Math.cos(i / 30));
    await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => r())));
  }
  const frames = (await page.evaluate(() => window.clears)) - c0, seconds = (Date.now() - s0) / 1000;
  await page.mouse.up();
  const still = await page.evaluate(() => window.bounce.timeFrames(10, false));
  const moving = await page.evaluate(() => window.bounce.timeFrames(40, true));
  console.log(`| ${path.basename(scene)} ${res} | ${count} | ${(recordBytes / 1e6).toFixed(1)} MB in ${recordSeconds.toFixed(2)} s | ` +
    `usable in ${usable.toFixed(2)} s | ${(frames / seconds).toFixed(1)} fps dragging (${frames} frames in ${seconds.toFixed(1)} s) | ` +
    `${(1000 / moving).toFixed(1)} fps moving, ${(1000 / still).toFixed(1)} fps full (frames drawn back to back) |`);
} finally {
  await browser.close();
  tool.kill();
}
