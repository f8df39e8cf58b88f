// The Training Builder by clicking and typing, on a copy of the shipped
// training in DESIGNS_DIR: opens fig10_training.yaml; adds a task "drill"
// (the checker says it is unreachable and has no way to END); clicks the
// mission2 box then the drill box and types a condition that is no number
// (the loader's error shows inline with its line and key) and deletes that
// edge; adds "mission2 → drill if score LT 5" and "drill → END" by clicks and
// typing; saves; then edits again while "someone else" changes the file on
// disk, and Save says so (409) without writing; Reload shows the disk's file.
// usage: node training_builder_check.cjs BASE_URL TOKEN OUT_DIR WEB_DIR DESIGNS_DIR
const fs = require('node:fs');
const path = require('node:path');
const { launch, run, openReady, checkState, settled } = require('./browser.cjs');
const [base, token, outDir, webDir, designsDir] = process.argv.slice(2);
const file = path.join(designsDir, 'fig10_training.yaml');

const errorsShown = (page) => page.$$eval('#errors li', (l) => l.map((e) => ({ text: e.textContent, key: e.dataset.key, line: Number(e.dataset.line) })));

async function addEdgeByClicks(page, from, to, field, op, value) {
  await page.click(`#graph g.node[data-name="${from}"] rect`);
  await page.click(`#graph g.node[data-name="${to}"] rect`);
  await page.selectOption('#edge-field', field);
  if (field !== 'always') {
    await page.selectOption('#edge-op', op);
    await page.fill('#edge-value', '');
    await page.type('#edge-value', value);
  }
  await page.click('#add-edge');
}

run(async () => {
  const browser = await launch(webDir);
  const result = {};
  try {
    const { page, errors, status } = await openReady(browser, `${base}/training.html?token=${encodeURIComponent(token)}&file=fig10_training.yaml`, { width: 1400, height: 1100 });
    result.status = status;
    result.opened = await checkState(page);
    result.nav = await page.$$eval('#builders a', (a) => a.map((e) => [e.getAttribute('href').split('?')[0], e.className]));
    result.boxes = await page.$$eval('#graph g.node', (g) => g.map((e) => e.dataset.name));
    result.arrows = await page.$$eval('#graph g.edge', (g) => g.length);
    result.loop_labels = await page.$$eval('#graph g.edge text', (t) => t.map((e) => e.textContent).filter((s) => s.includes('↻')));

    // A task on its own: unreachable, no way to END.
    await page.fill('#node-name', 'drill');
    await page.selectOption('#node-task', 'neutralize_object.yaml');
    await page.fill('#node-attempts', '1');
    await page.click('#add-node');
    await settled(page, 'bad');
    result.lone_task_errors = await errorsShown(page);
    result.lone_task_save_disabled = await page.$eval('#save', (b) => b.disabled);

    // A condition that is no number: the loader's error, inline, with line and key.
    await addEdgeByClicks(page, 'mission2', 'drill', 'score', 'LT', 'five');
    await page.waitForFunction(() => [...document.querySelectorAll('#errors li')].some((l) => l.textContent.includes('not a number')), null, { timeout: 10000 });
    result.bad_condition_errors = await errorsShown(page);
    result.bad_edges_drawn = await page.$$eval('#graph g.edge.bad', (g) => g.map((e) => `${e.dataset.from}→${e.dataset.to}`));
    await page.screenshot({ path: path.join(outDir, 'training_builder_error.png'), fullPage: true });
    const badIndex = await page.$eval('#edges tr.bad', (tr) => tr.dataset.index);
    await page.click(`#edges button.delete-edge[data-index="${badIndex}"]`);
    await settled(page, 'bad');

    // The real edges, by clicking the boxes and typing the number.
    await addEdgeByClicks(page, 'mission2', 'drill', 'score', 'LT', '5');
    result.edge_note = await page.$eval('#edge-note', (e) => e.textContent);
    await settled(page, 'bad');
    result.after_first_edge_errors = await errorsShown(page);
    await addEdgeByClicks(page, 'drill', 'END', 'always');
    await settled(page, 'ok');
    result.valid = await checkState(page);
    result.edges = await page.$$eval('#edges tr[data-index]', (r) => r.map((tr) => [...tr.children].slice(1, 4).map((td) => td.textContent)));
    result.drawn_new_edge = await page.$$eval('#graph g.edge', (g) => g.filter((e) => e.dataset.from === 'mission2' && e.dataset.to === 'drill')
      .map((e) => e.querySelector('text').textContent));
    await page.screenshot({ path: path.join(outDir, 'training_builder.png'), fullPage: true });
    await page.click('#save');
    await page.waitForFunction(() => document.getElementById('save-state').textContent === 'saved', null, { timeout: 10000 });
    result.saved_version = await page.$eval('#version', (e) => e.textContent);

    // Someone else changes the file after the page loaded it: Save refuses.
    await page.fill('input.attempts[data-node="drill"]', '3');
    await page.dispatchEvent('input.attempts[data-node="drill"]', 'change');
    await settled(page, 'ok');
    fs.appendFileSync(file, '# changed by someone else\n');
    await page.click('#save');
    await page.waitForFunction(() => !document.getElementById('conflict').hidden, null, { timeout: 10000 });
    result.conflict_text = await page.$eval('#conflict-text', (e) => e.textContent);
    result.save_state_after_conflict = await page.$eval('#save-state', (e) => e.textContent);
    result.disk_after_conflict = fs.readFileSync(file, 'utf8');
    await page.screenshot({ path: path.join(outDir, 'training_builder_conflict.png') });
    await page.click('#reload');
    await page.waitForFunction(() => document.getElementById('conflict').hidden, null, { timeout: 10000 });
    result.attempts_after_reload = await page.$eval('input.attempts[data-node="drill"]', (e) => e.value);
    result.page_errors = errors;
  } finally {
    await browser.close();
  }
  return result;
});
