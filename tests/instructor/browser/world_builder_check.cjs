// The Environment Builder by mouse and typing, on a copy of sim/worlds/
// building.yaml in WORLDS_DIR: clicks door_ab on the map and drags it into
// the opening of wall_b_corridor (its hinge snaps to the opening's edge),
// types its yaw and width; types a bad width (the loader's error inline
// with line and key) and mends it; clicks the hazardous object and deletes
// it; drags a new region and types its name; saves; then edits again while
// "someone else" changes the file on disk, and Save says so (409) without
// writing; Reload shows the disk's file.
// usage: node world_builder_check.cjs BASE_URL TOKEN OUT_DIR WEB_DIR WORLDS_DIR
const fs = require('node:fs');
const path = require('node:path');
const { launch, run, openReady } = require('./browser.cjs');
const [base, token, outDir, webDir, worldsDir] = process.argv.slice(2);
const file = path.join(worldsDir, 'building.yaml');

const errorsShown = (page) => page.$$eval('#errors li', (l) => l.map((e) => ({ text: e.textContent, key: e.dataset.key, line: Number(e.dataset.line) })));
async function settled(page, cls) {
  try {
    await page.waitForFunction((c) => {
      const s = window.riseWorldBuilder && window.riseWorldBuilder.state;
      return document.getElementById('check-state').className === c && s && !s.checking && !s.pending;
    }, cls, { timeout: 15000 });
  } catch (e) {
    const seen = await page.evaluate(() => ({ check: document.getElementById('check-state').textContent,
      errors: [...document.querySelectorAll('#errors li')].map((l) => l.textContent), selected: window.riseWorldBuilder.state.selected }));
    throw new Error(`waiting for the check to be ${cls}: ${JSON.stringify(seen)}`);
  }
}

// The page's pixel nearest to a world point, in the page's coordinates (the
// mouse's: whole pixels, as the events carry them).
async function at(page, x, y) {
  const box = await (await page.$('#map')).boundingBox();
  const [u, v] = await page.evaluate(([a, b]) => window.riseWorldBuilder.toCanvas(a, b), [x, y]);
  return [Math.round(box.x + u), Math.round(box.y + v)];
}

async function drag(page, from, to) {
  const a = await at(page, ...from), b = await at(page, ...to);
  await page.mouse.move(...a);
  await page.mouse.down();
  await page.mouse.move(a[0] + (b[0] - a[0]) / 3, a[1] + (b[1] - a[1]) / 3, { steps: 4 });
  await page.mouse.move(...b, { steps: 8 });
  await page.mouse.up();
}

async function typeField(page, key, value) {
  const input = page.locator(`#props input[data-key="${key}"]`);
  await input.fill(String(value));
  await input.press('Tab');
}

const selectedName = (page) => page.$eval('#selected-name', (e) => e.textContent);
const doorBox = (page) => page.evaluate(() => {
  const b = window.riseWorldBuilder.state.view.boxes.find((x) => x.kind === 'door');
  return b && { center: b.center.map((v) => Math.round(v * 1000) / 1000), yaw: b.yaw };
});

run(async () => {
  const browser = await launch(webDir);
  const result = {};
  try {
    const { page, errors, status } = await openReady(browser, `${base}/world_builder.html?token=${encodeURIComponent(token)}&file=building.yaml`, { width: 1600, height: 1200 });
    result.status = status;
    result.opened = await page.$eval('#check-state', (e) => e.className);
    result.entities = await page.$$eval('#entities button', (b) => b.map((e) => e.dataset.entity));
    result.nav = await page.$$eval('#builders a', (a) => a.map((e) => e.getAttribute('href').split('?')[0]));
    result.stats_before = await page.evaluate(() => window.riseWorldBuilder.stats());
    result.door_before = await doorBox(page);

    // door_ab: clicked on the map, dragged to the opening of wall_b_corridor (x 6..6.9 at y 3).
    await page.mouse.click(...await at(page, 3.0, 0.0));
    result.selected = await selectedName(page);
    await drag(page, [3.0, 0.0], [6.04, 3.53]);  // the hinge lands 4 cm off the opening's edge: snapped onto it
    await settled(page, 'ok');
    result.hinge_after_drag = await page.evaluate(() => window.riseWorldBuilder.state.world.doors[0].hinge);
    await typeField(page, 'yaw_deg', 0);
    await typeField(page, 'width', 0.9);
    await settled(page, 'ok');
    result.door_after = await doorBox(page);

    // A width the loader refuses: its words inline, with line and key; no saving.
    await typeField(page, 'width', -1);
    await settled(page, 'bad');
    result.bad_width_errors = await errorsShown(page);
    result.bad_width_save_disabled = await page.$eval('#save', (b) => b.disabled);
    result.bad_width_marked = await page.$$eval('#entities button.bad', (b) => b.map((e) => e.dataset.entity));
    await typeField(page, 'width', 0.9);
    await settled(page, 'ok');

    // The hazardous object: clicked, deleted.
    await page.mouse.click(...await at(page, 6.0, 1.5));
    result.selected_object = await selectedName(page);
    await page.click('#delete');
    await settled(page, 'ok');

    // A region dragged out in room A, then named.
    await page.check('input[name="tool"][value="region"]');
    await drag(page, [-3.0, -2.0], [-2.0, -1.0]);  // a pixel is ~2.5 cm: the corners snap to the 5 cm grid
    await settled(page, 'ok');
    result.new_region = await page.evaluate(() => window.riseWorldBuilder.state.world.regions.at(-1));
    await typeField(page, 'name', 'drop_zone');
    await settled(page, 'ok');
    result.entities_after = await page.$$eval('#entities button', (b) => b.map((e) => e.dataset.entity));

    await page.click('#save');
    await page.waitForFunction(() => document.getElementById('save-state').textContent === 'saved', null, { timeout: 10000 });
    result.saved_version = await page.$eval('#version', (e) => e.textContent);
    result.stats_after = await page.evaluate(() => window.riseWorldBuilder.stats());
    await page.screenshot({ path: path.join(outDir, 'world_builder.png'), fullPage: true });
    result.disk_after_save = fs.readFileSync(file, 'utf8');

    // Someone else changes the file while the page edits it: Save refuses (409) and says so.
    await page.mouse.click(...await at(page, -2.5, -1.5));  // drop_zone
    await typeField(page, 'max.2', 2.5);
    await settled(page, 'ok');
    fs.appendFileSync(file, '# changed by someone else\n');
    await page.click('#save');
    await page.waitForFunction(() => !document.getElementById('conflict').hidden, null, { timeout: 10000 });
    result.conflict_text = await page.$eval('#conflict-text', (e) => e.textContent);
    result.save_state_after_conflict = await page.$eval('#save-state', (e) => e.textContent);
    result.disk_after_conflict = fs.readFileSync(file, 'utf8');
    await page.screenshot({ path: path.join(outDir, 'world_builder_conflict.png'), fullPage: true });
    await page.click('#reload');
    await page.waitForFunction(() => document.getElementById('conflict').hidden, null, { timeout: 10000 });
    result.region_after_reload = await page.evaluate(() => window.riseWorldBuilder.state.world.regions.at(-1));
    result.page_errors = errors;
  } finally {
    await browser.close();
  }
  return result;
});
