// The lighting tool's page: spreadsheet, render window and 3D view over the JSON API of
// src/bounce/tool/server.cpp (docs/lighting-tool.md).
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { TransformControls } from 'three/addons/controls/TransformControls.js';

const $ = (id) => document.getElementById(id);
const state = { version: -1, crop: null, running: false, edited: new Set() };
window.bounce = state;  // for the browser test

function showError(msg) { $('error').textContent = msg || ''; }

async function api(path, body) {
  const opts = body === undefined ? {} : { method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(body) };
  let res = await fetch(path, opts);
  // A busy tool answers 503 with Retry-After (never a reset): ask again, a few times.
  for (let tries = 0; res.status === 503 && tries < 5; ++tries) {
    await new Promise((r) => setTimeout(r, 1000 * (+res.headers.get('Retry-After') || 1)));
    res = await fetch(path, opts);
  }
  const type = res.headers.get('Content-Type') || '';
  const data = type.includes('json') ? await res.json() : await res.arrayBuffer();
  if (!res.ok) throw new Error(data.error || `${path}: ${res.status}`);
  return { data, res };
}

/// View arrays (records, triangles) as float32 bytes, not JSON numbers: Sponza's records are
/// 4 MB so, against 18.7 MB of JSON the server gzipped for over half a minute. The layout comes in X-Meta.
async function arrays(path) {
  const { data, res } = await api(path + (path.includes('?') ? '&' : '?') + 'format=binary');
  const meta = JSON.parse(res.headers.get('X-Meta'));
  let at = 0;
  for (const [name, length] of meta.arrays) { meta[name] = new Float32Array(data, at, length); at += 4 * length; }
  return meta;
}

// ---- spreadsheet ----
function shown(v) { return v === null || v === undefined ? '' : typeof v === 'string' ? v : JSON.stringify(v); }
function parsed(text) { try { return JSON.parse(text); } catch { return text; } }

async function loadParams() {
  const { data: rows } = await api('/api/params');
  const body = $('sheet').tBodies[0];
  body.innerHTML = '';
  for (const r of rows) {
    const tr = document.createElement('tr');
    tr.dataset.key = r.key;
    if (state.edited.has(r.key)) tr.classList.add('edited');
    const range = Array.isArray(r.range) ? `${+r.range[0].toPrecision(6)} .. ${+r.range[1].toPrecision(6)}` : '';
    tr.innerHTML = `<td title="${r.doc || ''}"></td><td><input></td><td></td><td>${r.unit || ''}</td><td>${range}</td><td>${r.needs}</td>`;
    tr.cells[0].textContent = r.key;
    tr.cells[2].textContent = shown(r.default);
    const input = tr.querySelector('input');
    input.value = shown(r.value);
    input.dataset.accepted = input.value;  // what the server holds: a rejected edit goes back to it
    input.setAttribute('aria-label', r.key);
    input.addEventListener('change', () => edit(r.key, input, tr));
    body.appendChild(tr);
  }
  filterRows();
}

async function edit(key, input, tr) {
  try {
    const { data } = await api('/api/edit', { key, value: parsed(input.value) });
    input.dataset.accepted = input.value;
    input.classList.remove('bad');
    tr.classList.add('edited');
    state.edited.add(key);
    showError('');
    await refreshStatus();
    return data;
  } catch (e) {
    // The cell shows the value in force again; the message says what was refused and why.
    input.value = input.dataset.accepted;
    input.classList.add('bad');
    showError(e.message);
  }
}

function filterRows() {
  const f = $('filter').value.toLowerCase();
  for (const tr of $('sheet').tBodies[0].rows) tr.style.display = tr.dataset.key.toLowerCase().includes(f) ? '' : 'none';
}

// ---- render window ----
async function render(action) {
  try {
    const body = action ? { action } : {};
    if (state.crop && $('region-mode').checked) body.crop = state.crop;
    await api('/api/render', body);
    showError('');
    state.running = true;
    poll();
  } catch (e) { showError(e.message); }
}

const VALUE_LAYERS = new Set(['N', 'bentnormal', 'depth', 'ao', 'refined']);

