// The virtual panel page: its widgets follow the keyboard (W moves the drive
// stick's dot, read from the page and from the canvas pixels; Space shows the
// dead-man held; Esc latches the e-stop: banner, striped button, failsafe from
// the server; 1/2/3 set the speed mode) and the mouse (pressed on the arm
// stick, its dot goes there); a second page for trainee FB_ID shows the
// PanelFeedback the test publishes for it (LEDs, displays, buzzer); then
// dead-man (Space) and forward (W) held drive the robot in rise-sim and the
// speed display shows rise-sim's feedback; released, then a gamepad (a Gamepad
// API object the page's navigator.getGamepads returns, as a browser gives a
// plugged pad: LB held, left stick forward) drives again; then the page is
// closed with the pad still held.
// usage: node panel_check.cjs BASE_URL TOKEN TRAINEE OUT_DIR WEB_DIR FB_ID
const path = require('node:path');
const { launch, run } = require('./browser.cjs');
const [base, token, id, outDir, webDir, fbId] = process.argv.slice(2);

// The drive stick as the page says it drew it, and the centroid of the dot's
// colour in the canvas's pixels.
function driveStick(page) {
  return page.evaluate(() => {
    const c = document.querySelector('canvas[data-stick="drive"]');
    const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    const want = window.risePanel.stickColour.match(/\w\w/g).map((h) => parseInt(h, 16));
    let n = 0, sx = 0, sy = 0;
    for (let i = 0; i < d.length; i += 4) {
      if (Math.abs(d[i] - want[0]) + Math.abs(d[i + 1] - want[1]) + Math.abs(d[i + 2] - want[2]) < 30) {
        const p = i / 4; n++; sx += p % c.width; sy += Math.floor(p / c.width);
      }
    }
    return { page: window.risePanel.sticks().drive, pixels: n, cx: n ? sx / n : null, cy: n ? sy / n : null };
  });
}

async function nextSends(page, n = 3) {
  const s0 = await page.evaluate(() => window.risePanel.sent());
  await page.waitForFunction((s) => window.risePanel.sent() >= s, s0 + n, { timeout: 5000 });
}

// What the page shows of the dead-man, the e-stop and the speed switch.
function widgets(page) {
  return page.evaluate(() => {
    const dm = document.querySelector('button[data-control="deadman"]'), es = document.querySelector('button.estop');
    const banner = document.getElementById('estop-banner'), r = banner.getBoundingClientRect();
    const speed = document.querySelector('[data-switch="speed"]');
    return {
      deadman_held: dm.dataset.held, deadman_class: dm.className, deadman_text: document.getElementById('deadman-state').textContent,
      deadman_colour: getComputedStyle(dm).backgroundColor,
      estop_button: es.dataset.held, estop_image: getComputedStyle(es).backgroundImage, estop_colour: getComputedStyle(es).backgroundColor,
      banner_visible: !banner.hidden && r.height > 40, banner_height: r.height, banner_text: banner.hidden ? '' : banner.textContent,
      speed_value: speed.querySelector('[data-switch-value]').textContent,
      speed_on: [...speed.querySelectorAll('button.on')].map((b) => b.dataset.position),
      sent_speed: window.risePanel.state.switches.speed,
    };
  });
}

