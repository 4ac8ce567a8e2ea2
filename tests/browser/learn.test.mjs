// The Learn page: lessons with equations and links into the lab.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { useLab, server, browser, openLab } from './harness.mjs';

useLab();

test('the lessons show the papers\' equations and link into the lab', async () => {
  const { page, problems, context } = await openLab(browser, server.url);
  await page.getByRole('navigation', { name: 'Lab sections' }).getByRole('link', { name: 'Learn' }).click();
  await page.getByRole('heading', { level: 2, name: /Why measure force through motor current/ }).waitFor();
  assert.ok((await page.locator('math').count()) >= 12);
  // Every controller of the lesson shows its law, captioned.
  for (const caption of [
    /^Current restriction \(paper 000/,
    /^Threshold-proportional control \(paper 003/,
    /^Incremental fuzzy feed law \(paper 002, eq 6\)/,
    /^Weighted-average defuzzification \(paper 002, eq 7/,
    /^Centroid defuzzification/,
    /^PI with back-calculation anti-windup/,
    /^Sliding variable and adaptive law \(paper 001/,
  ]) {
    const figure = page.getByRole('figure', { name: caption });
    assert.equal(await figure.count(), 1, `one figure captioned ${caption}`);
    assert.equal(await figure.locator('math').count(), 1, `an equation captioned ${caption}`);
  }
  // The fuzzy link opens the Fuzzy rules page with paper 002's dynamics-based table (repaired Table 4).
  assert.equal(
    await page.getByRole('link', { name: 'Try it: Edit the dynamics-based fuzzy rules' }).getAttribute('href'),
    '#/fuzzy?rules=0001122001123401123451123445123445523444553444456',
  );
  // The signal-chain link opens the page preset to paper 000's filter: its values are in the fields.
  await page.getByRole('link', { name: "Try it: Paper 000's 10th-order Butterworth low-pass" }).click();
  await page.getByRole('heading', { level: 1, name: /Signal chain/ }).waitFor();
  assert.equal(await page.getByLabel('Filter type').inputValue(), 'lowpass');
  assert.equal(await page.getByLabel('Order').inputValue(), '10');
  assert.equal(await page.getByLabel('Cut-off (Hz)', { exact: true }).inputValue(), '5');
  assert.equal(await page.getByLabel('Sample rate (Hz)').inputValue(), '10000');
  assert.equal(
    await page.getByRole('button', { name: 'Wang et al.: 10th-order low-pass, 5 Hz' }).getAttribute('aria-pressed'),
    'true',
  );
  await page.getByText('5 second-order sections').waitFor();
  await page.goBack();
  // Paper 003's spindle filter: second order at 260 Hz.
  await page.getByRole('link', { name: "Try it: Paper 003's spindle-current filter" }).click();
  await page.getByRole('heading', { level: 1, name: /Signal chain/ }).waitFor();
  assert.equal(await page.getByLabel('Order').inputValue(), '2');
  assert.equal(await page.getByLabel('Cut-off (Hz)', { exact: true }).inputValue(), '260');
  await page.getByText('1 second-order section', { exact: true }).waitFor();
  await page.goBack();
  await page.getByRole('link', { name: 'Try it: Fixed feed against threshold control' }).click();
  const table = page.getByRole('table', { name: /Metrics of the runs/ });
  await table.getByRole('columnheader', { name: 'B: threshold' }).waitFor({ timeout: 60_000 });
  assert.equal(await page.getByLabel('Preset', { exact: true }).inputValue(), 'kim-step-doc');
  assert.deepEqual(problems, []);
  await context.close();
});
