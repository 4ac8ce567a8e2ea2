// The computation workers (issue 28): Simulate's run and Compare's variants compute in Web Workers
// built from the core alone, so the page's thread stays free; independent variants compute at once
// on different workers; a run's trace streams back in pieces and its chart draws the start of the
// cut before the run is done; the savings' reference runs compute in a worker too, beside the run
// from its teach cut on; Cancel
// terminates the worker at once; a run made in a worker equals the native CLI's, byte for byte in
// the exported trace. The Signal chain page's bench recording, the Machine page's open-loop
// recording, the Fuzzy rules page's run and Tune's teach cuts compute in a worker too.
//
// The pool publishes `data-workers` (its size) and `data-busy-workers` (the workers computing now)
// on <html>; the tests wait on those and on what the page shows, never on time.
//
// The CLI binary is the one `cargo test --features cli,charts` builds; if missing, it is built here.
import { test, before } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { readFile, writeFile, mkdir } from 'node:fs/promises';
import { join } from 'node:path';
import { useLab, server, browser, openLab, openLabWithThrowingWorker, artifacts, watchLongTasks, nativeCli } from './harness.mjs';

let cutlab;
const RUN_TIMEOUT = 60_000;
before(() => {
  cutlab = nativeCli();
});
useLab();

/** Waits until `count` workers compute at once. */
async function waitForBusyWorkers(page, count) {
  await page.waitForFunction((n) => document.documentElement.dataset.busyWorkers === String(n), count, { timeout: RUN_TIMEOUT });
}

test('a long run computes in a worker while the page thread stays free', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/simulate?preset=kim-circular-taper&controller=pi');
  const longestTask = await watchLongTasks(page);
  await waitForBusyWorkers(page, 1);
  // From here until the result arrives the run computes in the worker: no task of the page's own
  // thread may take more than the browser's 50 ms long-task threshold (the observer reports only
  // those), so none may be reported at all.
  await page.evaluate(() => { window.cutlabLongTasks.length = 0; });
  await waitForBusyWorkers(page, 0);
  const duringRun = await longestTask();
  assert.equal(duringRun, 0, `a page task took ${duringRun} ms while the worker computed`);
  const table = page.getByRole('table', { name: /Metrics of the run/ });
  await table.getByRole('row', { name: /Cycle time/ }).getByRole('cell').first().waitFor({ timeout: RUN_TIMEOUT });
  assert.match(await table.getByRole('row', { name: /Cycle time/ }).textContent(), /\d/);
  // One worker per core the browser reports (2 on the reference machine), each started from the
  // workers' loader (www/worker-loader.js, which imports cutlab-worker.js); the first one, which
  // index.html started, is the pool's, not a worker beside it.
  const size = await page.evaluate(() => Number(document.documentElement.dataset.workers));
  const cores = await page.evaluate(() => navigator.hardwareConcurrency);
  assert.equal(size, Math.min(Math.max(cores, 1), 8));
  const workers = page.workers().map((w) => w.url());
  assert.equal(workers.length, size);
  assert.ok(workers.every((u) => u.endsWith('/worker-loader.js')), `workers: ${workers}`);
  assert.deepEqual(problems, []);
  await context.close();
});

test("a long run's chart draws the start of its trace while the worker still computes", async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/simulate?preset=kim-circular-taper&controller=pi');
  // (The first test holds the page's tasks under 50 ms through the same run, previews included.)
  // Every change of the rows the charts draw (`data-trace-rows` on the charts), with whether a
  // worker was still computing and whether the metrics were shown at that moment.
  await page.evaluate(() => {
    window.cutlabDrawn = [];
    new MutationObserver(() => {
      const charts = document.querySelector('.charts');
      window.cutlabDrawn.push({
        rows: Number(charts?.dataset.traceRows ?? 0),
        computing: document.documentElement.dataset.busyWorkers !== '0',
        metrics: document.querySelector('table.metrics') !== null,
      });
    }).observe(document.body, { subtree: true, attributes: true, attributeFilter: ['data-trace-rows'] });
  });
  const table = page.getByRole('table', { name: /Metrics of the run/ });
  await table.getByRole('row', { name: /Cycle time/ }).getByRole('cell').first().waitFor({ timeout: RUN_TIMEOUT });
  await waitForBusyWorkers(page, 0);
  const finalRows = await page.locator('.charts').evaluate((c) => Number(c.dataset.traceRows));
  const drawn = await page.evaluate(() => window.cutlabDrawn);
  // Part of the trace was drawn while the worker computed and before any metrics showed: the
  // streamed start of the cut, shorter than the finished run.
  const partial = drawn.filter((d) => d.computing && !d.metrics && d.rows > 0);
  assert.ok(partial.length > 0, `drawn: ${JSON.stringify(drawn)}`);
  assert.ok(partial[0].rows < finalRows, `first drawn ${partial[0].rows} rows of ${finalRows}`);
  assert.deepEqual(problems, []);
  await context.close();
});

