// The Machine page: a preset's path, depth profile, forces and currents; the brake bench's line.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { useLab, server, browser, openLab, screenshot, nativeCli } from './harness.mjs';

useLab();

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

test('paper 004\'s network learned from trial cuts in a worker equals the native cutlab learn', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/plant?preset=kim-step-doc');
  const panel = page.getByRole('region', { name: "Paper 004's network, learned on this machine" });
  await panel.getByRole('button', { name: 'Learn from trial cuts' }).click();
  const exponents = panel.getByRole('table', { name: /Learned exponents/ });
  await exponents.waitFor({ timeout: 120_000 });
  const native = JSON.parse(execFileSync(nativeCli(), ['learn', '--scenario', 'kim-step-doc', '--json']).toString());
  const shown = (e) => `${e.exponent.toFixed(2)} ± ${e.uncertainty.toFixed(2)}`;
  for (const [k, learned] of native.from_force.learned.entries()) {
    const symbol = { 'feed-per-tooth': 'f', 'axial-depth': 'a_p', 'radial-width': 'a_e' }[learned.input];
    const row = exponents.getByRole('row').filter({ has: page.getByRole('rowheader', { name: symbol, exact: true }) });
    const cells = await row.getByRole('cell').allTextContents();
    assert.equal(cells[0], shown(learned), symbol);
    assert.equal(cells[1], shown(native.from_estimate.learned[k]), symbol);
  }
  const residuals = panel.getByRole('table', { name: 'Trial cuts and residuals' });
  assert.equal(await residuals.getByRole('row').count(), native.cuts.length + 1);
  // Trial cuts need a cutter: the brake bench has none.
  await page.getByLabel('Preset').selectOption('wang-brake-bench');
  await panel.getByText('Trial cuts need a cutter: choose a mill preset.').waitFor();
  assert.equal(await panel.getByRole('button', { name: 'Learn from trial cuts' }).isDisabled(), true);
  assert.equal(await exponents.count(), 0);
  assert.deepEqual(problems, []);
  await context.close();
});

test('paper 004\'s network learned from a table of your own trial cuts equals cutlab learn --cuts, and every row left out is named', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/plant?preset=kim-step-doc');
  const panel = page.getByRole('region', { name: "Paper 004's network, learned from your own trial cuts" });
  const table = new URL('../../www/data/kim-step-doc-trial-cuts.csv', import.meta.url).pathname;
  await panel.getByLabel('Trial-cut table (CSV)').setInputFiles(table);
  const exponents = panel.getByRole('table', { name: /Exponents learned from your cuts/ });
  await exponents.waitFor();
  const native = JSON.parse(execFileSync(nativeCli(), ['learn', '--cuts', table, '--json']).toString());
  for (const learned of native.learned.learned) {
    const symbol = { 'feed-per-tooth': 'f', 'axial-depth': 'a_p', 'radial-width': 'a_e' }[learned.input];
    const row = exponents.getByRole('row').filter({ has: page.getByRole('rowheader', { name: symbol, exact: true }) });
    const cells = await row.getByRole('cell').allTextContents();
    assert.equal(cells[0], `${learned.exponent.toFixed(2)} ± ${learned.uncertainty.toFixed(2)}`, symbol);
  }
  const cuts = panel.getByRole('table', { name: 'Your trial cuts and residuals' });
  assert.equal(await cuts.getByRole('row').count(), native.lines.length + 1);

  // Another shop's table: semicolons, decimal commas, its own names, no tool columns, a row with
  // a gap. Refused until the tool is given, then learned with the gap's row named.
  let text = 'Width of cut (mm);FZ [mm];ap;Force [N]\n';
  for (const [i, ae] of [4, 5, 6].entries()) {
    for (const [j, fz] of [0.08, 0.1, 0.12].entries()) {
      const depth = 1 + ((i + 2 * j) % 3);
      const force = 600 * ae ** 0.8 * fz ** 0.7 * depth;
      text += `${ae};${fz};${depth};${force.toFixed(6)}\n`.replaceAll('.', ',');
    }
  }
  text += '5;0,1;;300\n';
  await panel.getByLabel('Trial-cut table (CSV)').setInputFiles({ name: 'shop.csv', mimeType: 'text/csv', buffer: Buffer.from(text) });
  await panel.getByRole('alert').filter({ hasText: 'shop.csv: no column for the tool diameter d' }).waitFor();
  await panel.getByLabel('Tool diameter (mm), if the table has no d column').fill('20');
  await panel.getByLabel('Teeth, if the table has no z column').fill('2');
  await panel.getByRole('list', { name: 'Rows left out' }).getByText('Line 11, ap: the depth of cut a_p is missing').waitFor();
  const feed = exponents.getByRole('row').filter({ has: page.getByRole('rowheader', { name: 'f', exact: true }) });
  assert.equal((await feed.getByRole('cell').allTextContents())[0], '0.70 ± 0.00');
  await panel.getByLabel('Teeth, if the table has no z column').fill('2.5');
  await panel.getByRole('alert').filter({ hasText: 'Teeth: 2.5 is not a whole number above 0' }).waitFor();
  assert.deepEqual(problems, []);
  await context.close();
});
