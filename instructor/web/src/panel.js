// The virtual panel: on-screen sticks and buttons, the keyboard and any
// gamepad the browser sees, sent to the server at a steady rate; the server
// publishes them as PanelState under the daemon's safety rules (a page that
// stops sending fails safe there, not here). The widgets show what is sent
// (every input merged), and the console's feedback (PanelFeedback) comes back
// over the stream as LEDs and displays.
import { getJson, postJson, stream, el, token } from './common.js';

const params = new URLSearchParams(location.search);
const id = params.get('id') || 't1';
// This page load: its close refuses the updates still on their way (a beacon
// can overtake a request in flight, which would revive the panel after it).
const pageId = Array.from(crypto.getRandomValues(new Uint8Array(8)), (b) => b.toString(16).padStart(2, '0')).join('');
const SEND_PERIOD_MS = 20;  // 50 Hz, well inside the server's 200 ms timeout
const STICK = { size: 180, reach: 75, dot: 14, colour: '#1f6feb' };  // the tests find the dot by its colour

const ui = { axes: {}, buttons: {}, switches: {} };    // on-screen controls
const keys = new Set();
let estopLatched = false;
let controls = [];
let definition = { leds: [], displays: [] };
const sticks = {};  // label → {xName, yName, canvas, x, y, px, py}: the dot as last drawn

function control(role, name) { return controls.find((c) => (role && c.role === role) || c.name === name); }

function drawStick(s, x, y) {
  if (s.x === x && s.y === y) return;
  const g = s.canvas.getContext('2d'), c = STICK.size / 2;
  g.clearRect(0, 0, STICK.size, STICK.size);
  g.strokeStyle = '#555'; g.beginPath(); g.arc(c, c, c - 5, 0, 2 * Math.PI); g.stroke();
  g.beginPath(); g.moveTo(c - 8, c); g.lineTo(c + 8, c); g.moveTo(c, c - 8); g.lineTo(c, c + 8); g.stroke();
  Object.assign(s, { x, y, px: c + x * STICK.reach, py: c - y * STICK.reach });
  g.fillStyle = STICK.colour; g.beginPath(); g.arc(s.px, s.py, STICK.dot, 0, 2 * Math.PI); g.fill();
  s.readout.textContent = 'x ' + x.toFixed(2) + '  y ' + y.toFixed(2);
}

function stick(xName, yName, label) {
  const c = el('canvas', { class: 'stick', width: STICK.size, height: STICK.size, 'data-stick': label });
  const s = sticks[label] = { xName, yName, canvas: c, readout: el('div', { class: 'readout' }) };
  const move = (e) => {
    const r = c.getBoundingClientRect();
    const x = ((e.clientX - r.left) / r.width - 0.5) * 2, y = -((e.clientY - r.top) / r.height - 0.5) * 2;
    const n = Math.max(1, Math.hypot(x, y));
    ui.axes[xName] = x / n; ui.axes[yName] = y / n;
  };
  c.addEventListener('pointerdown', (e) => { c.setPointerCapture(e.pointerId); move(e); });
  c.addEventListener('pointermove', (e) => { if (e.buttons) move(e); });
  const release = () => { ui.axes[xName] = 0; ui.axes[yName] = 0; };
  c.addEventListener('pointerup', release); c.addEventListener('pointercancel', release);
  drawStick(s, 0, 0);
  return el('div', {}, el('div', {}, label + ' stick'), c, s.readout);
}

function holdButton(name, label, cls = 'big') {
  const b = el('button', { class: cls, 'data-control': name }, label);
  const set = (v) => { ui.buttons[name] = v; };
  b.addEventListener('pointerdown', (e) => { b.setPointerCapture(e.pointerId); set(true); });
  b.addEventListener('pointerup', () => set(false)); b.addEventListener('pointercancel', () => set(false));
  return b;
}

function buildAxes(box) {
  const axes = controls.filter((c) => c.kind === 'axis').map((c) => c.name);
  if (axes.includes('drive_x') && axes.includes('drive_y')) box.append(stick('drive_x', 'drive_y', 'drive'));
  if (axes.includes('arm_x') && axes.includes('arm_y')) box.append(stick('arm_x', 'arm_y', 'arm'));
  for (const a of axes.filter((n) => !['drive_x', 'drive_y', 'arm_x', 'arm_y'].includes(n))) {
    const s = el('input', { type: 'range', min: -1, max: 1, step: 0.01, value: 0, 'data-control': a });
    s.addEventListener('input', () => { ui.axes[a] = parseFloat(s.value); });
    s.addEventListener('change', () => { ui.axes[a] = 0; });  // springs back: show() moves the slider
    box.append(el('div', {}, el('div', {}, a), s));
  }
}