async function keyboardWidgets(page, result) {
  result.stick_rest = await driveStick(page);
  await page.keyboard.down('KeyW');
  await page.waitForFunction(() => window.risePanel.sticks().drive.y === 1, null, { timeout: 5000 });
  result.stick_w = await driveStick(page);
  await page.keyboard.up('KeyW');
  await page.waitForFunction(() => window.risePanel.sticks().drive.y === 0, null, { timeout: 5000 });
  result.stick_released = await driveStick(page);
  result.idle = await widgets(page);
  await page.keyboard.down('Space');
  await nextSends(page);
  result.space = await widgets(page);
  await page.keyboard.up('Space');
  await page.keyboard.press('Escape');
  await page.waitForFunction(() => window.risePanel.panel && window.risePanel.panel.failsafe, null, { timeout: 5000 });
  result.estop = await widgets(page);
  result.estop_panel = await page.evaluate(() => window.risePanel.panel);
  await page.screenshot({ path: path.join(outDir, 'instructor_panel_estop.png') });
  await page.keyboard.press('Escape');
  await page.waitForFunction(() => window.risePanel.panel && !window.risePanel.panel.failsafe, null, { timeout: 5000 });
  result.estop_released = await widgets(page);
  result.speeds = [];
  for (const k of ['Digit3', 'Digit1', 'Digit2']) {
    await page.keyboard.press(k);
    await nextSends(page);
    result.speeds.push(await widgets(page));
  }
  // The mouse: pressed a quarter of the arm stick's width right of its middle, its dot goes there.
  const arm = await page.locator('canvas[data-stick="arm"]').boundingBox();
  await page.mouse.move(arm.x + arm.width * 0.75, arm.y + arm.height / 2);
  await page.mouse.down();
  await page.waitForFunction(() => window.risePanel.sticks().arm.x > 0.4, null, { timeout: 5000 });
  result.arm_mouse = await page.evaluate(() => window.risePanel.sticks().arm);
  await page.mouse.up();
  await page.waitForFunction(() => window.risePanel.sticks().arm.x === 0, null, { timeout: 5000 });
  // The server's PanelState follows (through the mapper, LCM and the stream).
  await page.waitForFunction(() => window.risePanel.panel.switches.speed === 'medium', null, { timeout: 5000 });
  result.speed_panel = await page.evaluate(() => window.risePanel.panel.switches.speed);
}

// The test publishes PanelFeedback for trainee fbId (nothing else does).
async function feedbackPage(browser, result) {
  const page = await browser.newPage({ viewport: { width: 1100, height: 800 } });
  await page.goto(base + '/panel.html?id=' + encodeURIComponent(fbId) + '&token=' + encodeURIComponent(token));
  await page.waitForFunction(() => window.risePanel && window.risePanel.feedback, null, { timeout: 10000 });
  result.feedback = await page.evaluate(() => ({
    leds: Object.fromEntries([...document.querySelectorAll('[data-led]')].map((l) => [l.dataset.led, l.classList.contains('lit')])),
    displays: Object.fromEntries([...document.querySelectorAll('[data-display]')].map((d) => [d.dataset.display, d.querySelector('b').textContent])),
    lit_colour: getComputedStyle(document.querySelector('.led.lit i')).backgroundColor,
    buzzer: document.getElementById('buzzer').textContent,
  }));
  await page.close();
}

run(async () => {
  const browser = await launch(webDir);
  const result = {};
  try {
    const page = await browser.newPage({ viewport: { width: 1100, height: 800 } });
    const errors = [];
    page.on('pageerror', (e) => errors.push(String(e)));
    await page.addInitScript(() => { window.__pad = null; navigator.getGamepads = () => [window.__pad]; });
    result.status = (await page.goto(base + '/panel.html?id=' + encodeURIComponent(id) + '&token=' + encodeURIComponent(token))).status();
    await page.waitForFunction(() => window.risePanel && window.risePanel.sent() > 0 && window.risePanel.robot, null, { timeout: 20000 });
    result.buttons = await page.locator('button[data-control]').count();
    result.sticks = await page.locator('canvas[data-stick]').count();
    await keyboardWidgets(page, result);
    await feedbackPage(browser, result);
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
    // rise-sim's feedback (10 Hz): the speed display shows the robot moving.
    await page.waitForFunction(() => parseFloat(document.querySelector('[data-display="speed"] b').textContent) > 0.05, null, { timeout: 10000 });
    result.sim_speed_display = await page.textContent('[data-display="speed"] b');
    result.driving = await widgets(page);
    result.stick_driving = await driveStick(page);
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
    result.gamepad_widgets = await widgets(page);
    result.gamepad_stick = await driveStick(page);
    result.page_errors = errors;
    // Closing with the pad still held: only the server's rules stop the robot.
    await page.close();
    result.closed = true;
  } finally {
    await browser.close();
  }
  return result;
});
