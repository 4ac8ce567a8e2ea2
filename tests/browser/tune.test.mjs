// The Tune page: a teach-in, a two-parameter sweep with its heat map, and a search whose best
// point opens in Simulate — all found by role and label, as a person would.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { serveDist, launchBrowser, openLab } from './harness.mjs';

const RUN_TIMEOUT = 180_000;

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

test('a teach-in proposes the paper target and its reference current', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/tune');
  await page.getByRole('checkbox', { name: 'maneerat-doc-1' }).uncheck();
  await page.getByRole('checkbox', { name: 'liu-current-step' }).check();
  await page.getByRole('button', { name: 'Teach-in' }).click();
  const table = page.getByRole('table', { name: 'Teach-in' });
  await table.waitFor({ timeout: RUN_TIMEOUT });
  const row = table.getByRole('row', { name: /liu-current-step/ });
  // Paper 002 regulates the spindle to 25 A: the teach-in gives that current back.
  assert.match(await row.innerText(), /25\.0\d\d/);
  assert.deepEqual(problems, []);
  await context.close();
});

test('a sweep of two parameters fills a table and a heat map, and a search links its best', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/tune');
  await page.getByLabel('Controller', { exact: true }).selectOption('pi');
  await page.getByLabel('Method', { exact: true }).selectOption('sweep');
  await page.getByLabel('Values per parameter').fill('2');
  await page.getByRole('button', { name: 'Run' }).click();
  const table = page.getByRole('table', { name: 'Evaluations' });
  await table.waitFor({ timeout: RUN_TIMEOUT });
  assert.equal(await table.getByRole('row').count(), 1 + 4);
  await page.getByRole('img', { name: /Objective over the two parameters/ }).waitFor();
  // Every evaluation opens in Simulate, and so does a cell picked on the map (keyboard here).
  assert.equal(await table.getByRole('link', { name: /^Open [1-4] in Simulate$/ }).count(), 4);
  await page.getByRole('img', { name: /Objective over the two parameters/ }).press('Enter');
  await page.waitForFunction(() => location.hash.startsWith('#/simulate'));
  await page.goBack();
  await page.waitForFunction(() => location.hash.startsWith('#/tune'));

  // A search: at most 5 evaluations of one parameter, then open the best in Simulate.
  await page.getByLabel('Tune a second parameter').uncheck();
  await page.getByLabel('Method', { exact: true }).selectOption('search');
  await page.getByLabel('Evaluations at most').fill('5');
  await page.getByRole('button', { name: 'Run' }).click();
  await page.getByRole('status').filter({ hasText: /Best of [0-9]+ evaluations/ }).waitFor({ timeout: RUN_TIMEOUT });
  await page.getByRole('link', { name: 'Open the best in Simulate' }).click();
  // A hash change fires no load event: wait for the hash itself.
  await page.waitForFunction(() => location.hash.startsWith('#/simulate'));
  // The Simulate page reads the link (and writes its own form back into it).
  await page.getByRole('heading', { name: /Simulate/ }).waitFor();
  const hash = await page.evaluate(() => location.hash);
  for (const part of ['preset=maneerat-doc-1', 'controller=pi', 'kp=']) {
    assert.ok(hash.includes(part), `${part} in ${hash}`);
  }
  // A bad bound is a message beside the form, not a crash.
  await page.goto(`${server.url}#/tune`);
  await page.getByLabel('Parameter 1 from').fill('abc');
  await page.getByRole('button', { name: 'Run' }).click();
  await page.getByRole('alert').filter({ hasText: 'from' }).waitFor();
  assert.deepEqual(problems, []);
  await context.close();
});
