// What every builder page shares about its file (the server side is
// instructor/design_files.hpp): the version the page loaded, a save that
// carries it, and the banner when the file changed on disk since (HTTP 409)
// with its two ways out: reload the disk's file, or overwrite it knowingly.
import { postJson } from './common.js';

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