async function fetchImage() {
  // Nothing rendered yet: there is no image to ask for.
  if (!state.status || !state.status.image.layers.length) return;
  const layer = $('layer').value, exposure = $('exposure').value;
  try {
    const { data, res } = await api(`/api/image?layer=${encodeURIComponent(layer)}&exposure=${exposure}`);
    // Two fetches can overlap (a render's poll and the once-a-second listener): an image older
    // than the one shown, e.g. a preview answered late, must not replace the finished frame.
    const version = +res.headers.get('X-Version');
    if (version < state.version) return;
    const w = +res.headers.get('X-Width'), h = +res.headers.get('X-Height');
    const canvas = $('image');
    canvas.width = w; canvas.height = h;
    canvas.getContext('2d').putImageData(new ImageData(new Uint8ClampedArray(data), w, h), 0, 0);
    state.version = version;
  } catch (e) { showError(e.message); }
}

const STAT_KEYS = [['phases_s', 'visibility', 's'], ['phases_s', 'gather', 's'], ['phases_s', 'shading', 's'], ['records', null, ''],
  ['records_new', null, ''], ['records_kept', null, ''], ['records_moved', null, ''], ['records_regathered', null, ''],
  ['records_reshaded', null, ''], ['refined_fragments', null, ''], ['rays_per_gather', null, 'rays/record'], ['gather_rays_per_pixel', null, 'M rays/MP'],
  ['shading_misses', null, ''], ['total_s', null, 's']];

function showStats(stats) {
  const body = $('stats').tBodies[0];
  body.innerHTML = '';
  for (const [k, sub, unit] of STAT_KEYS) {
    let v = stats[k];
    if (sub) v = v ? v[sub] : undefined;
    if (v === undefined) v = sub ? 0 : undefined;
    if (v === undefined) continue;
    const tr = body.insertRow();
    tr.insertCell().textContent = sub ? `${sub} time` : k === 'gather_rays_per_pixel' ? 'gather rays' : k.replaceAll('_', ' ');
    // Counts are shown whole (13 898 records, as the status and `bounce cache info` say); times and rates to 4 digits.
    tr.insertCell().textContent = `${typeof v === 'number' ? (Number.isInteger(v) ? v : +v.toPrecision(4)) : v} ${unit}`;
    tr.dataset.stat = sub || k;
  }
}

/// What each render action does, as the header says it (the status carries the action's name).
const ACTION_WORDS = { reshade: 're-shade', regather: 're-gather', rasterize: 'new deep file', frame: 'frame' };

async function refreshStatus() {
  const { data: s } = await api('/api/status');
  // Answers can arrive out of order (the once-a-second listener's and a render's own polls): an
  // older snapshot than the one shown would say a running render is done. The server numbers them.
  if (state.status && s.serial <= state.status.serial) return state.status;
  // A light edit re-shaded over the old records: the bounce light is the old lights' until a re-gather.
  const stale = s.bounce_stale ? 'bounce light is stale: Re-gather to update it' : '';
  $('pending').textContent = [s.pending ? `pending: ${ACTION_WORDS[s.pending]}` : '', stale].filter(Boolean).join(' · ');
  const p = s.progress;
  $('bar').style.width = p.total ? `${100 * p.done / p.total}%` : s.state === 'done' ? '100%' : '0';
  // A slider move renders the frames up to the one asked for in order (each frame's records
  // depend on the frames before it, as on the farm): say which one is being rendered.
  const replay = s.replay && s.replay.from < s.replay.to
    ? ` — frame ${s.frame} of ${s.replay.from}-${s.replay.to}: frames are rendered in order so frame ${s.replay.to} is the farm's` : '';
  $('unread').textContent = (s.unread || []).join('\n');
  $('progress-text').textContent = `${s.state}${s.action ? ' (' + ACTION_WORDS[s.action] + ')' : ''}${p.phase ? ': ' + p.phase : ''}${replay}${s.message ? ' — ' + s.message : ''}`;
  switch (s.state) {
    case 'failed': showError(s.message); break;
    case 'idle': case 'running': case 'done': case 'cancelled': break;
    default: showError(`unknown session state ${s.state}`);
  }
  const sel = $('layer');
  if (s.image.layers.length && sel.options.length !== s.image.layers.length) {
    const cur = sel.value;
    sel.innerHTML = s.image.layers.map((l) => `<option>${l}</option>`).join('');
    sel.value = s.image.layers.includes(cur) ? cur : 'beauty';
  }
  if (s.shot && s.shot.animated) {
    $('shot-label').hidden = false;
    const f = $('shot-frame');
    f.min = s.shot.first, f.max = s.shot.last;
    if (document.activeElement !== f) f.value = s.frame;
    $('shot-frame-value').textContent = s.frame;
  }
  state.status = s;  // newer than the one shown (checked above): fetchImage reads it
  if (s.image.version !== state.version) await fetchImage();
  // A page that has never rendered is black: say how to start.
  $('hint').hidden = s.image.layers.length > 0 || s.state === 'running';
  if (s.state !== 'running') {
    // Keyed on the finished render's version, not on seeing it run: the once-a-second listener's
    // status can arrive after a render started and still say "done" (the render before it).
    if (state.running || s.image.version !== state.recordsOf) {
      state.recordsOf = s.image.version;
      showStats(s.stats); state.recordsLoading = Promise.all([loadRecords(), loadCacheFiles()]);
    }
    state.running = false;
  }
  return s;
}

