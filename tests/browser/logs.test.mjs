// The Logs page: a sample log opened with the file picker and another dropped on the page, the
// columns mapped, the signal chain filtering one and showing its spectrum, a calibration from the
// log, two controllers replayed, and both CSV exports; a big file streams with a progress bar and
// Cancel, and the page never freezes.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFile, writeFile, mkdtemp, rm } from 'node:fs/promises';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { useLab, server, browser, openLab, screenshot, watchLongTasks, root } from './harness.mjs';

const DAQ = 'synthetic-maneerat-doc-2-daq.csv';
const EXPORT = 'synthetic-kim-step-doc-export.csv';
const TIMEOUT = 120_000;

useLab();

/** Clicks `button` and returns the text of the file it downloads. */
async function downloadText(page, button) {
  const [download] = await Promise.all([
    page.waitForEvent('download'),
    page.getByRole('button', { name: button }).click(),
  ]);
  return { name: download.suggestedFilename(), text: await readFile(await download.path(), 'utf8') };
}

/** Drops a file with `bytes` named `name` on the element `zone`, as a person dragging it would. */
async function dropFile(page, zone, name, bytes) {
  const dataTransfer = await page.evaluateHandle(([fileName, data]) => {
    const transfer = new DataTransfer();
    transfer.items.add(new File([new Uint8Array(data)], fileName, { type: 'text/csv' }));
    return transfer;
  }, [name, [...bytes]]);
  await zone.dispatchEvent('dragover', { dataTransfer });
  await zone.dispatchEvent('drop', { dataTransfer });
}

