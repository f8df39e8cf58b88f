// The Robot Builder (/robot_builder.html): opens a robot file of the
// server's --robots folder, draws the robot in 3D (its URDF's links and
// joint axes, wheels or tracks, the laser's fan, the camera frusta), lists
// its values in a property panel — motor limits, the control mapping with
// the panel's control names to pick from, sounds, sensors — and checks each
// change with the loader rise-sim uses (errors beside the value, with line
// and key). Save writes only the changed values, in place in the file's text
// (every comment stays), or says that the file changed on disk (409). Test
// drive runs rise-sim with the saved file in the sandbox world; the virtual
// panel of that station drives it, and the view follows its RobotState.
import { drawBuilderNav } from './builder_nav.js';
import * as THREE from 'three';
import { getJson, postJson, stream, el, token } from './common.js';
import { ConflictBanner, errorText as fileErrorText, postCheck, requestError, saveDesign } from './design_file.js';
import { createView, camera, buildWorld, robotMesh, poseRobot, placeChase, canvasStats } from './scene3d.js';

const $ = (id) => document.getElementById(id);
const params = new URLSearchParams(location.search);
const state = {
  file: '', version: '', scalars: [], robot: null, panel: null,
  edits: new Map(), check: null, checkSeq: 0, drive: null, driveState: null, pushes: 0,
};
let conflict = null;


// ---- the property panel ----------------------------------------------------
const MOTOR_KEY = /\.(max_mps|max_radps|max_torque_nm|max_speed_radps|max_speed_mps|max|max_effort|break_torque_nm|speed_mps|max_force_n|gain_per_s)$/;
const CHOICES = [
  [/^sounds\.[^.]+\.source$/, ['drive_speed', 'arm_rate', 'gripper_speed']],
  [/^sounds\.[^.]+\.on$/, ['collision_started', 'joint_broken', 'door_opened', 'door_closed', 'tipped_over', 'stairs_climbed',
    'region_entered', 'button']],
  [/^control\.joints\.[^.]+\.mode$/, ['position', 'velocity', 'effort']],
];
const READ_ONLY = new Set(['robot', 'kind', 'urdf']);

function section(path) {
  if (path.startsWith('sounds.')) return 'sounds';
  if (path.startsWith('sensors.')) return 'sensors';
  if (MOTOR_KEY.test(path) && /^(control|wheels|tracks)\./.test(path)) return 'motors';
  if (path.startsWith('control.')) return 'control';
  return 'body';
}

function lastKey(path) { return path.replace(/\[\d+\]$/, '').split('.').pop(); }
function parentOf(path) { return path.slice(0, path.lastIndexOf('.')); }

function controlNames(kind) { return ((state.panel && state.panel.controls) || []).filter((c) => c.kind === kind); }

// Which panel controls a value names: axis, button or switch (null: free text).
function controlKind(path) {
  const k = lastKey(path);
  if (k === 'axis') return 'axis';
  if (k === 'switch') return 'switch';
  if (k === 'button' || k === 'open' || k === 'close' || /\.buttons\[\d\]$/.test(path)) return 'button';
  return null;
}

// The values shown: the file's, each changed one as edited, and an `invert`
// for every axis mapping that lacks one (added to the file when ticked).
function rows() {
  const out = state.scalars.map((s) => ({ path: s.path, line: s.line, value: s.value, original: s.value }));
  const have = new Set(out.map((r) => r.path));
  for (const r of state.scalars) {
    if (lastKey(r.path) !== 'axis' || !r.path.startsWith('control.')) continue;
    const inv = parentOf(r.path) + '.invert';
    if (!have.has(inv)) { out.push({ path: inv, line: 0, value: 'false', original: 'false', absent: true }); have.add(inv); }
  }
  for (const r of out) if (state.edits.has(r.path)) r.value = state.edits.get(r.path);
  return out;
}

