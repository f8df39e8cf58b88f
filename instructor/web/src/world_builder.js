// The Environment Builder (/world_builder.html): opens a world file of the
// server's --worlds folder, draws it top-down (world_map.js, as the console
// does) and in 3D (scene3d.js); walls (with openings), doors, stairs,
// objects, props and regions are selected, moved, added and deleted with the
// mouse (snapping to 5 cm and to wall ends and openings) or typed in the
// property panel. Every change is checked by the server with the loader of
// rise-sim, whose error shows here with its line and key; Save writes the
// YAML atomically (keeping the file's comments), or says that the file
// changed on disk since it was loaded (409) and offers to reload or overwrite.
import { drawBuilderNav } from './builder_nav.js';
import * as THREE from 'three';
import { getJson, postJson, el, token } from './common.js';
import { ConflictBanner, errorText, requestError, saveDesign, showCheck, showEdited, showSaved } from './design_file.js';
import { drawWorld, mapView, worldBounds, BOX_FILLS } from './world_map.js';
import { createView, camera, buildWorld, renderInto, canvasStats } from './scene3d.js';

const $ = (id) => document.getElementById(id);
const params = new URLSearchParams(location.search);
const GRID_M = 0.05;
const DEG = Math.PI / 180;
// The entity lists, in the order a click finds them (small things over big ones).
const LISTS = ['doors', 'objects', 'props', 'boxes', 'stairs', 'walls', 'regions'];
// The property panel's order: as the files write them.
const KEY_ORDER = ['name', 'kind', 'from', 'to', 'hinge', 'start', 'center_m', 'min', 'max', 'size_m', 'width', 'height',
  'thickness', 'yaw_deg', 'open_deg_max', 'break_torque_nm', 'break_time_ms', 'mass_kg', 'friction_torque_nm',
  'return_nm_per_rad', 'steps', 'riser_m', 'tread_m', 'width_m', 'landing_m'];
const state = {
  file: '', version: '', world: null, view: null, bounds: null,
  check: null, checkSeq: 0, checking: false, pending: false, dirty: false,
  selected: null,  // {list, i}
  drag: null,
};
let conflict = null;

// ---- geometry of the model's entities (world metres) ----------------------
const rot = (p, yaw) => [p[0] * Math.cos(yaw) - p[1] * Math.sin(yaw), p[0] * Math.sin(yaw) + p[1] * Math.cos(yaw)];
const add2 = (a, b) => [a[0] + b[0], a[1] + b[1]];