async function poll() {
  const s = await refreshStatus().catch((e) => showError(e.message));
  if (s && s.state === 'running') setTimeout(poll, 150);
}

function setupRegion() {
  const canvas = $('image'), rect = $('rect');
  let start = null;
  const toPixel = (e) => {
    const b = canvas.getBoundingClientRect();
    return [Math.round((e.clientX - b.left) * canvas.width / b.width), Math.round((e.clientY - b.top) * canvas.height / b.height)];
  };
  canvas.addEventListener('mousedown', (e) => { if ($('region-mode').checked) { start = toPixel(e); e.preventDefault(); } });
  window.addEventListener('mousemove', (e) => {
    if (!start) return;
    const [x, y] = toPixel(e);
    const clamp = (v, hi) => Math.max(0, Math.min(hi, v));
    const x0 = clamp(Math.min(start[0], x), canvas.width), x1 = clamp(Math.max(start[0], x), canvas.width);
    const y0 = clamp(Math.min(start[1], y), canvas.height), y1 = clamp(Math.max(start[1], y), canvas.height);
    state.crop = x1 > x0 && y1 > y0 ? [x0, x1, y0, y1] : null;
    const s = canvas.getBoundingClientRect().width / canvas.width;
    Object.assign(rect.style, { display: 'block', left: `${x0 * s}px`, top: `${y0 * s}px`, width: `${(x1 - x0) * s}px`, height: `${(y1 - y0) * s}px` });
  });
  window.addEventListener('mouseup', () => { start = null; });
  $('region-mode').addEventListener('change', () => { if (!$('region-mode').checked) rect.style.display = 'none'; });
}

// ---- 3D view ----
const view = {};
// Level of detail while the camera moves: software WebGL (the browser test's SwiftShader) takes
// ~0.3 s for a full frame of Sponza (66 k triangles, 93 k records), so a moving view draws half
// the resolution, at most this many triangles and records, and the full view once it stops.
const kMoving = { triangles: 6000, records: 8000, pixelRatio: 0.35 };

/// An order of n items whose every prefix is spread evenly over them (a stride coprime to n), so
/// a draw range of the first k is a decimated view of all.
function evenOrder(n) {
  let step = Math.max(1, Math.round(n * 0.6180339887));
  const gcd = (a, b) => (b ? gcd(b, a % b) : a);
  while (n > 1 && gcd(step, n) !== 1) step++;
  return Uint32Array.from({ length: n }, (_, k) => (k * step) % n);
}

/// Milliseconds per frame of `n` frames drawn as the orbit moves the camera (bench/tool-open.mjs):
/// each waits for the GPU (one pixel read back), as the next frame on screen would.
state.timeFrames = (n, moving) => {
  setMoving(moving);
  const gl = view.renderer.getContext(), px = new Uint8Array(4), t0 = performance.now();
  for (let i = 0; i < n; i++) {
    view.camera.position.applyAxisAngle(new THREE.Vector3(0, 1, 0), 0.02);
    view.camera.lookAt(view.orbit.target);
    view.renderer.render(view.scene, view.camera);
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
  }
  const ms = (performance.now() - t0) / n;
  setMoving(false);
  return ms;
};

function setMoving(moving) {
  view.moving = moving;
  view.renderer.setPixelRatio(window.devicePixelRatio * (moving ? kMoving.pixelRatio : 1));
  if (view.geometry) view.geometry.geometry.setDrawRange(0, moving ? 3 * kMoving.triangles : Infinity);
  if (view.records && view.records.isPoints) view.records.geometry.setDrawRange(0, moving ? kMoving.records : Infinity);
  redraw();
}

