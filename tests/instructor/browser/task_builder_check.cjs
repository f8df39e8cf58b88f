// The Task Builder by mouse and keyboard, on a copy of the shipped
// approach_object.yaml in DESIGNS_DIR: opens it (the world drawn, the kinds
// offered from the server); drags the start pose, turns it by its heading
// knob and types the yaw back; drags a new region "drill_zone" ahead of the
// robot and resizes it by a corner; adds an event whose name is taken (the
// loader's error shows inline with line and key) and deletes it; adds a
// reach_region event on the new region with points and makes it end the
// task; edits the time_exceeded event's threshold; raises the time limit; saves; then "Try it": drives the robot with
// the virtual panel page it opened for the sandbox station (dead-man + forward keys)
// into the region and reads the report the page shows; tries again and
// stops it from the page (the report: interrupted).
// usage: node task_builder_check.cjs BASE_URL TOKEN OUT_DIR WEB_DIR
const path = require('node:path');
const { launch, run, openReady, settled } = require('./browser.cjs');
const [base, token, outDir, webDir] = process.argv.slice(2);

const errorsShown = (page) => page.$$eval('#errors li', (l) => l.map((e) => ({ text: e.textContent, key: e.dataset.key, line: Number(e.dataset.line) })));
const at = (page, x, y) => page.evaluate(([a, b]) => window.riseTaskBuilder.pagePoint(a, b), [x, y]);

async function drag(page, from, to) {
  const a = await at(page, ...from), b = await at(page, ...to);
  await page.mouse.move(a[0], a[1]);
  await page.mouse.down();
  for (let i = 1; i <= 8; ++i) await page.mouse.move(a[0] + ((b[0] - a[0]) * i) / 8, a[1] + ((b[1] - a[1]) * i) / 8);
  await page.mouse.up();
}

async function addEvent(page, name, kind, points, param) {
  await page.fill('#event-name', name);
  await page.selectOption('#event-kind', kind);
  if (param) await page.selectOption(`#param-${param[0]}`, param[1]);
  await page.fill('#event-points', String(points));
  await page.click('#add-event');
}

