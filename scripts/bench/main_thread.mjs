// What the page's long main-thread tasks are made of while the lab starts and computes: for
// Simulate and Compare (four variants) on three presets, the longest main-thread task from
// navigation until the runs and their savings are shown, from a Chromium trace (no sampling
// profiler, so the tasks run at their own pace), with the browser's own work inside it: the
// navigation's commit, V8's lazy compilation of the page module's functions on their first call,
// style and layout, paint, garbage collection. Issue 28 holds every task to 50 ms (what
// Chromium's `longtask` entries report, the task's wall time).
//
//   trunk build --release --offline
//   node scripts/bench/main_thread.mjs [--rounds 3] [--cores real,1] [--min-ms 30]
//
// `--cores` lists the core counts the browser reports in turn (`navigator.hardwareConcurrency`,
// so the pool's size; "real" is the machine's own): with one worker the page's thread has a
// core of its own on the 2-core machine, so the comparison shows what the workers' competition
// for the cores adds. Each page and core count is loaded --rounds times in a fresh context; the
// table holds each one's longest task over all rounds. (The trace's thread clock, `tdur`, is not
// used: on the reference machine it reports 55–62 ms for a 100 ms busy loop.) Prints a Markdown
// table and one JSON line. CUTLAB_DIST=<directory> serves another build.
import { serveDist, launchBrowser } from '../../tests/browser/harness.mjs';

const arg = (name, fallback) => {
  const i = process.argv.indexOf(name);
  return i > 0 ? process.argv[i + 1] : fallback;
};
const rounds = Number(arg('--rounds', 3));
const coreCounts = arg('--cores', 'real,1').split(',');
const minMs = Number(arg('--min-ms', 30));
const TIMEOUT = 120_000;
const PRESETS = ['kim-step-doc', 'maneerat-doc-2', 'kim-circular-taper'];
const PAGES = (preset) => [`#/simulate?preset=${preset}`, `#/compare?preset=${preset}&variants=4`];

/** Until the metrics table is filled and no run or reference search is under way. */
const settled = (page) => page.waitForFunction(() => {
  const rows = [...document.querySelectorAll('table.metrics tbody tr')];
  const shown = rows.some((r) => /Cycle time/.test(r.textContent) && /\d/.test(r.querySelector('td')?.textContent ?? ''));
  const busy = document.getElementById('savings-progress') !== null
    || [...document.querySelectorAll('[role=status]')].some((e) => /Running|teach cut|closed loop/.test(e.textContent));
  return shown && !busy;
}, null, { timeout: TIMEOUT, polling: 50 });

/** The browser's work a task can hold, by the trace events that time it (nested ones apart: the
 * lazy compilation and garbage collection happen inside the app's script). */
const PARTS = [
  ['navigation', ['DocumentLoader::CommitNavigation']],
  ['lazy compile', ['wasm.CompileLazy']],
  ['style and layout', ['UpdateLayoutTree', 'Layout']],
  ['paint', ['PrePaint', 'Paint', 'Commit']],
  ['GC', ['MinorGC', 'MajorGC']],
];

/** The main-thread tasks of one load of `url` over `minMs`, as { atMs, wallMs, parts }. */
async function tasksOf(browser, url, cores) {
  const context = await browser.newContext({ viewport: { width: 1280, height: 900 } });
  if (cores !== 'real') {
    await context.addInitScript((n) => {
      Object.defineProperty(Navigator.prototype, 'hardwareConcurrency', { get: () => n });
    }, Number(cores));
  }
  const page = await context.newPage();
  const problems = [];
  page.on('console', (m) => { if (m.type() === 'error') problems.push(m.text()); });
  page.on('pageerror', (e) => problems.push(e.message));
  await browser.startTracing(page, { categories: ['toplevel', 'blink.user_timing', 'loading', 'devtools.timeline', 'v8.wasm'] });
  await page.goto(url);
  await settled(page);
  const events = JSON.parse((await browser.stopTracing()).toString()).traceEvents;
  await context.close();
  if (problems.length) throw new Error(`console errors on ${url}: ${problems.join('; ')}`);
  const start = events.find((e) => e.name === 'navigationStart' && e.args?.data?.documentLoaderURL?.startsWith(url.split('#')[0]));
  if (!start) throw new Error(`no navigation to ${url} in the trace`);
  const onMain = (e) => e.pid === start.pid && e.tid === start.tid && e.ph === 'X';
  const tasks = events.filter((e) => onMain(e) && e.ts >= start.ts
    && e.name === 'ThreadControllerImpl::RunTask' && e.dur >= minMs * 1000);
  const inside = events.filter((e) => onMain(e) && PARTS.some(([, names]) => names.includes(e.name)));
  return tasks.map((t) => {
    const parts = Object.fromEntries(PARTS.map(([part, names]) => [part, inside
      .filter((e) => names.includes(e.name) && e.ts >= t.ts && e.ts < t.ts + t.dur)
      .reduce((sum, e) => sum + e.dur / 1000, 0)]));
    return { atMs: (t.ts - start.ts) / 1000, wallMs: t.dur / 1000, parts };
  });
}

const server = await serveDist(process.env.CUTLAB_DIST);
const browser = await launchBrowser();
const worst = {};
try {
  for (let r = 0; r < rounds; r++) {
    for (const cores of coreCounts) {
      for (const preset of PRESETS) {
        for (const hash of PAGES(preset)) {
          const key = `${hash.split('?')[0].slice(2)} ${preset}, cores ${cores}`;
          for (const t of await tasksOf(browser, server.url + hash, cores)) {
            if (t.wallMs > (worst[key]?.wallMs ?? 0)) worst[key] = t;
          }
        }
      }
    }
  }
} finally {
  await browser.close();
  await server.close();
}
const ms = (v) => `${Math.round(v)} ms`;
console.log(`| page, preset, cores reported | longest task | at | ${PARTS.map(([part]) => part).join(' | ')} |`);
console.log(`|---|---:|---:|${PARTS.map(() => '---:').join('|')}|`);
for (const [key, t] of Object.entries(worst)) {
  console.log(`| ${key} | ${ms(t.wallMs)} | ${ms(t.atMs)} | ${PARTS.map(([part]) => ms(t.parts[part])).join(' | ')} |`);
}
console.log(JSON.stringify({ rounds, min_ms: minMs, worst }));