function edit(path, value, original) {
  if (value === original) state.edits.delete(path); else state.edits.set(path, value);
  $('save-state').textContent = state.edits.size ? `${state.edits.size} change(s), not saved` : '';
  render();
  check();
}

function select(options, value, onChange, note) {
  const s = el('select', { onchange: (e) => onChange(e.target.value) });
  const names = options.slice();
  if (!names.includes(value)) names.unshift(value);
  for (const n of names) s.append(el('option', { value: n }, n + (options.includes(n) ? '' : note)));
  s.value = value;
  return s;
}

function inputFor(r) {
  const set = (v) => edit(r.path, v, r.original);
  const attrs = { 'data-path': r.path };
  let input;
  if (READ_ONLY.has(r.path)) input = el('code', {}, r.value);
  else if (lastKey(r.path) === 'invert') {
    input = el('input', { type: 'checkbox', onchange: (e) => set(e.target.checked ? 'true' : 'false') });
    input.checked = r.value === 'true';
  } else if (controlKind(r.path)) {
    input = select(controlNames(controlKind(r.path)).map((c) => c.name), r.value, set, ' (not on the panel)');
  } else if (lastKey(r.path) === 'position') {
    const sw = controlNames('switch').find((c) => c.name === (state.edits.get(parentOf(r.path) + '.switch') ||
      (state.scalars.find((s) => s.path === parentOf(r.path) + '.switch') || {}).value));
    input = select(sw ? sw.positions : [], r.value, set, ' (not a position of the switch)');
  } else if (CHOICES.some(([re]) => re.test(r.path))) {
    input = select(CHOICES.find(([re]) => re.test(r.path))[1], r.value, set, '');
  } else {
    input = el('input', { value: r.value, size: 14, onchange: (e) => set(e.target.value.trim()) });
  }
  for (const [k, v] of Object.entries(attrs)) input.setAttribute(k, v);
  return input;
}

const errorText = (e) => fileErrorText(e, state.file);

function renderProps() {
  const errors = (state.check && state.check.errors) || [];
  const tables = { motors: [], control: [], sounds: [], sensors: [], body: [] };
  for (const r of rows()) {
    const mine = errors.filter((e) => e.key && (e.key === r.path || e.key.startsWith(r.path + '.')));
    const changed = state.edits.has(r.path);
    tables[section(r.path)].push(el('tr', { class: mine.length ? 'bad' : changed ? 'changed' : '' },
      el('td', { class: 'dim' }, r.line ? String(r.line) : '+'),
      el('td', {}, el('code', {}, r.path)),
      el('td', {}, inputFor(r)),
      el('td', { class: 'error', 'data-error-for': r.path }, mine.map(errorText).join('; '))));
  }
  for (const [name, trs] of Object.entries(tables)) $('props-' + name).replaceChildren(...trs);
}

function renderCheck() {
  const c = state.check;
  const s = $('check-state');
  if (!c) { s.textContent = 'not checked yet'; s.className = 'warn'; return; }
  s.textContent = c.ok ? 'ok: rise-sim --robot loads it' : `${c.errors.length} error(s): not saved until fixed`;
  s.className = c.ok ? 'ok' : 'bad';
  $('errors').replaceChildren(...c.errors.map((e) => el('li', { class: 'bad' }, errorText(e))));
  $('yaml').textContent = c.yaml || '';
  $('save').disabled = !c.ok || !state.edits.size;
}

function render() { renderProps(); renderCheck(); }

async function check() {
  const answer = await postCheck(state, `/api/builder/robot/${encodeURIComponent(state.file)}/check`, { edits: editList() });
  if (!answer) return;
  const body = answer.body;
  state.check = answer.check;
  if (body.robot) showRobot(body.robot);
  render();
}

function editList() { return [...state.edits].map(([path, value]) => ({ path, value })); }

// ---- the 3D view -------------------------------------------------------------
const view = { renderer: null, scene: null, cam: null, robot: null, azimuth: -2.3, elevation: 0.45, distance: 2.6 };

