// The Task Builder (/task_builder.html): opens a task file of the server's
// --designs folder and draws its world top-down (world_map.js, as the
// console's map); the user drags the start pose (and turns it by its heading
// knob), drags new regions and moves or resizes them, picks objects and
// regions for events of the kinds the executor scores (the list and their
// keys come from the server, from the loader's own table), sets points,
// end_on, success and the time limit. Every change is checked by the server
// as `rise-trainer check` checks a task, its errors shown with their line
// and key; Save writes the YAML atomically or says the file changed on disk
// (409). "Try it" runs the saved task in rise-sim with rise-trainer on the
// sandbox station, opens the virtual panel page of that station (a window
// of its own) for the user to drive, and shows the report when the task ends.
import { drawBuilderNav } from './builder_nav.js';
import { getJson, postJson, el, token, ROBOT_COLOUR } from './common.js';
import { ConflictBanner, errorText, postCheck, saveDesign, edited, showCheck, showSaved } from './design_file.js';
import { worldBounds, mapView, drawWorld, drawObjects, drawRobot, drawRegion } from './world_map.js';

const $ = (id) => document.getElementById(id);
const params = new URLSearchParams(location.search);
const colourHex = '#' + ROBOT_COLOUR.toString(16).padStart(6, '0');
const state = {
  file: '', version: '', task: null, world: null, kinds: [], check: null, checkSeq: 0, dirty: false,
  view: null, drag: null, picked: { region: '', object: '' }, polling: null,
  editing: -1,  // the event the form updates (-1: it adds one)
};
let conflict = null;

const round = (v) => Math.round(v * 100) / 100;
const kindOf = (name) => state.kinds.find((k) => k.kind === name);
const startPose = () => {
  const t = state.task;
  if (t.start) return t.start;
  const s = state.world ? state.world.robot_start : [0, 0, 0];
  return { x: s[0], y: s[1], yaw_deg: (s[2] * 180) / Math.PI };
};

// ---- files ----------------------------------------------------------------
async function loadListing() {
  const l = await getJson('/api/builder/tasks');
  state.kinds = l.kinds;
  $('file').replaceChildren(...l.tasks.map((t) => el('option', { value: t.file }, t.file + (t.error ? ' (does not load)' : ''))));
  $('event-kind').replaceChildren(...state.kinds.map((k) => el('option', { value: k.kind }, k.kind)));
  return l.tasks;
}

async function openFile(file) {
  const r = await getJson('/api/builder/task/' + encodeURIComponent(file));
  state.file = file;
  $('file').value = file;
  state.editing = -1;
  $('add-event').textContent = 'Add event';
  state.version = r.version;
  state.dirty = false;
  conflict.hide();
  $('version').textContent = 'version ' + r.version;
  $('save-state').textContent = '';
  state.world = r.world_json || null;
  state.view = null;
  if (r.load_error) {
    state.task = null;
    state.check = { ok: false, yaml: r.text, errors: r.load_error.split('\n').map((m) => ({ message: m, line: 0, key: '' })) };
  } else {
    state.task = r.task;
    state.check = r.check;
    if (r.world_error) state.check.errors.push({ message: r.world_error, line: 0, key: '' });
  }
  render();
}

// Live check: the newest answer wins (an older request may come back later).
async function check() {
  const answer = await postCheck(state, `/api/builder/task/${encodeURIComponent(state.file)}/check`, { task: state.task });
  if (!answer) return;
  state.check = answer.check;
  render();
}

const changed = () => edited(state, render, check);

async function save(version, file = state.file) {
  $('save').disabled = true;
  const { status, body } = await saveDesign('/api/builder/task/' + encodeURIComponent(file), version, { task: state.task });
  if (status === 409 && file !== state.file) {
    $('save-state').textContent = 'not saved: ' + file + ' exists';  // "save as" a name taken: no banner
    $('save-state').className = 'bad';
  } else if (showSaved(status, body, conflict)) {
    if (file !== state.file) {
      await loadListing();
      state.file = file;
      $('file').value = file;
    }
    Object.assign(state, { version: body.version, dirty: false });
  } else if (body.errors) {
    state.check = body;
  }
  render();
}