test('two Compare variants compute at once, on two workers', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/compare?preset=kim-circular-taper&variants=2');
  const cores = await page.evaluate(() => navigator.hardwareConcurrency);
  if (cores < 2) {
    // A one-core browser gets a pool of one; the variants then take turns.
    await context.close();
    return;
  }
  // Both variants are under way before either has finished: two workers busy at once, and the
  // progress says so.
  await waitForBusyWorkers(page, 2);
  await page.getByRole('status').filter({ hasText: '2 runs on 2 workers' }).waitFor({ timeout: RUN_TIMEOUT });
  const table = page.getByRole('table', { name: /Metrics of the runs/ });
  await table.getByRole('columnheader', { name: /^B: / }).waitFor({ timeout: RUN_TIMEOUT });
  await waitForBusyWorkers(page, 0);
  assert.deepEqual(problems, []);
  await context.close();
});

test("Compare's variants beyond the workers start from the teach cut a variant before them made", async () => {
  // Every runs request the page sends to a worker, as the number of calibrations it carries.
  const context = await browser.newContext({ viewport: { width: 1280, height: 720 } });
  await context.addInitScript(() => {
    window.cutlabRunRequests = [];
    const post = Worker.prototype.postMessage;
    Worker.prototype.postMessage = function (message, ...rest) {
      const request = typeof message?.request === 'string' ? JSON.parse(message.request) : null;
      if (request?.kind === 'runs') window.cutlabRunRequests.push(request.calibrations.length);
      return post.call(this, message, ...rest);
    };
  });
  const page = await context.newPage();
  const problems = [];
  page.on('console', (m) => { if (m.type() === 'error') problems.push(m.text()); });
  page.on('pageerror', (e) => problems.push(e.message));
  await page.goto(server.url + '#/compare?preset=maneerat-doc-2&variants=4');
  const table = page.getByRole('table', { name: /Metrics of the runs/ });
  await table.getByRole('columnheader', { name: /^D: / }).waitFor({ timeout: RUN_TIMEOUT });
  const cores = await page.evaluate(() => navigator.hardwareConcurrency);
  const sent = await page.evaluate(() => window.cutlabRunRequests);
  // One request per variant: as many start at once as there are workers, each making the
  // (shared) teach cut; the others are sent as those finish, with its calibration.
  assert.equal(sent.length, 4, JSON.stringify(sent));
  const workers = Math.min(cores, 4);
  assert.ok(sent.slice(workers).every((n) => n === 1), JSON.stringify(sent));
  assert.ok(sent.filter((n) => n === 0).length <= workers, JSON.stringify(sent));
  assert.deepEqual(problems, []);
  await context.close();
});

