// The virtual panel: on-screen sticks and buttons, the keyboard and any
// gamepad the browser sees, sent to the server at a steady rate; the server
// publishes them as PanelState under the daemon's safety rules (a page that
// stops sending fails safe there, not here).
import { getJson, postJson, stream, el, token } from './common.js';

const params = new URLSearchParams(location.search);
const id = params.get('id') || 't1';
const SEND_PERIOD_MS = 20;  // 50 Hz, well inside the server's 200 ms timeout

const ui = { axes: {}, buttons: {}, switches: {} };    // on-screen controls
const keys = new Set();
let estopLatched = false;
let controls = [];

function control(role, name) { return controls.find((c) => (role && c.role === role) || c.name === name); }

function stick(xName, yName, label) {
  const c = el('canvas', { class: 'stick', width: 180, height: 180, 'data-stick': label });
  const draw = () => {
    const g = c.getContext('2d'); g.clearRect(0, 0, 180, 180);
    g.strokeStyle = '#555'; g.beginPath(); g.arc(90, 90, 85, 0, 2 * Math.PI); g.stroke();
    const x = ui.axes[xName] || 0, y = ui.axes[yName] || 0;
    g.fillStyle = '#1f6feb'; g.beginPath(); g.arc(90 + x * 75, 90 - y * 75, 14, 0, 2 * Math.PI); g.fill();
  };
  const move = (e) => {
    const r = c.getBoundingClientRect();
    const x = ((e.clientX - r.left) / r.width - 0.5) * 2, y = -((e.clientY - r.top) / r.height - 0.5) * 2;
    const n = Math.max(1, Math.hypot(x, y));
    ui.axes[xName] = x / n; ui.axes[yName] = y / n; draw();
  };
  c.addEventListener('pointerdown', (e) => { c.setPointerCapture(e.pointerId); move(e); });
  c.addEventListener('pointermove', (e) => { if (e.buttons) move(e); });
  const release = () => { ui.axes[xName] = 0; ui.axes[yName] = 0; draw(); };
  c.addEventListener('pointerup', release); c.addEventListener('pointercancel', release);
  draw();
  return el('div', {}, el('div', {}, label), c);
}

function holdButton(name, label, cls = 'big') {
  const b = el('button', { class: cls, 'data-control': name }, label);
  const set = (v) => { ui.buttons[name] = v; b.classList.toggle('on', v); };
  b.addEventListener('pointerdown', (e) => { b.setPointerCapture(e.pointerId); set(true); });
  b.addEventListener('pointerup', () => set(false)); b.addEventListener('pointercancel', () => set(false));
  return b;
}

function build() {
  const box = document.getElementById('controls');
  const axes = controls.filter((c) => c.kind === 'axis').map((c) => c.name);
  if (axes.includes('drive_x') && axes.includes('drive_y')) box.append(stick('drive_x', 'drive_y', 'drive'));
  if (axes.includes('arm_x') && axes.includes('arm_y')) box.append(stick('arm_x', 'arm_y', 'arm'));
  for (const a of axes.filter((n) => !['drive_x', 'drive_y', 'arm_x', 'arm_y'].includes(n))) {
    const s = el('input', { type: 'range', min: -1, max: 1, step: 0.01, value: 0, 'data-control': a });
    s.addEventListener('input', () => { ui.axes[a] = parseFloat(s.value); });
    s.addEventListener('change', () => { s.value = 0; ui.axes[a] = 0; });
    box.append(el('div', {}, el('div', {}, a), s));
  }
  const buttons = el('div', {});
  for (const c of controls.filter((x) => x.kind === 'button')) {
    if (c.role === 'estop') {
      const b = el('button', { class: 'big estop', 'data-control': c.name }, 'E-STOP');
      b.addEventListener('click', () => { estopLatched = !estopLatched; b.classList.toggle('on', estopLatched); });
      buttons.append(b);
    } else {
      buttons.append(holdButton(c.name, c.role === 'deadman' ? 'DEAD-MAN (hold)' : c.name));
    }
  }
  box.append(buttons);
  for (const c of controls.filter((x) => x.kind === 'switch')) {
    ui.switches[c.name] = c.positions[0];
    const group = el('div', { 'data-switch': c.name }, el('div', {}, c.name));
    for (const p of c.positions) {
      const b = el('button', { 'data-position': p }, p);
      b.addEventListener('click', () => { ui.switches[c.name] = p; refreshSwitches(); });
      group.append(b);
    }
    box.append(group);
  }
  refreshSwitches();
}

function refreshSwitches() {
  for (const g of document.querySelectorAll('[data-switch]'))
    for (const b of g.querySelectorAll('button')) b.classList.toggle('on', ui.switches[g.dataset.switch] === b.dataset.position);
}

function cycleSwitch(name, to) {
  const c = control(null, name); if (!c || c.kind !== 'switch') return;
  ui.switches[name] = to !== undefined ? c.positions[Math.min(to, c.positions.length - 1)]
    : c.positions[(c.positions.indexOf(ui.switches[name]) + 1) % c.positions.length];
  refreshSwitches();
}

