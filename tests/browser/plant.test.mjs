// The Machine page: a preset's path, depth profile, forces and currents; the brake bench's line.
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

test('a mill preset shows its tool path, depth profile, forces, torque and currents', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/plant?preset=kim-circular-taper');
  for (const name of ['Tool path', 'Depth and width of cut along the path', 'Cutting forces', 'Spindle torque', 'Phase currents', 'RMS currents']) {
    await page.getByRole('img', { name }).waitFor({ timeout: 60_000 });
  }
  await page.getByLabel('Feed override (%)').fill('300');
  await page.getByText('300 % is outside 0–255 %').waitFor();
  await screenshot(page, 'plant');
  assert.deepEqual(problems, []);
  await context.close();
});

test('the brake bench gives paper 000\'s linear RMS-current-versus-load line with an idle offset', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/plant?preset=wang-brake-bench');
  await page.getByRole('img', { name: 'RMS current against brake torque' }).waitFor({ timeout: 60_000 });
  const text = await page.getByRole('status').filter({ hasText: 'RMS current =' }).textContent();
  const [, idle, steps, r2] = text.match(/= ([\d.]+) A \+ [\d.]+ A\/\(N·m\).* over (\d+) load steps.*R² = ([\d.]+)/);
  assert.ok(Number(idle) > 0.1, `idle ${idle}`);
  assert.ok(Number(r2) > 0.99, `R² ${r2}`);
  // The preset steps the excitation 0 → 1 A → 0 in 0.1 A steps: 11 loading and 10 unloading steps.
  assert.equal(Number(steps), 21);

  // Every load step has its spectrum, each labelled with its load in the chart's legend.
  const labels = [];
  for (const [name, count] of [
    ['Spectrum of the phase current at each loading step', 11],
    ['Spectrum of the phase current at each unloading step', 10],
  ]) {
    const chart = page.getByRole('figure').filter({ has: page.getByRole('img', { name }) });
    const series = chart.getByRole('button', { name: /^\d+\.\d\d N·m$/ });
    assert.equal(await series.count(), count, name);
    labels.push(...(await series.allTextContents()).map((l) => l.trim()));
  }
  assert.equal(labels.length, Number(steps));
  assert.equal(new Set(labels).size, labels.length, `one series per load: ${labels}`);
  assert.ok(labels.includes('0.00 N·m'), `the unloaded step: ${labels}`);
  assert.deepEqual(problems, []);
  await context.close();
});
