// The Console Builder (/console_builder.html): opens a panel definition of
// the server's --consoles folder, shows every signal of its sources live
// (the server reads them with rise-hild's source classes), learns the one the
// user moves (the signal that changed most for its range in the window, with
// its rest, min and max proposing invert, deadband, range or positions),
// edits and adds controls, checks each change with the loader rise-hild uses
// (errors with line and key, beside their control), previews the PanelState
// the PanelMapper makes of it, and saves the YAML (a comment per control)
// atomically, or says the file changed on disk (409) and offers the way out.
import { drawBuilderNav } from './builder_nav.js';
import { getJson, postJson, el, token } from './common.js';
import { ConflictBanner, errorText as fileErrorText, postCheck, saveDesign, edited, showCheck, showSaved } from './design_file.js';

const $ = (id) => document.getElementById(id);
const params = new URLSearchParams(location.search);
const state = {
  file: '', version: '', controls: [], sources: [], signals: [], check: null, checkSeq: 0,
  dirty: false, editing: -1, live: false, proposal: null, values: [], learning: '',
};
let conflict = null;

// ---- A control's fields: [[key, value], ...] in file order ----
const get = (c, k) => { const f = c.fields.find((x) => x[0] === k); return f ? f[1] : undefined; };
function set(c, k, v) {
  const i = c.fields.findIndex((x) => x[0] === k);
  if (v === undefined || v === '' || v === null) { if (i >= 0) c.fields.splice(i, 1); return; }
  if (i >= 0) c.fields[i][1] = v; else c.fields.push([k, v]);
}


async function openFile(file) {
  const r = await getJson('/api/builder/console/' + encodeURIComponent(file));
  Object.assign(state, { file, version: r.version, dirty: false, editing: -1 });
  $('file').value = file;
  conflict.hide();
  $('version').textContent = 'version ' + r.version;
  $('save-state').textContent = '';
  if (r.load_error) {
    state.controls = [];
    state.check = { ok: false, yaml: r.text, errors: [{ message: r.load_error, line: 0, key: '', control: -1 }] };
  } else {
    state.controls = r.controls;
    state.sources = r.sources;
    state.check = r.check;
  }
  $('c-source').replaceChildren(...state.sources.map((s) => el('option', { value: s.name }, `${s.name} (${s.protocol})`)));
  resetForm();
  render();
}

async function check() {
  const answer = await postCheck(state, `/api/builder/console/${encodeURIComponent(state.file)}/check`,
                                 { controls: state.controls }, { control: -1 });
  if (!answer) return;
  state.check = answer.check;
  render();
}

const changed = () => edited(state, render, check);

const errorText = (e) => fileErrorText(e, state.file, true);
const show = (v) => Array.isArray(v) ? `[${v.map(show).join(', ')}]` : v === undefined ? '' : String(v);

function render() {
  const ok = showCheck(state.check, 'ok: rise-hild --panel would load it', errorText);
  const errors = (state.check && state.check.errors) || [];
  $('save').disabled = !ok || !state.dirty;
  renderControls(errors);
}

function renderControls(errors) {
  const bad = new Map(errors.filter((e) => e.control >= 0).map((e) => [e.control, errorText(e)]));
  const rows = [el('tr', {}, ...['name', 'kind', 'source', 'signal', 'role', 'motion', 'safe', 'comment', ''].map((h) => el('th', {}, h)))];
  state.controls.forEach((c, i) => {
    const edit = el('button', { class: 'edit', 'data-index': i }, 'edit');
    edit.addEventListener('click', () => editControl(i));
    const del = el('button', { class: 'delete', 'data-index': i }, 'delete');
    del.addEventListener('click', () => { state.controls.splice(i, 1); changed(); });
    const row = el('tr', { class: bad.has(i) ? 'bad' : '', 'data-name': show(get(c, 'name')) },
      ...['name', 'kind', 'source', 'signal', 'role', 'motion', 'safe'].map((k) => el('td', {}, show(get(c, k)))),
      el('td', { class: 'dim' }, c.comment || ''), el('td', {}, edit, del));
    rows.push(row);
    if (bad.has(i)) rows.push(el('tr', { class: 'bad error-row' }, el('td', { colspan: 9 }, '↑ ' + bad.get(i))));
  });
  $('controls').replaceChildren(...rows);
}

// ---- The form ----
function safeOptions() {
  const kind = $('c-kind').value;
  if (kind === 'axis') return ['0.0', '-1.0', '1.0'];
  if (kind === 'button') return ['false', 'true'];
  return positions();
}
const positions = () => $('c-positions').value.split(',').map((p) => p.trim()).filter(Boolean);

function formKind() {
  const kind = $('c-kind').value;
  $('axis-fields').hidden = kind !== 'axis';
  $('switch-fields').hidden = kind !== 'switch';
  const s = $('c-safe'), v = s.value, options = safeOptions();
  s.replaceChildren(...options.map((o) => el('option', { value: o }, o)));
  if (options.includes(v)) s.value = v;
}