// ---- rendering --------------------------------------------------------------

// "events[3].region" → "events[3]": what an error belongs to.
function badEntries() {
  const bad = new Set();
  for (const e of (state.check && state.check.errors) || []) {
    const m = /^(events|regions)\[\d+\]/.exec(e.key || '');
    if (m) bad.add(m[0]);
  }
  return bad;
}

function render() {
  const ok = showCheck(state.check, 'ok: rise-trainer check would load it', (e) => errorText(e, state.file));
  $('save').disabled = !state.task || !ok || !state.dirty;
  $('try').disabled = !state.task || state.dirty;
  $('try').title = state.dirty ? 'save first: it runs the saved file' : '';
  if (!state.task) return;
  const bad = badEntries();
  renderHeader();
  renderRegions(bad);
  renderEvents(bad);
  renderParams();
  drawMap();
}

function renderHeader() {
  const t = state.task, s = startPose();
  const keep = (id, v) => { if (document.activeElement !== $(id)) $(id).value = v; };
  keep('task-name', t.task);
  keep('task-title', t.title);
  keep('time-limit', t.time_limit_s);
  keep('start-x', round(s.x));
  keep('start-y', round(s.y));
  keep('start-yaw', round(s.yaw_deg));
  $('paths').textContent = `robot ${t.robot} · world ${t.world}`;
}

function numberInput(value, onChange, attrs = {}) {
  const i = el('input', Object.assign({ type: 'number', step: '0.1', style: 'width: 5em', value }, attrs));
  i.addEventListener('change', () => { const v = parseFloat(i.value); if (Number.isFinite(v)) onChange(v); });
  return i;
}

function renderRegions(bad) {
  const rows = [el('tr', {}, ...['name', 'min x, y, z', 'max x, y, z', 'comment', ''].map((h) => el('th', {}, h)))];
  state.task.regions.forEach((r, i) => {
    const corner = (key) => el('td', {}, ...[0, 1, 2].map((k) => numberInput(round(r[key][k]), (v) => { r[key][k] = v; changed(); },
      { class: `region-${key}`, 'data-region': r.name })));
    const del = el('button', { class: 'delete-region', 'data-region': r.name }, 'delete');
    del.addEventListener('click', () => { state.task.regions.splice(i, 1); changed(); });
    rows.push(el('tr', { class: bad.has(`regions[${i}]`) ? 'bad' : '', 'data-region': r.name }, el('td', {}, r.name),
                 corner('min'), corner('max'), el('td', {}, r.comment || ''), el('td', {}, del)));
  });
  $('regions').replaceChildren(...rows);
}

// An event's kind-specific keys, as "region: near_object, hold_s: 1".
function paramText(e) {
  const k = kindOf(e.kind);
  return ((k && k.params) || []).map((p) => {
    const v = e[p.key];
    if (p.type === 'names') return v && v.length ? `${p.key}: [${v.join(', ')}]` : '';
    if ((p.type === 'seconds' || p.type === 'metres') && !p.required && !v) return '';
    if (p.type === 'per' && v !== 'second') return '';
    return `${p.key}: ${v}`;
  }).filter(Boolean).join(', ');
}

function renderEvents(bad) {
  const t = state.task;
  const rows = [el('tr', {}, ...['name', 'kind', 'keys', 'points', 'end on', 'success', 'comment', ''].map((h) => el('th', {}, h)))];
  t.events.forEach((e, i) => {
    const points = numberInput(e.points, (v) => { e.points = Math.round(v); changed(); }, { step: '1', class: 'points', 'data-event': e.name });
    const box = (list, cls) => {
      const c = el('input', { type: 'checkbox', class: cls, 'data-event': e.name });
      c.checked = t[list].includes(e.name);
      c.addEventListener('change', () => {
        t[list] = t[list].filter((n) => n !== e.name);
        if (c.checked) t[list].push(e.name);
        changed();
      });
      return c;
    };
    const edit = el('button', { class: 'edit-event', 'data-event': e.name }, 'edit');
    edit.addEventListener('click', () => editEvent(i));
    const del = el('button', { class: 'delete-event', 'data-event': e.name }, 'delete');
    del.addEventListener('click', () => {
      state.editing = -1;
      t.events.splice(i, 1);
      t.end_on = t.end_on.filter((n) => n !== e.name);
      t.success = t.success.filter((n) => n !== e.name);
      changed();
    });
    rows.push(el('tr', { class: bad.has(`events[${i}]`) ? 'bad' : '', 'data-event': e.name }, el('td', {}, e.name), el('td', {}, e.kind),
                 el('td', {}, paramText(e)), el('td', {}, points), el('td', {}, box('end_on', 'end-on')),
                 el('td', {}, box('success', 'success')), el('td', {}, e.comment || ''), el('td', {}, edit, del)));
  });
  $('events').replaceChildren(...rows);
}

