// The Compare page: one click on a paper's comparison runs it; the table marks the best values.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { serveDist, launchBrowser, openLab, screenshot } from './harness.mjs';

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

test('a paper comparison runs its controllers side by side with the best values marked', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/compare', { width: 1440, height: 900 });
  await page.getByRole('button', { name: 'Paper 001: adaptive control at DOC 4 mm' }).click();
  const table = page.getByRole('table', { name: /Metrics of the runs/ });
  await table.getByRole('columnheader', { name: /C: pi/ }).waitFor({ timeout: 120_000 });
  for (const name of ['A: fixed', 'B: mrac', 'C: pi']) {
    await table.getByRole('columnheader', { name }).waitFor();
  }
  // One set of reference runs serves every variant: each column gets its saving.
  const saving = table.getByRole('row').filter({ has: page.getByRole('rowheader', { name: 'Saving vs safe fixed feed (%)' }) });
  await saving.filter({ hasText: /\d\s*$/ }).waitFor({ timeout: 120_000 });
  assert.equal((await saving.getByRole('cell').allTextContents()).filter((t) => /\d/.test(t)).length, 3);
  const stars = await table.getByLabel('best').count();
  assert.ok(stars >= 5, `only ${stars} best marks`);
  assert.equal(await page.getByLabel('Preset', { exact: true }).inputValue(), 'maneerat-doc-4');
  assert.match(page.url(), /b\.controller=mrac/);
  await screenshot(page, 'compare');
  assert.deepEqual(problems, []);
  await context.close();
});

test('variants can be added and removed', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/compare?preset=maneerat-doc-1');
  await page.getByRole('group', { name: 'Variant B' }).waitFor();
  await page.getByRole('button', { name: 'Add a variant' }).click();
  await page.getByRole('group', { name: 'Variant C' }).waitFor();
  await page.getByRole('button', { name: 'Remove the last variant' }).click();
  await page.getByRole('group', { name: 'Variant C' }).waitFor({ state: 'detached' });
  assert.equal(await page.getByRole('button', { name: 'Remove the last variant' }).isDisabled(), true);
  assert.deepEqual(problems, []);
  await context.close();
});