function segmentDistance(p, a, b) {
  const d = [b[0] - a[0], b[1] - a[1]], len2 = d[0] * d[0] + d[1] * d[1];
  const t = len2 ? Math.max(0, Math.min(1, ((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / len2)) : 0;
  return Math.hypot(p[0] - a[0] - t * d[0], p[1] - a[1] - t * d[1]);
}

function doorEnd(d) { return add2(d.hinge, rot([d.width, 0], d.yaw_deg * DEG)); }
function stairsLength(s) { return s.steps * s.tread_m + s.landing_m; }

// The corners of an entity's footprint (for drawing the selection and hit tests).
function footprint(list, e) {
  const rect = (origin, yaw, x0, x1, y0, y1) => [[x0, y0], [x1, y0], [x1, y1], [x0, y1]].map((c) => add2(origin, rot(c, yaw)));
  switch (list) {
    case 'walls': {
      const yaw = Math.atan2(e.to[1] - e.from[1], e.to[0] - e.from[0]), len = Math.hypot(e.to[0] - e.from[0], e.to[1] - e.from[1]);
      return rect(e.from, yaw, 0, len, -e.thickness / 2, e.thickness / 2);
    }
    case 'doors': return rect(e.hinge, e.yaw_deg * DEG, 0, e.width, -e.thickness / 2, e.thickness / 2);
    case 'stairs': return rect(e.start, e.yaw_deg * DEG, 0, stairsLength(e), -e.width_m / 2, e.width_m / 2);
    case 'regions': return rect([0, 0], 0, e.min[0], e.max[0], e.min[1], e.max[1]);
    case 'objects': return rect(e.center_m, 0, -e.size_m[0] / 2, e.size_m[0] / 2, -e.size_m[1] / 2, e.size_m[1] / 2);
    default: return rect(e.center_m, (e.yaw_deg || 0) * DEG, -e.size_m[0] / 2, e.size_m[0] / 2, -e.size_m[1] / 2, e.size_m[1] / 2);
  }
}

function inside(p, poly) {
  let c = false;
  for (let i = 0, j = poly.length - 1; i < poly.length; j = i++) {
    if ((poly[i][1] > p[1]) !== (poly[j][1] > p[1]) &&
        p[0] < (poly[j][0] - poly[i][0]) * (p[1] - poly[i][1]) / (poly[j][1] - poly[i][1]) + poly[i][0]) c = !c;
  }
  return c;
}

function hits(list, e, p, tol) {
  if (list === 'walls') return segmentDistance(p, e.from, e.to) <= e.thickness / 2 + tol;
  if (list === 'doors') return segmentDistance(p, e.hinge, doorEnd(e)) <= e.thickness / 2 + tol;
  return inside(p, footprint(list, e));
}

// The point a move snaps: a wall's start, a door's hinge, a region's corner, a centre.
function anchor(list, e) {
  switch (list) {
    case 'walls': return e.from;
    case 'doors': return e.hinge;
    case 'stairs': return e.start;
    case 'regions': return e.min;
    default: return e.center_m;
  }
}

function translate(list, e, d) {
  const move = (p) => { p[0] += d[0]; p[1] += d[1]; };
  if (list === 'walls') { move(e.from); move(e.to); } else if (list === 'regions') { move(e.min); move(e.max); } else move(anchor(list, e));
}

// Wall ends, the edges of openings and door hinges, but those of `skip`.
function snapPoints(skip) {
  const out = [];
  state.world.walls.forEach((w, i) => {
    if (skip && skip.list === 'walls' && skip.i === i) return;
    out.push(w.from, w.to);
    const len = Math.hypot(w.to[0] - w.from[0], w.to[1] - w.from[1]), u = [(w.to[0] - w.from[0]) / len, (w.to[1] - w.from[1]) / len];
    for (const o of w.openings) for (const a of [o.at_m, o.at_m + o.width_m]) out.push([w.from[0] + u[0] * a, w.from[1] + u[1] * a]);
  });
  state.world.doors.forEach((d, i) => { if (!(skip && skip.list === 'doors' && skip.i === i)) out.push(d.hinge); });
  return out;
}

const round = (v) => Math.round(v * 1e6) / 1e6;
function snap(p, skip) {
  if (!$('snap').checked) return [round(p[0]), round(p[1])];
  const tol = Math.max(0.15, 10 / state.frame.s);
  let best = null, bestD = tol;
  for (const q of snapPoints(skip)) { const d = Math.hypot(q[0] - p[0], q[1] - p[1]); if (d <= bestD) { best = q; bestD = d; } }
  if (best) return [best[0], best[1]];
  return [round(Math.round(p[0] / GRID_M) * GRID_M), round(Math.round(p[1] / GRID_M) * GRID_M)];
}

// ---- the file -------------------------------------------------------------
async function loadListing() {
  const l = await getJson('/api/builder/worlds');
  $('file').replaceChildren(...l.worlds.map((w) => el('option', { value: w.file }, w.file + (w.error ? ' (does not load)' : ''))));
  return l.worlds;
}

function setBounds() {
  const b = worldBounds(state.view);
  state.bounds = { min: [b.min[0] - 1.5, b.min[1] - 1.5], max: [b.max[0] + 1.5, b.max[1] + 1.5] };
}

async function openFile(file) {
  const r = await getJson('/api/builder/world/' + encodeURIComponent(file));
  state.file = file;
  $('file').value = file;
  state.version = r.version;
  state.dirty = false;
  state.selected = null;
  conflict.hide();
  $('version').textContent = 'version ' + r.version;
  $('save-state').textContent = '';
  if (r.load_error) {
    state.world = null;
    state.check = { ok: false, yaml: r.text, errors: r.load_error.split('\n').map((m) => ({ message: m, line: 0, key: '' })) };
    render();
    return;
  }
  state.world = r.world;
  state.view = r.view;
  setBounds();
  state.check = { ok: true, yaml: r.text, errors: [] };
  build3d();
  render();
}

// Live check: one request at a time, the last edit checked last.
async function check() {
  if (state.checking) { state.pending = true; return; }
  state.checking = true;
  const seq = ++state.checkSeq;
  $('check-state').textContent = 'checking…';
  $('check-state').className = 'warn';
  try {
    const r = await postJson(`/api/builder/world/${encodeURIComponent(state.file)}/check`, { world: state.world });
    const body = await r.json();
    state.check = r.ok ? body : requestError(body);
    if (r.ok && body.ok) { state.view = body.view; build3d(); }
  } finally {
    state.checking = false;
  }
  if (state.pending) { state.pending = false; check(); return; }
  if (seq === state.checkSeq) render();
}

function changed(renderPanel = true) {
  state.dirty = true;
  showEdited();
  render(renderPanel);
  check();
}

async function save(version) {
  $('save-state').textContent = 'saving…';
  const { status, body } = await saveDesign('/api/builder/world/' + encodeURIComponent(state.file), version, { world: state.world });
  if (showSaved(status, body, conflict)) Object.assign(state, { version: body.version, dirty: false });
  else if (body.errors) state.check = body;
  render();
}

// ---- rendering ------------------------------------------------------------
// "doors[0].width" → {entity: "doors[0]", field: "width"}.
function errorPlaces() {
  return ((state.check && state.check.errors) || []).map((e) => {
    const m = /^([a-z_]+\[\d+\])(?:\.(.*))?$/.exec(e.key || '');
    return m ? { entity: m[1], field: m[2] || '' } : { entity: e.key || '', field: '' };
  });
}

function render(renderPanel = true) {
  const ok = showCheck(state.check, 'ok: rise-sim --world would load it', (e) => errorText(e, state.file, true));
  $('save').disabled = !state.world || !ok || !state.dirty || state.checking;
  $('delete').disabled = !state.selected;
  if (!state.world) return;
  drawMap();
  renderEntities();
  // Not while the user types there (a check's answer would replace the input).
  if (renderPanel && !$('props').contains(document.activeElement)) renderProps();
}

function selectedEntity() {
  return state.selected ? state.world[state.selected.list][state.selected.i] : null;
}

function drawMap() {
  const c = $('map'), g = c.getContext('2d');
  state.frame = mapView(c, state.bounds);
  drawWorld(g, state.frame, state.view);
  const { px, s } = state.frame;
  // Movable objects and the robot's start, as the console shows them.
  for (const o of state.world.objects) {
    const poly = footprint('objects', o).map((p) => px(...p));
    g.fillStyle = '#e3b341'; g.beginPath(); poly.forEach(([x, y], k) => (k ? g.lineTo(x, y) : g.moveTo(x, y))); g.fill();
  }
  const st = state.world.robot_start, [sx, sy] = px(...st.xy_m);
  g.strokeStyle = '#ff5a00'; g.lineWidth = 2; g.beginPath(); g.arc(sx, sy, 0.3 * s, 0, 2 * Math.PI);
  g.moveTo(sx, sy); g.lineTo(sx + Math.cos(st.yaw_deg * DEG) * 0.5 * s, sy - Math.sin(st.yaw_deg * DEG) * 0.5 * s); g.stroke();
  // Doors: their swing (±open_deg_max) as arcs.
  for (const d of state.world.doors) {
    const [hx, hy] = px(...d.hinge), yaw = d.yaw_deg * DEG, open = d.open_deg_max * DEG;
    g.strokeStyle = 'rgba(160,82,45,0.7)'; g.lineWidth = 1; g.setLineDash([4, 3]);
    g.beginPath(); g.arc(hx, hy, Math.max(0, d.width) * s, -(yaw + open), -(yaw - open)); g.stroke(); g.setLineDash([]);
    g.fillStyle = BOX_FILLS.door; g.beginPath(); g.arc(hx, hy, 3, 0, 2 * Math.PI); g.fill();
  }
  const e = selectedEntity();
  if (!e) return;
  const poly = footprint(state.selected.list, e).map((p) => px(...p));
  g.strokeStyle = '#e3b341'; g.lineWidth = 2;
  g.beginPath(); poly.forEach(([x, y], k) => (k ? g.lineTo(x, y) : g.moveTo(x, y))); g.closePath(); g.stroke();
  if (state.selected.list === 'walls') for (const p of [e.from, e.to]) { const [x, y] = px(...p); g.fillStyle = '#e3b341'; g.fillRect(x - 4, y - 4, 8, 8); }
}

function renderEntities() {
  const bad = new Set(errorPlaces().map((p) => p.entity));
  const buttons = [];
  for (const list of LISTS) state.world[list].forEach((e, i) => {
    const sel = state.selected && state.selected.list === list && state.selected.i === i;
    buttons.push(el('button', { class: [sel ? 'selected' : '', bad.has(`${list}[${i}]`) ? 'bad' : ''].join(' ').trim(),
      'data-entity': e.name, 'data-list': list, onclick: () => select({ list, i }) }, `${list.replace(/s$/, '')} ${e.name}`));
  });
  $('entities').replaceChildren(...buttons);
}

// One input per number (arrays: one per component), text for names; data-key "hinge.0".
function field(obj, key, onSet, badFields, prefix = '') {
  const v = obj[key], k = prefix + key;
  const isBad = badFields.some((f) => f && (f === k || f.startsWith(k + '.') || f.startsWith(k + '[') || k.startsWith(f + '.')));
  const input = (value, set, sub) => {
    const text = typeof value === 'string';
    const i = el('input', { type: text ? 'text' : 'number', step: 'any', value: String(value), 'data-key': sub,
                            class: (text && key === 'name' ? 'name ' : '') + (isBad ? 'bad' : '') });
    i.addEventListener('change', () => {
      const x = text ? i.value : parseFloat(i.value);
      if (!text && !Number.isFinite(x)) { i.classList.add('bad'); return; }
      set(x); onSet();
    });
    return i;
  };
  const inputs = Array.isArray(v) ? v.map((c, n) => input(c, (x) => { v[n] = x; }, `${k}.${n}`))
    : [input(v, (x) => { obj[key] = x; }, k)];
  return el('div', { class: 'row' + (isBad ? ' bad' : '') }, el('span', {}, key), ...inputs);
}

function renderProps() {
  const e = selectedEntity();
  const box = $('props');
  const places = errorPlaces();
  const done = () => changed(false);
  if (!e) {
    $('selected-name').textContent = '(the world; click an entity on the map to select it)';
    const w = state.world, bad = places.filter((p) => !p.entity.includes('[')).map((p) => p.entity);
    const rows = [field(w, 'world', done, bad), field(w, 'ground_friction', done, bad),
      field(w.robot_start, 'xy_m', done, bad, 'robot_start.'), field(w.robot_start, 'yaw_deg', done, bad, 'robot_start.')];
    if (w.ceiling) rows.push(field(w.ceiling, 'height_m', done, bad, 'ceiling.'), field(w.ceiling, 'thickness_m', done, bad, 'ceiling.'));
    box.replaceChildren(...rows);
    return;
  }
  const { list, i } = state.selected;
  $('selected-name').textContent = `${list}[${i}] ${e.name}`;
  const bad = places.filter((p) => p.entity === `${list}[${i}]`).map((p) => p.field);
  const rank = (k) => (KEY_ORDER.indexOf(k) + KEY_ORDER.length + 1) % (KEY_ORDER.length + 1);
  const keys = Object.keys(e).filter((k) => k !== 'openings').sort((a, b) => rank(a) - rank(b));
  const rows = keys.map((k) => field(e, k, done, bad));
  if (list === 'walls') rows.push(...openingRows(e, bad));
  if (list === 'doors') rows.push(el('div', { class: 'row' }, el('span', {}, 'hinge side'),
    el('button', { id: 'flip-hinge', onclick: () => { flipHinge(e); changed(); } }, 'hinge at the other end')));
  box.replaceChildren(...rows);
}

// A door hinged at its other end: the same closed panel, swinging from the other jamb.
function flipHinge(d) {
  d.hinge = doorEnd(d).map(round);
  d.yaw_deg = round(((d.yaw_deg + 180 + 180) % 360) - 180);
}

function openingRows(wall, bad) {
  const rows = wall.openings.map((o, n) => el('div', { class: 'row' }, el('span', {}, `opening ${n}`),
    ...['at_m', 'width_m', 'height_m'].map((k) => field(o, k, () => changed(false), bad, `openings[${n}].`).lastChild),
    el('button', { class: 'delete-opening', onclick: () => { wall.openings.splice(n, 1); changed(); } }, 'delete')));
  rows.push(el('button', { id: 'add-opening', onclick: () => {
    const len = Math.hypot(wall.to[0] - wall.from[0], wall.to[1] - wall.from[1]);
    wall.openings.push({ at_m: round(Math.max(0, (len - 0.9) / 2)), width_m: Math.min(0.9, len), height_m: Math.min(2.0, wall.height) });
    changed();
  } }, 'add opening'));
  return rows;
}

// ---- 3D -------------------------------------------------------------------
const view = {};
function setup3d() {
  const canvas = $('view3d');
  Object.assign(view, createView(canvas));
  view.cam = camera(55, canvas.width / canvas.height);
}

function build3d() {
  if (!view.scene || !state.view) return;
  if (view.group) view.scene.remove(view.group);
  view.group = new THREE.Group();
  buildWorld(view.group, state.view);
  view.scene.add(view.group);
  const { min, max } = state.bounds, c = [(min[0] + max[0]) / 2, (min[1] + max[1]) / 2];
  const span = Math.max(max[0] - min[0], max[1] - min[1]);
  view.cam.position.set(c[0] - 0.1 * span, c[1] - 0.6 * span, 0.5 * span);
  view.cam.lookAt(c[0], c[1], 0);
  const w = view.renderer.domElement.width, h = view.renderer.domElement.height;
  renderInto(view.renderer, view.scene, view.cam, { x: 0, y: 0, w, h });
}

// ---- the mouse ------------------------------------------------------------
function mouseWorld(ev) {
  const c = $('map'), r = c.getBoundingClientRect();
  return state.frame.metres((ev.clientX - r.left) * c.width / r.width, (ev.clientY - r.top) * c.height / r.height);
}

function hitTest(p) {
  const tol = 6 / state.frame.s;
  for (const list of LISTS) {
    const items = state.world[list];
    for (let i = items.length - 1; i >= 0; --i) if (hits(list, items[i], p, tol)) return { list, i };
  }
  return null;
}

function select(ref) {
  state.selected = ref;
  render();
}

function uniqueName(base) {
  const names = new Set(LISTS.flatMap((l) => state.world[l].map((e) => e.name)));
  for (let n = 1; ; ++n) if (!names.has(`${base}_${n}`)) return `${base}_${n}`;
}

const tool = () => document.querySelector('input[name="tool"]:checked').value;

// A new entity of `kind` at p (or from p to q, dragged).
function addEntity(kind, p, q) {
  const w = state.world;
  let list, e;
  switch (kind) {
    case 'wall':
      if (Math.hypot(q[0] - p[0], q[1] - p[1]) < 0.05) return;
      list = 'walls'; e = { name: uniqueName('wall'), from: p, to: q, height: 2.5, thickness: 0.15, openings: [] }; break;
    case 'region': {
      const tiny = Math.abs(q[0] - p[0]) < 0.05 || Math.abs(q[1] - p[1]) < 0.05;
      const a = tiny ? p : [Math.min(p[0], q[0]), Math.min(p[1], q[1])], b = tiny ? [p[0] + 1, p[1] + 1] : [Math.max(p[0], q[0]), Math.max(p[1], q[1])];
      list = 'regions'; e = { name: uniqueName('region'), min: [a[0], a[1], 0], max: [round(b[0]), round(b[1]), 1.5] }; break;
    }
    case 'door':
      list = 'doors'; e = { name: uniqueName('door'), hinge: p, width: 0.9, height: 2.0, thickness: 0.04, yaw_deg: 0, open_deg_max: 90,
                            break_torque_nm: 1500, break_time_ms: 20, mass_kg: 20, friction_torque_nm: 2, return_nm_per_rad: 1 }; break;
    case 'stairs':
      list = 'stairs'; e = { name: uniqueName('stairs'), start: p, yaw_deg: 0, steps: 6, riser_m: 0.17, tread_m: 0.28, width_m: 1.2, landing_m: 1.5 }; break;
    case 'object':
      list = 'objects'; e = { name: uniqueName('object'), size_m: [0.3, 0.3, 0.3], mass_kg: 5, center_m: [p[0], p[1], 0.15] }; break;
    default:
      list = 'props'; e = { name: uniqueName('prop'), kind: 'shelf', center_m: [p[0], p[1], 1], size_m: [0.4, 1.2, 2], yaw_deg: 0 };
  }
  w[list].push(e);
  state.selected = { list, i: w[list].length - 1 };
  document.querySelector('input[name="tool"][value="select"]').checked = true;
  changed();
}

function deleteSelected() {
  if (!state.selected) return;
  state.world[state.selected.list].splice(state.selected.i, 1);
  state.selected = null;
  changed();
}

function onMouseDown(ev) {
  if (!state.world) return;
  const p = mouseWorld(ev);
  const t = tool();
  if (t !== 'select') { state.drag = { adding: t, from: snap(p) }; return; }
  const e = selectedEntity();
  // A selected wall's end: stretch it.
  if (e && state.selected.list === 'walls') {
    const tol = 8 / state.frame.s;
    for (const end of ['from', 'to'])
      if (Math.hypot(e[end][0] - p[0], e[end][1] - p[1]) <= tol) { state.drag = { end, ref: state.selected, moved: false }; return; }
  }
  const ref = hitTest(p);
  state.selected = ref;
  if (ref) {
    const ent = state.world[ref.list][ref.i];
    state.drag = { ref, start: p, anchor: [...anchor(ref.list, ent)], original: JSON.parse(JSON.stringify(ent)), moved: false };
  }
  render();
}

function onMouseMove(ev) {
  if (!state.world || !state.frame) return;
  const p = mouseWorld(ev);
  $('cursor').textContent = `x ${p[0].toFixed(2)} m, y ${p[1].toFixed(2)} m` + (state.drag && state.drag.ref ? ' — moving' : '');
  const d = state.drag;
  if (!d || d.adding) return;
  if (d.end) {
    const e = state.world[d.ref.list][d.ref.i];
    e[d.end] = snap(p, d.ref);
  } else {
    const target = snap([d.anchor[0] + p[0] - d.start[0], d.anchor[1] + p[1] - d.start[1]], d.ref);
    const e = JSON.parse(JSON.stringify(d.original));
    translate(d.ref.list, e, [target[0] - d.anchor[0], target[1] - d.anchor[1]]);
    for (const k of ['from', 'to', 'hinge', 'start', 'min', 'max', 'center_m']) if (e[k]) { e[k][0] = round(e[k][0]); e[k][1] = round(e[k][1]); }
    state.world[d.ref.list][d.ref.i] = e;
  }
  d.moved = true;
  changed();
}

function onMouseUp(ev) {
  const d = state.drag;
  state.drag = null;
  if (!d || !state.world) return;
  if (d.adding) addEntity(d.adding, d.from, snap(mouseWorld(ev)));
  else render();
}

// ---- start ------------------------------------------------------------------

window.riseWorldBuilder = {
  state,
  // Canvas pixels (CSS, relative to the canvas' top-left) of a world point: the tests aim the mouse with it.
  toCanvas(x, y) {
    const c = $('map'), r = c.getBoundingClientRect(), [u, v] = state.frame.px(x, y);
    return [u * r.width / c.width, v * r.height / c.height];
  },
  stats: () => ({ map: canvasStats($('map')), view3d: canvasStats($('view3d')) }),
};

async function main() {
  drawBuilderNav($('builders'), 'world_builder.html');
  conflict = new ConflictBanner($('conflict'), {
    onReload: () => openFile(state.file),
    onOverwrite: (current) => save(current),
  });
  setup3d();
  const worlds = await loadListing();
  $('file').addEventListener('change', () => openFile($('file').value));
  $('save').addEventListener('click', () => save(state.version));
  $('delete').addEventListener('click', deleteSelected);
  const map = $('map');
  map.addEventListener('mousedown', onMouseDown);
  window.addEventListener('mousemove', onMouseMove);
  window.addEventListener('mouseup', onMouseUp);
  document.addEventListener('keydown', (ev) => {
    if ((ev.key === 'Delete' || ev.key === 'Backspace') && ev.target === document.body) deleteSelected();
  });
  const first = params.get('file') || (worlds[0] && worlds[0].file);
  if (first) await openFile(first);
  document.body.dataset.ready = '1';
}
main().catch((e) => { $('check-state').textContent = 'error: ' + e.message; $('check-state').className = 'bad'; });
