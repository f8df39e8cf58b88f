// What every builder page shares about its file (the server side is
// instructor/design_files.hpp): the version the page loaded, a save that
// carries it, and the banner when the file changed on disk since (HTTP 409)
// with its two ways out: reload the disk's file, or overwrite it knowingly;
// the live check and how a check's errors and a save's answer are shown
// (#check-state, #errors, #yaml, #save-state, #version on every page).
import { el, postJson } from './common.js';

const byId = (id) => document.getElementById(id);

// POSTs {version, ...payload}; resolves to {status, body}.
export async function saveDesign(url, version, payload) {
  const r = await postJson(url, Object.assign({ version }, payload));
  let body = {};
  try {
    body = await r.json();
  } catch (e) {
    body = { error: `HTTP ${r.status}` };
  }
  return { status: r.status, body };
}

// The banner: an element holding #conflict-text, #reload and #overwrite.
export class ConflictBanner {
  constructor(box, { onReload, onOverwrite }) {
    this.box = box;
    this.current = '';
    box.querySelector('#reload').addEventListener('click', () => onReload());
    box.querySelector('#overwrite').addEventListener('click', () => onOverwrite(this.current));
  }
  // A 409's body: its words and the version on disk now (what "overwrite" saves over).
  show(body) {
    this.current = body.current_version || '';
    this.box.querySelector('#conflict-text').textContent = body.error;
    this.box.hidden = false;
  }
  hide() { this.box.hidden = true; }
}

// A request the server refused (not the loader's errors) as a check that failed.
export function requestError(body, extra = {}) {
  return { ok: false, yaml: '', errors: [Object.assign({ message: body.error, line: 0, key: '' }, extra)] };
}

// POSTs a live check of the page's model; the newest answer wins (an older
// request may come back later): resolves to {check, body}, or null when a
// newer check was sent since. state.checkSeq counts them.
export async function postCheck(state, url, payload, extra = {}) {
  const seq = ++state.checkSeq;
  byId('check-state').textContent = 'checking…';
  byId('check-state').className = 'warn';
  const r = await postJson(url, payload);
  const body = await r.json();
  if (seq !== state.checkSeq) return null;
  return { check: r.ok ? body : requestError(body, extra), body };
}

// "file:line: key: message"; the file named when it is not `file` (always with `alwaysFile`).
export function errorText(e, file, alwaysFile = false) {
  const named = alwaysFile ? e.file || file : e.file && e.file !== file ? e.file : '';
  const where = e.line ? `${named ? named + ':' : ''}${e.line}:` : '';
  return [where, e.key ? e.key + ':' : '', e.message].filter(Boolean).join(' ');
}

// A check in #check-state, #errors (one item per error, with its key and
// line) and #yaml; `okWords` what the program would do. Returns whether it is ok.
export function showCheck(check, okWords, text) {
  const ok = Boolean(check && check.ok);
  const errors = (check && check.errors) || [];
  byId('check-state').textContent = !check ? 'not checked yet' : ok ? okWords :
    `${errors.length} error${errors.length === 1 ? '' : 's'}: not saved until fixed`;
  byId('check-state').className = ok ? 'ok' : 'bad';
  byId('errors').replaceChildren(...errors.map((e) => el('li', { 'data-key': e.key || '', 'data-line': e.line || 0 }, text(e))));
  byId('yaml').textContent = (check && check.yaml) || '';
  return ok;
}

// What the page shows after an edit.
export function showEdited() {
  byId('save-state').textContent = 'edited, not saved';
  byId('save-state').className = 'warn';
}

// An edit of the page's model: marked unsaved, drawn, checked.
export function edited(state, render, check) {
  state.dirty = true;
  showEdited();
  render();
  check();
}

// A save's answer in #save-state and #version, the banner on a 409; returns
// whether it saved. The caller keeps the new version and takes body.errors.
export function showSaved(status, body, conflict) {
  const s = byId('save-state');
  if (status === 200) {
    byId('version').textContent = 'version ' + body.version;
    s.textContent = 'saved';
    s.className = 'ok';
    conflict.hide();
    return true;
  }
  if (status === 409) {
    conflict.show(body);
    s.textContent = 'not saved: changed on disk';
  } else {
    s.textContent = 'not saved: ' + (body.error || 'HTTP ' + status);
  }
  s.className = 'bad';
  return false;
}