function initView() {
  const el = $('view');
  view.renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  view.renderer.setSize(el.clientWidth, el.clientHeight);
  el.appendChild(view.renderer.domElement);
  view.scene = new THREE.Scene();
  view.camera = new THREE.PerspectiveCamera(45, el.clientWidth / el.clientHeight, 0.01, 1e7);
  view.orbit = new OrbitControls(view.camera, view.renderer.domElement);
  view.drag = new TransformControls(view.camera, view.renderer.domElement);
  view.drag.addEventListener('dragging-changed', (e) => {
    view.orbit.enabled = !e.value;
    if (!e.value && view.drag.object) moveLight(view.drag.object);
  });
  // TransformControls is no Object3D since three r169: its gizmo is.
  view.scene.add(view.drag.getHelper());
  view.scene.add(new THREE.AmbientLight(0xffffff, 0.6));
  const sun = new THREE.DirectionalLight(0xffffff, 0.8);
  sun.position.set(1, 2, 1.5);
  view.scene.add(sun);
  view.renderer.domElement.addEventListener('click', pickLight);
  // Drawn when something changed, not every frame: an idle page costs no CPU (a software-GL
  // browser drawing continuously slowed the tool's own renders beside it).
  view.orbit.addEventListener('change', redraw);
  view.orbit.addEventListener('start', () => setMoving(true));
  view.orbit.addEventListener('end', () => setMoving(false));
  view.drag.addEventListener('change', redraw);
  redraw();
}

function redraw() {
  if (view.redrawing) return;
  view.redrawing = requestAnimationFrame(() => { view.redrawing = 0; view.renderer.render(view.scene, view.camera); });
}

async function loadScene() {
  const s = await arrays('/api/scene?max_triangles=100000');
  $('scene-name').textContent = state.status ? state.status.scene : '';
  if (view.geometry) view.scene.remove(view.geometry);
  const g = new THREE.BufferGeometry(), order = evenOrder(s.triangles.length / 9);
  const tris = new Float32Array(s.triangles.length);
  order.forEach((t, k) => tris.set(s.triangles.subarray(9 * t, 9 * t + 9), 9 * k));
  g.setAttribute('position', new THREE.Float32BufferAttribute(tris, 3));
  g.computeVertexNormals();
  view.geometry = new THREE.Mesh(g, new THREE.MeshLambertMaterial({ color: 0x888888, side: THREE.DoubleSide, transparent: true, opacity: 0.55 }));
  view.scene.add(view.geometry);
  const c = s.camera;
  const cam = new THREE.PerspectiveCamera(c.fov, c.width / c.height, 0.05 * dist(c.position, c.look_at), dist(c.position, c.look_at));
  cam.position.set(...c.position); cam.up.set(...c.up); cam.lookAt(...c.look_at); cam.updateMatrixWorld(); cam.updateProjectionMatrix();
  if (view.frustum) view.scene.remove(view.frustum);
  view.frustum = new THREE.CameraHelper(cam);
  view.scene.add(view.frustum);
  if (!view.placed) {
    view.camera.position.set(...c.position); view.orbit.target.set(...c.look_at); view.orbit.update(); view.placed = true;
  }
  redraw();  // one frame after this function's changes, the handles' too
  if (view.drag.dragging) return;  // the handles are rebuilt after the drag's own edit
  // Unmoved handles stay as they are: rebuilding them on an edit that moves no light (an
  // intensity) re-attached the gizmo and dropped a drag a lighter was starting.
  const placing = JSON.stringify([s.bounds, s.lights.filter((l) => l.position).map((l) => [l.key, l.position])]);
  if (view.lights && placing === view.placing) return;
  view.placing = placing;
  // The gizmo follows its light to the new handle (a detached handle may not stay attached).
  const held = view.drag.object ? view.drag.object.userData.key : null;
  view.drag.detach();
  for (const h of view.lights || []) view.scene.remove(h);
  const size = dist(s.bounds[0], s.bounds[1]) * 0.015;
  view.lights = s.lights.filter((l) => l.position).map((l) => {
    const m = new THREE.Mesh(new THREE.SphereGeometry(size), new THREE.MeshBasicMaterial({ color: 0xffdd55 }));
    m.position.set(...l.position);
    m.userData = l;
    view.scene.add(m);
    return m;
  });
  const again = view.lights.find((m) => m.userData.key === held);
  if (again && !view.drag.dragging) view.drag.attach(again);
}

function dist(a, b) { return Math.hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]); }