function setupView() {
  const canvas = $('view3d');
  Object.assign(view, createView(canvas));
  view.cam = camera(45, canvas.width / canvas.height);
  const grid = new THREE.GridHelper(6, 24, 0x555555, 0x888888); grid.rotation.x = Math.PI / 2; view.ground = grid;
  view.scene.add(grid);
  let drag = null;
  canvas.addEventListener('pointerdown', (e) => { drag = [e.clientX, e.clientY]; canvas.setPointerCapture(e.pointerId); });
  canvas.addEventListener('pointerup', () => { drag = null; });
  canvas.addEventListener('pointermove', (e) => {
    if (!drag) return;
    view.azimuth -= (e.clientX - drag[0]) * 0.01;
    view.elevation = Math.max(-0.2, Math.min(1.4, view.elevation + (e.clientY - drag[1]) * 0.01));
    drag = [e.clientX, e.clientY];
    drawView();
  });
  canvas.addEventListener('wheel', (e) => { e.preventDefault(); view.distance = Math.max(0.5, view.distance * (e.deltaY > 0 ? 1.1 : 0.9)); drawView(); });
}

function mountFrame(position, rpy) {
  const g = new THREE.Group();
  g.position.set(...position);
  g.rotation.set(rpy[0], rpy[1], rpy[2], 'ZYX');  // R = Rz(yaw)·Ry(pitch)·Rx(roll), as the robot file's rpy
  return g;
}

// The laser's scan plane (its x–y plane, beam 0 towards −y), drawn out to 1.5 m at most.
function laserFan(l) {
  const g = mountFrame(l.position, l.rpy);
  const r = Math.min(l.max_range, 1.5);
  const fan = new THREE.Mesh(new THREE.CircleGeometry(r, 48, -l.fov / 2, l.fov),
    new THREE.MeshBasicMaterial({ color: 0xd03030, transparent: true, opacity: 0.3, side: THREE.DoubleSide, depthWrite: false }));
  g.add(fan);
  g.add(new THREE.Mesh(new THREE.CylinderGeometry(0.04, 0.04, 0.06, 16).rotateX(Math.PI / 2), new THREE.MeshLambertMaterial({ color: 0x202020 })));
  g.name = 'laser';
  return g;
}

// A camera's view pyramid (it looks along its x axis, z up).
function frustum(c) {
  const g = mountFrame(c.position, c.rpy);
  const d = 0.35, w = 0.2, h = 0.15, corners = [[d, w, h], [d, -w, h], [d, -w, -h], [d, w, -h]];
  const pts = [];
  for (const k of corners) pts.push(0, 0, 0, ...k);
  for (let i = 0; i < 4; i++) pts.push(...corners[i], ...corners[(i + 1) % 4]);
  const geo = new THREE.BufferGeometry(); geo.setAttribute('position', new THREE.Float32BufferAttribute(pts, 3));
  g.add(new THREE.LineSegments(geo, new THREE.LineBasicMaterial({ color: 0x2060d0 })));
  g.name = 'camera:' + c.name;
  return g;
}

// A tracked robot's two belts: the bottom run between the rollers and the front run rising at the approach angle.
function tracks(robot) {
  const t = robot.tracks, size = robot.chassis_size || [0.8, 0.5, 0.25];
  const g = new THREE.Group(); g.name = 'tracks';
  const z = -(size[2] / 2 + robot.clearance) + t.radius;
  const mat = new THREE.MeshLambertMaterial({ color: 0x303030 });
  for (const side of [1, -1]) {
    const run = new THREE.Mesh(new THREE.CapsuleGeometry(t.radius, t.length, 6, 16), mat);
    run.rotation.z = Math.PI / 2; run.position.set(0, side * t.gauge / 2, z); g.add(run);
    const front = new THREE.Mesh(new THREE.CapsuleGeometry(t.radius * 0.8, t.approach_length, 6, 12), mat);
    front.rotation.set(0, -(Math.PI / 2 - t.approach), 0);
    front.position.set(t.length / 2 + Math.cos(t.approach) * t.approach_length / 2, side * t.gauge / 2,
      z + Math.sin(t.approach) * t.approach_length / 2);
    g.add(front);
  }
  return g;
}