test('Cancel terminates the worker at once and a fresh one runs the next run', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/simulate?preset=kim-circular-taper&controller=threshold');
  const started = [];
  page.on('worker', (w) => started.push(w));
  // The run's own Cancel (in the run's form: the savings' reference search, started beside the
  // run from its teach cut on, has one of its own).
  const cancel = page.getByRole('form', { name: 'Run settings' }).getByRole('button', { name: 'Cancel' });
  await cancel.waitFor({ timeout: RUN_TIMEOUT });
  const before = started.length;
  await cancel.click();
  // No worker computes any more, and the cancelled one was replaced by a new worker.
  await waitForBusyWorkers(page, 0);
  await page.getByText(/^Cancelled\./).waitFor();
  // A fresh worker replaces the cancelled one (started in the click's task; its event may follow).
  if (started.length <= before) await page.waitForEvent('worker', { timeout: RUN_TIMEOUT });
  assert.ok(started.length > before);
  // The next run completes.
  await page.getByLabel('Seed').fill('2');
  await waitForBusyWorkers(page, 1);
  await waitForBusyWorkers(page, 0);
  const table = page.getByRole('table', { name: /Metrics of the run/ });
  await table.getByRole('row', { name: /Cycle time/ }).getByRole('cell').first().waitFor({ timeout: RUN_TIMEOUT });
  assert.deepEqual(problems, []);
  await context.close();
});

test("the workers' module is downloaded once as the page loads, brotli-compressed as the page's, and every worker, a replaced one too, starts from it", async () => {
  const context = await browser.newContext({ viewport: { width: 1280, height: 720 } });
  const fetched = [];
  context.on('request', (r) => { if (/cutlab-worker_bg\.wasm$/.test(r.url())) fetched.push(r.url()); });
  const encodings = [];
  context.on('response', (r) => { if (/\.wasm$/.test(r.url())) encodings.push(r.headers()['content-encoding']); });
  const page = await context.newPage();
  const problems = [];
  page.on('console', (m) => { if (m.type() === 'error') problems.push(m.text()); });
  page.on('pageerror', (e) => problems.push(e.message));
  // The home page computes nothing, yet the pool is started as the app loads.
  await page.goto(server.url);
  await page.waitForFunction(() => Number(document.documentElement.dataset.workers) >= 1, null, { timeout: RUN_TIMEOUT });
  // The same document moves to a long run (a hash change, not a new load).
  await page.evaluate(() => { location.hash = '#/simulate?preset=kim-circular-taper&controller=threshold'; });
  // A cancelled run's worker is replaced; the replacement runs the next run.
  await page.getByRole('form', { name: 'Run settings' }).getByRole('button', { name: 'Cancel' }).click();
  await page.getByText(/^Cancelled\./).waitFor();
  await page.getByLabel('Seed').fill('2');
  const table = page.getByRole('table', { name: /Metrics of the run/ });
  await table.getByRole('row', { name: /Cycle time/ }).getByRole('cell').first().waitFor({ timeout: RUN_TIMEOUT });
  assert.equal(fetched.length, 1, `the workers' module was fetched ${fetched.length} times`);
  // Both modules came as the release build precompressed them (scripts/precompress.mjs, served
  // as a host that sends precompressed files would: tests/browser/harness.mjs).
  assert.deepEqual(encodings, ['br', 'br']);
  assert.deepEqual(problems, []);
  await context.close();
});

test("a run made in a worker exports the native CLI's trace, byte for byte", async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/simulate?preset=maneerat-doc-1&controller=pi&kp=1.5');
  const table = page.getByRole('table', { name: /Metrics of the run/ });
  await table.getByRole('row', { name: /Cycle time/ }).getByRole('cell').first().waitFor({ timeout: RUN_TIMEOUT });
  await page.getByRole('status').filter({ hasText: 'Running' }).waitFor({ state: 'detached', timeout: RUN_TIMEOUT });
  const download = async (name) => {
    const [file] = await Promise.all([page.waitForEvent('download'), page.getByRole('button', { name }).click()]);
    return readFile(await file.path(), 'utf8');
  };
  const config = await download('Configuration (JSON)');
  const trace = await download('Trace (CSV)');
  const metrics = await download('Metrics (CSV)');
  const dir = join(artifacts, 'workers');
  await mkdir(dir, { recursive: true });
  await writeFile(join(dir, 'config.json'), config);
  execFileSync(cutlab, ['sim', '--config', join(dir, 'config.json'), '--csv', join(dir, 'native.csv')]);
  const native = await readFile(join(dir, 'native.csv'), 'utf8');
  assert.ok(trace.split('\n').length > 100);
  assert.equal(trace, native, 'the worker-made trace differs from the CLI run of the same configuration');
  assert.match(metrics, /^metric,value\ncycle_time_s,\d/);
  assert.deepEqual(problems, []);
  await context.close();
});

