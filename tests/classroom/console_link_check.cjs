// The console page's trainee list across a cut link (classroom_test.sh):
// once the trainee's row shows it live, prints READY; then it waits for the
// row to show it lost (the time, Date.now(), when the page first did, its
// text, and the trainee list's option) and live again.
// usage: node console_link_check.cjs BASE_URL TOKEN TRAINEE WEB_DIR
const path = require('node:path');
const { launch, run } = require(path.join(__dirname, '..', 'instructor', 'browser', 'browser.cjs'));
const [base, token, id, webDir] = process.argv.slice(2);

// Resolves with Date.now() once the trainee's row shows `state`, checked every 10 ms.
function rowState(page, state, timeoutMs) {
  return page.evaluate(([id, state, timeoutMs]) => new Promise((resolve, reject) => {
    const t0 = Date.now();
    const timer = setInterval(() => {
      const row = document.querySelector('#panels tr[data-trainee="' + id + '"]');
      if (row && row.dataset.link === state) { clearInterval(timer); resolve(Date.now()); }
      else if (Date.now() - t0 > timeoutMs) { clearInterval(timer); reject(new Error(id + ' never shown ' + state)); }
    }, 10);
  }), [id, state, timeoutMs]);
}

const linkText = (page) => page.textContent('#panels tr[data-trainee="' + id + '"] .link span');

run(async () => {
  const browser = await launch(webDir);
  const result = {};
  try {
    const page = await browser.newPage({ viewport: { width: 1280, height: 900 } });
    await page.goto(base + '/?token=' + encodeURIComponent(token));
    await rowState(page, 'live', 30000);
    console.log('READY');
    result.lost_at_ms = await rowState(page, 'lost', 20000);
    result.lost_row = await linkText(page);
    result.lost_option = await page.textContent('#trainee option[value="' + id + '"]');
    await rowState(page, 'live', 20000);
    result.live_row = await linkText(page);
  } finally {
    await browser.close();
  }
  return result;
});
