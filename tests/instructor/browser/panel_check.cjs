// The virtual panel page: dead-man (Space) and forward (W) held on the
// keyboard drive the robot in rise-sim; released, then a gamepad (a Gamepad
// API object the page's navigator.getGamepads returns, as a browser gives a
// plugged pad: LB held, left stick forward) drives again; then the page is
// closed with the pad still held.
// usage: node panel_check.cjs BASE_URL TOKEN TRAINEE OUT_DIR WEB_DIR
const path = require('node:path');
const { launch, run } = require('./browser.cjs');
const [base, token, id, outDir, webDir] = process.argv.slice(2);

run(async () => {
  const browser = await launch(webDir);
  const result = {};
  try {
    const page = await browser.newPage({ viewport: { width: 1100, height: 700 } });
    await page.addInitScript(() => { window.__pad = null; navigator.getGamepads = () => [window.__pad]; });
    result.status = (await page.goto(base + '/panel.html?id=' + encodeURIComponent(id) + '&token=' + encodeURIComponent(token))).status();
    await page.waitForFunction(() => window.risePanel && window.risePanel.sent() > 0 && window.risePanel.robot, null, { timeout: 20000 });
    result.buttons = await page.locator('button[data-control]').count();
    result.sticks = await page.locator('canvas[data-stick]').count();
    const p0 = await page.evaluate(() => window.risePanel.robot.position);
    result.start = p0;
    await page.keyboard.down('Space');
    await page.keyboard.down('KeyW');
    await page.waitForFunction((p0) => {
      const r = window.risePanel.robot, p = window.risePanel.panel;
      return p && !p.failsafe && p.deadman && r && Math.hypot(r.position[0] - p0[0], r.position[1] - p0[1]) > 0.5;
    }, p0, { timeout: 30000 });
    result.moved_to = await page.evaluate(() => window.risePanel.robot.position);
    result.panel = await page.evaluate(() => window.risePanel.panel);
    await page.screenshot({ path: path.join(outDir, 'instructor_panel.png') });
    await page.keyboard.up('KeyW');
    await page.keyboard.up('Space');
    await page.waitForFunction(() => window.risePanel.panel && !window.risePanel.panel.deadman, null, { timeout: 10000 });
    result.released = await page.evaluate(() => window.risePanel.panel.deadman);
    await page.evaluate(() => {
      window.__pad = { connected: true, id: 'test pad', axes: [0, -1, 0, 0],
                       buttons: Array.from({ length: 16 }, (_, i) => ({ pressed: i === 4, value: i === 4 ? 1 : 0 })) };
    });
    await page.waitForFunction(() => {
      const p = window.risePanel.panel;
      return p && p.deadman && !p.failsafe && p.axes.drive_y > 0.9;
    }, null, { timeout: 10000 });
    result.gamepad_panel = await page.evaluate(() => window.risePanel.panel);
    result.gamepad_label = await page.textContent('#gamepad');
    // Closing with the pad still held: only the server's rules stop the robot.
    await page.close();
    result.closed = true;
  } finally {
    await browser.close();
  }
  return result;
});
