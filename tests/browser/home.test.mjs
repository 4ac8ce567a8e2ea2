// The home page: what the lab is for, the loop whose blocks open their pages, where to start,
// and the five papers — the page the lab opens on.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { useLab, server, browser, openLab } from './harness.mjs';

useLab();

const LOOP = [
  ['Motor currents', 'The simulated machine'],
  ['Signal chain', 'Signal chain: filter design'],
  ['Force estimate', 'Machine logs'],
  ['Controller', 'Compare controllers'],
  ['Safety envelope', 'Simulate a closed loop'],
  ['Feed override', 'Hardware: a machine over the serial line'],
];

test('the lab opens on the home page, whose loop picture opens each page', async () => {
  const { page, problems, context } = await openLab(browser, server.url);
  await page.getByRole('heading', { level: 1, name: /adaptive cutting-force control/ }).waitFor();
  const nav = page.getByRole('navigation', { name: 'Lab sections' });
  assert.equal(await nav.getByRole('link', { name: 'Home' }).getAttribute('aria-current'), 'page');
  const picture = page.getByRole('list', { name: 'The force-control loop' });
  assert.equal(await picture.getByRole('listitem').count(), LOOP.length);
  for (const [block, heading] of LOOP) {
    await picture.getByRole('link', { name: new RegExp(`^${block}`) }).click();
    await page.getByRole('heading', { level: 1, name: heading }).waitFor();
    await page.goBack();
    await page.getByRole('list', { name: 'The force-control loop' }).waitFor();
  }
  // The three starting points and the five papers.
  for (const name of ['Learn the ideas', "Simulate a paper's experiment", 'Bring your own log', 'connect your machine']) {
    await page.getByRole('link', { name }).waitFor();
  }
  const papers = page.getByRole('region', { name: 'The papers' }).getByRole('listitem');
  assert.equal(await papers.count(), 5);
  assert.match(await papers.nth(4).textContent(), /Paper 004\. Xiaolong Shen.*Sensorless Cutting Force Induced Error/);
  assert.deepEqual(problems, []);
  await context.close();
});

test('on a phone the home page does not scroll sideways', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/home', { width: 390, height: 844 });
  await page.getByRole('list', { name: 'The force-control loop' }).waitFor();
  const [documentWidth, viewportWidth] = await page.evaluate(() => [
    document.documentElement.scrollWidth,
    window.innerWidth,
  ]);
  assert.ok(documentWidth <= viewportWidth, `${documentWidth} px wide in a ${viewportWidth} px viewport`);
  assert.deepEqual(problems, []);
  await context.close();
});
