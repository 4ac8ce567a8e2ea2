// The computation workers (issue 28), measured as a person meets them: the release build (dist/)
// served on localhost and driven in Debian's Chromium by playwright-core. For each preset, a
// fresh page opened at `#/simulate?preset=…`, timed from navigation start:
//
//   first chart points   the charts draw the first rows of the run's trace (`data-trace-rows` on
//                        the charts above 0): the start of the cut, streamed from the worker
//   run complete         the metrics table shows the run's cycle time (metrics come at the end)
//   savings complete     both savings rows show a number, or the reference runs (in a worker too)
//                        have ended for a run that has none to show (its program not finished)
//
// and, on the default preset over a link throttled to 10 Mbit/s each way with 20 ms latency
// (Chromium's own network emulation, CDP `Network.emulateNetworkConditions`, cache disabled),
// the time to the first chart points and to the first metrics; then the Tune page's 60-evaluation
// search (its default scenarios and kim-step-doc), from Run to the best shown, with the most
// workers that computed at once, and the same search with one worker. Both modules' sizes come from
// `scripts/wasm-size`, printed beside the table by `scripts/bench/run`.
//
//   node scripts/bench/workers.mjs [--rounds 3] [--only tune]
//
// `--only tune` times the Tune searches alone; CUTLAB_DIST=<directory> serves another build than
// dist/ (to compare two builds round by round).
//
// Each case runs --rounds times in a fresh page; the best round is kept (the machine is shared).
// Prints a Markdown table and one JSON line.
import { serveDist, launchBrowser } from '../../tests/browser/harness.mjs';

const rounds = Number(process.argv[process.argv.indexOf('--rounds') + 1]) || 3;
const tuneOnly = process.argv.includes('--only') && process.argv[process.argv.indexOf('--only') + 1] === 'tune';
const TIMEOUT = Number(process.env.BENCH_TIMEOUT_MS) || 120_000;
const PRESETS = ['kim-step-doc', 'maneerat-doc-2', 'kim-circular-taper'];
/** The throttled link: 10 Mbit/s each way, in bytes per second, and a round trip's latency. */
const THROTTLE = { offline: false, latency: 20, downloadThroughput: 10e6 / 8, uploadThroughput: 10e6 / 8 };

/** Installed before the app loads: when the charts first draw rows, when the metrics show, when
 * both savings rows are filled. */
function instrument() {
  window.cutlabTimes = { firstPoints: null, metrics: null, savings: null, searchSeen: false };
  const look = () => {
    const t = window.cutlabTimes;
    const now = performance.now();
    if (t.firstPoints === null && Number(document.querySelector('.charts')?.dataset.traceRows ?? 0) > 0) {
      t.firstPoints = now;
    }
    const rows = [...document.querySelectorAll('table.metrics tbody tr')];
    if (t.metrics === null && rows.some((r) => /Cycle time/.test(r.textContent) && /\d/.test(r.querySelector('td')?.textContent ?? ''))) {
      t.metrics = now;
    }
    // Done when both savings show a number, or when the search has been and gone (a run
    // that did not finish its program, stopped by the envelope, has no savings to show: "—").
    const searching = document.getElementById('savings-progress') !== null;
    t.searchSeen ||= searching;
    const savings = rows.filter((r) => /Saving vs/.test(r.textContent));
    const filled = savings.length === 2 && savings.every((r) => /\d/.test(r.querySelector('td')?.textContent ?? ''));
    if (t.savings === null && t.metrics !== null && (filled || (t.searchSeen && !searching))) {
      t.savings = now;
    }
  };
  new MutationObserver(look).observe(document, { subtree: true, childList: true, characterData: true, attributes: true, attributeFilter: ['data-trace-rows'] });
}

async function round(browser, url, throttled, until) {
  const context = await browser.newContext({ viewport: { width: 1280, height: 900 } });
  await context.addInitScript(instrument);
  const page = await context.newPage();
  const problems = [];
  page.on('console', (m) => { if (m.type() === 'error') problems.push(m.text()); });
  page.on('pageerror', (e) => problems.push(e.message));
  if (throttled) {
    const cdp = await context.newCDPSession(page);
    await cdp.send('Network.enable');
    await cdp.send('Network.setCacheDisabled', { cacheDisabled: true });
    await cdp.send('Network.emulateNetworkConditions', THROTTLE);
  }
  await page.goto(url);
  try {
    await page.waitForFunction((keys) => keys.every((k) => window.cutlabTimes[k] !== null), until, { timeout: TIMEOUT });
  } catch (e) {
    throw new Error(`${url}: ${JSON.stringify(await page.evaluate(() => window.cutlabTimes))} (${e.message})`);
  }
  const times = await page.evaluate(() => window.cutlabTimes);
  await context.close();
  return { times, problems };
}