function buildButtons(box) {
  const buttons = el('div', { class: 'buttons' });
  for (const c of controls.filter((x) => x.kind === 'button')) {
    if (c.role === 'estop') {
      const b = el('button', { class: 'big estop', 'data-control': c.name }, 'E-STOP');
      b.addEventListener('click', () => { estopLatched = !estopLatched; });
      buttons.append(b);
    } else {
      buttons.append(holdButton(c.name, c.role === 'deadman' ? 'DEAD-MAN (hold)' : c.name));
    }
  }
  box.append(buttons);
}

function buildSwitches(box) {
  for (const c of controls.filter((x) => x.kind === 'switch')) {
    ui.switches[c.name] = c.positions[0];
    const group = el('div', { 'data-switch': c.name, class: 'switch' }, el('div', {}, c.name),
      el('div', { class: 'switch-value', 'data-switch-value': c.name }));
    for (const p of c.positions) {
      const b = el('button', { 'data-position': p }, p);
      b.addEventListener('click', () => { ui.switches[c.name] = p; });
      group.append(b);
    }
    box.append(group);
  }
}

// The console's LEDs and displays, as the definition names them (the feedback may name more).
function buildFeedback() {
  const box = document.getElementById('feedback');
  for (const n of definition.leds) box.append(led(n));
  for (const d of definition.displays) box.append(display(d.name));
}
function led(name) { return el('span', { class: 'led', 'data-led': name }, el('i', {}), name); }
function display(name) { return el('span', { class: 'display', 'data-display': name }, name + ' ', el('b', {}, '—')); }

function build() {
  const box = document.getElementById('controls');
  buildAxes(box); buildButtons(box); buildSwitches(box); buildFeedback();
}

function cycleSwitch(name, to) {
  const c = control(null, name); if (!c || c.kind !== 'switch') return;
  ui.switches[name] = to !== undefined ? c.positions[Math.min(to, c.positions.length - 1)]
    : c.positions[(c.positions.indexOf(ui.switches[name]) + 1) % c.positions.length];
}

addEventListener('keydown', (e) => {
  if (e.repeat) return;
  keys.add(e.code);
  if (e.code === 'Escape') estopLatched = !estopLatched;
  if (e.code === 'KeyM') cycleSwitch('mode');
  if (e.code === 'Digit1') cycleSwitch('speed', 0);
  if (e.code === 'Digit2') cycleSwitch('speed', 1);
  if (e.code === 'Digit3') cycleSwitch('speed', 2);
  if (e.code === 'Space') e.preventDefault();
});
addEventListener('keyup', (e) => keys.delete(e.code));
addEventListener('blur', () => keys.clear());  // a key held while the window lost focus is released

function key(a, b) { return (keys.has(a) ? 1 : 0) - (keys.has(b) ? 1 : 0); }

// A connected gamepad's part of the state; returns whether there was one.
function addGamepad(gp, out, add) {
  const ax = (i) => (Math.abs(gp.axes[i] || 0) > 0.08 ? gp.axes[i] : 0), bt = (i) => !!(gp.buttons[i] && gp.buttons[i].pressed);
  add('drive_x', ax(0)); add('drive_y', -ax(1)); add('arm_x', ax(2)); add('arm_y', -ax(3));
  const dm = control('deadman');
  if (dm && (bt(4) || bt(5))) out.buttons[dm.name] = true;
  if (bt(0)) out.buttons.gripper_close = true;
  if (bt(2)) out.buttons.gripper_open = true;
  if (bt(1) && control('estop')) estopLatched = true;
}

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
    if (gp && gp.connected) { pads++; addGamepad(gp, out, add); }
  }
  document.getElementById('gamepad').textContent = pads ? pads + ' gamepad(s)' : 'no gamepad';
  if (es) out.buttons[es.name] = estopLatched;
  for (const n of Object.keys(out.buttons)) if (!control(null, n)) delete out.buttons[n];
  for (const n of Object.keys(out.axes)) if (!control(null, n)) delete out.axes[n];
  return out;
}

