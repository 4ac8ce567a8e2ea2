// The Logs page computes in the workers (issue 28): each controller's replay is a job of its
// own, sent with the log's mapped columns, and its results show on the page; on a big log two
// controllers replay at once on two workers; Cancel during a replay terminates its workers, keeps
// the log, and the next replay succeeds. The signal chain computes in a worker too, sent with its
// column: on a big log the page's thread stays free while it computes, and a setting changed
// during the computation cancels it (its worker is replaced) and computes the new one. A worker
// that throws fails the job it computes (the chain, the first job after a log opens) with the
// reason, the log stays, and the next chain and replay succeed.
//
// The pool publishes `data-busy-workers` (the workers computing now) on <html>. The tests wait on
// that and on what the page shows, never on time.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { writeFile, mkdtemp, rm } from 'node:fs/promises';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { useLab, server, browser, openLab, openLabWithThrowingWorker, root } from './harness.mjs';

const DAQ = 'synthetic-maneerat-doc-2-daq.csv';
const TIMEOUT = 120_000;

useLab();

/** From now on, the most workers busy at once; returns a function that reads it. */
async function watchBusyWorkers(page) {
  await page.evaluate(() => {
    window.cutlabMostBusy = 0;
    new MutationObserver(() => {
      const busy = Number(document.documentElement.dataset.busyWorkers ?? 0);
      window.cutlabMostBusy = Math.max(window.cutlabMostBusy, busy);
    }).observe(document.documentElement, { attributes: true, attributeFilter: ['data-busy-workers'] });
  });
  return () => page.evaluate(() => window.cutlabMostBusy);
}

/** Waits until `count` workers compute at once. */
async function waitForBusyWorkers(page, count) {
  await page.waitForFunction((n) => document.documentElement.dataset.busyWorkers === String(n), count, { timeout: TIMEOUT });
}

/** Waits until the signal chain on `column` has shown its statistics and no worker computes. */
async function waitForChain(page, column) {
  await page.getByRole('heading', { name: `Statistics of ${column}` }).waitFor({ timeout: TIMEOUT });
  await waitForBusyWorkers(page, 0);
}

/** Opens a 10 kHz log of `rows` rows (time, a spindle current at 3000 rpm, its speed) by the file
 * picker, made in a temporary file, and waits until it is loaded. */
async function openBigLog(page, rows) {
  const dir = await mkdtemp(join(tmpdir(), 'cutlab-logs-workers-'));
  const file = join(dir, 'long.csv');
  const lines = ['time [s],S_I [A],S_speed [rpm]'];
  for (let i = 0; i < rows; i++) {
    lines.push(`${(i / 1e4).toFixed(4)},${(10 + 4 * Math.sin(i / 5000) + 0.5 * Math.sin(i / 7)).toFixed(4)},3000`);
  }
  await writeFile(file, lines.join('\n') + '\n');
  await page.getByLabel('Open log files').setInputFiles(file);
  await page.getByRole('status').filter({ hasText: `Loaded long.csv: ${rows} rows × 3 columns` }).waitFor({ timeout: TIMEOUT });
  await rm(dir, { recursive: true });
}

/** Replays the chosen controllers (Threshold and PI) on a current target of `amperes`. */
async function replay(page, amperes) {
  await page.getByLabel('Target is a').selectOption('current');
  await page.getByLabel(/^Target value/).fill(String(amperes));
  await page.getByRole('button', { name: 'Replay', exact: true }).click();
}

const replayTable = (page) => page.getByRole('table', { name: 'What each controller would have done on this log' });

test('a replay computes in a worker and its results show', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/logs');
  await page.getByLabel('Open log files').setInputFiles(join(root, 'www', 'data', DAQ));
  await page.getByRole('status').filter({ hasText: `Loaded ${DAQ}: 12000 rows × 9 columns` }).waitFor({ timeout: TIMEOUT });
  await waitForChain(page, 'S_I_U [A]');
  const mostBusy = await watchBusyWorkers(page);
  await replay(page, 40);
  const table = replayTable(page);
  await table.getByRole('columnheader', { name: 'PI with anti-windup' }).waitFor({ timeout: TIMEOUT });
  await table.getByRole('columnheader', { name: 'Threshold-proportional' }).waitFor();
  await page.getByRole('region', { name: 'Envelope events of PI with anti-windup' }).getByText(/armed: the controller now sets the override/).waitFor();
  await waitForBusyWorkers(page, 0);
  assert.ok(await mostBusy() >= 1, 'no worker computed the replay');
  assert.ok(page.workers().length >= 1);
  assert.deepEqual(problems, []);
  await context.close();
});