/** The Tune page's Nelder–Mead search of at most 60 evaluations on its default scenarios and
 * kim-step-doc (issue 28's case), from the Run click to the best shown, and the most workers
 * that computed at once; with `cores` set, the browser reports that many cores (so the pool
 * has that many workers). */
async function tuneRound(browser, base, cores = null) {
  const context = await browser.newContext({ viewport: { width: 1280, height: 900 } });
  if (cores !== null) {
    await context.addInitScript((n) => {
      Object.defineProperty(Navigator.prototype, 'hardwareConcurrency', { get: () => n });
    }, cores);
  }
  const page = await context.newPage();
  const problems = [];
  page.on('console', (m) => { if (m.type() === 'error') problems.push(m.text()); });
  page.on('pageerror', (e) => problems.push(e.message));
  await page.goto(base + '#/tune');
  await page.getByRole('checkbox', { name: 'kim-step-doc' }).check();
  await page.getByLabel('Evaluations at most').fill('60');
  await page.evaluate(() => {
    window.cutlabMostBusy = 0;
    new MutationObserver(() => {
      window.cutlabMostBusy = Math.max(window.cutlabMostBusy, Number(document.documentElement.dataset.busyWorkers ?? 0));
    }).observe(document.documentElement, { attributes: true, attributeFilter: ['data-busy-workers'] });
  });
  const started = await page.evaluate(() => performance.now());
  await page.getByRole('button', { name: 'Run' }).click();
  await page.getByRole('status').filter({ hasText: /Best of [0-9]+ evaluations/ }).waitFor({ timeout: TIMEOUT });
  const ended = await page.evaluate(() => performance.now());
  const mostBusy = await page.evaluate(() => window.cutlabMostBusy);
  await context.close();
  return { ms: ended - started, mostBusy, problems };
}

const server = await serveDist(process.env.CUTLAB_DIST);
const browser = await launchBrowser();
const best = Object.fromEntries(PRESETS.map((p) => [p, { firstPoints: Infinity, metrics: Infinity, savings: Infinity }]));
const throttled = { firstPoints: Infinity, metrics: Infinity };
const tune = { ms: Infinity, mostBusy: 0 };
const tuneOneWorker = { ms: Infinity, mostBusy: 0 };
const problems = [];
try {
  for (let i = 0; i < rounds; i++) {
    for (const preset of tuneOnly ? [] : PRESETS) {
      const r = await round(browser, `${server.url}#/simulate?preset=${preset}`, false, ['firstPoints', 'metrics', 'savings']);
      for (const k of Object.keys(best[preset])) best[preset][k] = Math.min(best[preset][k], r.times[k]);
      problems.push(...r.problems);
    }
    if (!tuneOnly) {
      const t = await round(browser, `${server.url}#/simulate?preset=${PRESETS[0]}`, true, ['firstPoints', 'metrics']);
      for (const k of Object.keys(throttled)) throttled[k] = Math.min(throttled[k], t.times[k]);
      problems.push(...t.problems);
    }
    const u = await tuneRound(browser, server.url);
    tune.ms = Math.min(tune.ms, u.ms);
    tune.mostBusy = Math.max(tune.mostBusy, u.mostBusy);
    problems.push(...u.problems);
    const one = await tuneRound(browser, server.url, 1);
    tuneOneWorker.ms = Math.min(tuneOneWorker.ms, one.ms);
    tuneOneWorker.mostBusy = Math.max(tuneOneWorker.mostBusy, one.mostBusy);
    problems.push(...one.problems);
  }
} finally {
  await browser.close();
  await server.close();
}
const ms = (v) => `${Math.round(v).toLocaleString('en')} ms`;
console.log('| preset (Simulate, fresh page) | first chart points | run complete (metrics) | savings complete |');
console.log('|---|---:|---:|---:|');
for (const preset of PRESETS) {
  const b = best[preset];
  console.log(`| ${preset} | ${ms(b.firstPoints)} | ${ms(b.metrics)} | ${ms(b.savings)} |`);
}
console.log(`| ${PRESETS[0]} over 10 Mbit/s, 20 ms latency (throttled Chromium, no cache) | ${ms(throttled.firstPoints)} | ${ms(throttled.metrics)} | — |`);
console.log('');
console.log('| case | measured | workers at once |');
console.log('|---|---:|---:|');
console.log(`| Tune: search of at most 60 evaluations, maneerat-doc-1 and kim-step-doc, Run → best shown | ${ms(tune.ms)} | ${tune.mostBusy} |`);
console.log(`| Tune: the same search with one worker (the browser reporting one core) | ${ms(tuneOneWorker.ms)} | ${tuneOneWorker.mostBusy} |`);
console.log(JSON.stringify({ rounds, presets: best, throttled_10_mbit: throttled, tune_search: tune, tune_search_one_worker: tuneOneWorker, console_errors: problems.length }));
if (problems.length) {
  console.error(`workers bench: ${problems.length} console errors, first: ${problems[0]}`);
  process.exitCode = 1;
}
