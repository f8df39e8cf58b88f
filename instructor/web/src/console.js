// The instructor console: live map, 3D view, panels, faults, training, reports.
import * as THREE from 'three';
import { drawBuilderNav } from './builder_nav.js';
import { api, getJson, postJson, stream, el, token, ROBOT_COLOUR } from './common.js';
import { createView, camera, buildWorld, robotMesh as makeRobotMesh, poseRobot, placeObjects, onboardMount, placeOnboard,
  placeChase, cameraBlackedOut, renderInto, canvasStats } from './scene3d.js';
import { foldEvent, lineText } from './event_fold.js';
import { worldBounds, mapView, drawWorld, drawObjects, drawRobot } from './world_map.js';

const state = {
  world: null,
  trainees: new Map(),   // id → {panel_state, robot_state, task_status, trail: [[x,y]...]}
  selected: '',
  eventLines: [],  // the progress list, runs folded (event_fold.js)
  pushes: 0,
  dirty: true,
};
const colourHex = '#' + ROBOT_COLOUR.toString(16).padStart(6, '0');

function trainee(id) {
  if (!state.trainees.has(id)) {
    state.trainees.set(id, { trail: [] });
    const sel = document.getElementById('trainee');
    sel.append(el('option', { value: id }, id));
    if (!state.selected) { state.selected = id; sel.value = id; updatePanelLink(); }
  }
  return state.trainees.get(id);
}

function updatePanelLink() {
  document.getElementById('panel-link').href =
    'panel.html?id=' + encodeURIComponent(state.selected || 't1') + '&token=' + encodeURIComponent(token);
  drawBuilderNav(document.getElementById('builders'), '/');
}

// ---- top-down map (world_map.js) -----------------------------------------
function drawMap() {
  const c = document.getElementById('map'), g = c.getContext('2d');
  g.fillStyle = '#101215'; g.fillRect(0, 0, c.width, c.height);
  if (!state.world) return;
  const trails = [...state.trainees.values()].flatMap((t) => t.trail);
  const view = mapView(c, worldBounds(state.world, trails));
  drawWorld(g, view, state.world);
  for (const [id, t] of state.trainees) {
    const r = t.robot_state;
    drawObjects(g, view, state.world, r ? r.objects : null);
    if (t.trail.length > 1) {
      g.strokeStyle = id === state.selected ? 'rgba(255,90,0,0.8)' : 'rgba(255,255,255,0.4)'; g.lineWidth = 2;
      g.beginPath();
      t.trail.forEach((p, i) => { const [x, y] = view.px(p[0], p[1]); if (i) g.lineTo(x, y); else g.moveTo(x, y); });
      g.stroke();
    }
    if (r) drawRobot(g, view, r.position, r.yaw, colourHex, id);
  }
}

// ---- 3D view (the scene: scene3d.js, shared with the trainee page) ----------
const view = {};
function setup3d() {
  const canvas = document.getElementById('view3d');
  Object.assign(view, createView(canvas));
  view.chase = camera(60, canvas.width / canvas.height);
  view.onboard = camera(70, 4 / 3);
  view.robots = new Map();
}

function buildScene() {
  view.objects = buildWorld(view.scene, state.world).objects;
}

function robotMesh(id) {
  if (!view.robots.has(id)) {
    const g = makeRobotMesh(state.world);
    view.scene.add(g); view.robots.set(id, g);
  }
  return view.robots.get(id);
}

// The inset's rectangle in canvas pixels (y up, as WebGL's viewport).
function insetRect(w, h) {
  const iw = Math.round(w * 0.33), ih = Math.round(iw * 3 / 4);
  return { x: w - iw - 4, y: 4, w: iw, h: ih };
}

