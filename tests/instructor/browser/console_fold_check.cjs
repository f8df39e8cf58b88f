// The console's progress list folds a run of events: once the page is live it
// writes READY_FILE; the test then publishes a collision that goes on (per
// 150 ms: collision_continues of two parts and the trainer's penalty), one
// region_entered, and three more collision_continues, for trainee EV_ID. The
// page's lines are read back as shown.
// usage: node console_fold_check.cjs BASE_URL TOKEN EV_ID OUT_DIR WEB_DIR READY_FILE
const fs = require('node:fs');
const path = require('node:path');
const { launch, run } = require('./browser.cjs');
const [base, token, evId, outDir, webDir, readyFile] = process.argv.slice(2);

run(async () => {
  const browser = await launch(webDir);
  const result = {};
  try {
    const page = await browser.newPage({ viewport: { width: 1280, height: 1000 } });
    const errors = [];
    page.on('pageerror', (e) => errors.push(String(e)));
    result.status = (await page.goto(base + '/?token=' + encodeURIComponent(token))).status();
    await page.waitForFunction(() => document.getElementById('link').textContent === 'live', null, { timeout: 20000 });
    fs.writeFileSync(readyFile, 'live\n');
    // The last event the test sends: the second run's third collision_continues.
    await page.waitForFunction((id) => [...document.querySelectorAll('#events div')].some(
      (d) => d.textContent.startsWith(id + ' collision_continues ×3 ')), evId, { timeout: 30000 });
    result.lines = await page.evaluate((id) => [...document.querySelectorAll('#events div')]
      .filter((d) => d.textContent.startsWith(id + ' ')).map((d) => ({ text: d.textContent, count: Number(d.dataset.count) })), evId);
    await page.locator('#events').screenshot({ path: path.join(outDir, 'instructor_events.png') });
    result.page_errors = errors;
  } finally {
    await browser.close();
  }
  return result;
});