run(async () => {
  const browser = await launch(webDir);
  const result = {};
  try {
    const { page, errors, status } = await openReady(browser, `${base}/task_builder.html?token=${encodeURIComponent(token)}&file=approach_object.yaml`, { width: 1500, height: 1300 });
    result.status = status;
    result.opened = await page.$eval('#check-state', (e) => e.className);
    result.kinds = await page.$$eval('#event-kind option', (o) => o.map((e) => e.value));
    result.nav = await page.$$eval('#builders a', (a) => a.map((e) => e.getAttribute('href')));

    // The start pose: dragged, turned by its knob, the yaw typed back.
    await drag(page, [4.0, 0.0], [3.8, -0.15]);
    result.start_dragged = await page.evaluate(() => window.riseTaskBuilder.state.task.start);
    const s = result.start_dragged;
    const k = [s.x + 0.9 * Math.cos((s.yaw_deg * Math.PI) / 180), s.y + 0.9 * Math.sin((s.yaw_deg * Math.PI) / 180)];
    await drag(page, k, [s.x + 1, s.y + 1]);
    result.start_turned = await page.evaluate(() => window.riseTaskBuilder.state.task.start);
    await page.fill('#start-yaw', '');
    await page.type('#start-yaw', '36.87');
    await page.press('#start-yaw', 'Enter');
    await page.fill('#time-limit', '');
    await page.type('#time-limit', '60');
    await page.press('#time-limit', 'Enter');

    // A new region by dragging a rectangle, then one corner resized.
    await page.check('input[name=tool][value=region]');
    await page.fill('#region-name', 'drill_zone');
    await drag(page, [4.3, 0.1], [5.0, 0.8]);
    await page.check('input[name=tool][value=move]');
    await drag(page, [5.0, 0.8], [5.2, 1.0]);
    await settled(page, 'ok');
    result.regions = await page.evaluate(() => window.riseTaskBuilder.state.task.regions);

    // A taken name: the loader's words inline, with its line and key; then deleted.
    await addEvent(page, 'near_object', 'touch_object', 1);
    await settled(page, 'bad');
    result.duplicate_errors = await errorsShown(page);
    result.duplicate_yaml_line = await page.evaluate((n) => document.getElementById('yaml').textContent.split('\n')[n - 1],
                                                     result.duplicate_errors[0] ? result.duplicate_errors[0].line : 0);
    await page.click('#events tr:last-child button.delete-event');
    await settled(page, 'ok');

    // The new event on the new region, worth 7, ending the task.
    await addEvent(page, 'in_drill_zone', 'reach_region', 7, ['region', 'drill_zone']);
    await settled(page, 'ok');
    await page.check('input.end-on[data-event="in_drill_zone"]');
    await settled(page, 'ok');
    // A threshold edited: "slow" fires at 25 s instead of 20.
    await page.click('button.edit-event[data-event="slow"]');
    result.edit_form = { kind: await page.$eval('#event-kind', (e) => e.value), after_s: await page.$eval('#param-after_s', (e) => e.value) };
    await page.fill('#param-after_s', '');
    await page.type('#param-after_s', '25');
    await page.click('#add-event');
    await settled(page, 'ok');
    result.events = await page.evaluate(() => window.riseTaskBuilder.state.task.events.map((e) => e.name));
    result.end_on = await page.evaluate(() => window.riseTaskBuilder.state.task.end_on);
    await page.screenshot({ path: path.join(outDir, 'task_builder_edit.png'), fullPage: true });
    await page.click('#save');
    await page.waitForFunction(() => document.getElementById('save-state').textContent === 'saved', null, { timeout: 10000 });
    result.yaml = await page.$eval('#yaml', (e) => e.textContent);

    // Try it: the saved task in rise-sim, driven from the virtual panel page.
    const popup = page.waitForEvent('popup', { timeout: 20000 });
    await page.click('#try');
    await page.waitForFunction(() => document.getElementById('try-state').className === 'ok', null, { timeout: 20000 });
    // The page opened the station's virtual panel in a window of its own: the user drives there.
    const panel = await popup;
    panel.on('pageerror', (e) => errors.push('panel: ' + String(e)));
    await panel.waitForURL(/panel\.html\?id=/, { timeout: 20000 });
    result.panel_url = panel.url().replace(/token=[^&]*/, 'token=T');
    await panel.waitForFunction(() => window.risePanel && window.risePanel.state, null, { timeout: 20000 });
    await panel.keyboard.down('Space');
    await panel.keyboard.down('KeyW');
    await page.waitForFunction(() => !document.getElementById('report').hidden, null, { timeout: 60000 });
    await panel.keyboard.up('KeyW');
    await panel.keyboard.up('Space');
    result.report = await page.evaluate(() => window.riseTaskBuilder.report);
    result.report_rows = await page.$$eval('#report-events tr[data-event]', (r) => r.map((tr) => tr.dataset.event));
    result.report_summary = await page.$eval('#report-summary', (e) => e.textContent);
    result.try_state = await page.$eval('#try-state', (e) => e.textContent);
    const html = await page.$eval('#report-html', (a) => a.href);
    result.report_html_status = (await (await browser.newPage()).goto(html)).status();
    await page.screenshot({ path: path.join(outDir, 'task_builder.png'), fullPage: true });

    // Again, stopped from the page before anyone drives: rise-trainer ends the task and reports it.
    await page.click('#try');
    await page.waitForFunction(() => document.getElementById('try-state').className === 'ok', null, { timeout: 20000 });
    await page.waitForFunction(() => document.getElementById('report').hidden, null, { timeout: 5000 });
    await page.click('#stop');
    await page.waitForFunction(() => window.riseTaskBuilder.report && window.riseTaskBuilder.report.end_reason === 'interrupted',
                               null, { timeout: 20000 });
    result.stopped_report = await page.evaluate(() => window.riseTaskBuilder.report);
    result.stopped_state = await page.$eval('#try-state', (e) => e.textContent);
    result.page_errors = errors;
  } finally {
    await browser.close();
  }
  return result;
});