addEventListener('keydown', (e) => {
  if (e.repeat) return;
  keys.add(e.code);
  if (e.code === 'Escape') { estopLatched = !estopLatched; const b = document.querySelector('.estop'); if (b) b.classList.toggle('on', estopLatched); }
  if (e.code === 'KeyM') cycleSwitch('mode');
  if (e.code === 'Digit1') cycleSwitch('speed', 0);
  if (e.code === 'Digit2') cycleSwitch('speed', 1);
  if (e.code === 'Digit3') cycleSwitch('speed', 2);
  if (e.code === 'Space') e.preventDefault();
});
addEventListener('keyup', (e) => keys.delete(e.code));
addEventListener('blur', () => keys.clear());  // a key held while the window lost focus is released

function key(a, b) { return (keys.has(a) ? 1 : 0) - (keys.has(b) ? 1 : 0); }

// Everything merged: a control is held if any input holds it; sticks add up (clamped).
function current() {
  const out = { axes: {}, buttons: {}, switches: Object.assign({}, ui.switches) };
  const add = (n, v) => { out.axes[n] = Math.max(-1, Math.min(1, (out.axes[n] || 0) + v)); };
  for (const c of controls.filter((x) => x.kind === 'axis')) add(c.name, ui.axes[c.name] || 0);
  add('drive_y', key('KeyW', 'KeyS')); add('drive_x', key('KeyD', 'KeyA'));
  add('arm_y', key('ArrowUp', 'ArrowDown')); add('arm_x', key('ArrowRight', 'ArrowLeft')); add('arm_twist', key('KeyE', 'KeyQ'));
  for (const c of controls.filter((x) => x.kind === 'button')) out.buttons[c.name] = !!ui.buttons[c.name];
  const dm = control('deadman'), es = control('estop');
  if (dm && keys.has('Space')) out.buttons[dm.name] = true;
  if (keys.has('KeyO')) out.buttons.gripper_open = true;
  if (keys.has('KeyC')) out.buttons.gripper_close = true;
  let pads = 0;
  for (const gp of (navigator.getGamepads ? navigator.getGamepads() : [])) {
    if (!gp || !gp.connected) continue;
    pads++;
    const ax = (i) => (Math.abs(gp.axes[i] || 0) > 0.08 ? gp.axes[i] : 0), bt = (i) => !!(gp.buttons[i] && gp.buttons[i].pressed);
    add('drive_x', ax(0)); add('drive_y', -ax(1)); add('arm_x', ax(2)); add('arm_y', -ax(3));
    if (dm && (bt(4) || bt(5))) out.buttons[dm.name] = true;
    if (bt(0)) out.buttons.gripper_close = true;
    if (bt(2)) out.buttons.gripper_open = true;
    if (bt(1) && es) { estopLatched = true; }
  }
  document.getElementById('gamepad').textContent = pads ? pads + ' gamepad(s)' : 'no gamepad';
  if (es) out.buttons[es.name] = estopLatched;
  for (const n of Object.keys(out.buttons)) if (!control(null, n)) delete out.buttons[n];
  for (const n of Object.keys(out.axes)) if (!control(null, n)) delete out.axes[n];
  return out;
}

let inFlight = false, sent = 0;
async function send() {
  if (inFlight) return;  // a stalled request must not queue up stale states
  inFlight = true;
  try {
    const r = await postJson('/api/virtual/' + encodeURIComponent(id), current());
    sent++;
    const s = document.getElementById('panel-status');
    if (!r.ok) { s.textContent = 'server: HTTP ' + r.status + ' ' + await r.text(); s.className = 'bad'; }
  } catch (e) {
    document.getElementById('panel-status').textContent = 'not reaching the server';
  } finally { inFlight = false; }
}

function onUpdate(u) {
  const r = u.channels['rise/' + id + '/robot_state'], p = u.channels['rise/' + id + '/panel_state'];
  if (r) {
    const v = r.value;
    document.getElementById('robot-pos').textContent =
      'x=' + v.position[0].toFixed(2) + ' y=' + v.position[1].toFixed(2) + ' v=' + v.speed_mps.toFixed(2);
    window.risePanel.robot = v;
  }
  if (p) {
    const s = document.getElementById('panel-status'), v = p.value;
    s.textContent = v.failsafe ? 'FAILSAFE ' + v.failsafe_reason : v.deadman ? 'driving' : 'dead-man released';
    s.className = v.failsafe ? 'bad' : 'ok';
    window.risePanel.panel = v;
  }
}

window.risePanel = { robot: null, panel: null, sent: () => sent };

async function main() {
  document.getElementById('trainee-id').textContent = 'trainee ' + id;
  controls = (await getJson('/api/panel')).controls;
  build();
  setInterval(send, SEND_PERIOD_MS);
  stream(onUpdate);
  // Leaving the page: tell the server at once (it fails safe on the timeout anyway).
  addEventListener('pagehide', () => navigator.sendBeacon('/api/virtual/' + encodeURIComponent(id) + '/close?token=' + encodeURIComponent(token), ''));
}
main().catch((e) => { document.getElementById('panel-status').textContent = 'error: ' + e.message; });
