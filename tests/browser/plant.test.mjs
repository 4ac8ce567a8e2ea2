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
  await page.getByRole('img', { name: 'Spectrum of the phase current at load steps' }).waitFor();
  const text = await page.getByRole('status').filter({ hasText: 'RMS current =' }).textContent();
  const [, idle, r2] = text.match(/= ([\d.]+) A \+ [\d.]+ A\/\(N·m\).*R² = ([\d.]+)/);
  assert.ok(Number(idle) > 0.1, `idle ${idle}`);
  assert.ok(Number(r2) > 0.99, `R² ${r2}`);
  assert.deepEqual(problems, []);
  await context.close();
});
