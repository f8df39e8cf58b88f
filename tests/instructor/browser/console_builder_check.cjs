// The Console Builder by clicking and typing, on a copy of rise_console.yaml
// whose console (an emulator the C++ test runs) has a button the definition
// does not bind, pressed and released over and over: opens the console's
// sources (every signal listed live), starts learn mode, and takes the signal
// it proposes; types a name, picks kind button and safe value false; first
// without a signal (the loader's error shows inline, with line and key),
// then as proposed; watches the preview (PanelState through the PanelMapper)
// follow the press; saves.
// usage: node console_builder_check.cjs BASE_URL TOKEN OUT_DIR WEB_DIR CONSOLES_DIR
const fs = require('node:fs');
const path = require('node:path');
const { launch, run, openReady, checkState, settled } = require('./browser.cjs');
const [base, token, outDir, webDir, consolesDir] = process.argv.slice(2);


run(async () => {
  const browser = await launch(webDir);
  const result = {};
  try {
    const { page, errors, status } = await openReady(browser, `${base}/console_builder.html?token=${encodeURIComponent(token)}&file=rise_console.yaml`, { width: 1400, height: 1300 });
    result.status = status;
    result.opened = await checkState(page);
    result.controls = await page.$$eval('#controls tr[data-name]', (r) => r.map((tr) => tr.dataset.name));
    result.nav = await page.$$eval('#builders a', (a) => a.map((e) => e.getAttribute('href')));

    // The console's sources, live.
    await page.click('#live-start');
    await page.waitForFunction(() => document.getElementById('live-state').className === 'ok', null, { timeout: 20000 });
    result.signals = await page.$$eval('#signals tr[data-signal]', (r) => r.map((tr) => tr.dataset.signal));

    // Learn: the C++ test's emulator keeps pressing the console's horn.
    await page.fill('#learn-seconds', '3');
    await page.click('#learn');
    await page.waitForFunction(() => document.getElementById('learn-state').textContent.startsWith('move it now'), null, { timeout: 5000 });
    result.learn_shown = await page.$eval('#learn-state', (e) => e.textContent);
    await page.waitForFunction(() => document.getElementById('proposal').textContent !== '', null, { timeout: 15000 });
    result.proposal = await page.$eval('#proposal', (e) => e.textContent);
    result.form = await page.evaluate(() => ({
      signal: document.getElementById('c-signal').value, kind: document.getElementById('c-kind').value,
      source: document.getElementById('c-source').value, comment: document.getElementById('c-comment').value,
    }));

    // Named, kind and safe value picked; first with the signal cleared: the loader's error.
    const proposed = result.form.signal;
    await page.type('#c-name', 'horn');
    await page.selectOption('#c-kind', 'button');
    await page.selectOption('#c-safe', 'false');
    await page.fill('#c-signal', '');
    await page.click('#c-add');
    await settled(page, 'bad');
    result.missing_signal_errors = await page.$$eval('#errors li', (l) => l.map((e) => ({ text: e.textContent, key: e.dataset.key, line: Number(e.dataset.line) })));
    result.error_row = await page.$eval('#controls tr.error-row', (e) => e.textContent);
    result.save_disabled_on_error = await page.$eval('#save', (b) => b.disabled);
    await page.click('#controls tr[data-name="horn"] button.edit');
    await page.fill('#c-signal', proposed);
    await page.click('#c-add');
    await settled(page, 'ok');
    result.valid = await checkState(page);

    // The preview runs the edited definition: horn follows the press.
    await page.waitForSelector('#preview tr[data-control="horn"]', { timeout: 15000 });
    // Every value the horn's cell shows until it has shown two (the page redraws it on each poll).
    const cell = '#preview tr[data-control="horn"] td.value';
    await page.waitForFunction((sel) => {
      const seen = (window.__hornSeen ||= new Set());
      const e = document.querySelector(sel);
      if (e) seen.add(e.textContent);
      return seen.size >= 2;
    }, cell, { polling: 'raf', timeout: 4000 }).catch((e) => console.log('horn wait: ' + e.message));
    const seen = new Set(await page.evaluate(() => [...(window.__hornSeen || [])]));
    result.preview_horn = [...seen].sort();
    await page.screenshot({ path: path.join(outDir, 'console_builder.png'), fullPage: true });

    await page.click('#save');
    await page.waitForFunction(() => document.getElementById('save-state').textContent === 'saved', null, { timeout: 10000 });
    result.saved_text = fs.readFileSync(path.join(consolesDir, 'rise_console.yaml'), 'utf8');
    result.page_errors = errors;
  } finally {
    await browser.close();
  }
  return result;
});