function render3d() {
  if (!view.renderer || !state.world) return;
  for (const [id, t] of state.trainees) {
    const r = t.robot_state; if (!r) continue;
    poseRobot(robotMesh(id), r);
    placeObjects(view.objects, r);
  }
  const sel = state.trainees.get(state.selected);
  const r = sel && sel.robot_state;
  const pos = r ? new THREE.Vector3(...r.position) : new THREE.Vector3(state.world.robot_start[0], state.world.robot_start[1], 0.2);
  placeChase(view.chase, pos, r ? r.yaw : state.world.robot_start[2]);
  const w = view.renderer.domElement.width, h = view.renderer.domElement.height;
  renderInto(view.renderer, view.scene, view.chase, { x: 0, y: 0, w, h });
  if (r) {
    const m = onboardMount(state.world);
    placeOnboard(view.onboard, m, robotMesh(state.selected));
    // The camera sends nothing while blacked out: the inset is black, labelled.
    const blackout = cameraBlackedOut(r, m.name);
    renderInto(view.renderer, view.scene, view.onboard, insetRect(w, h), blackout);
    setCameraLabel(blackout ? 'camera blackout (' + m.name + ')' : '');
  } else {
    setCameraLabel('');
  }
}

function setCameraLabel(text) {
  const l = document.getElementById('camera-label');
  l.textContent = text; l.hidden = !text;
}

// ---- panels, training, events --------------------------------------------
function fmt(x, d = 2) { return typeof x === 'number' ? x.toFixed(d) : '—'; }

// A trainee's link (live, stale, lost) and its clock's measured offset.
function linkCells(link) {
  if (!link) return [];
  const text = link.state === 'lost' ? 'LOST (nothing for ' + fmt(link.heard_ago_ms / 1000, 1) + ' s)'
    : link.state === 'stale' ? 'stale (' + fmt(link.arrival_age_ms, 0) + ' ms old)' : 'live';
  const clock = typeof link.clock_offset_ms === 'number'
    ? ' clock ' + (link.clock_offset_ms >= 0 ? '+' : '') + fmt(link.clock_offset_ms, 1) + ' ms' : '';
  return [el('span', { class: link.state === 'live' ? 'ok' : 'bad' }, text), clock];
}

// The trainee list marks the lost ones.
function renderTraineeList() {
  for (const o of document.getElementById('trainee').options) {
    const t = state.trainees.get(o.value), lost = t && t.link && t.link.state === 'lost';
    const text = o.value + (lost ? ' (lost)' : '');
    if (o.textContent !== text) o.textContent = text;
  }
}

function renderPanels() {
  const rows = [];
  for (const [id, t] of state.trainees) {
    const p = t.panel_state;
    const status = !p ? el('span', { class: 'warn' }, 'no PanelState')
      : p.failsafe ? el('span', { class: 'bad' }, 'FAILSAFE ' + p.failsafe_reason) : el('span', { class: 'ok' }, 'ok');
    const axes = p ? Object.entries(p.axes).map(([k, v]) => k + '=' + fmt(v)).join(' ') : '';
    const sw = p ? Object.entries(p.switches).map(([k, v]) => k + '=' + v).join(' ') : '';
    const faults = p && p.active_faults.length ? p.active_faults.join(', ') : '';
    const link = t.link;
    rows.push(el('tr', { 'data-trainee': id, 'data-link': link ? link.state : '' }, el('td', {}, id),
      el('td', { class: 'link' }, ...linkCells(link)), el('td', {}, status),
      el('td', {}, p ? (p.deadman ? 'dead-man held' : 'dead-man released') : ''),
      el('td', {}, axes), el('td', {}, sw), el('td', { class: 'faults' }, faults)));
    for (const s of (p ? p.sources : [])) {
      const health = !s.connected ? el('span', { class: 'bad' }, 'down' + (s.down_reason ? ': ' + s.down_reason : '')) : s.stale ? el('span', { class: 'bad' }, 'stale')
        : el('span', { class: 'ok' }, 'ok');
      rows.push(el('tr', { class: 'source' }, el('td', {}, ''), el('td', {}, ''), el('td', {}, 'source ' + s.name), el('td', {}, health),
        el('td', {}, s.url), el('td', {}, 'age ' + fmt(s.age_ms, 0) + ' ms'), el('td', {}, 'ok ' + s.frames_ok + ' bad ' + s.frames_bad)));
    }
  }
  document.getElementById('panels').replaceChildren(el('table', {}, ...rows));
}

