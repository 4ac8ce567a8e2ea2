// The signal-chain page: design a filter by its labelled controls and see the response redraw.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { serveDist, launchBrowser, openLab, canvasPixels, waitForRedraw, screenshot } from './harness.mjs';

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

test('the lab loads with its navigation and the signal-chain section', async () => {
  const { page, problems, context } = await openLab(browser, server.url);
  const nav = page.getByRole('navigation', { name: 'Lab sections' });
  await nav.getByRole('link', { name: 'Signal chain' }).click();
  await page.getByRole('heading', { level: 1, name: /Signal chain/ }).waitFor();
  assert.equal(await page.getByRole('link', { name: 'Signal chain' }).getAttribute('aria-current'), 'page');
  await screenshot(page, 'signal-chain');
  assert.deepEqual(problems, []);
  await context.close();
});

test('changing the filter order redraws the magnitude response', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/signal');
  const magnitude = page.getByRole('img', { name: 'Magnitude response' });
  await magnitude.waitFor();
  await page.getByText('5 second-order sections').waitFor();
  const before = await canvasPixels(magnitude);
  await page.getByLabel('Order').fill('2');
  await waitForRedraw(magnitude, before);
  await page.getByText('1 second-order section', { exact: true }).waitFor();
  assert.deepEqual(problems, []);
  await context.close();
});

test('an invalid value is explained beside its field and nothing breaks', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/signal');
  const cutoff = page.getByLabel('Cut-off (Hz)', { exact: true });
  await cutoff.fill('abc');
  await page.getByText('"abc" is not a number').waitFor();
  assert.equal(await cutoff.getAttribute('aria-invalid'), 'true');
  // A cut-off above Nyquist is the core's error, shown beside the field too.
  await cutoff.fill('6000');
  assert.equal(await cutoff.getAttribute('aria-invalid'), 'true');
  await page.getByText(/Nyquist/i).waitFor();
  // What the user typed stays in the field.
  assert.equal(await cutoff.inputValue(), '6000');
  await cutoff.fill('100');
  assert.equal(await cutoff.getAttribute('aria-invalid'), 'false');
  await screenshot(page, 'signal-chain-error');
  assert.deepEqual(problems, []);
  await context.close();
});

test('a band-pass design asks for the upper cut-off', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/signal');
  const upper = page.getByLabel('Upper cut-off (Hz)');
  assert.equal(await upper.isVisible(), false);
  await page.getByLabel('Filter type').selectOption({ label: 'Band-pass' });
  await upper.waitFor({ state: 'visible' });
  await page.getByLabel('Lower cut-off (Hz)', { exact: true }).fill('40');
  await upper.fill('400');
  await page.getByText('10 second-order sections').waitFor();
  assert.deepEqual(problems, []);
  await context.close();
});
