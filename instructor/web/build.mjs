// Builds the pages into dist/ from the npm packages (three.js bundled by
// esbuild): run at set-up (run.sh), nothing is fetched when the pages run.
import { build } from 'esbuild';
import { cpSync, mkdirSync, rmSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const dist = join(here, 'dist');
rmSync(dist, { recursive: true, force: true });
mkdirSync(dist, { recursive: true });
await build({
  entryPoints: ['console.js', 'panel.js', 'trainee.js', 'training.js', 'world_builder.js', 'robot_builder.js', 'task_builder.js', 'console_builder.js'].map((f) => join(here, 'src', f)),
  bundle: true,
  format: 'esm',
  minify: true,
  sourcemap: false,
  target: 'es2020',
  outdir: dist,
  logLevel: 'warning',
});
for (const f of ['index.html', 'panel.html', 'trainee.html', 'training.html', 'world_builder.html', 'robot_builder.html', 'task_builder.html', 'console_builder.html', 'style.css']) cpSync(join(here, 'src', f), join(dist, f));
console.log('built', dist);
