// Browser test of the lighting tool (issue 17): Debian's chromium, headless, driven by
// playwright-core (nothing is downloaded). Starts `bounce light` on a copy of the Cornell box,
// then: render, change the light's intensity in the spreadsheet and re-shade (the image's pixels
// must change), drag a sub-viewport and re-gather it (only its pixels may change), and check
// that the 3D view shows as many records as the cache file holds. A screenshot of each step goes
// to the output folder (argv[2], default build/browser-test).
// Exit 77 (CTest: skipped) when chromium or playwright-core is missing, unless
// BOUNCE_REQUIRE_BROWSER=1 (CI), which makes that a failure.
import { spawn, execFileSync } from 'node:child_process';
import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import os from 'node:os';
import { fileURLToPath } from 'node:url';

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
const bin = process.env.BOUNCE_BINARY || path.join(root, 'build/bounce');
const outDir = path.resolve(process.argv[2] || path.join(root, 'build/browser-test'));
const chromiumPath = process.env.CHROMIUM || '/usr/bin/chromium';
const required = process.env.BOUNCE_REQUIRE_BROWSER === '1';

function skip(why) {
  console.error(`browser test: ${why}`);
  process.exit(required ? 1 : 77);
}

let chromium;
try { ({ chromium } = await import('playwright-core')); } catch { skip('playwright-core is not installed (npm ci)'); }
if (!fs.existsSync(chromiumPath)) skip(`no chromium at ${chromiumPath} (apt install chromium)`);
if (!fs.existsSync(path.join(root, 'node_modules/three/build/three.module.js'))) skip('three is not installed (npm ci)');

fs.mkdirSync(outDir, { recursive: true });
const work = fs.mkdtempSync(path.join(os.tmpdir(), 'bounce-light-'));
fs.cpSync(path.join(root, 'scenes/cornell'), path.join(work, 'scene'), { recursive: true });

fs.cpSync(path.join(root, 'scenes/shots'), path.join(work, 'shots'), { recursive: true });
fs.cpSync(path.join(root, 'scenes/cornell'), path.join(work, 'cornell'), { recursive: true });

// Waits without a timeout of their own: under ThreadSanitizer on a loaded 2-core machine a
// request the page makes after a render can take tens of seconds (30 s, Playwright's default,
// was once too short for an edit's answer).
const slowWait = 120000;

/// `bounce light` on `scene` (small and quick); resolves to [server, url].
async function startLight(scene, out) {
  const server = spawn(bin, ['light', scene, '--port', '0', '--out', out, '--threads', '2', '--set', 'camera.resolution=[160,120]',
    '--set', 'render.spp=1', '--set', 'render.rays=128', '--set', 'render.light_samples=2'], { stdio: ['ignore', 'pipe', 'inherit'] });
  const url = await new Promise((resolve, reject) => {
    let text = '';
    server.stdout.on('data', (d) => { text += d; const m = text.match(/(http:\/\/\S+)\s/); if (m) resolve(m[1]); });
    server.on('exit', (code) => reject(new Error(`bounce light exited with ${code}`)));
    setTimeout(() => reject(new Error('bounce light printed no URL')), 120000);  // a loaded machine under TSan
  });
  return [server, url];
}
const [server, url] = await startLight(path.join(work, 'scene/cornell.json'), path.join(work, 'out'));
let shotServer = null;

