// The Compare page: one click on a paper's comparison runs it; the table marks the best values.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFile } from 'node:fs/promises';
import { useLab, server, browser, openLab, screenshot } from './harness.mjs';

const RUN_TIMEOUT = 120_000;

/** Clicks `button` and returns the text of the file it downloads. */
async function downloadText(page, button) {
  const [download] = await Promise.all([
    page.waitForEvent('download'),
    page.getByRole('button', { name: button }).click(),
  ]);
  return { name: download.suggestedFilename(), text: await readFile(await download.path(), 'utf8') };
}

/** The metrics CSV without the savings rows, which fill in later from background runs. */
const withoutSavings = (csv) => csv.split('\n').filter((line) => !line.startsWith('saving_')).join('\n');

useLab();

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
  // Every run here spends more than 1 % of its cycle above the force limit (the programmed feed
  // enters DOC 4 mm overloaded): none is crowned on any row but the time above the limit itself,
  // and the note under the table names each with its time.
  const note = page.getByText(/^not marked best on any row but the time above the limit: above the force limit/);
  await note.waitFor();
  for (const name of ['A: fixed', 'B: mrac', 'C: pi']) {
    assert.ok((await note.textContent()).includes(`${name} (`), `the note names ${name}`);
  }
  const marked = await table.getByRole('row').filter({ has: page.getByLabel('best') }).getByRole('rowheader').allTextContents();
  assert.equal(marked.length, 1, `best marks on ${marked.join(', ')}`);
  assert.match(marked[0], /^Time above limit/);
  assert.equal(await page.getByLabel('Preset', { exact: true }).inputValue(), 'maneerat-doc-4');
  assert.match(page.url(), /b\.controller=mrac/);
  await screenshot(page, 'compare');
  assert.deepEqual(problems, []);
  await context.close();
});