function resetForm() {
  for (const id of ['c-name', 'c-signal', 'c-deadband', 'c-range-min', 'c-range-max', 'c-positions', 'c-comment']) $(id).value = '';
  $('c-role').value = '';
  $('c-motion').checked = false;
  $('c-invert').checked = false;
  state.editing = -1;
  $('form-title').textContent = 'New control';
  $('c-add').textContent = 'Add control';
  $('c-cancel').hidden = true;
  formKind();
}

function editControl(i) {
  const c = state.controls[i];
  resetForm();
  state.editing = i;
  $('form-title').textContent = 'Edit ' + show(get(c, 'name'));
  $('c-add').textContent = 'Update control';
  $('c-cancel').hidden = false;
  $('c-name').value = show(get(c, 'name'));
  $('c-kind').value = show(get(c, 'kind')) || 'axis';
  $('c-source').value = show(get(c, 'source')) || (state.sources[0] && state.sources[0].name) || '';
  $('c-signal').value = show(get(c, 'signal'));
  $('c-role').value = show(get(c, 'role'));
  $('c-motion').checked = show(get(c, 'motion')) === 'true';
  $('c-invert').checked = show(get(c, 'invert')) === 'true';
  $('c-deadband').value = show(get(c, 'deadband'));
  const range = get(c, 'range');
  if (Array.isArray(range)) [$('c-range-min').value, $('c-range-max').value] = range;
  const pos = get(c, 'positions');
  if (Array.isArray(pos)) $('c-positions').value = pos.join(', ');
  formKind();
  $('c-safe').value = show(get(c, 'safe'));
  $('c-comment').value = c.comment || '';
}

// The form into a control; an edited one keeps the keys the form does not show.
function fromForm() {
  const old = state.editing >= 0 ? state.controls[state.editing] : null;
  const c = { comment: $('c-comment').value.trim(), fields: old ? old.fields.map((f) => [f[0], f[1]]) : [] };
  const kind = $('c-kind').value;
  const firstSource = state.sources[0] && state.sources[0].name;
  set(c, 'name', $('c-name').value.trim());
  set(c, 'kind', kind);
  set(c, 'source', $('c-source').value && ($('c-source').value !== firstSource || get(c, 'source')) ? $('c-source').value : undefined);
  set(c, 'signal', $('c-signal').value.trim());
  set(c, 'role', $('c-role').value || undefined);
  set(c, 'motion', $('c-motion').checked ? 'true' : undefined);
  const axis = kind === 'axis';
  set(c, 'invert', axis && $('c-invert').checked ? 'true' : undefined);
  set(c, 'deadband', axis ? $('c-deadband').value.trim() : undefined);
  const lo = $('c-range-min').value.trim(), hi = $('c-range-max').value.trim();
  set(c, 'range', axis && lo !== '' && hi !== '' ? [lo, hi] : undefined);
  set(c, 'positions', kind === 'switch' ? positions() : undefined);
  // safe goes last, as in the shipped files.
  set(c, 'safe', undefined);
  set(c, 'safe', $('c-safe').value);
  return c;
}

function addControl() {
  const c = fromForm();
  if (state.editing >= 0) state.controls[state.editing] = c; else state.controls.push(c);
  resetForm();
  changed();
}

// ---- Live view and learning ----
async function startLive() {
  $('live-state').textContent = 'opening…';
  const r = await postJson(`/api/builder/console/${encodeURIComponent(state.file)}/live`, {});
  const body = await r.json();
  if (!r.ok) {
    $('live-state').textContent = body.error;
    $('live-state').className = 'bad';
    return;
  }
  state.signals = body.signals;
  state.live = true;
  $('learn').disabled = false;
  renderSignals();
  check();  // starts the preview of the definition as edited
  poll();
}

function renderSignals() {
  const rows = [el('tr', {}, ...['source', 'signal', 'on the wire', 'kind', 'value', ''].map((h) => el('th', {}, h)))];
  for (const s of state.signals)
    rows.push(el('tr', { 'data-signal': s.signal, 'data-id': s.id }, el('td', {}, s.source), el('td', {}, s.signal),
                 el('td', { class: 'dim' }, s.wire || ''), el('td', {}, s.kind),
                 el('td', { class: 'value', id: 'v' + s.id }, ''), el('td', {}, s.bound ? '●' : '')));
  $('signals').replaceChildren(...rows);
}

