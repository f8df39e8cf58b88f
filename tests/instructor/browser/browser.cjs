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

module.exports = { launch, parsePos, run };
