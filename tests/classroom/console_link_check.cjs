// The console page's trainee list across a cut link (classroom_test.sh):
// once the trainee's row shows it live, prints READY; then it waits for the
// row to show it lost (the time, Date.now(), when the page first did, its
// text, and the trainee list's option) and live again.
// usage: node console_link_check.cjs BASE_URL TOKEN TRAINEE WEB_DIR
const path = require('node:path');
const { launch, run } = require(path.join(__dirname, '..', 'instructor', 'browser', 'browser.cjs'));
const [base, token, id, webDir] = process.argv.slice(2);

// Resolves, once the trainee's row shows `state`, with Date.now() then and,
// read at that moment, the row's link text and the trainee list's entry. A
// MutationObserver sees every change, even two pushes handled back to back.
function rowState(page, state, timeoutMs) {
  return page.evaluate(([id, state, timeoutMs]) => new Promise((resolve, reject) => {
    const check = () => {
      const row = document.querySelector('#panels tr[data-trainee="' + id + '"]');
      if (!row || row.dataset.link !== state) return false;
      const option = document.querySelector('#trainee option[value="' + id + '"]');
      const span = row.querySelector('.link span');
      resolve({ at_ms: Date.now(), row: span && span.textContent, option: option && option.textContent });
      return true;
    };
    if (check()) return;
    const observer = new MutationObserver(() => { if (check()) { observer.disconnect(); clearTimeout(timer); } });
    observer.observe(document.body, { subtree: true, childList: true, attributes: true, characterData: true });
    const timer = setTimeout(() => { observer.disconnect(); reject(new Error(id + ' never shown ' + state)); }, timeoutMs);
  }), [id, state, timeoutMs]);
}

run(async () => {
  const browser = await launch(webDir);
  const result = {};
  try {
    const page = await browser.newPage({ viewport: { width: 1280, height: 900 } });
    // No animation frames: the map and the 3D view are not drawn. Software
    // WebGL (SwiftShader, no GPU here) would take a whole core at every push
    // and delay the list by seconds; the list is updated on each push, not
    // per frame, and the drawing is instructor_browser_test's to check.
    await page.addInitScript(() => { window.requestAnimationFrame = () => 0; });
    await page.goto(base + '/?token=' + encodeURIComponent(token));
    await rowState(page, 'live', 60000);
    console.log('READY');
    const lost = await rowState(page, 'lost', 30000);
    Object.assign(result, { lost_at_ms: lost.at_ms, lost_row: lost.row, lost_option: lost.option });
    const live = await rowState(page, 'live', 30000);
    Object.assign(result, { live_at_ms: live.at_ms, live_row: live.row, live_option: live.option });
  } finally {
    await browser.close();
  }
  return result;
});
