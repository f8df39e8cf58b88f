// The trainee's page (/trainee.html?id=ID&token=T): the world as the robot's
// onboard camera sees it, full window, with a heads-up display (speed, the
// panel's state, the task and its time left), a switchable third-person
// picture-in-picture and minimap, and the robot's sounds (sound.js). It only
// reads the server's stream, so it works beside rise-hild and the real
// console as beside the virtual panel.
import * as THREE from 'three';
import { getJson, stream, ROBOT_COLOUR } from './common.js';
import { softwareWebGL, createView, camera, buildWorld, robotMesh, poseRobot, placeObjects, onboardMount, placeOnboard, placeChase,
  setDoorOpen, cameraBlackedOut, renderInto, canvasStats } from './scene3d.js';
import { SoundPlayer } from './sound.js';

const id = new URLSearchParams(location.search).get('id') || '';
const state = {
  id, world: null, robot_state: null, panel_state: null, task_status: null,
  panel_arrival_ms: 0,      // when the last PanelState came (page clock)
  task_events: [],          // this trainee's TaskEvents, newest last
  open_doors: new Set(),    // from the SimEvents door_opened / door_closed
  pushes: 0, dirty: true, pip: true, minimap: true,
  hud_log: [],              // each change of the panel line: {text, failsafe, panel_utime, arrival_ms, dom_ms, frame_ms}
  cues: { received: 0, by_name: {} },  // SoundCues for this trainee, whether or not sound is on
};
// Milliseconds since the epoch on the page's clock (the tests compare it
// with PanelState.utime, the publisher's wall clock, on the same host).
const nowMs = () => performance.timeOrigin + performance.now();
const $ = (x) => document.getElementById(x);
const fmt = (x, d = 1) => (typeof x === 'number' ? x.toFixed(d) : '—');
// No PanelState for this long: the console's link is lost (rise-hild gone).
const PANEL_LOST_MS = 500;

// ---- heads-up display ------------------------------------------------------
function panelLine() {
  const p = state.panel_state;
  if (!p) return ['no PanelState', 'warn'];
  if (nowMs() - state.panel_arrival_ms > PANEL_LOST_MS) return ['PANEL LOST: no PanelState for ' + fmt((nowMs() - state.panel_arrival_ms) / 1000) + ' s', 'bad'];
  if (p.failsafe && p.failsafe_causes.includes('e-stop')) return ['E-STOP', 'bad'];
  if (p.failsafe) return ['FAILSAFE: ' + p.failsafe_reason, 'bad'];
  return p.deadman ? ['OK · dead-man held', 'ok'] : ['OK · dead-man released', 'warn'];
}

// The panel line, timed: when it changes, the page notes the PanelState's
// utime, when its push arrived, when the text was in the DOM and when the
// next frame was painted.
function renderPanelLine(arrivalMs) {
  const [text, cls] = panelLine(), box = $('hud-panel');
  if (box.textContent === text) return;
  box.textContent = text; box.className = 'hud-box hud-center ' + cls;
  const entry = { text, failsafe: cls === 'bad', panel_utime: state.panel_state ? state.panel_state.utime : 0,
                  arrival_ms: arrivalMs, dom_ms: nowMs() };
  requestAnimationFrame(() => { entry.frame_ms = nowMs(); });
  state.hud_log.push(entry);
  if (state.hud_log.length > 200) state.hud_log.shift();
}

function renderHud(arrivalMs) {
  renderPanelLine(arrivalMs);
  const r = state.robot_state, p = state.panel_state;
  $('hud-speed').textContent = r ? fmt(Math.abs(r.speed_mps), 2) + ' m/s' : '— m/s';
  $('hud-mode').textContent = p ? Object.entries(p.switches).map(([k, v]) => k + ' ' + v).join(' · ') : '';
  const t = state.task_status;
  $('hud-task').textContent = t ? (t.task + ' · ' + t.state + ' · score ' + t.score) : 'no task';
  $('hud-time').textContent = t && t.time_limit_s > 0 ? fmt(Math.max(0, t.time_limit_s - t.task_time_s), 0) + ' s left' : '';
  $('hud-events').replaceChildren(...state.task_events.slice(-4).map((e) => {
    const d = document.createElement('div');
    d.textContent = e.name + ' ' + (e.points >= 0 ? '+' : '') + e.points + ' → ' + e.score;
    return d;
  }));
}

// ---- the live stream -----------------------------------------------------
function onEvent(e) {
  if (e.channel_kind === 'task_event') state.task_events.push(e);
  else if (e.kind === 'door_opened' || e.kind === 'door_closed') {
    if (e.kind === 'door_opened') state.open_doors.add(e.a); else state.open_doors.delete(e.a);
    setDoorOpen(view.doors, e.a, e.kind === 'door_opened', state.robot_state);
  }
  if (state.task_events.length > 100) state.task_events.shift();
}