let failures = 0;
function check(ok, what) {
  console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`);
  if (!ok) failures++;
}

/// Waits until `page` shows a finished render of at least `minVersion`: the status says it is no
/// longer running and the image on the page is that status's own (not a preview answered late).
async function renderDone(page, minVersion) {
  await page.waitForFunction((v) => window.bounce.status && window.bounce.status.state !== 'running' && window.bounce.version >= v &&
    window.bounce.version === window.bounce.status.image.version, minVersion, { timeout: 300000 });
  return page.evaluate(() => window.bounce.status);
}

/// Issue 28's list of what a lighter found, on the glossy Cornell box (a spot light with a handle).
async function lighterFound() {
  const [glossy, glossyUrl] = await startLight(path.join(work, 'cornell/glossy-bump.json'), path.join(work, 'glossy-out'));
  try {
    const a = await browser.newPage({ viewport: { width: 1400, height: 900 } });
    a.setDefaultTimeout(slowWait);
    const errs = [];
    a.on('pageerror', (e) => errs.push(e.message));
    a.on('console', (m) => { if (m.type() === 'error' && !m.text().startsWith('Failed to load resource')) errs.push(m.text()); });
    await a.goto(glossyUrl, { timeout: 120000 });  // the server may be busy with its first render
    await a.waitForFunction(() => window.bounce && window.bounce.ready, null, { timeout: 120000 });
    const imageOf = (page) => page.evaluate(() => {
      const c = document.getElementById('image');
      return Array.from(c.getContext('2d').getImageData(0, 0, c.width, c.height).data);
    });
    await a.click('#rasterize');
    await renderDone(a, 1);
    const cell = (page, key) => page.locator(`input[aria-label="${key}"]`);

    // The range and "needs" columns are in view at 1400 px.
    const panel = await a.locator('#sheet-panel').boundingBox(), needs = await a.locator('#sheet th:last-child').boundingBox();
    check(needs.x + needs.width <= panel.x + panel.width + 1, `the "needs" column is in view (ends at ${needs.x + needs.width}, panel at ${panel.x + panel.width})`);
    // A rejected value leaves the cell at the value in force, and says why.
    await a.fill('#filter', 'lights.0');
    const before = await cell(a, 'lights.0.intensity').inputValue();
    await cell(a, 'lights.0.intensity').fill('-5');
    await cell(a, 'lights.0.intensity').dispatchEvent('change');
    await a.waitForFunction(() => document.getElementById('error').textContent.includes('out of range'));
    check(await cell(a, 'lights.0.intensity').inputValue() === before, `a rejected value goes back to ${before}`);
    // Depth is a ramp, not white; normals show negative components.
    for (const [layer, test, what] of [['depth', (px) => new Set(px.filter((_, i) => i % 4 === 0)).size > 8, 'depth is a ramp of greys'],
      ['N', (px) => px.some((v, i) => i % 4 < 3 && v < 100) && px.some((v, i) => i % 4 < 3 && v > 156), 'N shows negative and positive components']]) {
      await a.selectOption('#layer', layer);
      await a.waitForTimeout(500);
      check(test(await imageOf(a)), what);
    }
    await a.selectOption('#layer', 'beauty');
    await a.waitForTimeout(500);
    // A second page learns of the first page's edits.
    // Another browser context: its own connections, as another lighter's browser would have
    // (in one context a second page's first requests sometimes queued behind the first page's
    // connections under load; docs/lighting-tool.md).
    const other = await browser.newContext({ viewport: { width: 1400, height: 900 } });
    const b = await other.newPage();
    b.setDefaultTimeout(slowWait);
    await b.goto(glossyUrl, { timeout: 120000 });  // the server may be busy with its first render
    await b.waitForFunction(() => window.bounce && window.bounce.ready, null, { timeout: 120000 });
    await cell(a, 'lights.0.intensity').fill('2000000');
    await cell(a, 'lights.0.intensity').dispatchEvent('change');
    const told = await b.waitForFunction(() => {
      const i = document.querySelector('input[aria-label="lights.0.intensity"]');
      return i && i.value === '2000000';
    }, null, { timeout: 15000 }).then(() => true).catch(() => false);
    check(told, 'the second page shows the first page\'s edit');
    await other.close();
    // The light's handle can be dragged: the spot's position changes through an edit.
    await a.fill('#filter', '');
    await a.locator('#view-panel').scrollIntoViewIfNeeded();
    // Once the page has rebuilt its handles for the edits so far (a rebuild re-attaches the gizmo).
    await a.waitForFunction(() => window.bounce.status && window.bounce.editsShown === window.bounce.status.edits, null, { timeout: 60000 });
    const was = await cell(a, 'lights.0.position').inputValue();
    // Up to three tries: under ThreadSanitizer a late reply can still rebuild the view mid-gesture.
    let moved = false;
    for (let attempt = 0; attempt < 3 && !moved; attempt++) {
      const [hx, hy] = await a.evaluate(() => window.bounce.handleOnScreen(0));
      await a.mouse.click(hx, hy);
      await a.mouse.move(hx, hy);
      await a.mouse.down();
      await a.mouse.move(hx + 40, hy - 20, { steps: 8 });
      await a.mouse.up();
      moved = await a.waitForFunction((w) => document.querySelector('input[aria-label="lights.0.position"]').value !== w, was,
        { timeout: 10000 }).then(() => true).catch(() => false);
    }
    check(moved, `dragging the light's handle edits its position (was ${was}, now ${await cell(a, 'lights.0.position').inputValue()})`);
    // Stop leaves the image the render started from, not its partial preview.
    const shown = await imageOf(a), v = await a.evaluate(() => window.bounce.version);
    await a.fill('#filter', 'render.rays');
    await cell(a, 'render.rays').fill('40000');
    await cell(a, 'render.rays').dispatchEvent('change');
    await a.click('#regather');
    await a.waitForFunction((w) => window.bounce.version > w, v, { timeout: 60000 });
    await a.click('#stop');
    const stopped = await renderDone(a, v + 2);
    check(stopped.state === 'cancelled', `the render was stopped (${stopped.state})`);
    await a.waitForTimeout(500);
    const after = await imageOf(a);
    check(after.length === shown.length && after.every((x, i) => x === shown[i]), 'after Stop the page shows the image from before the render');
    check(errs.length === 0, `no page errors on the glossy box${errs.length ? ': ' + errs.join('; ') : ''}`);
    await a.screenshot({ path: path.join(outDir, '6-lighter-found.png'), fullPage: true, timeout: 120000 });
    await a.close();
  } finally {
    glossy.kill();
  }
}