function renderTraining() {
  const rows = [el('tr', {}, ...['trainee', 'training', 'node', 'task', 'attempt', 'state', 'time', 'score', 'done', 'training score']
    .map((h) => el('th', {}, h)))];
  for (const [id, t] of state.trainees) {
    const s = t.task_status; if (!s) continue;
    rows.push(el('tr', {}, ...[id, s.training, s.node, s.task, s.attempt, s.state,
      fmt(s.task_time_s, 1) + ' / ' + fmt(s.time_limit_s, 0) + ' s', s.score, s.tasks_done, s.training_score]
      .map((v) => el('td', {}, v))));
  }
  document.getElementById('training').replaceChildren(el('table', {}, ...rows));
  const log = document.getElementById('events');
  log.replaceChildren(...state.eventLines.slice(-60).map((l) => el('div', { 'data-count': l.count }, lineText(l))));
  log.scrollTop = log.scrollHeight;
}

function renderRobotLine() {
  const t = state.trainees.get(state.selected), r = t && t.robot_state;
  if (r) document.getElementById('robot-pos').textContent =
    state.selected + ': x=' + fmt(r.position[0]) + ' y=' + fmt(r.position[1]) + ' yaw=' + fmt(r.yaw * 180 / Math.PI, 0) + '° v=' + fmt(r.speed_mps);
}

// ---- faults and scenario -------------------------------------------------
async function setupFaults() {
  const box = document.getElementById('faults'), out = document.getElementById('fault-result');
  let kinds = [];
  try { kinds = (await getJson('/api/faults')).faults; } catch (e) { box.textContent = 'faults: ' + e.message; }
  for (const f of kinds) {
    box.append(el('button', { 'data-fault': f.name, onclick: async () => {
      const r = await postJson('/api/fault/inject', { trainee: state.selected, fault: f.name });
      out.textContent = 'inject ' + f.name + ': ' + (r.ok ? 'published' : 'HTTP ' + r.status + ' ' + await r.text());
    } }, f.label || f.name));
  }
  if (kinds.length) box.append(el('button', { id: 'fault-clear', onclick: async () => {
    const r = await postJson('/api/fault/clear', { trainee: state.selected, fault: '*' });
    out.textContent = 'clear: ' + (r.ok ? 'published' : 'HTTP ' + r.status);
  } }, 'clear all faults'));
  const sc = document.getElementById('scenario');
  await setupScenarios(sc, out);
  for (const cmd of ['pause', 'resume', 'step', 'reset']) {
    sc.append(el('button', { 'data-sim': cmd, onclick: async () => {
      const r = await api('/api/sim/' + encodeURIComponent(state.selected) + '/' + cmd, { method: 'POST' });
      out.textContent = 'sim ' + cmd + ': ' + (r.ok ? 'published' : 'HTTP ' + r.status);
    } }, 'sim ' + cmd));
  }
}

// Scenario files (rise-instructor serve --scenarios-dir): start one against
// the selected trainee (run by `rise-instructor scenario`), stop it.
async function setupScenarios(box, out) {
  let info;
  try { info = await getJson('/api/scenarios'); } catch (e) { box.append(el('div', {}, 'scenarios: ' + e.message)); return; }
  const pick = el('select', { id: 'scenario-file' }, ...info.files.map((f) =>
    el('option', { value: f.file }, f.error ? f.file + ' (' + f.error + ')' : f.name + ' — ' + f.faults + ' faults, seed ' + f.seed)));
  const seed = el('input', { id: 'scenario-seed', type: 'number', placeholder: 'seed', style: 'width:6em' });
  const status = el('span', { id: 'scenario-status' });
  const refresh = async () => {
    const s = await getJson('/api/scenarios');
    status.textContent = Object.entries(s.running).map(([id, r]) => id + ': ' + r.file + ' (seed ' + r.seed + ')').join(', ') || 'no scenario running';
  };
  const post = async (what) => {
    const body = { trainee: state.selected, file: pick.value };
    if (seed.value !== '') body.seed = parseInt(seed.value, 10);
    const r = await postJson('/api/scenario/' + what, body);
    out.textContent = 'scenario ' + what + ': ' + (r.ok ? 'ok' : 'HTTP ' + r.status + ' ' + await r.text());
    refresh();
  };
  box.append(el('div', {}, 'scenario ', pick, seed,
    el('button', { id: 'scenario-start', onclick: () => post('start') }, 'start'),
    el('button', { id: 'scenario-stop', onclick: () => post('stop') }, 'stop'), ' ', status));
  if (!info.enabled) status.textContent = 'scenario control off (--scenarios-dir, --instructor-key)';
  else refresh();
}