// The new event's inputs for its kind's keys (regions: the task's and the world's; objects: the world's).
function renderParams() {
  const k = kindOf($('event-kind').value);
  if (!k) return;
  const box = $('event-params');
  if (box.dataset.kind === k.kind && box.dataset.names === names().join()) return syncPicked();
  box.dataset.kind = k.kind;
  box.dataset.names = names().join();
  $('kind-what').textContent = `${k.kind}: ${k.what}` + (k.params.length ? ' — ' + k.params.map((p) => `${p.key}: ${p.what}`).join('; ') : '');
  if (document.activeElement !== $('event-max')) $('event-max').value = k.default_max_count;
  box.replaceChildren(...k.params.map((p) => {
    let input;
    if (p.type === 'region' || p.type === 'object') {
      const options = p.type === 'region' ? regionNames() : objectNames();
      input = el('select', { id: 'param-' + p.key }, ...options.map((n) => el('option', { value: n }, n)));
    } else if (p.type === 'per') {
      input = el('select', { id: 'param-' + p.key }, el('option', { value: 'collision' }, 'collision'), el('option', { value: 'second' }, 'second'));
    } else if (p.type === 'names') {
      input = el('input', { id: 'param-' + p.key, size: '14', placeholder: 'a, b' });
    } else {
      input = el('input', { id: 'param-' + p.key, type: 'number', step: '0.1', min: '0', size: '4', value: p.required ? '10' : '0' });
    }
    return el('label', { title: p.what }, p.key + (p.required ? '' : ' (optional)') + ' ', input);
  }));
  syncPicked();
}

const regionNames = () => [...state.task.regions.map((r) => r.name), ...((state.world && state.world.regions) || []).map((r) => r.name)];
const objectNames = () => ((state.world && state.world.objects) || []).map((o) => o.name);
const names = () => [...regionNames(), '|', ...objectNames()];

// What was last clicked on the map goes into the form's region/object.
function syncPicked() {
  for (const key of ['region', 'object']) {
    const s = $('param-' + key);
    if (s && state.picked[key] && [...s.options].some((o) => o.value === state.picked[key])) s.value = state.picked[key];
  }
}

// An event's values into the form; "Update event" then writes them back in its place.
function editEvent(i) {
  const e = state.task.events[i];
  state.editing = i;
  $('event-name').value = e.name;
  $('event-kind').value = e.kind;
  renderParams();
  for (const p of kindOf(e.kind).params) {
    const v = e[p.key];
    $('param-' + p.key).value = p.type === 'names' ? (v || []).join(', ') : v;
  }
  $('event-points').value = e.points;
  $('event-max').value = e.max_count;
  $('event-comment').value = e.comment || '';
  $('add-event').textContent = 'Update event';
}