/// Issue 50: only the page the printed URL opened drives the tool. Another origin's page (here
/// another port of this machine: the same site, so the tool's SameSite cookie goes with its
/// requests) posts an edit as a CSRF page would, with a "simple" request that needs no
/// preflight; a browser without the token opens the tool. Both are refused; nothing changes.
async function attackers() {
  // The lighter's own page in a context of its own (a page made by browser.newPage cannot share
  // its context): it holds the tool's cookie when the attacker's page opens beside it.
  const lighter = await browser.newContext();
  const page = await lighter.newPage();
  await page.goto(url, { timeout: 120000 });
  const tool = new URL(url).origin;
  const edit = JSON.stringify({ key: 'render.min_spacing', value: 2.5 });
  const evil = http.createServer((req, res) => {
    res.writeHead(200, { 'Content-Type': 'text/html' });
    // Issue 65: it also frames the tool, as a clickjacking page would under an invisible overlay.
    res.end(`<!doctype html><iframe id="framed" src="${tool}/"></iframe><script>
      const post = (type) => fetch(${JSON.stringify(tool)} + '/api/edit', { method: 'POST', mode: 'no-cors', credentials: 'include',
        headers: { 'Content-Type': type }, body: ${JSON.stringify(edit)} }).then(() => 'sent', () => 'failed');
      window.tries = Promise.all([post('text/plain'), post('application/x-www-form-urlencoded')]);
    </script>`);
  });
  await new Promise((resolve) => evil.listen(0, '127.0.0.1', resolve));
  try {
    const evilPage = await lighter.newPage();
    await evilPage.goto(`http://127.0.0.1:${evil.address().port}/`);
    const sent = await evilPage.evaluate(() => window.tries);
    // The browser refuses to show the tool inside another origin's page (frame-ancestors 'none'):
    // the frame holds an error page, with no Update button to be clicked.
    await evilPage.waitForLoadState('load');
    const framed = evilPage.frames().find((f) => f !== evilPage.mainFrame());
    const buttons = framed ? await framed.evaluate(() => document.querySelectorAll('#update, #rasterize').length).catch(() => 0) : 0;
    check(framed && buttons === 0, `another origin's page cannot frame the tool (frame ${framed && framed.url()}, ${buttons} buttons in it)`);
    await evilPage.close();
    const rows = await page.evaluate(() => fetch('/api/params').then((r) => r.json()));
    const spacing = rows.find((r) => r.key === 'render.min_spacing');
    check(sent.length === 2 && spacing && spacing.value !== 2.5,
      `another origin's page posted an edit (${sent.join(', ')}) and the tool did not apply it (min_spacing ${spacing && spacing.value})`);
  } finally {
    evil.close();
    await lighter.close();
  }
  const stranger = await browser.newContext();
  const answer = await (await stranger.newPage()).goto(tool + '/', { timeout: 120000 });
  const body = await answer.text();
  check(answer.status() === 403 && body.includes('token'), `a browser without the token is refused (${answer.status()}: ${body.slice(0, 80)})`);
  const api = await (await stranger.newPage()).goto(tool + '/api/params?token=wrong' + new URL(url).searchParams.get('token'));
  check(api.status() === 403, `a wrong token is refused (${api.status()})`);
  await stranger.close();
}

