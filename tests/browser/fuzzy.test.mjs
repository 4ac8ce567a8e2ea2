// The Fuzzy rules page: edit the table, see the surface change, inspect firing rules, FLL in and out.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { readFile } from 'node:fs/promises';
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

test('editing a rule cell changes the control surface and the link', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/fuzzy');
  await page.getByRole('button', { name: 'Experience-based (MacVicar-Whelan)' }).click();
  const surface = page.getByRole('img', { name: 'Control surface U(E, EC)' });
  await surface.waitFor();
  const cell = page.getByLabel('Output when E is PB and EC is PB');
  assert.equal(await cell.inputValue(), 'PB');
  const before = await canvasPixels(surface);
  await cell.selectOption('NB');
  await waitForRedraw(surface, before);
  assert.equal(await cell.inputValue(), 'NB');
  assert.match(page.url(), /rules=\d{48}0/);
  // Keyboard: the cells are native selects.
  await cell.focus();
  await page.keyboard.press('ArrowDown');
  assert.equal(await cell.inputValue(), 'NM');
  await screenshot(page, 'fuzzy');
  // The edited table goes to the Simulate page with the link.
  await page.getByRole('link', { name: 'Simulate with this table' }).click();
  await page.getByText('Using the rule table edited on the Fuzzy rules page.').waitFor();
  assert.equal(await page.getByLabel('Controller', { exact: true }).inputValue(), 'fuzzy-dynamics');
  assert.deepEqual(problems, []);
  await context.close();
});

test('the rule viewer lists the rules that fire for a chosen point', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/fuzzy');
  await page.getByRole('button', { name: 'Dynamics-based (paper 002, Table 4)' }).click();
  await page.getByLabel('E (scaled)', { exact: true }).fill('2');
  await page.getByLabel('EC (scaled)', { exact: true }).fill('-2');
  const firing = page.getByRole('list', { name: 'Firing rules' });
  await firing.getByText('if E is PS and EC is NS then U is ZO').waitFor();
  await page.getByRole('status').filter({ hasText: 'U = 0.000' }).waitFor();
  // Clicking the surface picks a point.
  const surface = page.getByRole('img', { name: 'Control surface U(E, EC)' });
  const box = await surface.boundingBox();
  await page.mouse.click(box.x + box.width * 0.8, box.y + box.height * 0.3);
  assert.notEqual(await page.getByLabel('E (scaled)', { exact: true }).inputValue(), '2');
  // By keyboard: focus the map, move the cursor two cells left and one down, pick with Enter.
  await surface.focus();
  await page.keyboard.press('Home');
  await page.getByText('Cursor: E = 0.00, EC = 0.00').waitFor();
  for (const key of ['ArrowLeft', 'ArrowLeft', 'ArrowDown']) await page.keyboard.press(key);
  const readout = await page.getByText(/^Cursor: E = /).textContent();
  const [, cursorE, cursorEc] = readout.match(/E = (-?[\d.]+), EC = (-?[\d.]+)/);
  assert.ok(Number(cursorE) < 0 && Number(cursorEc) < 0, readout);
  await page.keyboard.press('Enter');
  assert.equal(Number(await page.getByLabel('E (scaled)', { exact: true }).inputValue()), Number(cursorE));
  assert.equal(Number(await page.getByLabel('EC (scaled)', { exact: true }).inputValue()), Number(cursorEc));
  assert.deepEqual(problems, []);
  await context.close();
});

test('FLL exports, a broken FLL is explained by line, and a run supplies a moment', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/fuzzy');
  const [download] = await Promise.all([
    page.waitForEvent('download'),
    page.getByRole('button', { name: 'Export FLL' }).click(),
  ]);
  const fll = await readFile(await download.path(), 'utf8');
  assert.match(fll, /RuleBlock: rules/);
  const text = page.getByLabel('Engine text (FLL or FIS)');
  await text.fill(fll.replace('term: PB Triangle 4 6 6', 'term: PB Zigzag 4 6 6'));
  await page.getByRole('button', { name: 'Import FLL' }).click();
  await page.getByText(/The FLL could not be read: line \d+: term PB: shape Zigzag is not one of fuzzylite's terms/).waitFor();
  // A file that changes one rule changes that cell of the table.
  const cell = page.getByLabel('Output when E is NB and EC is NB');
  const before = await cell.inputValue();
  const changedTo = before === 'PB' ? 'NB' : 'PB';
  const ruleLine = fll.split('\n').find((l) => /rule: if E is NB and EC is NB then U is/.test(l));
  await text.fill(fll.replace(ruleLine, ruleLine.replace(/U is \w+/, `U is ${changedTo}`)));
  await page.getByRole('button', { name: 'Import FLL' }).click();
  await page.getByText(/could not be read/).waitFor({ state: 'detached' });
  assert.equal(await cell.inputValue(), changedTo);
  await text.fill(fll);
  await page.getByRole('button', { name: 'Import FLL' }).click();
  assert.equal(await cell.inputValue(), before);
  // A simulated run with this table; the slider picks a moment's E and EC.
  await page.getByLabel('Preset', { exact: true }).selectOption('maneerat-doc-1');
  await page.getByRole('button', { name: 'Run with this table' }).click();
  const slider = page.getByLabel(/Moment:/);
  await slider.waitFor({ timeout: 60_000 });
  const trace = page.getByRole('img', { name: 'E and EC of the run' });
  await trace.waitFor();
  const drawn = await canvasPixels(trace);
  await slider.fill('150');
  await page.getByLabel(/Moment: \d+\.\d\d s/).waitFor();
  // The picked moment moves on the trace.
  await waitForRedraw(trace, drawn);
  assert.deepEqual(problems, []);
  await context.close();
});