test("the savings' reference runs compute in a worker and equal the native CLI's", async () => {
  // kim-material-taper ships no references: its savings need the fixed-feed search (and its cut,
  // 47 s, is long enough after its teach cut for the search to start beside it).
  const { page, problems, context } = await openLab(browser, server.url, '#/simulate?preset=kim-material-taper&controller=pi');
  // Whether the savings' search was ever under way (its progress bar shown) while the run's
  // metrics were shown and a worker computed: after the run, only the search can be that work.
  // And whether it started beside the run, on the other worker, before the run's metrics showed:
  // it needs only the run's teach cut, which the run's first streamed piece carries.
  await page.evaluate(() => {
    window.cutlabSearchInWorker = false;
    window.cutlabSearchBesideRun = false;
    new MutationObserver(() => {
      const busy = document.documentElement.dataset.busyWorkers;
      const metrics = document.querySelector('table.metrics');
      if (document.getElementById('savings-progress') && metrics && busy === '1') window.cutlabSearchInWorker = true;
      if (document.getElementById('savings-progress') && !metrics && busy === '2') window.cutlabSearchBesideRun = true;
    }).observe(document, { subtree: true, childList: true, attributes: true });
  });
  const table = page.getByRole('table', { name: /Metrics of the run/ });
  const saving = (name) => table.getByRole('row').filter({ has: page.getByRole('rowheader', { name }) }).getByRole('cell').first();
  await saving('Saving vs safe fixed feed (%)').filter({ hasText: /\d/ }).waitFor({ timeout: RUN_TIMEOUT });
  await waitForBusyWorkers(page, 0);
  assert.ok(await page.evaluate(() => window.cutlabSearchInWorker), 'the search never ran in a worker');
  assert.ok(await page.evaluate(() => window.cutlabSearchBesideRun), 'the search did not start until the run had ended');
  const download = async (name) => {
    const [file] = await Promise.all([page.waitForEvent('download'), page.getByRole('button', { name }).click()]);
    return readFile(await file.path(), 'utf8');
  };
  const config = await download('Configuration (JSON)');
  const metrics = await download('Metrics (CSV)');
  const dir = join(artifacts, 'workers');
  await mkdir(dir, { recursive: true });
  await writeFile(join(dir, 'savings-config.json'), config);
  execFileSync(cutlab, ['sim', '--config', join(dir, 'savings-config.json'), '--json', join(dir, 'savings-native.json')]);
  const native = JSON.parse(await readFile(join(dir, 'savings-native.json'), 'utf8')).metrics;
  const fromPage = Object.fromEntries(metrics.trim().split('\n').slice(1).map((line) => line.split(',')));
  for (const key of ['saving_vs_programmed_pct', 'saving_vs_safe_fixed_pct']) {
    assert.equal(Number(fromPage[key]), native[key], `${key}: page ${fromPage[key]}, CLI ${native[key]}`);
  }
  assert.deepEqual(problems, []);
  await context.close();
});

test('a worker that throws fails its run with the reason, is replaced, and the next run succeeds', async () => {
  // The first worker to start throws on its first request (a bug in the worker).
  const { page, problems, context, served } = await openLabWithThrowingWorker(browser, server.url, '#/simulate?preset=maneerat-doc-1&controller=pi');
  await page.getByRole('alert').filter({ hasText: /the computation worker stopped: .*worker bug for the test/ }).waitFor({ timeout: RUN_TIMEOUT });
  // A fresh worker took the thrower's place: the next run completes.
  await page.getByLabel('Seed').fill('2');
  const table = page.getByRole('table', { name: /Metrics of the run/ });
  await table.getByRole('row', { name: /Cycle time/ }).getByRole('cell').first().waitFor({ timeout: RUN_TIMEOUT });
  await page.getByRole('alert').filter({ hasText: /worker bug/ }).waitFor({ state: 'detached' });
  assert.ok(served() >= 2, `${served()} worker scripts served`);
  assert.deepEqual(problems, []);
  await context.close();
});