function pickLight(e) {
  const b = view.renderer.domElement.getBoundingClientRect();
  const ray = new THREE.Raycaster();
  ray.setFromCamera(new THREE.Vector2(((e.clientX - b.left) / b.width) * 2 - 1, -((e.clientY - b.top) / b.height) * 2 + 1), view.camera);
  const hit = ray.intersectObjects(view.lights || [])[0];
  if (hit) { view.drag.attach(hit.object); redraw(); }
}

async function moveLight(handle) {
  const l = handle.userData, p = handle.position;
  const off = l.offset || [0, 0, 0];
  let value = [p.x - off[0], p.y - off[1], p.z - off[2]];
  if (l.towards) {  // a distant light: the direction from the handle to the scene's centre
    const d = new THREE.Vector3(l.towards[0] - p.x, l.towards[1] - p.y, l.towards[2] - p.z).normalize();
    value = [d.x, d.y, d.z];
  }
  value = value.map((v) => +v.toPrecision(6));
  const tr = [...$('sheet').tBodies[0].rows].find((r) => r.dataset.key === l.key);
  if (tr) { tr.querySelector('input').value = JSON.stringify(value); await edit(l.key, tr.querySelector('input'), tr); }
}

async function loadRecords() {
  const files = $('cache-file');
  let file = files.value && files.selectedIndex > 0 ? `&file=${encodeURIComponent(files.value)}` : '';
  if ($('records-in-region').checked && state.crop) file += `&region=${state.crop.join(',')}`;
  // Level of detail: discs are triangles each, so fewer of them than points (the count still
  // says how many the cache holds).
  const limit = $('record-shape').value === 'discs' ? 20000 : 200000;
  let r;
  const ask = (state.recordsAsked = (state.recordsAsked || 0) + 1);
  try { r = await arrays(`/api/records?limit=${limit}${file}`); } catch { $('record-count').textContent = 'records: 0'; return; }
  if (ask !== state.recordsAsked) return;  // a later request is on its way: answers may come out of order
  if (view.records) view.scene.remove(view.records);
  const ao = $('record-colour').value === 'ao';
  let max = 1e-9;
  for (let i = 0; i < r.E.length; i++) max = Math.max(max, r.E[i]);
  const colour = (i, c) => (ao ? r.ao[i] : Math.sqrt(r.E[3 * i + c] / max));
  if ($('record-shape').value === 'discs') {
    // One disc per record in its tangent plane, of its validity radius.
    const mesh = new THREE.InstancedMesh(new THREE.CircleGeometry(1, 16), new THREE.MeshBasicMaterial({ side: THREE.DoubleSide }), r.shown);
    const m = new THREE.Matrix4(), q = new THREE.Quaternion(), z = new THREE.Vector3(0, 0, 1), col = new THREE.Color();
    for (let i = 0; i < r.shown; i++) {
      q.setFromUnitVectors(z, new THREE.Vector3(r.n[3 * i], r.n[3 * i + 1], r.n[3 * i + 2]));
      m.compose(new THREE.Vector3(r.p[3 * i], r.p[3 * i + 1], r.p[3 * i + 2]), q, new THREE.Vector3(r.r[i], r.r[i], r.r[i]));
      mesh.setMatrixAt(i, m);
      mesh.setColorAt(i, col.setRGB(colour(i, 0), colour(i, 1), colour(i, 2)));
    }
    view.records = mesh;
  } else {
    const g = new THREE.BufferGeometry(), order = evenOrder(r.shown);
    const points = new Float32Array(r.shown * 3), colours = new Float32Array(r.shown * 3);
    order.forEach((i, k) => { for (let c = 0; c < 3; c++) points[3 * k + c] = r.p[3 * i + c], colours[3 * k + c] = colour(i, c); });
    g.setAttribute('position', new THREE.Float32BufferAttribute(points, 3));
    g.setAttribute('color', new THREE.Float32BufferAttribute(colours, 3));
    view.records = new THREE.Points(g, new THREE.PointsMaterial({ size: 4, sizeAttenuation: false, vertexColors: true }));
  }
  view.records.visible = $('show-records').checked;
  state.recordsDrawn = $('record-shape').value;
  view.scene.add(view.records);
  redraw();
  $('record-count').textContent = `records: ${r.count} (frame ${r.frame})` + (r.in_region !== r.count ? `, ${r.in_region} in the sub-viewport` : '') +
    (r.shown < r.in_region ? `, ${r.shown} drawn` : '');
  $('record-count').dataset.count = r.count;
}