// Each moving joint's axis as an arrow in its frame (driven ones brighter).
function jointAxes(group, robot) {
  const driven = new Set(robot.driven_joints || []);
  for (const j of group.userData.joints || []) {
    if (j.type === 'fixed') continue;
    const arrow = new THREE.ArrowHelper(j.axis.clone().normalize(), new THREE.Vector3(), 0.25, driven.has(j.name) ? 0xffd000 : 0xe0b000, 0.06, 0.04);
    arrow.name = 'axis:' + j.name;
    j.link.parent.add(arrow);
  }
}

function robotGroup(robot) {
  const g = new THREE.Group();
  const body = robotMesh({ robot });
  g.add(body);
  if (body.userData.joints) jointAxes(body, robot);
  if (robot.tracks) g.add(tracks(robot));
  if (robot.laser) g.add(laserFan(robot.laser));
  for (const c of robot.cameras || []) g.add(frustum(c));
  return g;
}

function showRobot(robot) {
  state.robot = robot;
  if (view.robot) view.scene.remove(view.robot);
  view.robot = robotGroup(robot);
  view.scene.add(view.robot);
  const size = robot.chassis_size || [0.8, 0.5, 0.25];
  view.ground.position.z = -(size[2] / 2 + (robot.clearance || 0));  // the ground under the base frame
  const parts = [robot.kind, robot.links ? `${robot.links.length} links, ${robot.joints.length} joints` : 'chassis box',
    robot.laser ? `laser ${Math.round(robot.laser.fov * 180 / Math.PI)}°` : 'no laser', `${(robot.cameras || []).length} camera(s)`];
  $('view-note').textContent = parts.join(' · ');
  drawView();
}

function drawView() {
  if (!view.renderer) return;
  const d = view.distance, c = view.cam;
  c.position.set(d * Math.cos(view.azimuth) * Math.cos(view.elevation), d * Math.sin(view.azimuth) * Math.cos(view.elevation),
    d * Math.sin(view.elevation));
  c.lookAt(0, 0, 0);
  const cv = $('view3d');
  view.renderer.setViewport(0, 0, cv.width, cv.height); view.renderer.setScissor(0, 0, cv.width, cv.height);
  view.renderer.render(view.scene, c);
}

// ---- the test drive ----------------------------------------------------------
const drive = { renderer: null, scene: null, cam: null, robot: null, es: null, dirty: false };

async function startDrive() {
  if (state.edits.size && !(await save())) return;
  $('drive-state').textContent = 'starting rise-sim…';
  const r = await postJson(`/api/builder/robot/${encodeURIComponent(state.file)}/drive`, {});
  const body = await r.json();
  if (!r.ok) { $('drive-state').textContent = body.error || `HTTP ${r.status}`; return; }
  state.drive = body;
  $('drive-state').textContent = `rise-sim runs ${body.robot} on station ${body.station}`;
  $('drive-stop').disabled = false;
  $('drive-box').hidden = false;
  $('drive-station').textContent = body.station;
  $('drive-panel').src = `${body.panel}&token=${encodeURIComponent(token)}`;
  if (!drive.renderer) {
    const canvas = $('drive3d');
    Object.assign(drive, createView(canvas));
    drive.cam = camera(60, canvas.width / canvas.height);
    buildWorld(drive.scene, await getJson('/api/world'));
  }
  if (drive.robot) drive.scene.remove(drive.robot);
  drive.robot = robotGroup(state.robot);
  drive.scene.add(drive.robot);
  if (!drive.es) drive.es = stream(onStream);
}