/**
 * From now on, records the most workers computing at once (`window.cutlabMostBusy`), from every
 * change of `data-busy-workers` (its value before and after, so a job that starts and ends
 * between two callbacks still counts).
 */
async function recordBusyWorkers(page) {
  await page.evaluate(() => {
    window.cutlabMostBusy = 0;
    new MutationObserver((records) => {
      for (const r of records) {
        const now = Number(r.target.getAttribute('data-busy-workers') ?? 0);
        window.cutlabMostBusy = Math.max(window.cutlabMostBusy, Number(r.oldValue ?? 0), now);
      }
    }).observe(document.documentElement, { attributes: true, attributeOldValue: true, attributeFilter: ['data-busy-workers'] });
  });
}

/** Goes to `hash` within the app (the page is not reloaded, so a recorder set up before stays). */
async function goTo(page, hash) {
  await page.evaluate((h) => { window.location.hash = h; }, hash);
}

/** Asserts a worker computed since `recordBusyWorkers`, and that none computes any more. */
async function assertComputedInWorker(page, what) {
  await waitForBusyWorkers(page, 0);
  const most = await page.evaluate(() => window.cutlabMostBusy);
  assert.ok(most >= 1, `${what}: no worker computed (most busy at once: ${most})`);
  assert.ok(page.workers().length >= 1, `${what}: the pool started no worker`);
}

test("the Signal chain page's bench recording computes in a worker and its spectrum still shows", async () => {
  // From the home page, which computes nothing, so any worker seen after is the bench's.
  const { page, problems, context } = await openLab(browser, server.url, '#/');
  await recordBusyWorkers(page);
  await goTo(page, '#/signal');
  await page.getByText(/Strongest peak of the raw current: 4\.\d\d Hz, \d\.\d{3} A\./).waitFor({ timeout: RUN_TIMEOUT });
  await page.getByRole('img', { name: 'Amplitude spectrum of i_u' }).waitFor();
  await assertComputedInWorker(page, 'the bench recording');
  assert.deepEqual(problems, []);
  await context.close();
});

test("the Machine page's recording computes in a worker and its charts still show", async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/');
  await recordBusyWorkers(page);
  await goTo(page, '#/plant?preset=wang-brake-bench');
  await page.getByRole('img', { name: 'RMS current against brake torque' }).waitFor({ timeout: RUN_TIMEOUT });
  assert.match(await page.getByRole('status').filter({ hasText: 'RMS current =' }).textContent(), /over 21 load steps/);
  await assertComputedInWorker(page, "the machine's recording");
  // A new override records again, in a worker again.
  await page.evaluate(() => { window.cutlabMostBusy = 0; });
  await page.getByLabel('Feed override (%)').fill('80');
  await page.waitForFunction(() => window.cutlabMostBusy >= 1, null, { timeout: RUN_TIMEOUT });
  await page.getByRole('img', { name: 'RMS current against brake torque' }).waitFor({ timeout: RUN_TIMEOUT });
  await assertComputedInWorker(page, "the machine's second recording");
  assert.deepEqual(problems, []);
  await context.close();
});

test("the Fuzzy rules page's run computes in a worker and its moment slider still shows", async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/fuzzy');
  await recordBusyWorkers(page);
  await page.getByRole('button', { name: 'Run with this table' }).click();
  await page.getByLabel(/Moment: \d+\.\d\d s/).waitFor({ timeout: RUN_TIMEOUT });
  await assertComputedInWorker(page, 'the fuzzy run');
  assert.deepEqual(problems, []);
  await context.close();
});

test("Tune's teach cuts compute in a worker and the teach-in table still shows", async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/tune');
  await recordBusyWorkers(page);
  await page.getByRole('button', { name: 'Teach-in' }).click();
  await page.getByRole('table', { name: 'Teach-in' }).getByRole('row', { name: /maneerat-doc-1/ }).waitFor({ timeout: RUN_TIMEOUT });
  await assertComputedInWorker(page, 'the teach cuts');
  assert.deepEqual(problems, []);
  await context.close();
});