function addEvent() {
  const name = $('event-name').value.trim(), k = kindOf($('event-kind').value);
  if (!name || !k) return;
  const e = { name, kind: k.kind, points: parseInt($('event-points').value, 10) || 0,
              max_count: parseInt($('event-max').value, 10), comment: $('event-comment').value.trim() };
  if (!Number.isFinite(e.max_count)) e.max_count = k.default_max_count;
  for (const p of k.params) {
    const v = $('param-' + p.key).value;
    if (p.type === 'seconds' || p.type === 'metres') e[p.key] = parseFloat(v) || 0;
    else if (p.type === 'names') e[p.key] = v.split(',').map((s) => s.trim()).filter(Boolean);
    else e[p.key] = v;
  }
  const t = state.task, old = state.editing >= 0 ? t.events[state.editing] : null;
  if (old) {
    // A renamed event keeps its place in end_on and success.
    t.events[state.editing] = e;
    for (const list of ['end_on', 'success']) t[list] = t[list].map((n) => (n === old.name ? e.name : n));
  } else {
    t.events.push(e);
  }
  state.editing = -1;
  $('add-event').textContent = 'Add event';
  $('event-name').value = '';
  $('event-comment').value = '';
  changed();
}

// ---- the map: draw, and drag things on it ----------------------------------------
function drawMap() {
  const c = $('map'), g = c.getContext('2d');
  g.fillStyle = '#101215'; g.fillRect(0, 0, c.width, c.height);
  if (!state.world) return;
  const s = startPose();
  if (!state.view || !state.drag) {
    const points = [[s.x, s.y], ...state.task.regions.flatMap((r) => [r.min, r.max])];
    state.view = mapView(c, worldBounds(state.world, points));
  }
  const view = state.view;
  drawWorld(g, view, state.world);
  drawObjects(g, view, state.world);
  for (const r of state.task.regions) {
    const picked = r.name === state.picked.region;
    drawRegion(g, view, r, picked ? 'rgba(56,139,253,0.45)' : 'rgba(56,139,253,0.28)', '#79c0ff');
    g.fillStyle = '#79c0ff';
    for (const [x, y] of corners(r)) { const [u, v] = view.px(x, y); g.fillRect(u - 3, v - 3, 6, 6); }
  }
  if (state.drag && state.drag.kind === 'new') drawRegion(g, view, state.drag.region, 'rgba(56,139,253,0.2)', '#79c0ff');
  const yaw = (s.yaw_deg * Math.PI) / 180;
  drawRobot(g, view, [s.x, s.y], yaw, colourHex, 'start');
  const [ku, kv] = view.px(...knob(s));
  g.fillStyle = '#fff'; g.beginPath(); g.arc(ku, kv, 5, 0, 2 * Math.PI); g.fill();
}

const corners = (r) => [[r.min[0], r.min[1]], [r.max[0], r.min[1]], [r.max[0], r.max[1]], [r.min[0], r.max[1]]];
const knob = (s) => [s.x + 0.9 * Math.cos((s.yaw_deg * Math.PI) / 180), s.y + 0.9 * Math.sin((s.yaw_deg * Math.PI) / 180)];
const inBox = (p, min, max) => p[0] >= min[0] && p[0] <= max[0] && p[1] >= min[1] && p[1] <= max[1];

// The canvas pixel of a pointer event (the canvas may be shown scaled).
function canvasPoint(ev) {
  const c = $('map'), b = c.getBoundingClientRect();
  return [((ev.clientX - b.left) * c.width) / b.width, ((ev.clientY - b.top) * c.height) / b.height];
}

// What a press at `p` (m) / `px` (canvas pixels) grabs, most specific first.
function grab(p, px) {
  const view = state.view, s = startPose();
  const near = (x, y, r = 8) => { const [u, v] = view.px(x, y); return Math.hypot(u - px[0], v - px[1]) <= r; };
  if (near(...knob(s))) return { kind: 'turn' };
  if (Math.hypot(p[0] - s.x, p[1] - s.y) < 0.45) return { kind: 'robot', dx: s.x - p[0], dy: s.y - p[1] };
  for (const r of state.task.regions) {
    const i = corners(r).findIndex(([x, y]) => near(x, y));
    if (i >= 0) return { kind: 'corner', region: r, corner: i };
  }
  for (const r of state.task.regions)
    if (inBox(p, r.min, r.max)) return { kind: 'region', region: r, from: p, min: [...r.min], max: [...r.max] };
  for (const o of state.world.objects) {
    const h = o.size.map((v) => v / 2);
    if (inBox(p, [o.center[0] - h[0], o.center[1] - h[1]], [o.center[0] + h[0], o.center[1] + h[1]])) return { kind: 'object', name: o.name };
  }
  for (const r of state.world.regions) if (inBox(p, r.min, r.max)) return { kind: 'world-region', name: r.name };
  return null;
}

