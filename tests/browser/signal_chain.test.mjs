// The signal-chain page: design a filter by its labelled controls, see the response redraw, and
// find the design in the URL.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { useLab, server, browser, openLab, canvasPixels, waitForRedraw, screenshot, watchLongTasks } from './harness.mjs';

useLab();

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

test('the design lives in the URL, without its defaults, and a reload reproduces it', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/signal');
  const hashIs = (hash) => page.waitForFunction((h) => window.location.hash === h, hash);
  await page.getByText('5 second-order sections').waitFor();
  assert.equal(new URL(page.url()).hash, '#/signal');
  await page.getByLabel('Order').fill('4');
  await hashIs('#/signal?order=4');
  // A preset is written by its name, and its button shows it is chosen.
  const spindle = page.getByRole('button', { name: 'Kim et al.: spindle motor, 260 Hz' });
  assert.equal(await spindle.getAttribute('aria-pressed'), 'false');
  await spindle.click();
  await hashIs('#/signal?preset=kim-spindle-260hz');
  assert.equal(await spindle.getAttribute('aria-pressed'), 'true');
  // Editing a preset's value leaves the preset: the fields are written instead.
  await page.getByLabel('Cut-off (Hz)', { exact: true }).fill('300');
  await hashIs('#/signal?order=2&cutoff=300');
  assert.equal(await spindle.getAttribute('aria-pressed'), 'false');
  await page.getByLabel('Filter type').selectOption({ label: 'Band-pass' });
  await page.getByLabel('Upper cut-off (Hz)').fill('900');
  await hashIs('#/signal?kind=bandpass&order=2&cutoff=300&upper=900');
  await page.reload();
  await page.getByRole('heading', { level: 1, name: /Signal chain/ }).waitFor();
  assert.equal(await page.getByLabel('Filter type').inputValue(), 'bandpass');
  assert.equal(await page.getByLabel('Order').inputValue(), '2');
  assert.equal(await page.getByLabel('Lower cut-off (Hz)', { exact: true }).inputValue(), '300');
  assert.equal(await page.getByLabel('Upper cut-off (Hz)').inputValue(), '900');
  assert.equal(await page.getByLabel('Sample rate (Hz)').inputValue(), '10000');
  await page.getByText('2 second-order sections').waitFor();
  assert.deepEqual(problems, []);
  await context.close();
});

test('a link with invalid values shows them beside their fields and nothing breaks', async () => {
  const { page, problems, context } = await openLab(
    browser,
    server.url,
    '#/signal?kind=nonsense&order=0&cutoff=abc&rate=10000',
  );
  await page.getByRole('heading', { level: 1, name: /Signal chain/ }).waitFor();
  // An unknown kind cannot be shown by the select: the default stays.
  assert.equal(await page.getByLabel('Filter type').inputValue(), 'lowpass');
  const cutoff = page.getByLabel('Cut-off (Hz)', { exact: true });
  assert.equal(await cutoff.inputValue(), 'abc');
  assert.equal(await cutoff.getAttribute('aria-invalid'), 'true');
  await page.getByText('"abc" is not a number').waitFor();
  await cutoff.fill('100');
  // The order's own error shows once the cut-off parses.
  const order = page.getByLabel('Order');
  assert.equal(await order.inputValue(), '0');
  await page.getByText(/order must be a whole number from 1 to 20/).waitFor();
  assert.equal(await order.getAttribute('aria-invalid'), 'true');
  await order.fill('4');
  assert.equal(await order.getAttribute('aria-invalid'), 'false');
  await page.getByText('2 second-order sections').waitFor();
  assert.deepEqual(problems, []);
  await context.close();
});

test('the signal chain simulates the bench current in a worker, without freezing the page', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/signal');
  // Long tasks (main-thread work over 50 ms), measured by the browser from the moment the page
  // is up, while it simulates 13 s of the brake bench and analyses it.
  const longestTask = await watchLongTasks(page);
  for (const name of ['Phase current before and after filtering', 'Three-phase RMS current', 'Amplitude spectrum of i_u']) {
    await page.getByRole('img', { name }).waitFor();
  }
  // The bench's spectrum peak (paper 000's 4 Hz supply frequency) ends the work.
  await page.getByText(/Strongest peak of the raw current: 4\.\d\d Hz/).waitFor({ timeout: 60_000 });
  // A new design re-filters the recording.
  await page.getByLabel('Order').fill('4');
  await page.getByText('2 second-order sections').waitFor();
  const longest = await longestTask();
  assert.ok(longest < 100, `the page froze for ${longest} ms`);
  assert.deepEqual(problems, []);
  await context.close();
});