function onStream(u) {
  if (!state.drive) return;
  for (const c of Object.values(u.channels)) {
    if (c.trainee !== state.drive.station || c.kind !== 'robot_state') continue;
    state.driveState = c.value; state.pushes++; drive.dirty = true;
  }
}

function driveFrame() {
  if (drive.dirty && drive.robot && state.driveState) {
    drive.dirty = false;
    const r = state.driveState;
    poseRobot(drive.robot, r);
    placeChase(drive.cam, drive.robot.position, r.yaw, 3.0, 1.8);
    const cv = $('drive3d');
    drive.renderer.setViewport(0, 0, cv.width, cv.height); drive.renderer.setScissor(0, 0, cv.width, cv.height);
    drive.renderer.render(drive.scene, drive.cam);
    $('drive-speed').textContent = `speed ${r.speed_mps.toFixed(2)} m/s at (${r.position[0].toFixed(2)}, ${r.position[1].toFixed(2)})`;
  }
  requestAnimationFrame(driveFrame);
}

async function stopDrive() {
  await postJson('/api/builder/drive/stop', {});
  state.drive = null;
  $('drive-stop').disabled = true;
  $('drive-state').textContent = 'stopped';
}

// ---- files -----------------------------------------------------------------
async function openFile(file) {
  const r = await getJson('/api/builder/robot/' + encodeURIComponent(file));
  state.file = file; $('file').value = file;
  state.version = r.version;
  state.scalars = r.scalars;
  state.edits.clear();
  state.check = r;
  conflict.hide();
  $('version').textContent = 'version ' + r.version;
  $('save-state').textContent = '';
  if (r.robot) showRobot(r.robot);
  render();
  const u = new URL(location.href); u.searchParams.set('file', file); history.replaceState(null, '', u);
}

// Saves the edits over `version`; true when saved.
async function save(version = state.version) {
  const { status, body } = await saveDesign(`/api/builder/robot/${encodeURIComponent(state.file)}`, version, { edits: editList() });
  if (status === 409) { conflict.show(body); $('save-state').textContent = 'not saved: changed on disk'; return false; }
  if (status !== 200) {
    state.check = body.errors ? body : requestError(body);
    render();
    $('save-state').textContent = 'not saved: ' + (body.error || status);
    return false;
  }
  await openFile(state.file);
  $('save-state').textContent = 'saved (version ' + body.version + ')';
  return true;
}

async function main() {
  drawBuilderNav($('builders'), 'robot_builder.html');
  conflict = new ConflictBanner($('conflict'), {
    onReload: () => openFile(state.file),
    onOverwrite: (current) => save(current),
  });
  setupView();
  state.panel = await getJson('/api/panel');
  $('panel-name').textContent = state.panel.name;
  const list = await getJson('/api/builder/robots');
  $('file').replaceChildren(...list.robots.map((r) => el('option', { value: r.file }, r.file + (r.error ? ' (does not load)' : ` (${r.kind})`))));
  $('file').addEventListener('change', (e) => openFile(e.target.value));
  $('save').addEventListener('click', () => save());
  $('drive').addEventListener('click', () => startDrive());
  $('drive-stop').addEventListener('click', () => stopDrive());
  const want = params.get('file');
  const first = list.robots.find((r) => r.file === want) || list.robots[0];
  if (first) await openFile(first.file);
  requestAnimationFrame(driveFrame);
  document.body.dataset.ready = '1';
}

window.riseRobotBuilder = { state, stats: () => ({ view3d: canvasStats($('view3d')), drive3d: drive.renderer ? canvasStats($('drive3d')) : null }),
  // The named parts drawn (tracks, laser, camera:NAME, axis:JOINT, the URDF's links).
  scene: () => { const names = []; if (view.robot) view.robot.traverse((o) => { if (o.name) names.push(o.name); }); return names; } };
main().catch((e) => { $('save-state').textContent = 'error: ' + e.message; });
