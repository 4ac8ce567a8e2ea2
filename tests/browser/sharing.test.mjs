// Tune, Logs and Hardware keep what is settable in the URL: a reload (or the link, shared)
// restores it — never a person's own file or serial port (a Logs link's column mapping waits for
// the next log opened instead).
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { useLab, server, browser, openLab } from './harness.mjs';

const LONG = 60_000;

useLab();

/** Reloads and waits for the app again. */
async function reload(page) {
  await page.reload();
  await page.getByRole('navigation', { name: 'Lab sections' }).waitFor();
}

test('Tune: a reload restores the scenarios, the parameters and the search settings', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/tune');
  await page.getByRole('checkbox', { name: /maneerat-doc-1/ }).uncheck();
  await page.getByRole('checkbox', { name: /kim-step-doc/ }).check();
  await page.getByLabel('Controller', { exact: true }).selectOption('mrac');
  await page.getByLabel('Parameter 1 from').fill('0.02');
  await page.getByLabel('Tune a second parameter').uncheck();
  await page.getByLabel('Method', { exact: true }).selectOption('sweep');
  await page.getByLabel('Values per parameter').fill('3');
  await page.getByLabel('Weight of the cycle time').fill('2');
  await page.waitForFunction(() => location.hash.includes('cycle=2'));
  const hash = await page.evaluate(() => location.hash);
  await reload(page);
  assert.equal(await page.evaluate(() => location.hash), hash);
  assert.equal(await page.getByRole('checkbox', { name: /maneerat-doc-1/ }).isChecked(), false);
  assert.equal(await page.getByRole('checkbox', { name: /kim-step-doc/ }).isChecked(), true);
  assert.equal(await page.getByLabel('Controller', { exact: true }).inputValue(), 'mrac');
  assert.equal(await page.getByLabel('Parameter 1 from').inputValue(), '0.02');
  assert.equal(await page.getByLabel('Tune a second parameter').isChecked(), false);
  assert.equal(await page.getByLabel('Method', { exact: true }).inputValue(), 'sweep');
  assert.equal(await page.getByLabel('Values per parameter').inputValue(), '3');
  assert.equal(await page.getByLabel('Weight of the cycle time').inputValue(), '2');
  assert.deepEqual(problems, []);
  await context.close();
});

test('Logs: a reload opens the same sample log with the same analysis settings', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/logs');
  await page.getByRole('button', { name: /^Synthetic CNC export/ }).click();
  const loaded = page.getByRole('status').filter({ hasText: 'Loaded synthetic-kim-step-doc-export.csv' });
  await loaded.waitFor({ timeout: LONG });
  await page.getByLabel('Low-pass order').fill('6');
  await page.waitForFunction(() => location.hash.includes('sample=') && location.hash.includes('order=6'));
  await reload(page);
  await loaded.waitFor({ timeout: LONG });
  assert.equal(await page.getByLabel('Low-pass order').inputValue(), '6');
  assert.deepEqual(problems, []);
  await context.close();
});

test('Logs: a reload restores the column mapping, the analysed column and the replay form', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/logs');
  await page.getByRole('button', { name: /^Synthetic CNC export/ }).click();
  const loaded = page.getByRole('status').filter({ hasText: 'Loaded synthetic-kim-step-doc-export.csv' });
  await loaded.waitFor({ timeout: LONG });
  // The measured force is taken out of the mapping; the feed drive's current is analysed.
  const force = page.getByLabel('Kraft [N]', { exact: true });
  assert.equal(await force.inputValue(), 'force');
  await force.selectOption('');
  await page.getByLabel('Column', { exact: true }).selectOption('X_Strom [A]');
  // The replay: MRAC instead of the threshold loop, on paper 003's machine, at 10.4 A.
  await page.getByLabel('Replay Threshold-proportional').uncheck();
  await page.getByLabel('Replay Lyapunov adaptive (MRAC)').check();
  await page.getByLabel("Machine's override input").selectOption('whole-percent');
  await page.getByLabel(/^Target value/).fill('10.4');
  await page.waitForFunction(() => location.hash.includes('target_a=10.4')
    && location.hash.includes('machine=whole-percent') && location.hash.includes('column='));
  const hash = await page.evaluate(() => location.hash);
  assert.match(hash, /map\.spindle-current=/);
  assert.doesNotMatch(decodeURIComponent(hash), /map\.force=/);
  assert.match(hash, /replay=pi%2Cmrac|replay=pi,mrac/);

  await reload(page);
  await loaded.waitFor({ timeout: LONG });
  assert.equal(await page.getByLabel('Kraft [N]', { exact: true }).inputValue(), '');
  assert.equal(await page.getByLabel('S_Strom [A]', { exact: true }).inputValue(), 'spindle-current');
  assert.equal(await page.getByLabel('Column', { exact: true }).inputValue(), 'X_Strom [A]');
  assert.equal(await page.getByLabel('Replay Threshold-proportional').isChecked(), false);
  assert.equal(await page.getByLabel('Replay PI with anti-windup').isChecked(), true);
  assert.equal(await page.getByLabel('Replay Lyapunov adaptive (MRAC)').isChecked(), true);
  assert.equal(await page.getByLabel("Machine's override input").inputValue(), 'whole-percent');
  assert.equal(await page.getByLabel(/^Target value/).inputValue(), '10.4');
  assert.equal(await page.evaluate(() => location.hash), hash);
  assert.deepEqual(problems, []);
  await context.close();
});

test('Logs: a link that maps columns without a sample says it waits for the next log', async () => {
  const { page, problems, context } = await openLab(browser, server.url,
    '#/logs?map.spindle-current=X_Strom%20%5BA%5D&map.time=Zeit%20%5Bs%5D');
  const note = page.getByRole('note').filter({ hasText: /maps 2 columns to channels/ });
  await note.waitFor();
  await page.getByRole('button', { name: /^Synthetic CNC export/ }).click();
  await page.getByRole('status').filter({ hasText: 'Loaded synthetic-kim-step-doc-export.csv' }).waitFor({ timeout: LONG });
  // The export has those columns: the link's mapping is its mapping, and the note is gone.
  assert.equal(await page.getByLabel('X_Strom [A]', { exact: true }).inputValue(), 'spindle-current');
  assert.equal(await page.getByLabel('S_Strom [A]', { exact: true }).inputValue(), '');
  assert.equal(await note.count(), 0);
  assert.deepEqual(problems, []);
  await context.close();
});

test('Hardware: a reload restores the run and host settings, and the link names no port', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/hardware');
  await page.getByLabel('Host watchdog').fill('2.5');
  await page.waitForFunction(() => location.hash.includes('2.5'));
  const hash = await page.evaluate(() => location.hash);
  assert.doesNotMatch(hash, /port/i);
  await reload(page);
  assert.equal(await page.getByLabel('Host watchdog').inputValue(), '2.5');
  assert.deepEqual(problems, []);
  await context.close();
});