test('on a big log two controllers replay at once; Cancel keeps the log and the next replay succeeds', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/logs');
  // 360 s of a 10 kHz log (3.6 million rows, about 75 MB): a spindle current at 3000 rpm, long
  // enough that its replays (about a second each here) are still computing when Cancel is pressed.
  await openBigLog(page, 3_600_000);
  await waitForChain(page, 'S_I [A]');
  const cores = await page.evaluate(() => navigator.hardwareConcurrency);

  // Cancelled while the workers replay: the page says so, the workers stop, the log stays.
  await replay(page, 12);
  await waitForBusyWorkers(page, Math.min(cores, 2));
  await page.getByRole('status').filter({ hasText: cores >= 2 ? 'Replaying 2 controllers on 2 workers' : 'Replaying 2 controllers in a worker' }).waitFor();
  await page.getByRole('status').filter({ has: page.getByRole('progressbar', { name: /^Replaying/ }) })
    .getByRole('button', { name: 'Cancel' }).click();
  await page.getByText(/^Cancelled\./).waitFor();
  await waitForBusyWorkers(page, 0);
  assert.equal(await page.getByLabel('Analyse long.csv').count(), 1);
  assert.equal(await replayTable(page).count(), 0);

  // The next replay runs to its end and shows.
  await replay(page, 11);
  await waitForBusyWorkers(page, Math.min(cores, 2));
  const table = replayTable(page);
  await table.getByRole('columnheader', { name: 'PI with anti-windup' }).waitFor({ timeout: TIMEOUT });
  await table.getByRole('columnheader', { name: 'Threshold-proportional' }).waitFor();
  await waitForBusyWorkers(page, 0);
  assert.deepEqual(problems, []);
  await context.close();
});

test('a worker that throws fails the signal chain beside its controls, the log stays, and the next chain and replay succeed', async () => {
  // The first worker to start throws on its first request (a bug in the worker): the chain, the
  // first job after a log opens.
  const { page, problems, context, served } = await openLabWithThrowingWorker(browser, server.url, '#/logs');
  await page.getByLabel('Open log files').setInputFiles(join(root, 'www', 'data', DAQ));
  await page.getByRole('status').filter({ hasText: `Loaded ${DAQ}: 12000 rows × 9 columns` }).waitFor({ timeout: TIMEOUT });
  const failed = page.getByRole('alert').filter({ hasText: /^The signal chain failed: the computation worker stopped: .*worker bug for the test/ });
  await failed.waitFor({ timeout: TIMEOUT });
  await waitForBusyWorkers(page, 0);
  assert.equal(await page.getByLabel(`Analyse ${DAQ}`).count(), 1);
  // Fresh workers took the thrower's place: the chain computes again on a new setting, and a
  // replay completes.
  await page.getByLabel('Zero-phase low-pass cut-off (empty: none)').fill('100');
  await page.getByRole('heading', { name: 'Statistics of S_I_U [A]' }).waitFor({ timeout: TIMEOUT });
  await failed.waitFor({ state: 'detached' });
  await replay(page, 41);
  await replayTable(page).getByRole('columnheader', { name: 'PI with anti-windup' }).waitFor({ timeout: TIMEOUT });
  assert.ok(served() >= 2, `${served()} worker scripts served`);
  assert.deepEqual(problems, []);
  await context.close();
});

test('on a big log the signal chain computes in a worker, the page stays free, and a new cut-off cancels and recomputes it', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/logs');
  const started = [];
  page.on('worker', (worker) => started.push(worker));
  // 3.6 million rows (6 minutes at 10 kHz, about 75 MB).
  await openBigLog(page, 3_600_000);
  await waitForChain(page, 'S_I [A]');
  const mostBusy = await watchBusyWorkers(page);
  // The page's long tasks while the chain computes: from here until the workers are idle
  // (the answer's redraw, after that, is the page's drawing of 3.6 million rows, not the chain).
  await page.evaluate(() => {
    window.cutlabComputing = [];
    window.cutlabIdleAt = [];
    new PerformanceObserver((list) => {
      for (const entry of list.getEntries()) window.cutlabComputing.push([entry.startTime, entry.duration]);
    }).observe({ type: 'longtask' });
    new MutationObserver(() => {
      if (document.documentElement.dataset.busyWorkers === '0') window.cutlabIdleAt.push(performance.now());
    }).observe(document.documentElement, { attributes: true, attributeFilter: ['data-busy-workers'] });
  });
  const longestWhileComputing = () => page.evaluate(() => {
    const idleAt = Math.max(...window.cutlabIdleAt);
    return Math.max(0, ...window.cutlabComputing.filter(([start]) => start < idleAt).map(([, duration]) => duration));
  });
  // A zero-phase low-pass of order 20 on 3.6 million rows: the chain computes in a worker, long
  // enough that a new setting (debounced by a quarter second) arrives while it computes.
  await page.getByLabel('Low-pass order').fill('20');
  await page.getByLabel('Zero-phase low-pass cut-off (empty: none)').fill('100');
  await waitForBusyWorkers(page, 1);
  const workersBefore = started.length;
  // A new cut-off while it computes: the computation is cancelled (its worker terminated and
  // replaced) and the new one computes: above the log's Nyquist frequency, said.
  await page.getByLabel('Zero-phase low-pass cut-off (empty: none)').fill('6000');
  await page.getByText(/above its Nyquist frequency \(5000 Hz\), so the stage is skipped/).waitFor({ timeout: TIMEOUT });
  await waitForBusyWorkers(page, 0);
  assert.ok(started.length > workersBefore, 'no worker was replaced: the first computation was not cancelled');
  assert.ok(await mostBusy() >= 1, 'no worker computed the chain');
  const longest = await longestWhileComputing();
  assert.ok(longest < 100, `the page froze for ${longest} ms while the chain computed`);
  // The log stays, and the chain with a low-pass completes.
  await page.getByLabel('Zero-phase low-pass cut-off (empty: none)').fill('100');
  await page.getByRole('button', { name: 'zero-phase low-pass' }).waitFor({ timeout: TIMEOUT });
  assert.equal(await page.getByLabel('Analyse long.csv').count(), 1);
  assert.deepEqual(problems, []);
  await context.close();
});
