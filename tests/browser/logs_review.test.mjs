// The Logs page on what reviewers found wanting: a signed current named like an RMS is a phase
// current (and the guess says why), the assumed speed and start are said, the fit just made is the
// replay's calibration, and a file without data rows is refused while the open log stays.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { useLab, server, browser, openLab } from './harness.mjs';

const TIMEOUT = 120_000;

useLab();

/** A reviewer's DAQ log: 1 kHz, a 50 Hz current of ±5 then ±10 A, the force 150 then 300 N. */
function signedCurrentLog() {
  const lines = ['time_s,spindle_current_a,force_n'];
  for (let k = 0; k < 3000; k++) {
    const t = k / 1000;
    const [amplitude, force] = k < 1500 ? [5, 150] : [10, 300];
    lines.push(`${t.toFixed(3)},${(amplitude * Math.sin(2 * Math.PI * 50 * t)).toFixed(4)},${force}`);
  }
  return Buffer.from(lines.join('\n') + '\n');
}

test('a signed current calibrates as a phase, the fit is the replay\'s, an empty file is refused', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/logs', { width: 1440, height: 1000 });
  const open = page.getByLabel('Open log files');
  await open.setInputFiles({ name: 'good.csv', mimeType: 'text/csv', buffer: signedCurrentLog() });
  await page.getByRole('status').filter({ hasText: 'Loaded good.csv: 3000 rows × 3 columns' }).waitFor({ timeout: TIMEOUT });
  assert.equal(await page.getByRole('combobox', { name: 'spindle_current_a' }).inputValue(), 'spindle-phase');
  await page.getByRole('cell', { name: /swings down to -10: an RMS is never negative, so a phase current/ }).waitFor();

  // The fit just made is what the replay uses: no target needed, no "no calibration".
  await page.getByRole('button', { name: 'Calibrate', exact: true }).click();
  await page.getByRole('status').filter({ hasText: /^Fit: at 1000 rpm: I = / }).waitFor({ timeout: TIMEOUT });
  await page.getByText(/the speed is assumed to be 1000 rpm \(the log does not say it/).first().waitFor();
  await page.getByText(/its start is assumed to be there \(the log does not show it\)/).first().waitFor();
  assert.equal(await page.getByLabel('Calibration for the replay').inputValue(), 'fit');
  await page.getByRole('button', { name: 'Replay', exact: true }).click();
  const table = page.getByRole('table', { name: 'What each controller would have done on this log' });
  await table.getByRole('columnheader', { name: 'PI with anti-windup' }).waitFor({ timeout: TIMEOUT });
  assert.equal(await page.getByText('no calibration, so the controllers regulate the current').count(), 0);

  // An empty file and a header alone: one message each, and good.csv stays open.
  for (const [name, text, says] of [
    ['empty.csv', '', 'empty.csv: the file is empty'],
    ['headeronly.csv', 'a,b,c\n', 'headeronly.csv: line 1: no data rows: a header of 3 columns ("a, b, c")'],
  ]) {
    await open.setInputFiles({ name, mimeType: 'text/csv', buffer: Buffer.from(text) });
    await page.getByRole('alert').filter({ hasText: says }).waitFor({ timeout: TIMEOUT });
    assert.equal(await page.getByText(`Loaded ${name}`).count(), 0);
    assert.equal(await page.getByLabel(`Analyse ${name}`).count(), 0);
    assert.equal(await page.getByLabel('Analyse good.csv').isChecked(), true);
  }
  assert.deepEqual(problems, []);
  await context.close();
});