const browser = await chromium.launch({ executablePath: chromiumPath, args: ['--no-sandbox', '--enable-unsafe-swiftshader', '--use-angle=swiftshader'] });
try {
  const page = await browser.newPage({ viewport: { width: 1400, height: 900 } });
  page.setDefaultTimeout(slowWait);
  const errors = [];
  page.on('pageerror', (e) => errors.push(e.message));
  // three reports misuse (e.g. adding a non-Object3D) on the console, not as exceptions.
  page.on('console', (m) => { if (m.type() === 'error' && !m.text().startsWith('Failed to load resource')) errors.push(m.text()); });
  await page.goto(url, { timeout: 120000 });  // the server may be busy with its first render
  await page.waitForFunction(() => window.bounce && window.bounce.ready, null, { timeout: 120000 });
  check(await page.isVisible('#hint') && (await page.textContent('#hint')).includes('Update'),
    'a page with nothing rendered says to press Update');
  await attackers();

  const waitDone = (minVersion) => renderDone(page, minVersion);
  const pixels = () => page.evaluate(() => {
    const c = document.getElementById('image');
    return Array.from(c.getContext('2d').getImageData(0, 0, c.width, c.height).data);
  });
  const shot = (name) => page.screenshot({ path: path.join(outDir, name), fullPage: true, timeout: 120000 });

  // 1. The first render: a new deep file and cache.
  await page.click('#rasterize');
  let s = await waitDone(1);
  check(s.state === 'done', `first render finished (${s.state} ${s.message})`);
  check(!(await page.isVisible('#hint')), 'the hint is gone once there is an image');
  const first = await pixels();
  check(first.length === 160 * 120 * 4, 'the image is 160x120');
  await shot('1-render.png');

  // 2. The light's intensity in the spreadsheet, then a re-shade.
  await page.fill('#filter', 'light.emission');
  const input = page.locator('input[aria-label="materials.light.emission"]');
  await input.fill('[40, 28, 9]');
  await input.dispatchEvent('change');
  await page.waitForFunction(() => document.getElementById('pending').textContent.includes('re-shade'));
  const v1 = await page.evaluate(() => window.bounce.version);
  await page.click('#reshade');
  s = await waitDone(v1 + 1);
  const second = await pixels();
  let changed = 0;
  for (let i = 0; i < first.length; i++) changed += first[i] !== second[i];
  check(s.state === 'done' && changed > 1000, `the re-shade changed the image (${changed} channel values)`);
  check(s.stats.records_new === 0 && !(s.stats.phases_s || {}).visibility, 're-shade: 0 new records, no visibility pass');
  const staleShown = await page.waitForFunction(() => document.getElementById('pending').textContent.includes('bounce light is stale'),
    null, { timeout: 10000 }).then(() => true, () => false);
  check(staleShown, 'after the re-shade the page says the bounce light is stale (not "nothing pending")');
  await shot('2-reshade.png');

  // 3. A sub-viewport: drag a rectangle, re-gather it.
  await page.check('#region-mode');
  const box = await page.locator('#image').boundingBox();
  await page.mouse.move(box.x + box.width * 0.25, box.y + box.height * 0.25);
  await page.mouse.down();
  await page.mouse.move(box.x + box.width * 0.6, box.y + box.height * 0.7, { steps: 5 });
  await page.mouse.up();
  const crop = await page.evaluate(() => window.bounce.crop);
  check(Array.isArray(crop) && crop[1] > crop[0] && crop[3] > crop[2], `a rectangle was dragged (${crop})`);
  const v2 = await page.evaluate(() => window.bounce.version);
  await page.click('#regather');
  s = await waitDone(v2 + 1);
  const third = await pixels();
  let outside = 0;
  for (let y = 0; y < 120; y++)
    for (let x = 0; x < 160; x++) {
      if (x >= crop[0] && x < crop[1] && y >= crop[2] && y < crop[3]) continue;
      for (let c = 0; c < 4; c++) outside += third[4 * (y * 160 + x) + c] !== second[4 * (y * 160 + x) + c];
    }
  check(s.state === 'done' && s.stats.records_new > 0, `the sub-viewport was re-gathered (${s.stats.records_new} new records)`);
  check(outside === 0, `nothing outside the rectangle changed (${outside})`);
  await shot('3-subviewport.png');

  // 4. The 3D view shows the cache's records.
  // The view refreshes its records after the re-gather; a slow build (ThreadSanitizer) may
  // still show the count of the render before it, so wait for the cache's count first.
  const info = JSON.parse(execFileSync(bin, ['cache', 'info', path.join(work, 'out/session.bic'), '--json']).toString());
  await page.waitForFunction((n) => +document.getElementById('record-count').dataset.count === n, info.records,
                             { timeout: 60000 }).catch(() => {});
  const shown = await page.evaluate(() => +document.getElementById('record-count').dataset.count);
  check(shown === info.records, `the 3D view shows ${shown} records; the cache holds ${info.records}`);
  await page.selectOption('#record-shape', 'discs');
  await page.waitForFunction(() => window.bounce.recordsDrawn === 'discs');
  check(+(await page.evaluate(() => document.getElementById('record-count').dataset.count)) === info.records,
    'the records drawn as discs of their radius: the same count');
  await page.locator('#view-panel').scrollIntoViewIfNeeded();
  await shot('4-view.png');
  // Saving says where the file went (it said nothing).
  await page.fill('#save-scene-name', 'saved-by-test.json');
  await page.click('#save-scene');
  const saved = await page.waitForFunction(() => document.getElementById('saved').textContent.includes('saved-by-test.json'), null,
    { timeout: 30000 }).then(() => true).catch(() => false);
  check(saved && fs.existsSync(path.join(work, 'scene/saved-by-test.json')), `the page confirms the saved scene (${await page.textContent('#saved')})`);
  check(errors.length === 0, `no page errors${errors.length ? ': ' + errors.join('; ') : ''}`);

  // An edit of an object's geometry (here through the API, as a pipeline script would) asks for
  // a new deep file, and the header says so.
  await page.evaluate(() => fetch('/api/edit', { method: 'POST', headers: { 'Content-Type': 'application/json' },
    body: JSON.stringify({ key: 'objects.6.subdivision', value: 'catmull-clark' }) }));
  const askedDeep = await page.waitForFunction(() => document.getElementById('pending').textContent.includes('new deep file'), null,
    { timeout: 30000 }).then(() => true).catch(() => false);
  check(askedDeep, `an object's geometry edit asks for a new deep file (${await page.textContent('#pending')})`);

  // 5. A shot: the frame slider steps frames as `bounce render --frames` does (the same plans
  // from the same kept state), every frame leaves its cache, and the 3D view shows the
  // current frame's records; the cache-sequence slider plays them.
  let shotUrl;
  const shotSets = ['camera.resolution=[160,120]', 'render.spp=1', 'render.rays=128', 'render.light_samples=2'];
  [shotServer, shotUrl] = await startLight(path.join(work, 'shots/cornell-rolling.json'), path.join(work, 'shot-out'));
  await page.goto(shotUrl, { timeout: 120000 });  // the server may be busy with its first render
  await page.waitForFunction(() => window.bounce && window.bounce.ready, null, { timeout: 120000 });
  await page.click('#rasterize');
  s = await waitDone(1);
  const f1 = await pixels();
  check(await page.isVisible('#shot-frame'), 'an animated scene shows the frame slider');
  const step = async (frame) => {
    const v = await page.evaluate(() => window.bounce.version);
    await page.locator('#shot-frame').fill(String(frame));
    await page.locator('#shot-frame').dispatchEvent('change');
    return waitDone(v + 1);
  };
  s = await step(2);
  const f2 = await pixels();
  execFileSync(bin, ['render', path.join(work, 'shots/cornell-rolling.json'), '-q', '--threads', '2', '--gi', 'cache', '--frames', '1-2',
    ...shotSets.flatMap((x) => ['--set', x]), '--set', 'render.light_parts=true', '-o', path.join(work, 'cli.####.exr'),
    '--stats-json', path.join(work, 'cli.####.json')]);
  const cli = JSON.parse(fs.readFileSync(path.join(work, 'cli.0002.json')));
  const cliPixels = await page.evaluate(async (png) => {
    const img = new Image();
    img.src = 'data:image/png;base64,' + png;
    await img.decode();
    const c = new OffscreenCanvas(img.width, img.height), g = c.getContext('2d');
    g.drawImage(img, 0, 0);
    return Array.from(g.getImageData(0, 0, img.width, img.height).data);
  }, fs.readFileSync(path.join(work, 'cli.0002.png')).toString('base64'));
  let differ = 0;
  for (let i = 0; i < f2.length; i++) differ += f2[i] !== cliPixels[i];
  check(cliPixels.length === f2.length && differ === 0, `the slider's frame 2 after frame 1 is --frames 1-2's frame 2 (${differ} values differ)`);
  const same = ['records', 'records_new', 'records_kept', 'records_moved', 'records_regathered', 'records_reshaded'].filter((k) => s.stats[k] !== cli[k]);
  check(same.length === 0 && s.stats.rays.gather === cli.rays.gather,
    `and its statistics match (${s.stats.records_new} new, ${s.stats.records_reshaded} re-shaded, ${s.stats.rays.gather} gather rays; differ: ${same.join(', ')})`);
  s = await step(3);
  const f3 = await pixels();
  let moved = 0;
  for (let i = 0; i < f1.length; i++) moved += f1[i] !== f3[i];
  check(s.state === 'done' && s.frame === 3 && moved > 100, `frame 3 rendered (${s.state}, frame ${s.frame}, ${moved} values changed)`);
  const cacheStart = s.stats.plan && s.stats.plan.steps.find((step) => step.step === "cache start");
  check(cacheStart && cacheStart.from === "previous frame's records, judged",
    `frame 3 was planned from frame 2's records (${cacheStart && cacheStart.from})`);
  const count = (frame) => JSON.parse(execFileSync(bin, ['cache', 'info', path.join(work, `shot-out/session.000${frame}.bic`), '--json'])).records;
  const shownCount = async (n) => {
    await page.waitForFunction((m) => +document.getElementById('record-count').dataset.count === m, n, { timeout: 60000 }).catch(() => {});
    return page.evaluate(() => [+document.getElementById('record-count').dataset.count, document.getElementById('record-count').textContent]);
  };
  let [n, text] = await shownCount(count(3));
  check(n === count(3) && text.includes('frame 3'), `the 3D view shows frame 3's records: ${text}; its cache holds ${count(3)}`);
  // Play the cache sequence from its start: the slider walks the frames' caches.
  await page.evaluate(() => { const f = document.getElementById('frame'); f.value = 0; f.dispatchEvent(new Event('input')); });
  [n, text] = await shownCount(count(1));
  check(n === count(1) && text.includes('frame 1'), `the cache sequence starts at frame 1's records: ${text}`);
  await page.click('#play');
  [n, text] = await shownCount(count(3));
  check(n === count(3) && text.includes('frame 3'), `play reaches frame 3's records: ${text}`);
  await shot('5-shot-frame.png');
  check(errors.length === 0, `no page errors${errors.length ? ': ' + errors.join('; ') : ''}`);
  shotServer.kill();
  shotServer = null;
  await lighterFound();
} finally {
  await browser.close();
  server.kill();
  if (shotServer) shotServer.kill();
  fs.rmSync(work, { recursive: true, force: true });
}
console.log(failures ? `${failures} check(s) failed` : `all checks passed; screenshots in ${outDir}`);
process.exit(failures ? 1 : 0);