function onSound(c) {
  state.cues.received++;
  state.cues.by_name[c.name] = { gain: c.gain, pitch: c.pitch, continuous: c.continuous, sample: c.sample };
  if (sound.player) sound.player.cue(c);
}

function onUpdate(u) {
  const arrival = nowMs();
  state.pushes++;
  for (const c of Object.values(u.channels)) {
    if (c.trainee !== id) continue;
    state[c.kind] = c.value;
    if (c.kind === 'panel_state') state.panel_arrival_ms = arrival;
    state.dirty = true;
  }
  for (const e of u.events) if (e.trainee === id) { onEvent(e); state.dirty = true; }
  for (const s of u.sounds || []) if (s.trainee === id) onSound(s);
  renderHud(arrival);
}

// ---- 3D view, picture-in-picture, minimap ---------------------------------
const view = {};
function setup3d() {
  const canvas = $('view');
  // In software WebGL a full-window picture at full resolution takes the
  // main thread long enough to hold up the HUD: half resolution, no
  // antialiasing there.
  view.software = softwareWebGL();
  Object.assign(view, createView(canvas, !view.software));
  view.renderer.setPixelRatio(view.software ? 0.5 : 1);
  view.onboard = camera(70, 16 / 9);
  view.chase = camera(60, 4 / 3);
  Object.assign(view, buildWorld(view.scene, state.world));
  view.robot = robotMesh(state.world);
  view.scene.add(view.robot);
  view.mount = onboardMount(state.world);
  resize();
  window.addEventListener('resize', resize);
}

function resize() {
  const w = window.innerWidth, h = window.innerHeight;
  view.renderer.setSize(w, h, false);  // the drawing buffer: w × h × the pixel ratio
  view.onboard.aspect = w / h; view.onboard.updateProjectionMatrix();
  state.dirty = true;
}

// The picture-in-picture's rectangle (CSS pixels, y up): lower right.
function pipRect(w, h) {
  const pw = Math.round(w * 0.28), ph = Math.round(pw * 3 / 4);
  return { x: w - pw - 8, y: 28, w: pw, h: ph };
}

function render3d() {
  const r = state.robot_state, { x: w, y: h } = view.renderer.getSize(new THREE.Vector2());  // CSS pixels
  if (r) { poseRobot(view.robot, r); placeObjects(view.objects, r); }
  else { const s = state.world.robot_start; view.robot.position.set(s[0], s[1], 0.2); view.robot.rotation.set(0, 0, s[2]); }
  placeOnboard(view.onboard, view.mount, view.robot);
  const black = !!r && cameraBlackedOut(r, view.mount.name);
  renderInto(view.renderer, view.scene, view.onboard, { x: 0, y: 0, w, h }, black);
  $('blackout-label').textContent = black ? 'camera blackout (' + view.mount.name + ')' : '';
  $('blackout-label').hidden = !black;
  if (state.pip) {
    placeChase(view.chase, view.robot.position, new THREE.Euler().setFromQuaternion(view.robot.quaternion, 'ZYX').z);
    renderInto(view.renderer, view.scene, view.chase, pipRect(w, h));
  }
  if (state.minimap) drawMinimap();
}

// North-up, centred on the robot, 10 px a metre.
function drawMinimap() {
  const c = $('minimap'), g = c.getContext('2d'), s = 10;
  const at = view.robot.position;
  const px = (x, y) => [c.width / 2 + (x - at.x) * s, c.height / 2 - (y - at.y) * s];
  g.fillStyle = 'rgba(16,18,21,0.85)'; g.fillRect(0, 0, c.width, c.height);
  const box = (x, y, size, yaw, fill, pivot = 0.5) => {
    const [cx, cy] = px(x, y);
    g.save(); g.translate(cx, cy); g.rotate(-yaw);
    g.fillStyle = fill; g.fillRect(-size[0] * s * pivot, -size[1] * s / 2, size[0] * s, size[1] * s);
    g.restore();
  };
  const fills = { wall: '#8b949e', stairs: '#4c6ef5', box: '#6e7681', prop: '#6e5494' };
  for (const b of state.world.boxes) {
    if (b.kind !== 'door') { box(b.center[0], b.center[1], b.size, b.yaw, fills[b.kind] || fills.prop); continue; }
    const d = view.doors.get(b.name);  // drawn from its hinge, swung as in the 3D view
    box(d.position.x, d.position.y, b.size, d.rotation.z, '#a0522d', 0);
  }
  for (const [, m] of view.objects) box(m.position.x, m.position.y, [0.3, 0.3], 0, '#e3b341');
  const yaw = new THREE.Euler().setFromQuaternion(view.robot.quaternion, 'ZYX').z;
  const [x, y] = px(at.x, at.y);
  g.save(); g.translate(x, y); g.rotate(-yaw);
  g.fillStyle = '#' + ROBOT_COLOUR.toString(16).padStart(6, '0');
  g.beginPath(); g.moveTo(9, 0); g.lineTo(-6, 6); g.lineTo(-6, -6); g.closePath(); g.fill();
  g.restore();
}

