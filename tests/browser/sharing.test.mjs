// Tune, Logs and Hardware keep what is settable in the URL: a reload (or the link, shared)
// restores it — never a person's own file or serial port.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { serveDist, launchBrowser, openLab } from './harness.mjs';

const LONG = 60_000;

let server;
let browser;
before(async () => {
  server = await serveDist();
  browser = await launchBrowser();
});
after(async () => {
  await browser?.close();
  await server?.close();
});

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