function onDown(ev) {
  if (!state.task || !state.view) return;
  const px = canvasPoint(ev), p = state.view.metres(...px);
  const tool = document.querySelector('input[name=tool]:checked').value;
  if (tool === 'region') {
    state.drag = { kind: 'new', from: p, region: { name: $('region-name').value.trim() || 'zone', min: [p[0], p[1], 0], max: [p[0], p[1], 2], comment: '' } };
  } else {
    state.drag = grab(p, px);
    if (!state.drag) return;
    if (state.drag.kind === 'object') { state.picked.object = state.drag.name; state.drag = null; return render(); }
    if (state.drag.kind === 'world-region') { state.picked.region = state.drag.name; state.drag = null; return render(); }
    if (state.drag.region) state.picked.region = state.drag.region.name;
  }
  state.drag.moved = false;
  $('map').setPointerCapture(ev.pointerId);
}

function onMove(ev) {
  const d = state.drag;
  if (!d) return;
  const p = state.view.metres(...canvasPoint(ev)).map(round);
  d.moved = true;
  const t = state.task;
  if (d.kind === 'new') {
    d.region.min = [Math.min(d.from[0], p[0]), Math.min(d.from[1], p[1]), 0].map(round);
    d.region.max = [Math.max(d.from[0], p[0]), Math.max(d.from[1], p[1]), 2].map(round);
  } else if (d.kind === 'robot') {
    t.start = Object.assign({}, startPose(), { x: round(p[0] + d.dx), y: round(p[1] + d.dy) });
  } else if (d.kind === 'turn') {
    const s = startPose();
    t.start = Object.assign({}, s, { yaw_deg: round((Math.atan2(p[1] - s.y, p[0] - s.x) * 180) / Math.PI) });
  } else if (d.kind === 'corner') {
    // The dragged corner follows the pointer; the opposite one stays.
    const r = d.region, c = d.corner;
    (c === 0 || c === 3 ? r.min : r.max)[0] = p[0];
    (c === 0 || c === 1 ? r.min : r.max)[1] = p[1];
  } else if (d.kind === 'region') {
    const dx = round(p[0] - d.from[0]), dy = round(p[1] - d.from[1]);
    d.region.min = [round(d.min[0] + dx), round(d.min[1] + dy), d.min[2]];
    d.region.max = [round(d.max[0] + dx), round(d.max[1] + dy), d.max[2]];
  }
  renderHeader();
  drawMap();
}

function onUp() {
  const d = state.drag;
  state.drag = null;
  if (!d || !d.moved) return drawMap();
  if (d.kind === 'new') {
    if (d.region.max[0] - d.region.min[0] < 0.05 || d.region.max[1] - d.region.min[1] < 0.05) return drawMap();
    let name = d.region.name, n = 2;
    while (regionNames().includes(name)) name = `${d.region.name}${n++}`;
    d.region.name = name;
    state.task.regions.push(d.region);
    state.picked.region = name;
  }
  if (d.kind === 'corner') {
    const r = d.region;
    for (const k of [0, 1]) if (r.min[k] > r.max[k]) [r.min[k], r.max[k]] = [r.max[k], r.min[k]];
  }
  changed();
}

// ---- try it -------------------------------------------------------------------
async function tryIt() {
  $('report').hidden = true;
  window.riseTaskBuilder.report = null;
  // The panel's window is opened in the click itself (a browser blocks one
  // opened later), and sent to the station's page once the server answers.
  const panel = window.open('', 'rise-sandbox-panel');
  const r = await postJson(`/api/builder/task/${encodeURIComponent(state.file)}/try`, {});
  const body = await r.json();
  if (!r.ok) {
    if (panel) panel.close();
    $('try-state').textContent = 'not started: ' + body.error; $('try-state').className = 'bad';
    return;
  }
  $('panel-link').href = `${body.panel}&token=${encodeURIComponent(token)}`;
  $('panel-link').hidden = false;
  if (panel) panel.location.href = $('panel-link').href;
  $('stop').disabled = false;
  showTry(body);
  clearInterval(state.polling);
  state.polling = setInterval(poll, 500);
}