async function loadCacheFiles() {
  const { data: files } = await api('/api/caches');
  const sel = $('cache-file'), cur = sel.value;
  sel.innerHTML = '<option value="">session</option>' + files.map((f) => `<option>${f}</option>`).join('');
  sel.value = files.includes(cur) ? cur : '';
  const seq = files.filter((f) => /\d+\.bic$/.test(f));
  $('frame').max = Math.max(0, seq.length - 1);
  $('frame').dataset.files = JSON.stringify(seq);
}

// ---- other pages ----
// Every page asks the server what changed once a second: edits and renders made from another
// tab show here too (the status carries the session's edit count).
function listen() {
  let edits = state.status ? state.status.edits : 0;
  state.editsShown = edits;  // for the browser test: the spreadsheet and handles show these edits
  setInterval(async () => {
    if (state.running) return;  // poll() is following a render already
    try {
      const s = await refreshStatus();
      if (s.edits !== edits) { edits = s.edits; await loadParams(); await loadScene(); state.editsShown = edits; }
      if (s.state === 'running') { state.running = true; poll(); }
    } catch (e) { showError(e.message); }
  }, 1000);
}

// For the browser test: where light handle `i` is on the screen.
state.handleOnScreen = (i) => {
  const h = view.lights[i], b = view.renderer.domElement.getBoundingClientRect();
  const p = h.position.clone().project(view.camera);
  return [b.left + (p.x + 1) / 2 * b.width, b.top + (1 - p.y) / 2 * b.height];
};

// ---- wiring ----
async function main() {
  for (const a of ['reshade', 'regather', 'rasterize']) $(a).addEventListener('click', () => render(a));
  $('update').addEventListener('click', () => render(null));
  $('stop').addEventListener('click', () => api('/api/stop', {}).then(refreshStatus).catch((e) => showError(e.message)));
  $('layer').addEventListener('change', () => {
    // These layers are values, not light (the server shows them without exposure): say so.
    const value = VALUE_LAYERS.has($('layer').value);
    $('exposure').disabled = value;
    $('exposure').title = value ? 'not light: this layer is shown as values, without exposure' : '';
    fetchImage();
  });
  $('exposure').addEventListener('input', fetchImage);
  $('filter').addEventListener('input', filterRows);
  $('show-records').addEventListener('change', () => {
    if (view.records) { view.records.visible = $('show-records').checked; redraw(); }
  });
  $('record-colour').addEventListener('change', loadRecords);
  $('record-shape').addEventListener('change', loadRecords);
  $('play').addEventListener('click', () => {
    // Plays the cache sequence: one frame every half second, from the slider's position.
    if (view.playing) { clearInterval(view.playing); view.playing = null; return; }
    view.playing = setInterval(() => {
      const f = $('frame');
      if (+f.value >= +f.max) { clearInterval(view.playing); view.playing = null; return; }
      f.value = +f.value + 1;
      f.dispatchEvent(new Event('input'));
    }, 500);
  });
  $('records-in-region').addEventListener('change', loadRecords);
  $('shot-frame').addEventListener('change', async () => {
    try {
      await api('/api/frame', { frame: +$('shot-frame').value });
      showError('');
      state.running = true;
      poll();
    } catch (e) { showError(e.message); }
  });
  $('cache-file').addEventListener('change', loadRecords);
  $('frame').addEventListener('input', () => {
    const seq = JSON.parse($('frame').dataset.files || '[]');
    if (seq.length) { $('cache-file').value = seq[+$('frame').value]; loadRecords(); }
  });
  const post = (path, body) => api(path, body).then(({ data }) => { showError(''); return data; })
    .catch((e) => { showError(e.message); $('saved').textContent = ''; return null; });
  // A save says where the file went (the server answers with its path).
  const saved = (data) => { if (data) $('saved').textContent = `saved ${data.saved}`; return data; };
  $('save-scene').addEventListener('click', () => post('/api/save-scene', { name: $('save-scene-name').value || 'edited.json' }).then(saved));
  $('save-cache').addEventListener('click', () => post('/api/save-cache', { name: $('save-cache-name').value || 'shot.bic' }).then(saved).then(loadCacheFiles));
  $('load-cache').addEventListener('click', () => post('/api/load-cache', { file: $('cache-file').value || $('save-cache-name').value }).then(loadRecords));
  setupRegion();
  initView();
  await refreshStatus();
  // The status has asked for the records unless a render is running (then the last ones are shown).
  await Promise.all([loadParams(), loadScene(), state.recordsLoading || Promise.all([loadRecords(), loadCacheFiles()])]);
  listen();
  state.ready = true;
}

main().catch((e) => showError(e.message));
