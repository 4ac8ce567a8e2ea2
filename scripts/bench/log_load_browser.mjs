// Loading a big log in the browser (issue 15's benchmark, the browser half): the release build's
// Logs page streams FILE from the file picker into the reader, and the page reports how long it
// took. A measurement script, not a test: it prints what it measured.
//
//   python3 scripts/bench/log_load.py --file /tmp/big-log.csv    # makes the file (and times the native reader)
//   trunk build --release --offline                              # dist/
//   node scripts/bench/log_load_browser.mjs /tmp/big-log.csv [--rounds 3]
//
// Per round: the time from the file input's change to the log being loaded (the page's own
// "Loaded …: N rows × M columns in T s"), whether the progress bar was shown and how many times
// it moved, the longest main-thread task during the load (the page must never block for
// 100 ms), and the WebAssembly memory afterwards (its linear memory never shrinks: the peak).
import { basename } from 'node:path';
import { serveDist, launchBrowser, watchLongTasks } from '../../tests/browser/harness.mjs';

const file = process.argv[2];
if (!file) {
  console.error('usage: node scripts/bench/log_load_browser.mjs FILE [--rounds N]');
  process.exit(2);
}
const roundsAt = process.argv.indexOf('--rounds');
const rounds = roundsAt > 0 ? Number(process.argv[roundsAt + 1]) : 3;
const name = basename(file);

const server = await serveDist();
const browser = await launchBrowser();
const results = [];
try {
  for (let round = 0; round < rounds; round++) {
    const context = await browser.newContext({ viewport: { width: 1280, height: 900 } });
    const page = await context.newPage();
    const problems = [];
    page.on('console', (msg) => { if (msg.type() === 'error') problems.push(msg.text()); });
    page.on('pageerror', (err) => problems.push(err.message));
    // Keep the WebAssembly memory in sight (wasm-bindgen keeps its module private).
    await page.addInitScript(() => {
      const keep = (result) => {
        const exports = (result.instance ?? result).exports;
        if (exports?.memory) window.cutlabWasmMemory = exports.memory;
        return result;
      };
      const streaming = WebAssembly.instantiateStreaming;
      WebAssembly.instantiateStreaming = (...a) => streaming(...a).then(keep);
      const plain = WebAssembly.instantiate;
      WebAssembly.instantiate = (...a) => plain(...a).then(keep);
    });
    await page.goto(server.url + '#/logs');
    await page.getByRole('navigation', { name: 'Lab sections' }).waitFor();
    await page.evaluate(() => {
      window.cutlabProgress = { shown: false, moves: 0 };
      new MutationObserver(() => {
        if (document.getElementById('log-load-progress')) {
          window.cutlabProgress.shown = true;
          window.cutlabProgress.moves += 1;
        }
      }).observe(document.body, { subtree: true, childList: true, attributes: true });
    });
    const longestTask = await watchLongTasks(page);
    await page.getByLabel('Open log files').setInputFiles(file);
    const status = page.getByRole('status').filter({ hasText: `Loaded ${name}:` });
    await status.waitFor({ timeout: 600_000 });
    const text = await status.textContent();
    const seconds = Number(/in ([\d.]+) s\./.exec(text)[1]);
    const progress = await page.evaluate(() => window.cutlabProgress);
    const wasmBytes = await page.evaluate(() => window.cutlabWasmMemory?.buffer.byteLength ?? null);
    results.push({ seconds, text, progress, longest: await longestTask(), wasmBytes, problems });
    await context.close();
  }
} finally {
  await browser.close();
  await server.close();
}
const best = results.reduce((a, b) => (b.seconds < a.seconds ? b : a));
console.log(`${name}: best of ${rounds} rounds`);
for (const r of results) {
  console.log(`  ${r.seconds.toFixed(2)} s; progress bar shown: ${r.progress.shown} (${r.progress.moves} updates); ` +
    `longest task ${r.longest.toFixed(0)} ms; WebAssembly memory ${r.wasmBytes === null ? '?' : (r.wasmBytes / 2 ** 20).toFixed(0) + ' MB'}; ` +
    `console problems: ${r.problems.length}`);
}
console.log(`| browser (Chromium, release build, file picker) | ${best.seconds.toFixed(2)} | ` +
  `${best.wasmBytes === null ? '?' : (best.wasmBytes / 2 ** 20).toFixed(0)} (WebAssembly memory) | longest task ${best.longest.toFixed(0)} ms |`);
if (results.some((r) => r.problems.length > 0)) process.exitCode = 1;
