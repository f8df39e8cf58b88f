// The virtual panel page: dead-man (Space) and forward (W) held on the
// keyboard drive the robot in rise-sim; then the page is closed.
// usage: node panel_check.cjs BASE_URL TOKEN TRAINEE OUT_DIR WEB_DIR
const path = require('node:path');
const { launch, run } = require('./browser.cjs');
const [base, token, id, outDir, webDir] = process.argv.slice(2);

run(async () => {
  const browser = await launch(webDir);
  const result = {};
  try {
    const page = await browser.newPage({ viewport: { width: 1100, height: 700 } });
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
    // Closing with the keys still held: only the server's rules stop the robot.
    await page.close();
    result.closed = true;
  } finally {
    await browser.close();
  }
  return result;
});