test('two sample logs are opened, mapped, filtered, calibrated from, replayed and exported', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/logs', { width: 1440, height: 1000 });
  const longestTask = await watchLongTasks(page);

  // The file picker.
  await page.getByLabel('Open log files').setInputFiles(join(root, 'www', 'data', DAQ));
  await page.getByRole('status').filter({ hasText: `Loaded ${DAQ}: 12000 rows × 9 columns` }).waitFor({ timeout: TIMEOUT });
  // Drag and drop.
  const bytes = await readFile(join(root, 'www', 'data', EXPORT));
  await dropFile(page, page.getByRole('region', { name: 'Drop log files here' }), EXPORT, bytes);
  await page.getByRole('status').filter({ hasText: `Loaded ${EXPORT}: 1149 rows × 8 columns` }).waitFor({ timeout: TIMEOUT });
  // Both overlaid on the linked time axis, each by its mapped current.
  await page.getByRole('button', { name: `${DAQ}: S_I_U [A]` }).waitFor();
  await page.getByRole('button', { name: `${EXPORT}: S_Strom [A]` }).waitFor();

  // Back to the DAQ log: its mapping was guessed; a wrong choice is said beside the table and
  // fixed by choosing again.
  await page.getByLabel(`Analyse ${DAQ}`).check();
  await page.getByRole('status').filter({ hasText: 'delimiter comma, decimal point, a header; time Time [ms]; sample period 0.001 s' }).waitFor();
  const force = page.getByRole('combobox', { name: 'F [N]' });
  assert.equal(await force.inputValue(), 'force');
  assert.equal(await page.getByRole('combobox', { name: 'S_I_W [A]' }).inputValue(), 'spindle-phase');
  // The force is one column: choosing Phase takes it from F [N], and Phase holds no numbers.
  await page.getByRole('combobox', { name: 'Phase' }).selectOption('force');
  await page.getByRole('alert').filter({ hasText: 'column "Phase" holds no numbers' }).waitFor();
  assert.equal(await force.inputValue(), '');
  await page.getByRole('combobox', { name: 'Phase' }).selectOption('label');
  await force.selectOption('force');
  await page.getByRole('alert').filter({ hasText: 'holds no numbers' }).waitFor({ state: 'detached' });

  // The signal chain: a 100 Hz zero-phase low-pass on i_u, statistics per phase, the spectrum
  // with the spindle and tooth-passing markers (3000 rpm, four teeth: 50 and 200 Hz).
  await page.getByLabel('Zero-phase low-pass cut-off (empty: none)').fill('100');
  await page.getByLabel('Cutter teeth (tooth-passing marker)').fill('4');
  await page.getByRole('button', { name: 'zero-phase low-pass' }).waitFor({ timeout: TIMEOUT });
  const stats = page.getByRole('table', { name: /Per label segment/ });
  await stats.getByRole('rowheader', { name: 'Cut' }).waitFor();
  await stats.getByRole('rowheader', { name: 'Air' }).waitFor();
  await page.getByRole('img', { name: 'Spectrum of the chosen column' }).waitFor();
  await page.getByRole('button', { name: /tooth passing 200 Hz/ }).waitFor();
  await page.getByRole('button', { name: /spindle 50 Hz/ }).waitFor();
  await page.getByRole('status').filter({ hasText: /Spectral peaks: .* Hz/ }).waitFor();
  // A cut-off above the log's Nyquist frequency is a skipped stage, said.
  await page.getByLabel('Zero-phase low-pass cut-off (empty: none)').fill('800');
  await page.getByText(/above its Nyquist frequency \(500 Hz\), so the stage is skipped/).waitFor({ timeout: TIMEOUT });
  await page.getByLabel('Zero-phase low-pass cut-off (empty: none)').fill('100');
  // A setting that no longer validates marks the chain shown as stale, announced, until fixed.
  const banner = page.getByRole('status').filter({ hasText: 'These results are from the last valid settings' });
  assert.equal(await banner.count(), 0);
  await page.getByLabel('Cutter teeth (tooth-passing marker)').fill('abc');
  await banner.waitFor();
  assert.equal(await page.locator('.results.stale').count(), 1);
  await page.getByLabel('Cutter teeth (tooth-passing marker)').fill('4');
  await banner.waitFor({ state: 'detached' });

  // Calibration from the dynamometer column, saved where Simulate and the Hardware page look.
  await page.getByRole('button', { name: 'Calibrate', exact: true }).click();
  const fit = page.getByRole('status').filter({ hasText: /^Fit: at [\d.]+ rpm: I = .* R² 0\.9\d/ });
  await fit.waitFor({ timeout: TIMEOUT });
  await page.getByRole('img', { name: 'Calibration fit: current against force' }).waitFor();
  await page.getByRole('button', { name: 'Save calibration in this browser' }).click();
  await page.getByRole('status').filter({ hasText: 'Saved in this browser as' }).waitFor();
  const stored = JSON.parse(await page.evaluate(() => localStorage.getItem('cutlab-calibrations')));
  assert.equal(stored.length, 1);
  assert.equal(stored[0].format, 'cutlab-calibration');
  assert.equal(stored[0].calibration.estimator.feedback, 'spindle');

  // Two controllers replayed side by side on the calibrated force.
  assert.equal(await page.getByLabel('Replay Threshold-proportional').isChecked(), true);
  assert.equal(await page.getByLabel('Replay PI with anti-windup').isChecked(), true);
  await page.getByLabel('Calibration for the replay').selectOption('fit');
  await page.getByLabel('Target is a').selectOption('force');
  await page.getByLabel(/^Target value/).fill('300');
  await page.getByRole('button', { name: 'Replay', exact: true }).click();
  const table = page.getByRole('table', { name: 'What each controller would have done on this log' });
  await table.getByRole('columnheader', { name: 'PI with anti-windup' }).waitFor({ timeout: TIMEOUT });
  await table.getByRole('columnheader', { name: 'Threshold-proportional' }).waitFor();
  await page.getByRole('region', { name: 'Envelope events of PI with anti-windup' }).getByText(/armed: the controller now sets the override/).waitFor();
  await page.getByRole('button', { name: 'logged override' }).waitFor();

  // Exports: the replayed overrides and the analysed channels.
  const replayed = await downloadText(page, 'Replayed overrides (CSV)');
  assert.equal(replayed.name, 'cutlab-log-replay.csv');
  const lines = replayed.text.trim().split('\n');
  assert.equal(lines[0], 'run,time_s,current_a,force_est_n,requested_override_pct,override_pct,envelope_state,logged_override_pct,force_n');
  assert.ok(lines.some((l) => l.startsWith('threshold,')) && lines.some((l) => l.startsWith('pi,')));
  const channels = await downloadText(page, 'Analysed channels (CSV)');
  const header = channels.text.split('\n')[0];
  assert.ok(header.startsWith('time_s,S_I_U [A],S_I_V [A],S_I_W [A]'), header);
  assert.ok(header.endsWith('S_I_U [A] filtered,S_I_U [A] RMS'), header);
  assert.equal(channels.text.trim().split('\n').length, 12001);

  await screenshot(page, 'logs');
  const longest = await longestTask();
  assert.ok(longest < 100, `the page froze for ${longest} ms`);
  assert.deepEqual(problems, []);
  await context.close();
});

test('a big file streams with a progress bar and can be cancelled', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/logs');
  const longestTask = await watchLongTasks(page);
  // About 60 MB of a 10 kHz log.
  const rows = [];
  for (let i = 0; i < 20_000; i++) rows.push(`${(i / 1e4).toFixed(4)},${(10 * Math.sin(i / 7)).toFixed(5)},${(1000 + (i % 13)).toFixed(2)}`);
  const block = rows.join('\n') + '\n';
  const dir = await mkdtemp(join(tmpdir(), 'cutlab-logs-'));
  const file = join(dir, 'big.csv');
  await writeFile(file, 'time [s],S_I [A],S_speed [rpm]\n' + block.repeat(90));
  await page.getByLabel('Open log files').setInputFiles(file);
  const progress = page.getByRole('progressbar', { name: 'Loading big.csv' });
  await progress.waitFor({ timeout: TIMEOUT });
  await page.getByRole('button', { name: 'Cancel loading' }).click();
  await page.getByRole('status').filter({ hasText: 'Cancelled: big.csv was not loaded.' }).waitFor({ timeout: TIMEOUT });
  assert.equal(await page.getByLabel('Analyse big.csv').count(), 0);
  await rm(dir, { recursive: true });
  const longest = await longestTask();
  assert.ok(longest < 100, `the page froze for ${longest} ms`);
  assert.deepEqual(problems, []);
  await context.close();
});
