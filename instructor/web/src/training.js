// The Training Builder (/training.html): opens a training file of the
// server's --designs folder, draws its graph, adds tasks and conditioned
// edges, deletes them, edits repeats; every change is checked by the server
// with the loader `rise-trainer check` uses, whose errors show here with
// their line and key; Save writes the YAML atomically, or says that the file
// changed on disk since it was loaded (409) and offers to reload or overwrite.
import { drawBuilderNav } from './builder_nav.js';
import { getJson, el } from './common.js';
import { ConflictBanner, errorText, postCheck, saveDesign, edited, showCheck, showSaved } from './design_file.js';
import { draw } from './graph_draw.js';

const $ = (id) => document.getElementById(id);
const params = new URLSearchParams(location.search);
const state = {
  file: '', version: '', graph: null, tasks: [], fields: [], ops: [],
  check: null, checkSeq: 0, dirty: false, picked: [], fresh: -1,
};
let conflict = null;  // the ConflictBanner, once the page is up

async function loadListing() {
  const l = await getJson('/api/builder/trainings');
  state.tasks = l.tasks.filter((t) => !t.error);
  state.fields = l.fields;
  state.ops = l.ops;
  $('file').replaceChildren(...l.trainings.map((t) => el('option', { value: t.file }, t.file + (t.error ? ' (does not load)' : ''))));
  $('node-task').replaceChildren(...state.tasks.map((t) => el('option', { value: t.file }, `${t.file} (${t.name})`)));
  $('edge-op').replaceChildren(...state.ops.map((o) => el('option', { value: o }, o)));
  return l.trainings;
}

async function openFile(file) {
  const r = await getJson('/api/builder/training/' + encodeURIComponent(file));
  state.file = file;
  $('file').value = file;
  state.version = r.version;
  state.dirty = false;
  state.fresh = -1;
  conflict.hide();
  $('version').textContent = 'version ' + r.version;
  $('save-state').textContent = '';
  if (r.load_error) {
    state.graph = null;
    state.check = { ok: false, yaml: r.text, errors: r.load_error.split('\n').map((m) => ({ message: m, line: 0, key: '' })) };
    render();
    return;
  }
  state.graph = r.graph;
  state.check = r.check;
  render();
}

// Live check: the newest answer wins (an older request may come back later).
async function check() {
  const answer = await postCheck(state, `/api/builder/training/${encodeURIComponent(state.file)}/check`, { graph: state.graph });
  if (!answer) return;
  state.check = answer.check;
  render();
}

const changed = () => edited(state, render, check);

// "transitions[3].if" → "transitions[3]": what an error belongs to.
function badEntries() {
  const bad = new Set();
  for (const e of (state.check && state.check.errors) || []) {
    const m = /^(nodes|transitions)\[\d+\]/.exec(e.key || '');
    if (m) bad.add(m[0]);
  }
  return bad;
}

function render() {
  const g = state.graph;
  const bad = badEntries();
  const ok = showCheck(state.check, 'ok: rise-trainer check would load it', (e) => errorText(e, state.file));
  $('save').disabled = !g || !ok || !state.dirty;
  if (!g) {
    $('graph').replaceChildren();
    return;
  }
  draw($('graph'), g, { bad, picked: state.picked.at(-1) || '', fresh: state.fresh, onPick: pick });
  renderSelects();
  renderNodes(bad);
  renderEdges(bad);
}

function renderSelects() {
  const g = state.graph;
  const keep = (id, options) => {
    const s = $(id), v = s.value;
    s.replaceChildren(...options.map((o) => el('option', { value: o }, o)));
    if (options.includes(v)) s.value = v;
  };
  keep('edge-from', ['START', ...g.nodes.map((n) => n.name)]);
  keep('edge-to', [...g.nodes.map((n) => n.name), 'END']);
  fieldsFor($('edge-from').value);
}

// The condition fields a transition from `from` may test: none from START
// (there is no result yet), else the result's fields and its task's events.
function fieldsFor(from) {
  const node = state.graph.nodes.find((n) => n.name === from);
  const task = node && state.tasks.find((t) => t.file === node.task);
  const options = ['always', ...(node ? state.fields : []), ...((task && task.events) || []).map((e) => 'events.' + e)];
  const s = $('edge-field'), v = s.value;
  s.replaceChildren(...options.map((o) => el('option', { value: o }, o)));
  if (options.includes(v)) s.value = v;
  const always = s.value === 'always';
  $('edge-op').disabled = always;
  $('edge-value').disabled = always;
}

function renderNodes(bad) {
  const rows = [el('tr', {}, el('th', {}, 'name'), el('th', {}, 'task file'), el('th', {}, 'max attempts'), el('th', {}, 'comment'), el('th', {}))];
  state.graph.nodes.forEach((n, i) => {
    const attempts = el('input', { type: 'number', min: '1', value: n.max_attempts, size: '3', class: 'attempts', 'data-node': n.name });
    attempts.addEventListener('change', () => { n.max_attempts = parseInt(attempts.value, 10); changed(); });
    const del = el('button', { class: 'delete-node', 'data-node': n.name }, 'delete');
    del.addEventListener('click', () => deleteNode(n.name));
    rows.push(el('tr', { class: bad.has(`nodes[${i}]`) ? 'bad' : '' }, el('td', {}, n.name), el('td', {}, n.task),
                 el('td', {}, attempts), el('td', {}, n.comment || ''), el('td', {}, del)));
  });
  $('nodes').replaceChildren(...rows);
}