async function poll() {
  const s = await getJson('/api/builder/try');
  showTry(s);
  if (!s.active || s.task_done) { clearInterval(state.polling); state.polling = null; }
}

function showTry(s) {
  $('try-state').textContent = s.task_running ? `running on ${s.station}: drive with the virtual panel` :
    s.task_done ? `ended (rise-trainer exit ${s.task_exit_code})` : s.active ? 'starting…' : 'not running';
  $('try-state').className = s.task_running ? 'ok' : 'dim';
  $('stop').disabled = !s.task_running && !s.sim_running;
  if (!s.report) return;
  const r = s.report;
  $('report').hidden = false;
  $('report-summary').textContent = `${r.task}: score ${r.score}, ${r.success ? 'success' : 'no success'}, ended: ${r.end_reason} after ${r.time_s.toFixed(1)} s`;
  $('report-events').replaceChildren(el('tr', {}, ...['time (s)', 'event', 'kind', 'points'].map((h) => el('th', {}, h))),
    ...r.events.map((e) => el('tr', { 'data-event': e.name }, el('td', {}, e.time_s.toFixed(1)), el('td', {}, e.name),
                                     el('td', {}, e.kind), el('td', {}, e.points))));
  $('report-html').href = `${s.report_html}?token=${encodeURIComponent(token)}`;
  window.riseTaskBuilder.report = r;
}

async function stopTry() {
  const r = await postJson('/api/builder/try/stop', {});
  showTry(await r.json());
}

// ---- wiring ---------------------------------------------------------------------
function wireHeader() {
  const t = () => state.task;
  const on = (id, f) => $(id).addEventListener('change', () => { if (t()) { f($(id).value); changed(); } });
  on('task-name', (v) => { t().task = v.trim(); });
  on('task-title', (v) => { t().title = v; });
  on('time-limit', (v) => { t().time_limit_s = parseFloat(v) || 0; });
  on('start-x', (v) => { t().start = Object.assign({}, startPose(), { x: parseFloat(v) || 0 }); });
  on('start-y', (v) => { t().start = Object.assign({}, startPose(), { y: parseFloat(v) || 0 }); });
  on('start-yaw', (v) => { t().start = Object.assign({}, startPose(), { yaw_deg: parseFloat(v) || 0 }); });
}

function wireNav() {
  drawBuilderNav($('builders'), 'task_builder.html');
}

async function main() {
  conflict = new ConflictBanner($('conflict'), { onReload: () => openFile(state.file), onOverwrite: (v) => save(v) });
  window.riseTaskBuilder = {
    state,
    // A point of the world (m) in page pixels, for the tests' mouse drags.
    pagePoint: (x, y) => {
      const c = $('map'), b = c.getBoundingClientRect(), [u, v] = state.view.px(x, y);
      return [b.left + (u * b.width) / c.width, b.top + (v * b.height) / c.height];
    },
    report: null,
  };
  wireNav();
  const tasks = await loadListing();
  wireHeader();
  $('file').addEventListener('change', () => openFile($('file').value));
  $('event-kind').addEventListener('change', renderParams);
  $('add-event').addEventListener('click', addEvent);
  $('save').addEventListener('click', () => save(state.version));
  $('save-as-button').addEventListener('click', () => { const f = $('save-as').value.trim(); if (f) save('', f); });
  $('try').addEventListener('click', tryIt);
  $('stop').addEventListener('click', stopTry);
  $('panel-link').hidden = true;
  const map = $('map');
  map.addEventListener('pointerdown', onDown);
  map.addEventListener('pointermove', onMove);
  map.addEventListener('pointerup', onUp);
  const first = params.get('file') || (tasks[0] && tasks[0].file);
  if (first) await openFile(first);
  document.body.dataset.ready = '1';
}

main().catch((e) => { $('check-state').textContent = String(e); $('check-state').className = 'bad'; });