// The widgets follow the state being sent, whichever input set it.
function show(state) {
  for (const s of Object.values(sticks)) drawStick(s, state.axes[s.xName] || 0, state.axes[s.yName] || 0);
  for (const s of document.querySelectorAll('input[data-control]')) s.value = state.axes[s.dataset.control] || 0;
  for (const b of document.querySelectorAll('button[data-control]')) {
    const on = !!state.buttons[b.dataset.control];
    b.classList.toggle('on', on);
    b.dataset.held = on ? 'held' : 'released';
  }
  const es = control('estop'), latched = !!(es && state.buttons[es.name]);
  document.body.classList.toggle('estopped', latched);
  document.getElementById('estop-banner').hidden = !latched;
  const esButton = document.querySelector('button.estop');
  if (esButton) esButton.textContent = latched ? 'E-STOP LATCHED' : 'E-STOP';
  const dm = control('deadman'), held = !!(dm && state.buttons[dm.name]);
  const dmLine = document.getElementById('deadman-state');
  dmLine.textContent = held ? 'DEAD-MAN HELD' : 'dead-man released'; dmLine.className = held ? 'held' : '';
  for (const g of document.querySelectorAll('[data-switch]')) {
    const v = state.switches[g.dataset.switch];
    for (const b of g.querySelectorAll('button')) b.classList.toggle('on', v === b.dataset.position);
    g.querySelector('[data-switch-value]').textContent = v;
  }
  window.risePanel.state = state;
}

let inFlight = false, sent = 0;
async function send() {
  const state = current();
  show(state);
  if (inFlight) return;  // a stalled request must not queue up stale states
  inFlight = true;
  try {
    const r = await postJson('/api/virtual/' + encodeURIComponent(id) + '?page=' + pageId, state);
    sent++;
    const s = document.getElementById('panel-status');
    if (!r.ok) { s.textContent = 'server: HTTP ' + r.status + ' ' + await r.text(); s.className = 'bad'; }
  } catch (e) {
    document.getElementById('panel-status').textContent = 'not reaching the server';
  } finally { inFlight = false; }
}

function showFeedback(f) {
  const box = document.getElementById('feedback');
  for (const [n, on] of Object.entries(f.leds)) {
    let l = box.querySelector('[data-led="' + CSS.escape(n) + '"]');
    if (!l) { l = led(n); box.append(l); }
    l.classList.toggle('lit', on);
  }
  for (const [n, v] of Object.entries(f.displays)) {
    let d = box.querySelector('[data-display="' + CSS.escape(n) + '"]');
    if (!d) { d = display(n); box.append(d); }
    const def = definition.displays.find((x) => x.name === n);
    d.querySelector('b').textContent = v.toFixed(def ? def.decimals : 2);
  }
  const bz = document.getElementById('buzzer');
  bz.textContent = 'buzzer ' + f.buzzer + (f.rumble > 0 ? ' · rumble ' + f.rumble.toFixed(2) : '');
  bz.className = f.buzzer === 'off' ? '' : 'sounding';
  window.risePanel.feedback = f;
}

function onUpdate(u) {
  const ch = (kind) => u.channels['rise/' + id + '/' + kind];
  const r = ch('robot_state'), p = ch('panel_state'), f = ch('panel_feedback');
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
  if (f) showFeedback(f.value);
}

// For the tests and the curious: what the page shows and sends.
window.risePanel = { robot: null, panel: null, feedback: null, state: null, sent: () => sent,
                     sticks: () => Object.fromEntries(Object.entries(sticks).map(([k, s]) => [k, { x: s.x, y: s.y, px: s.px, py: s.py }])),
                     stickColour: STICK.colour };

async function main() {
  document.getElementById('trainee-id').textContent = 'trainee ' + id;
  const panel = await getJson('/api/panel');
  controls = panel.controls;
  definition = { leds: panel.leds || [], displays: panel.displays || [] };
  build();
  setInterval(send, SEND_PERIOD_MS);
  stream(onUpdate);
  // Leaving the page: tell the server at once (it fails safe on the timeout anyway).
  addEventListener('pagehide', () => navigator.sendBeacon('/api/virtual/' + encodeURIComponent(id) + '/close?page=' + pageId + '&token=' + encodeURIComponent(token), ''));
}
main().catch((e) => { document.getElementById('panel-status').textContent = 'error: ' + e.message; });
