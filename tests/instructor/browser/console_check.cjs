// The console page: 401 without the token, the robot moving on it while a
// scripted panel drives rise-sim, the map and 3D view drawn (pixel variance,
// the robot's colour in the 3D canvas), a fault button publishing, the
// camera-blackout button blacking out the camera inset until the fault ends.
// usage: node console_check.cjs BASE_URL TOKEN TRAINEE OUT_DIR WEB_DIR
const path = require('node:path');
const { launch, parsePos, run } = require('./browser.cjs');
const [base, token, id, outDir, webDir] = process.argv.slice(2);

run(async () => {
  const browser = await launch(webDir);
  const result = {};
  try {
    const page = await browser.newPage({ viewport: { width: 1280, height: 1000 } });
    const consoleErrors = [];
    page.on('pageerror', (e) => consoleErrors.push(String(e)));
    result.no_token_status = (await page.goto(base + '/')).status();
    result.wrong_token_status = (await page.goto(base + '/?token=wrong' + token)).status();
    result.status = (await page.goto(base + '/?token=' + encodeURIComponent(token))).status();
    await page.waitForFunction(() => document.getElementById('link').textContent === 'live', null, { timeout: 20000 });
    await page.selectOption('#trainee', id).catch(() => {});
    await page.waitForFunction((id) => {
      const s = document.getElementById('trainee');
      if (s.value !== id && [...s.options].some((o) => o.value === id)) { s.value = id; s.dispatchEvent(new Event('change')); }
      return s.value === id && document.getElementById('robot-pos').textContent.startsWith(id + ': x=');
    }, id, { timeout: 20000 });
    const first = await page.textContent('#robot-pos');
    result.first = parsePos(first);
    // The robot is driven by the test: wait until the page shows it 0.5 m further.
    await page.waitForFunction((p0) => {
      const m = /x=(-?[\d.]+) y=(-?[\d.]+)/.exec(document.getElementById('robot-pos').textContent);
      return m && Math.hypot(parseFloat(m[1]) - p0[0], parseFloat(m[2]) - p0[1]) > 0.5;
    }, result.first, { timeout: 30000 });
    result.later = parsePos(await page.textContent('#robot-pos'));
    // Pushes per second seen by the page over one second of page time.
    result.pushes_per_s = await page.evaluate(() => new Promise((resolve) => {
      const n0 = window.riseConsole.state.pushes; setTimeout(() => resolve(window.riseConsole.state.pushes - n0), 1000);
    }));
    // The stream keeps going: another push arrives (on a loaded machine the
    // page's main thread may sit out a whole second rendering, so the rate
    // above is a figure, this is the check).
    const n1 = await page.evaluate(() => window.riseConsole.state.pushes);
    await page.waitForFunction((n) => window.riseConsole.state.pushes > n, n1, { timeout: 15000 });
    result.push_continued = true;
    await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
    result.stats = await page.evaluate(() => window.riseConsole.stats());
    await page.locator('#view3d').screenshot({ path: path.join(outDir, 'instructor_view3d.png') });
    await page.screenshot({ path: path.join(outDir, 'instructor_console.png') });
    await page.waitForFunction(() => /no scenario running/.test(document.getElementById('scenario-status').textContent), null, { timeout: 10000 });
    result.scenario_options = await page.locator('#scenario-file option').count();
    await page.waitForFunction(() => document.getElementById('training').textContent.includes('approach_object'), null, { timeout: 10000 });
    result.training_text = await page.textContent('#training');
    result.report_link = await page.getAttribute('#reports a', 'href');
    const report = await page.request.get(base + result.report_link);  // the page's cookie carries the token
    result.report_status = report.status();
    result.report_body = await report.text();
    result.trainee_rows = await page.locator('#panels tr[data-trainee]').count();
    result.source_text = await page.textContent('#panels');
    await page.click('button[data-fault="stick-stuck"]');
    await page.waitForFunction(() => /inject stick-stuck: /.test(document.getElementById('fault-result').textContent), null, { timeout: 10000 });
    result.fault_result = await page.textContent('#fault-result');
    // rise-hild applies it and says so in PanelState.active_faults: the panels table shows it.
    await page.waitForFunction((id) => {
      const row = document.querySelector('#panels tr[data-trainee="' + id + '"] .faults');
      return row && row.textContent.includes('stick-stuck');
    }, id, { timeout: 15000 });
    result.page_faults = await page.textContent('#panels tr[data-trainee="' + id + '"] .faults');
    await page.screenshot({ path: path.join(outDir, 'instructor_console_fault.png') });
    // The camera-blackout button: rise-sim lists it in RobotState.active_faults
    // for its 10 s; the camera inset goes black, labelled, and comes back.
    result.inset_before = await page.evaluate(() => window.riseConsole.insetStats());
    await page.click('button[data-fault="camera-blackout"]');
    // Read in the same poll that sees the black inset: on a loaded machine the
    // fault's 10 s may be over by a later evaluate.
    const blackout = await (await page.waitForFunction(() => {
      const s = window.riseConsole.insetStats();
      const t = window.riseConsole.state.trainees.get(window.riseConsole.state.selected);
      return s.label.includes('camera blackout') && s.max < 8 && { inset: s, faults: t.robot_state.active_faults };
    }, null, { timeout: 15000 })).jsonValue();
    result.inset_blackout = blackout.inset;
    result.blackout_robot_faults = blackout.faults;
    await page.locator('#view3d-box').screenshot({ path: path.join(outDir, 'instructor_view3d_blackout.png') });
    await page.waitForFunction(() => {
      const s = window.riseConsole.insetStats();
      return s.label === '' && s.mean > 20;
    }, null, { timeout: 25000 });
    result.inset_after = await page.evaluate(() => window.riseConsole.insetStats());
    result.page_errors = consoleErrors;
  } finally {
    await browser.close();
  }
  return result;
});