test('variants running different rule tables are named by them, never alike', async () => {
  // Paper 002's dynamics table (`rules=`, 49 digits, level + 3 row by row), edited in one cell
  // two ways, and the experience table given to the dynamics controller.
  const dynamics = '0001122001123401123451123445123445523444553444456';
  const experience = '0000123000123400123450123456123456623456663456666';
  const edited1 = dynamics.slice(0, 48) + '0';
  const edited2 = '6' + dynamics.slice(1);
  const link = '#/compare?preset=liu-current-step&variants=4'
    + `&a.controller=fuzzy-dynamics&a.rules=${edited1}`
    + `&b.controller=fuzzy-dynamics&b.rules=${edited2}`
    + `&c.controller=fuzzy-dynamics&c.rules=${experience}`
    + `&d.controller=fuzzy-dynamics&d.rules=${edited1}`;
  const { page, problems, context } = await openLab(browser, server.url, link, { width: 1440, height: 900 });
  const table = page.getByRole('table', { name: /Metrics of the runs/ });
  const names = [
    'A: fuzzy-dynamics (edited table 1)',
    'B: fuzzy-dynamics (edited table 2)',
    'C: fuzzy-dynamics (experience table)',
    // The same table as A's: the same name.
    'D: fuzzy-dynamics (edited table 1)',
  ];
  for (const name of names) {
    await table.getByRole('columnheader', { name, exact: true }).waitFor({ timeout: RUN_TIMEOUT });
  }
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

test('a comparison exports traces, metrics and its configuration, and its link reproduces it', async () => {
  const hash = '#/compare?preset=maneerat-doc-1&seed=3&variants=2&a.controller=fixed&b.controller=pi&b.kp=0.5';
  // A high-DPI screen: the charts' backing store is in device pixels, so lines stay crisp.
  const { page, problems, context } = await openLab(browser, server.url, hash, { width: 1280, height: 720 }, 2);
  const table = page.getByRole('table', { name: /Metrics of the runs/ });
  await table.getByRole('columnheader', { name: 'B: pi' }).waitFor({ timeout: RUN_TIMEOUT });
  await page.getByRole('status').filter({ hasText: 'Running' }).waitFor({ state: 'detached', timeout: RUN_TIMEOUT });
  const force = page.getByRole('img', { name: /Cutting force/ });
  const size = await force.evaluate((c) => [c.width, c.clientWidth]);
  assert.ok(Math.abs(size[0] - 2 * size[1]) <= 2, `backing ${size[0]} px for ${size[1]} CSS px`);

  const traces = await downloadText(page, 'Traces (CSV)');
  assert.equal(traces.name, 'cutlab-compare-traces.csv');
  const lines = traces.text.trim().split('\n');
  assert.match(lines[0], /^run,time_s,depth_mm,/);
  assert.ok(lines.some((l) => l.startsWith('A: fixed,')) && lines.some((l) => l.startsWith('B: pi,')));
  const metrics = await downloadText(page, 'Metrics (CSV)');
  assert.match(metrics.text, /^metric,A: fixed,B: pi\ncycle_time_s,[\d.]+,[\d.]+\n/);
  const config = JSON.parse((await downloadText(page, 'Configuration (JSON)')).text);
  assert.equal(config.format, 'cutlab-runs');
  assert.deepEqual(config.runs.map((r) => r.controller.kind), ['fixed', 'pi']);
  assert.equal(config.runs[1].controller.params.kp, 0.5);
  assert.ok(config.runs.every((r) => r.seed === 3 && r.preset === 'maneerat-doc-1'));

  // The saved link, opened afresh, gives the same numbers.
  const again = await openLab(browser, config.link, '');
  await again.page.getByRole('table', { name: /Metrics of the runs/ }).getByRole('columnheader', { name: 'B: pi' }).waitFor({ timeout: RUN_TIMEOUT });
  await again.page.getByRole('status').filter({ hasText: 'Running' }).waitFor({ state: 'detached', timeout: RUN_TIMEOUT });
  const metricsAgain = await downloadText(again.page, 'Metrics (CSV)');
  assert.equal(withoutSavings(metricsAgain.text), withoutSavings(metrics.text));
  assert.deepEqual(again.problems, []);
  await again.context.close();

  // The saved file, opened on a fresh page: a damaged one is refused with its line and changes
  // nothing; the file itself reproduces the comparison.
  const fresh = await openLab(browser, server.url, '#/compare');
  const open = fresh.page.getByLabel('Open configuration…');
  const damaged = JSON.stringify(config, null, 2).replace('"kp": 0.5', '"kp": "half"');
  await open.setInputFiles({ name: 'damaged.json', mimeType: 'application/json', buffer: Buffer.from(damaged) });
  const refusal = fresh.page.getByRole('alert').filter({ hasText: 'damaged.json' });
  await refusal.waitFor();
  assert.match(await refusal.textContent(), /line \d+/);
  assert.equal(await fresh.page.getByLabel('Preset', { exact: true }).inputValue(), 'kim-step-doc');
  await open.setInputFiles({ name: 'cutlab-config.json', mimeType: 'application/json', buffer: Buffer.from(JSON.stringify(config)) });
  const loaded = fresh.page.getByRole('table', { name: /Metrics of the runs/ });
  await fresh.page.getByText('Opened cutlab-config.json (2 runs).').waitFor();
  assert.equal(await fresh.page.getByLabel('Preset', { exact: true }).inputValue(), 'maneerat-doc-1');
  await loaded.getByRole('columnheader', { name: 'B: pi' }).waitFor({ timeout: RUN_TIMEOUT });
  await loaded.getByRole('columnheader', { name: 'A: fixed' }).waitFor();
  await fresh.page.getByRole('status').filter({ hasText: 'Running' }).waitFor({ state: 'detached', timeout: RUN_TIMEOUT });
  const metricsLoaded = await downloadText(fresh.page, 'Metrics (CSV)');
  assert.equal(withoutSavings(metricsLoaded.text), withoutSavings(metrics.text));
  // A field that no longer validates marks the comparison shown as stale.
  const kp = fresh.page.getByRole('group', { name: 'Variant B' }).getByLabel('K_p (% per %)');
  await kp.fill('-5');
  const banner = fresh.page.getByRole('status').filter({ hasText: 'These results are from the last valid settings' });
  await banner.waitFor();
  await kp.fill('0.5');
  await banner.waitFor({ state: 'detached' });
  assert.deepEqual(fresh.problems, []);
  await fresh.context.close();
  assert.deepEqual(problems, []);
  await context.close();
});

test("the fuzzy rule bases' comparison starts from the paper's own settings", async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/compare?preset=kim-step-doc&rpm=1200&a.controller=pi&a.kp=0.9');
  await page.getByRole('button', { name: 'Paper 002: experience vs dynamics rules, sampled every 0.1 s' }).click();
  const table = page.getByRole('table', { name: /Metrics of the runs/ });
  await table.getByRole('columnheader', { name: 'B: fuzzy-dynamics' }).waitFor({ timeout: RUN_TIMEOUT });
  await table.getByRole('columnheader', { name: 'A: fuzzy-experience' }).waitFor();
  assert.equal(await page.getByLabel('Preset', { exact: true }).inputValue(), 'liu-current-step');
  // Edits made for another experiment are gone from the link.
  assert.doesNotMatch(page.url(), /rpm=|kp=/);
  assert.match(page.url(), /period=0\.1/);
  // The paper's own k_u (100 % per period) and EC in A/s (Table 2), and what the lab finds.
  for (const variant of ['Variant A', 'Variant B']) {
    const group = page.getByRole('group', { name: variant });
    assert.equal(await group.getByLabel(/Output range/).inputValue(), '100');
    assert.equal(await group.getByLabel(/EC time base/).inputValue(), '1');
  }
  // The finding is measured from the runs on the page, and its figures are the table's: the
  // experience rules keep cycling (no settling time), the dynamics rules settle.
  const settlingOf = async () => {
    const row = table.getByRole('row').filter({ has: page.getByRole('rowheader', { name: 'Max settling time (s)' }) });
    // A "—" says why to a screen reader (hidden text) and on hover (its title).
    const reasons = await row.locator('[title]').evaluateAll((cells) => cells.map((c) => c.title));
    assert.ok(reasons.every((r) => r.length > 10), `reasons ${reasons.join(' | ')}`);
    return (await row.getByRole('cell').allTextContents()).map((t) => t.replace(/none: .*$/, '').replace(/[*★]/g, '').trim());
  };
  const finding = page.getByRole('status').filter({ hasText: 'Measured:' });
  // A regular expression, case-sensitive: the string ' Reproduced.' also matches "Not reproduced.".
  await finding.filter({ hasText: /Reproduced\./ }).waitFor({ timeout: RUN_TIMEOUT });
  const [experience, dynamics] = await settlingOf();
  assert.equal(experience, '—');
  const settling = table.getByRole('row').filter({ has: page.getByRole('rowheader', { name: 'Max settling time (s)' }) });
  assert.equal(await settling.getByRole('cell').first().locator('[title]').getAttribute('title'), 'the force never settled after a depth step');
  // Never settling is a loss: the dynamics rules' settling time beats it and is marked best.
  assert.equal(await settling.getByRole('cell').nth(1).getByLabel('best').count(), 1);
  assert.equal(await settling.getByRole('cell').first().getByLabel('best').count(), 0);
  assert.match(await finding.textContent(), new RegExp(`in ${dynamics} s against never`));
  // Its twin samples every 0.2 s; the claim holds there too, measured from its own runs.
  const first = await finding.textContent();
  await page.getByRole('button', { name: 'Paper 002: experience vs dynamics rules, sampled every 0.2 s' }).click();
  await page.waitForFunction(
    (old) => [...document.querySelectorAll('[role=status]')].some(
      (e) => e.textContent.includes('Measured:') && e.textContent !== old && / Reproduced\./.test(e.textContent)),
    first,
    { timeout: RUN_TIMEOUT },
  );
  assert.match(page.url(), /period=0\.2/);
  const [slowExperience, slowDynamics] = await settlingOf();
  assert.equal(slowExperience, '—');
  assert.match(await finding.textContent(), new RegExp(`in ${slowDynamics} s against never`));
  assert.deepEqual(problems, []);
  await context.close();
});