// Drawn only when something new arrived, and at most 30 times a second:
// software WebGL (a station without a GPU) needs the CPU the rest of the
// station runs on.
let lastDraw = 0;
function frame(t) {
  if (state.dirty && t - lastDraw >= 33) { state.dirty = false; lastDraw = t; render3d(); }
  requestAnimationFrame(frame);
}

// ---- sound ------------------------------------------------------------------
// Browsers start audio only from a user gesture: the button.
const sound = { ctx: null, player: null, level: 0, peak: 0 };
async function toggleSound() {
  const b = $('sound-toggle');
  if (!sound.ctx) {
    sound.ctx = new AudioContext();
    sound.player = new SoundPlayer(sound.ctx);
    // The continuous cues held now start at their levels.
    for (const [name, c] of Object.entries(state.cues.by_name)) if (c.continuous) sound.player.hold(name, c.sample, c.gain, c.pitch);
    await sound.ctx.resume();
  } else if (sound.ctx.state === 'running') await sound.ctx.suspend();
  else await sound.ctx.resume();
  const on = sound.ctx.state === 'running';
  b.textContent = on ? 'sound on (click to mute)' : 'click to enable sound';
  b.classList.toggle('on', on);
}

// The output level, read every 25 ms (the analyser holds the last 46 ms), with
// the peak since it was last reset: a short one-shot is caught even when the
// page is slow to look.
function trackLevel() {
  if (!sound.player) return;
  sound.level = sound.player.level();
  sound.peak = Math.max(sound.peak, sound.level);
}

function showLevel() {
  const on = sound.player && sound.ctx.state === 'running';
  $('sound-level').textContent = on ? 'level ' + sound.level.toFixed(3) + ' (peak ' + sound.peak.toFixed(3) + ')' : '';
}

// ---- what the tests read -----------------------------------------------------
// A coarse luminance picture of the view (w × h cells), to tell whether it changed.
function thumbnail(w = 32, h = 18) {
  const c = document.createElement('canvas'); c.width = w; c.height = h;
  const g = c.getContext('2d'); g.drawImage($('view'), 0, 0, w, h);
  const d = g.getImageData(0, 0, w, h).data, out = [];
  for (let i = 0; i < d.length; i += 4) out.push(Math.round(0.299 * d[i] + 0.587 * d[i + 1] + 0.114 * d[i + 2]));
  return out;
}
window.riseTrainee = {
  state, thumbnail,
  camera: () => ({ position: view.onboard.position.toArray(), direction: view.onboard.getWorldDirection(new THREE.Vector3()).toArray() }),
  stats: () => canvasStats($('view')),
  software: () => view.software,
  doors: () => Object.fromEntries([...view.doors].map(([name, d]) => [name, d.rotation.z - d.userData.yaw])),
  resetPeak: () => { sound.peak = 0; },
  sound: () => ({ enabled: !!sound.ctx && sound.ctx.state === 'running', level: sound.player ? sound.player.level() : 0,
                  peak: sound.peak,
                  held: sound.player ? sound.player.held : {}, one_shots: sound.player ? sound.player.oneShots : 0,
                  voices: sound.player ? sound.player.voices.size : 0 }),
};

function setupControls() {
  $('sound-toggle').addEventListener('click', toggleSound);
  // The overlays switch at once; the 3D view drops or draws the
  // picture-in-picture at its next frame.
  const flip = (what, button, overlay) => {
    state[what] = !state[what]; state.dirty = true;
    $(button).classList.toggle('on', state[what]); $(overlay).hidden = !state[what];
  };
  const pip = () => flip('pip', 'pip-toggle', 'pip-label'), minimap = () => flip('minimap', 'minimap-toggle', 'minimap');
  $('pip-toggle').addEventListener('click', pip);
  $('minimap-toggle').addEventListener('click', minimap);
  window.addEventListener('keydown', (e) => {
    if (e.key === 'p' || e.key === 'P') pip();
    if (e.key === 'n' || e.key === 'N') minimap();
  });
  setInterval(() => { renderPanelLine(nowMs()); showLevel(); }, 100);  // a lost panel shows without a push
  setInterval(trackLevel, 25);
}

async function main() {
  $('hud-id').textContent = id || '(no ?id=)';
  if (!id) throw new Error('the page needs ?id=TRAINEE');
  state.world = await getJson('/api/world');
  const known = (await getJson('/api/trainees')).find((t) => t.id === id);
  for (const k of ['panel_state', 'robot_state', 'task_status']) if (known && known[k]) state[k] = known[k];
  if (state.panel_state) state.panel_arrival_ms = nowMs();
  setup3d();
  setupControls();
  renderHud(nowMs());
  stream(onUpdate, (ok) => { const l = $('hud-link'); l.textContent = ok ? 'live' : 'reconnecting…'; l.className = ok ? 'ok' : 'warn'; });
  requestAnimationFrame(frame);
}
main().catch((e) => { $('hud-link').textContent = 'error: ' + e.message; $('hud-link').className = 'bad'; });
