// The Learn page: lessons with equations and links into the lab.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { serveDist, launchBrowser, openLab } from './harness.mjs';

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

test('the lessons show the papers\' equations and link into the lab', async () => {
  const { page, problems, context } = await openLab(browser, server.url);
  await page.getByRole('navigation', { name: 'Lab sections' }).getByRole('link', { name: 'Learn' }).click();
  await page.getByRole('heading', { level: 2, name: /Why measure force through motor current/ }).waitFor();
  assert.ok((await page.locator('math').count()) >= 5);
  await page.getByRole('link', { name: 'Try it: Design the filter' }).click();
  await page.getByRole('heading', { level: 1, name: /Signal chain/ }).waitFor();
  await page.goBack();
  await page.getByRole('link', { name: 'Try it: Fixed feed against threshold control' }).click();
  const table = page.getByRole('table', { name: /Metrics of the runs/ });
  await table.getByRole('columnheader', { name: 'B: threshold' }).waitFor({ timeout: 60_000 });
  assert.equal(await page.getByLabel('Preset', { exact: true }).inputValue(), 'kim-step-doc');
  assert.deepEqual(problems, []);
  await context.close();
});
