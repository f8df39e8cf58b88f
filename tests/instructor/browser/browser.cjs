// Shared by the browser checks: Debian's chromium driven by playwright-core
// (instructor/web's devDependency), headless, WebGL through SwiftShader.
const path = require('node:path');

function launch(webDir) {
  const { chromium } = require(path.join(webDir, 'node_modules', 'playwright-core'));
  return chromium.launch({
    executablePath: process.env.RISE_CHROMIUM || '/usr/bin/chromium',
    headless: true,
    args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
  });
}

function parsePos(text) {
  const m = /x=(-?[\d.]+) y=(-?[\d.]+)/.exec(text || '');
  return m ? [parseFloat(m[1]), parseFloat(m[2])] : null;
}

// The result goes out as one JSON line the C++ test reads; a failure too.
function run(main) {
  main().then((result) => { console.log('RESULT ' + JSON.stringify(result)); process.exit(0); },
              (e) => { console.log('RESULT ' + JSON.stringify({ error: String(e && e.stack || e) })); process.exit(1); });
}

// A page at `url` once it says it is ready (body data-ready="1"); `errors`
// collects its uncaught errors, `status` is the HTTP status of its HTML.
async function openReady(browser, url, viewport) {
  const page = await browser.newPage({ viewport });
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  const status = (await page.goto(url)).status();
  await page.waitForFunction(() => document.body.dataset.ready === '1', null, { timeout: 20000 });
  return { page, errors, status };
}

// A builder page's #check-state, and waiting until its live check has
// answered with `cls` ("ok" or "bad").
const checkState = (page) => page.$eval('#check-state', (e) => ({ text: e.textContent, cls: e.className }));
const settled = (page, cls) => page.waitForFunction((c) => document.getElementById('check-state').className === c, cls, { timeout: 10000 });

module.exports = { launch, parsePos, run, openReady, checkState, settled };
