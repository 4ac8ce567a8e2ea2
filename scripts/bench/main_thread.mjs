// What the page's main thread does while the lab computes, as wall time against CPU time: for
// Simulate and Compare (four variants) on three presets, every main-thread task over --min-ms
// (default 30) from navigation until the runs and their savings are shown, from a Chromium trace
// (no sampling profiler). A task's wall time is what Chromium's `longtask` reports and the
// issue 28 target counts (≤ 50 ms); its CPU time (the trace's thread clock, `tdur`) is the work
// the page itself did in it. The difference is the time the page's thread waited for a core while
// the computation workers (one per core the browser reports) had them.
//
//   trunk build --release --offline
//   node scripts/bench/main_thread.mjs [--rounds 3] [--cores 2,1] [--min-ms 30]
//
// `--cores` lists the core counts the browser reports in turn (`navigator.hardwareConcurrency`,
// so the pool's size); "real" is the machine's own. Each page and core count is loaded --rounds
// times in a fresh context; the table holds the worst task of all rounds by wall time and by CPU
// time. Prints a Markdown table and one JSON line. CUTLAB_DIST=<directory> serves another build.
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

/** The main-thread tasks of one load of `url` over `minMs`, as { atMs, wallMs, cpuMs }. */
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
  await browser.startTracing(page, { categories: ['toplevel', 'blink.user_timing', 'loading'] });
  await page.goto(url);
  await settled(page);
  const events = JSON.parse((await browser.stopTracing()).toString()).traceEvents;
  await context.close();
  if (problems.length) throw new Error(`console errors on ${url}: ${problems.join('; ')}`);
  const start = events.find((e) => e.name === 'navigationStart' && e.args?.data?.documentLoaderURL?.startsWith(url.split('#')[0]));
  if (!start) throw new Error(`no navigation to ${url} in the trace`);
  return events
    .filter((e) => e.pid === start.pid && e.tid === start.tid && e.ph === 'X' && e.ts >= start.ts
      && e.name === 'ThreadControllerImpl::RunTask' && e.dur >= minMs * 1000)
    .map((e) => ({ atMs: (e.ts - start.ts) / 1000, wallMs: e.dur / 1000, cpuMs: (e.tdur ?? NaN) / 1000 }));
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
          const tasks = await tasksOf(browser, server.url + hash, cores);
          const w = (worst[key] ??= { wall: { wallMs: 0, cpuMs: 0, atMs: 0 }, cpuMs: 0 });
          for (const t of tasks) {
            if (t.wallMs > w.wall.wallMs) w.wall = t;
            w.cpuMs = Math.max(w.cpuMs, t.cpuMs);
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
console.log(`| page, preset, cores reported | longest task: wall (its CPU, at) | most CPU of one task |`);
console.log('|---|---:|---:|');
for (const [key, w] of Object.entries(worst)) {
  console.log(`| ${key} | ${ms(w.wall.wallMs)} (${ms(w.wall.cpuMs)}, at ${ms(w.wall.atMs)}) | ${ms(w.cpuMs)} |`);
}
console.log(JSON.stringify({ rounds, min_ms: minMs, worst }));