function renderEdges(bad) {
  const g = state.graph;
  const rows = [el('tr', {}, ...['#', 'from', 'if', 'to', 'comment', ''].map((h) => el('th', {}, h)))];
  g.transitions.forEach((t, i) => {
    const buttons = el('td', {});
    for (const [label, cls, fn] of [['↑', 'up', () => move(i, -1)], ['↓', 'down', () => move(i, 1)], ['delete', 'delete-edge', () => deleteEdge(i)]]) {
      const b = el('button', { class: cls, 'data-index': i }, label);
      b.addEventListener('click', fn);
      buttons.append(b);
    }
    const cls = bad.has(`transitions[${i}]`) ? 'bad' : i === state.fresh ? 'new' : '';
    rows.push(el('tr', { class: cls, 'data-index': i }, el('td', {}, i + 1), el('td', {}, t.from), el('td', {}, t.if || 'always'),
                 el('td', {}, t.to), el('td', {}, t.comment || ''), buttons));
  });
  $('edges').replaceChildren(...rows);
}

// Clicking boxes: the first is the new edge's "from", the next its "to".
function pick(name) {
  state.picked.push(name);
  if (state.picked.length > 2) state.picked = [name];
  if (state.picked.length === 1 && name !== 'END') $('edge-from').value = name;
  if (state.picked.length === 2 && name !== 'START') $('edge-to').value = name;
  fieldsFor($('edge-from').value);
  render();
}

function addNode() {
  const name = $('node-name').value.trim();
  const task = $('node-task').value;
  if (!name || !task) return;
  state.graph.nodes.push({ name, task, max_attempts: parseInt($('node-attempts').value, 10) || 1, comment: '' });
  $('node-name').value = '';
  state.fresh = -1;
  changed();
}

// A conditioned edge goes before the first unconditional one from its node
// (which would always win, transitions being tried in order); an
// unconditional one after the others from its node.
function addEdge() {
  const g = state.graph;
  const from = $('edge-from').value, to = $('edge-to').value, field = $('edge-field').value;
  const cond = field === 'always' ? '' : `${field} ${$('edge-op').value} ${$('edge-value').value.trim()}`;
  const edge = { from, to, if: cond, comment: $('edge-comment').value.trim() };
  const same = g.transitions.map((t, i) => [t, i]).filter(([t]) => t.from === from);
  const always = same.find(([t]) => !t.if);
  let at = g.transitions.length;
  if (cond && always) at = always[1];
  else if (same.length) at = same.at(-1)[1] + 1;
  g.transitions.splice(at, 0, edge);
  state.fresh = at;
  $('edge-note').textContent = `added as transition ${at + 1}` +
    (cond && always ? ` — before the unconditional ${from} → ${always[0].to}, which would otherwise always win` : '');
  $('edge-comment').value = '';
  state.picked = [];
  changed();
}

function deleteEdge(i) {
  state.graph.transitions.splice(i, 1);
  state.fresh = -1;
  changed();
}

function deleteNode(name) {
  const g = state.graph;
  g.nodes = g.nodes.filter((n) => n.name !== name);
  g.transitions = g.transitions.filter((t) => t.from !== name && t.to !== name);
  state.fresh = -1;
  changed();
}

function move(i, by) {
  const t = state.graph.transitions;
  const j = i + by;
  if (j < 0 || j >= t.length) return;
  [t[i], t[j]] = [t[j], t[i]];
  state.fresh = state.fresh === i ? j : state.fresh;
  changed();
}

async function save(version) {
  $('save').disabled = true;
  const { status, body } = await saveDesign('/api/builder/training/' + encodeURIComponent(state.file), version,
                                            { graph: state.graph });
  if (showSaved(status, body, conflict)) Object.assign(state, { version: body.version, dirty: false });
  else if (body.errors) state.check = body;
  render();
}

async function main() {
  conflict = new ConflictBanner($('conflict'), { onReload: () => openFile(state.file), onOverwrite: (v) => save(v) });
  const trainings = await loadListing();
  drawBuilderNav($('builders'), 'training.html');
  $('file').addEventListener('change', () => openFile($('file').value));
  $('edge-from').addEventListener('change', () => fieldsFor($('edge-from').value));
  $('edge-field').addEventListener('change', () => fieldsFor($('edge-from').value));
  $('add-node').addEventListener('click', addNode);
  $('add-edge').addEventListener('click', addEdge);
  $('save').addEventListener('click', () => save(state.version));
  const first = params.get('file') || (trainings[0] && trainings[0].file);
  if (first) await openFile(first);
  document.body.dataset.ready = '1';
}

main().catch((e) => { $('check-state').textContent = String(e); $('check-state').className = 'bad'; });