async function loadReports() {
  const list = await getJson('/api/reports');
  const box = document.getElementById('reports');
  if (!list.length) { box.textContent = 'no reports (rise-instructor serve --reports-dir DIR)'; return; }
  box.replaceChildren(...list.map((r) => el('div', {}, el('a', { href: r.url, target: '_blank' }, r.path))));
}

// ---- the live stream -----------------------------------------------------
function onUpdate(u) {
  state.pushes++;
  state.dirty = true;
  for (const c of Object.values(u.channels)) {
    const t = trainee(c.trainee);
    t[c.kind] = c.value;
    if (c.kind === 'robot_state') {
      const p = c.value.position, last = t.trail[t.trail.length - 1];
      if (!last || Math.hypot(p[0] - last[0], p[1] - last[1]) > 0.02) t.trail.push([p[0], p[1]]);
      if (t.trail.length > 5000) t.trail.shift();
    }
  }
  for (const [id, l] of Object.entries(u.links || {})) trainee(id).link = l;
  renderTraineeList();
  for (const e of u.events) { trainee(e.trainee); foldEvent(state.eventLines, e); }
  if (state.eventLines.length > 500) state.eventLines.splice(0, state.eventLines.length - 500);
  renderPanels(); renderTraining(); renderRobotLine();
}

// Drawn only when something new arrived: software WebGL (a machine without a
// GPU) would otherwise take the CPU the trainee stations need.
function frame() {
  if (state.dirty) { state.dirty = false; drawMap(); render3d(); }
  requestAnimationFrame(frame);
}

// The camera inset's mean luminance (0..255) and the label over it.
function insetStats() {
  const v = document.getElementById('view3d'), r = insetRect(v.width, v.height);
  const c = document.createElement('canvas'); c.width = r.w; c.height = r.h;
  const g = c.getContext('2d'); g.drawImage(v, r.x, v.height - r.y - r.h, r.w, r.h, 0, 0, r.w, r.h);
  const d = g.getImageData(0, 0, r.w, r.h).data;
  let sum = 0, max = 0;
  for (let i = 0; i < d.length; i += 4) {
    const y = 0.299 * d[i] + 0.587 * d[i + 1] + 0.114 * d[i + 2]; sum += y; max = Math.max(max, y);
  }
  const l = document.getElementById('camera-label');
  return { mean: sum / (d.length / 4), max, label: l.hidden ? '' : l.textContent };
}
window.riseConsole = { state, insetStats, stats: () => ({ map: canvasStats(document.getElementById('map')),
                                                          view3d: canvasStats(document.getElementById('view3d')) }) };

async function main() {
  document.getElementById('trainee').addEventListener('change', (e) => { state.selected = e.target.value; state.dirty = true; updatePanelLink(); });
  updatePanelLink();
  state.world = await getJson('/api/world');
  setup3d(); buildScene();
  for (const t of await getJson('/api/trainees')) {
    const x = trainee(t.id);
    for (const k of ['panel_state', 'robot_state', 'task_status', 'link']) if (t[k]) x[k] = t[k];
  }
  setupFaults(); loadReports();
  stream(onUpdate, (ok) => {
    const l = document.getElementById('link'); l.textContent = ok ? 'live' : 'reconnecting…'; l.className = ok ? 'ok' : 'warn';
  });
  requestAnimationFrame(frame);
}
main().catch((e) => { document.getElementById('link').textContent = 'error: ' + e.message; });