async function poll() {
  if (!state.live) return;
  try {
    const r = await getJson('/api/builder/console_live');
    state.values = r.values;
    r.values.forEach((v, i) => {
      const cell = $('v' + i);
      if (cell) cell.textContent = Number.isInteger(v) ? String(v) : v.toFixed(3);
    });
    $('live-state').textContent = r.sources.map((s) => `${s.name}: ${s.connected ? (s.stale ? 'stale' : 'live') : 'down ' + s.down_reason} (${s.frames_ok} frames)`).join('; ');
    $('live-state').className = r.sources.every((s) => s.connected && !s.stale) ? 'ok' : 'warn';
    $('learn-state').textContent = r.learning ? `move it now… ${r.learn_left_s.toFixed(1)} s` : '';
    // 'started' until an answer says the window runs (an answer sent before
    // the POST landed says it does not), then 'running' until it is over.
    if (r.learning && state.learning === 'started') state.learning = 'running';
    if (!r.learning && state.learning === 'running') {
      state.learning = '';
      if (r.proposal) propose(r.proposal);
    }
    renderPreview(r.preview);
  } catch (e) {
    $('live-state').textContent = String(e);
  }
  setTimeout(poll, 100);
}

function renderPreview(p) {
  if (!p) { $('preview-state').textContent = 'the definition as edited does not run yet (fix its errors)'; return; }
  $('preview-state').textContent = p.failsafe ? 'failsafe: ' + p.failsafe_reason : `ok, dead-man ${p.deadman ? 'held' : 'released'}`;
  $('preview-state').className = p.failsafe ? 'warn' : 'ok';
  const rows = [el('tr', {}, ...['control', 'kind', 'value', ''].map((h) => el('th', {}, h)))];
  for (const c of p.controls) {
    const v = typeof c.value === 'number' ? c.value.toFixed(3) : String(c.value);
    rows.push(el('tr', { 'data-control': c.name }, el('td', {}, c.name), el('td', {}, c.kind), el('td', { class: 'value' }, v),
                 el('td', { class: 'dim' }, c.forced_safe ? 'at its safe value' : '')));
  }
  $('preview').replaceChildren(...rows);
}

async function learn() {
  state.proposal = null;
  $('proposal').textContent = '';
  const r = await postJson('/api/builder/console_learn', { seconds: parseFloat($('learn-seconds').value) || 4 });
  if (!r.ok) { $('learn-state').textContent = (await r.json()).error; return; }
  state.learning = 'started';
}

// The learned signal into the form: the user names it and picks the rest.
function propose(p) {
  state.proposal = p;
  if (p.none) { $('proposal').textContent = p.none + ': try again'; return; }
  resetForm();
  $('c-source').value = p.source;
  $('c-signal').value = p.signal;
  $('c-kind').value = p.kind;
  let what = `${p.signal} of ${p.source} moved (rest ${p.rest}, ${p.min} .. ${p.max})`;
  if (p.kind === 'axis') {
    $('c-invert').checked = !!p.invert;
    $('c-deadband').value = String(p.deadband);
    if (p.range) [$('c-range-min').value, $('c-range-max').value] = p.range.map(String);
    what += `: invert ${p.invert ? 'yes' : 'no'}, deadband ${p.deadband}`;
  } else if (p.kind === 'switch') {
    $('c-positions').value = Array.from({ length: p.positions }, (_, i) => 'pos' + i).join(', ');
  } else {
    what += `: pressed = ${p.pressed_value}`;
  }
  if (p.bound) what += ' — already bound by the definition';
  formKind();
  $('c-comment').value = `learned: ${p.signal} of ${p.source}`;
  $('proposal').textContent = what;
  $('proposal').className = 'ok';
  $('c-name').focus();
}

async function save(version) {
  $('save').disabled = true;
  const { status, body } = await saveDesign('/api/builder/console/' + encodeURIComponent(state.file), version,
                                            { controls: state.controls });
  if (showSaved(status, body, conflict)) Object.assign(state, { version: body.version, dirty: false });
  else if (body.errors) state.check = body;
  render();
}

async function main() {
  drawBuilderNav($('builders'), 'console_builder.html');
  conflict = new ConflictBanner($('conflict'), { onReload: () => openFile(state.file), onOverwrite: (v) => save(v) });
  const listing = await getJson('/api/builder/consoles');
  $('file').replaceChildren(...listing.files.map((f) => el('option', { value: f }, f)));
  $('file').addEventListener('change', () => openFile($('file').value));
  $('c-kind').addEventListener('change', formKind);
  $('c-positions').addEventListener('change', formKind);
  $('c-role').addEventListener('change', () => {
    const role = $('c-role').value;
    if (role) { $('c-kind').value = 'button'; formKind(); $('c-safe').value = role === 'estop' ? 'true' : 'false'; }
  });
  $('c-add').addEventListener('click', addControl);
  $('c-cancel').addEventListener('click', resetForm);
  $('live-start').addEventListener('click', startLive);
  $('learn').addEventListener('click', learn);
  $('save').addEventListener('click', () => save(state.version));
  const first = params.get('file') || listing.files[0];
  if (first) await openFile(first);
  document.body.dataset.ready = '1';
}

main().catch((e) => { $('check-state').textContent = String(e); $('check-state').className = 'bad'; });
