// The Robot Builder by clicking and typing, on a copy of skid4.yaml (and its
// URDF) in ROBOTS_DIR: opens it, reads what the 3D view drew (links, joint
// axes, the laser's fan, the camera frustum); types a top speed that is no
// good (-1: the loader's error shows beside the value, with line and key,
// and Save stays off), then 0.3 m/s; picks the horn's button from the
// panel's buttons; saves; then "Test drive": rise-sim runs the saved file
// on the sandbox station, and the embedded virtual panel (its own page:
// fast speed clicked, dead-man Space and stick forward W held by the
// keyboard) drives it for HOLD_S seconds while the C++ test measures the
// speed from RobotState over LCM; the page's own speed line is read too.
// usage: node robot_builder_check.cjs BASE_URL TOKEN OUT_DIR WEB_DIR ROBOTS_DIR HOLD_S
const fs = require('node:fs');
const path = require('node:path');
const { launch, run, openReady, checkState, settled } = require('./browser.cjs');
const [base, token, outDir, webDir, robotsDir, holdS] = process.argv.slice(2);
const file = path.join(robotsDir, 'skid4.yaml');

const field = (p) => `[data-path="${p}"]`;

async function type(page, p, value) {
  await page.fill(field(p), '');
  await page.type(field(p), value);
  await page.dispatchEvent(field(p), 'change');
}

run(async () => {
  const browser = await launch(webDir);
  const result = {};
  try {
    const { page, errors, status } = await openReady(browser, `${base}/robot_builder.html?token=${encodeURIComponent(token)}&file=skid4.yaml`, { width: 1400, height: 1300 });
    result.status = status;
    result.opened = await checkState(page);
    result.nav = await page.$$eval('#builders a', (a) => a.map((e) => e.getAttribute('href').split('?')[0]));
    result.parts = await page.evaluate(() => window.riseRobotBuilder.scene());
    result.view_note = await page.$eval('#view-note', (e) => e.textContent);
    result.view_stats = await page.evaluate(() => window.riseRobotBuilder.stats().view3d);
    result.max_mps_before = await page.$eval(field('control.linear.max_mps'), (e) => e.value);
    result.axis_choices = await page.$$eval(`${field('control.linear.axis')} option`, (o) => o.map((e) => e.value));

    // A top speed that is no good: the loader's words beside the value, no saving.
    await type(page, 'control.linear.max_mps', '-1');
    await settled(page, 'bad');
    result.bad_inline = await page.$eval('[data-error-for="control.linear.max_mps"]', (e) => e.textContent);
    result.bad_list = await page.$$eval('#errors li', (l) => l.map((e) => e.textContent));
    result.bad_save_disabled = await page.$eval('#save', (b) => b.disabled);

    // The new limit, and the horn on a button of the panel (picked from the list).
    await type(page, 'control.linear.max_mps', '0.3');
    await settled(page, 'ok');
    result.horn_choices = await page.$$eval(`${field('sounds.horn.button')} option`, (o) => o.map((e) => e.textContent));
    await page.selectOption(field('sounds.horn.button'), 'gripper_open');
    await settled(page, 'ok');
    result.yaml_shown = await page.$eval('#yaml', (e) => e.textContent);
    await page.screenshot({ path: path.join(outDir, 'robot_builder.png'), fullPage: false });
    await page.click('#save');
    await page.waitForFunction(() => document.getElementById('save-state').textContent.startsWith('saved'), null, { timeout: 10000 });
    result.saved_state = await page.$eval('#save-state', (e) => e.textContent);
    result.disk_after_save = fs.readFileSync(file, 'utf8');

    // Test drive: rise-sim runs the saved file; the embedded virtual panel drives it.
    await page.click('#drive');
    await page.waitForFunction(() => /^speed -?\d/.test(document.getElementById('drive-speed').textContent), null, { timeout: 30000 });
    result.drive_state = await page.$eval('#drive-state', (e) => e.textContent);
    const panel = page.frameLocator('#drive-panel');
    await panel.locator('[data-switch="speed"] button[data-position="fast"]').click();
    await panel.locator('[data-switch="mode"] button[data-position="drive"]').click();
    console.log('HOLD start');
    await page.keyboard.down('Space');
    await page.keyboard.down('KeyW');
    const speeds = [];
    const end = Date.now() + Number(holdS) * 1000;
    while (Date.now() < end) {
      await page.waitForTimeout(250);
      speeds.push(await page.$eval('#drive-speed', (e) => e.textContent));
    }
    await page.screenshot({ path: path.join(outDir, 'robot_builder_drive.png'), fullPage: true });
    await page.keyboard.up('KeyW');
    await page.keyboard.up('Space');
    console.log('HOLD end');
    result.page_speeds = speeds.map((s) => parseFloat((/^speed (-?[\d.]+)/.exec(s) || [0, 'NaN'])[1]));
    result.drive_stats = await page.evaluate(() => window.riseRobotBuilder.stats().drive3d);
    await page.click('#drive-stop');
    await page.waitForFunction(() => document.getElementById('drive-state').textContent === 'stopped', null, { timeout: 10000 });

    // Another robot from the list: the tracked one, its belts and arm joints drawn, its break torques listed.
    await page.selectOption('#file', 'tracked_eod.yaml');
    await page.waitForFunction(() => document.getElementById('view-note').textContent.startsWith('tracked'), null, { timeout: 10000 });
    result.tracked_parts = await page.evaluate(() => window.riseRobotBuilder.scene());
    result.tracked_note = await page.$eval('#view-note', (e) => e.textContent);
    result.tracked_motors = await page.$$eval('#props-motors code', (c) => c.map((e) => e.textContent));
    await page.screenshot({ path: path.join(outDir, 'robot_builder_tracked.png') });
    result.page_errors = errors;
  } finally {
    await browser.close();
  }
  return result;
});
