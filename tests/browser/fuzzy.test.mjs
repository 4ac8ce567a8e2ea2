// The Fuzzy rules page: edit the table, see the surface change, inspect firing rules, FLL in and out.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFile } from 'node:fs/promises';
import { useLab, server, browser, openLab, canvasPixels, waitForRedraw, screenshot } from './harness.mjs';

useLab();

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

test('"Open in Compare" runs the edited table beside paper 002\'s own', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/fuzzy', { width: 1440, height: 900 });
  await page.getByRole('button', { name: 'Dynamics-based (paper 002, Table 4)' }).click();
  const cell = page.getByLabel('Output when E is PB and EC is PB');
  await cell.selectOption('NB');
  await page.getByRole('link', { name: 'Open in Compare' }).click();
  await page.getByRole('heading', { level: 1, name: /Compare/ }).waitFor();
  assert.match(page.url(), /b\.rules=\d{48}0/);
  const variantA = page.getByRole('group', { name: 'Variant A' });
  const variantB = page.getByRole('group', { name: 'Variant B' });
  for (const variant of [variantA, variantB]) {
    assert.equal(await variant.getByLabel('Controller', { exact: true }).inputValue(), 'fuzzy-dynamics');
  }
  await variantB.getByText('Using the rule table edited on the Fuzzy rules page.').waitFor();
  assert.equal(await variantA.getByText('Using the rule table edited on the Fuzzy rules page.').count(), 0);
  const table = page.getByRole('table', { name: /Metrics of the runs/ });
  // Named by the table it runs, not only by its controller, which A shares.
  await table.getByRole('columnheader', { name: 'B: fuzzy-dynamics (edited table)', exact: true }).waitFor({ timeout: 120_000 });
  await table.getByRole('columnheader', { name: 'A: fuzzy-dynamics', exact: true }).waitFor();
  assert.deepEqual(problems, []);
  await context.close();
});

test('the defuzzifier chosen is the one Simulate and Compare run, and the run is named by it', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/fuzzy', { width: 1440, height: 900 });
  await page.getByRole('button', { name: 'Dynamics-based (paper 002, Table 4)' }).click();
  await page.getByLabel('Defuzzifier', { exact: true }).selectOption('Centroid');
  await page.getByText(/with Centroid \(exact\) the table runs as the engine "paper002_dynamics_Centroid"/).waitFor();
  // Simulate runs the table and the defuzzifier as one engine, named after both.
  await page.getByRole('link', { name: 'Simulate with this table' }).click();
  await page.getByRole('heading', { level: 1, name: /Simulate/ }).waitFor();
  assert.equal(await page.getByLabel('Controller', { exact: true }).inputValue(), 'fuzzy-engine');
  await page.getByText(/^Engine "paper002_dynamics_Centroid": E = /).waitFor();
  assert.match(page.url(), /defuzzifier\*_Centroid/);
  const simulated = page.getByRole('table', { name: /Metrics of the run/ });
  await page.getByRole('status').filter({ hasText: 'Running' }).waitFor({ state: 'detached', timeout: RUN_TIMEOUT });
  assert.match(await simulated.getByRole('row', { name: /Cycle time/ }).textContent(), /\d/);
  // Back by the menu; an edited table with the same defuzzifier, in Compare beside paper 002's
  // own: the column names the engine it runs.
  await page.getByRole('navigation', { name: 'Lab sections' }).getByRole('link', { name: 'Fuzzy rules' }).click();
  assert.equal(await page.getByLabel('Defuzzifier', { exact: true }).inputValue(), 'Centroid');
  await page.getByLabel('Output when E is PB and EC is PB').selectOption('NB');
  await page.getByRole('link', { name: 'Open in Compare' }).click();
  await page.getByRole('heading', { level: 1, name: /Compare/ }).waitFor();
  const variantB = page.getByRole('group', { name: 'Variant B' });
  assert.equal(await variantB.getByLabel('Controller', { exact: true }).inputValue(), 'fuzzy-engine');
  await variantB.getByText(/^Engine "paper002_edited_Centroid": /).waitFor();
  const table = page.getByRole('table', { name: /Metrics of the runs/ });
  for (const name of ['A: fuzzy-dynamics', 'B: fuzzy-engine (paper002_edited_Centroid)']) {
    await table.getByRole('columnheader', { name, exact: true }).waitFor({ timeout: RUN_TIMEOUT });
  }
  // Paper 002's own defuzzifier again: the table runs on its own controller, as before.
  await page.goto(server.url + '#/fuzzy');
  await page.getByLabel('Defuzzifier', { exact: true }).selectOption('WeightedAverage');
  await page.getByRole('link', { name: 'Simulate with this table' }).click();
  assert.equal(await page.getByLabel('Controller', { exact: true }).inputValue(), 'fuzzy-dynamics');
  await page.getByText('Using the rule table edited on the Fuzzy rules page.').waitFor();
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
  // The force the table held, in newtons, against the target: not only E and EC scaled.
  await page.getByRole('img', { name: 'Force of the run' }).waitFor();
  for (const name of ['true force', 'target']) {
    await page.getByRole('button', { name, exact: true }).waitFor();
  }
  const drawn = await canvasPixels(trace);
  await slider.fill('150');
  await page.getByLabel(/Moment: \d+\.\d\d s/).waitFor();
  // The picked moment moves on the trace.
  await waitForRedraw(trace, drawn);
  assert.deepEqual(problems, []);
  await context.close();
});

// fuzzylite's example corpus, where Debian's fuzzylite package puts it: the files are LGPL/GPL,
// so the test reads them there and never copies them into the repository. linear_tip_calculator
// (Takagi–Sugeno) has two inputs and one output, and its tip rises with both inputs, as the feed
// should with E (a light cut) and EC (a cut getting lighter). The corpus's one Mamdani engine of
// that shape, investment_portfolio, lowers its output as its first input rises: as E it would
// push the feed the wrong way.
const CORPUS_ENGINE = '/usr/share/doc/fuzzylite/examples/takagi-sugeno/octave/linear_tip_calculator.fll';
const RUN_TIMEOUT = 120_000;

/** Waits until the chosen corpus file fills the engine's text field, then imports it. */
async function importChosenFile(page) {
  const text = await page.getByLabel('Engine text (FLL or FIS)').elementHandle();
  await page.waitForFunction((field) => field.value.startsWith('Engine: linear_tip_calculator'), text);
  await page.getByRole('button', { name: 'Import FLL or FIS' }).click();
}

test('an engine from fuzzylite\'s corpus is imported, shown whole, and runs in Simulate and beside paper 002\'s dynamics table in Compare', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/fuzzy', { width: 1440, height: 900 });
  await page.getByLabel('FLL or FIS file to import').setInputFiles(CORPUS_ENGINE);
  await importChosenFile(page);
  // Its variables, terms and rules, as a list: it is no 7×7 table.
  const rules = page.getByRole('list', { name: 'Rules', exact: true });
  await rules.waitFor();
  assert.equal(await rules.getByRole('listitem').count(), 4);
  assert.match(await rules.getByRole('listitem').first().textContent(), /^if FoodQuality is Bad and Service is Bad then Tip is TenPercent$/);
  const variables = await page.getByRole('list', { name: 'Variables and terms' }).textContent();
  for (const text of ['input FoodQuality on [1, 10]', 'input Service on [1, 10]', 'output Tip (WeightedAverage) on [10, 20]', 'TwentyPercent Linear']) {
    assert.ok(variables.includes(text), `${text} in ${variables}`);
  }
  await page.getByText(/Showing the imported engine "linear_tip_calculator"/).waitFor();
  // Its surface over the two inputs.
  await page.getByRole('img', { name: 'Control surface U(E, EC)' }).waitFor();

  // In Simulate, as the loop's controller (computed in a worker, as every Simulate run is).
  await page.getByRole('link', { name: 'Use in Simulate' }).click();
  assert.equal(await page.getByLabel('Controller', { exact: true }).inputValue(), 'fuzzy-engine');
  await page.getByText(/Engine "linear_tip_calculator": .* first input "FoodQuality" on \[1, 10\]/).waitFor();
  const simulated = page.getByRole('table', { name: /Metrics of the run/ });
  await simulated.getByRole('row', { name: /Cycle time/ }).getByRole('cell').first().waitFor({ timeout: RUN_TIMEOUT });
  await page.getByRole('status').filter({ hasText: 'Running' }).waitFor({ state: 'detached', timeout: RUN_TIMEOUT });
  assert.match(await simulated.getByRole('row', { name: /Cycle time/ }).textContent(), /\d/);
  assert.match(page.url(), /engine=Engine\*_linear!_tip!_calculator~/);

  // In Compare, beside paper 002's dynamics table: the table shows both with their metrics.
  await page.goto(server.url + '#/fuzzy');
  await page.getByRole('navigation', { name: 'Lab sections' }).waitFor();
  await page.getByLabel('FLL or FIS file to import').setInputFiles(CORPUS_ENGINE);
  await importChosenFile(page);
  await page.getByRole('link', { name: 'Use in Compare' }).click();
  const variantB = page.getByRole('group', { name: 'Variant B' });
  assert.equal(await variantB.getByLabel('Controller', { exact: true }).inputValue(), 'fuzzy-engine');
  await variantB.getByText(/second input "Service" on \[1, 10\]/).waitFor();
  const table = page.getByRole('table', { name: /Metrics of the runs/ });
  for (const name of ['A: fuzzy-dynamics', 'B: fuzzy-engine']) {
    await table.getByRole('columnheader', { name }).waitFor({ timeout: RUN_TIMEOUT });
  }
  await page.getByRole('status').filter({ hasText: 'Running' }).waitFor({ state: 'detached', timeout: RUN_TIMEOUT });
  const cycle = await table.getByRole('row', { name: /Cycle time/ }).getByRole('cell').allTextContents();
  assert.equal(cycle.filter((t) => /\d/.test(t)).length, 2, `cycle times ${cycle.join(' | ')}`);
  const error = await table.getByRole('row', { name: /Mean \|error\|/ }).first().getByRole('cell').allTextContents();
  assert.equal(error.filter((t) => /\d/.test(t)).length, 2, `force errors ${error.join(' | ')}`);
  // The two controllers are not the same law: their overrides differ.
  assert.notEqual(error[0], error[1]);
  assert.equal(await page.getByLabel('Preset', { exact: true }).inputValue(), 'liu-current-step');
  await screenshot(page, 'compare-fuzzy-engine');
  assert.deepEqual(problems, []);
  await context.close();
});

test('the rule base in use is pressed, and Compare names the experience table\'s variant by it', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/fuzzy', { width: 1440, height: 900 });
  const experience = page.getByRole('button', { name: 'Experience-based (MacVicar-Whelan)' });
  const dynamics = page.getByRole('button', { name: 'Dynamics-based (paper 002, Table 4)' });
  // The page opens on paper 002's own table.
  assert.equal(await dynamics.getAttribute('aria-pressed'), 'true');
  assert.equal(await experience.getAttribute('aria-pressed'), 'false');
  await experience.click();
  assert.equal(await experience.getAttribute('aria-pressed'), 'true');
  assert.equal(await dynamics.getAttribute('aria-pressed'), 'false');
  // Pressed looks pressed: filled, not the outline of the other.
  const fill = (b) => b.evaluate((el) => getComputedStyle(el).backgroundColor);
  assert.notEqual(await fill(experience), await fill(dynamics));
  // An edited table is neither base.
  const cell = page.getByLabel('Output when E is PB and EC is PB');
  await cell.selectOption('NB');
  assert.equal(await experience.getAttribute('aria-pressed'), 'false');
  await cell.selectOption('PB');
  assert.equal(await experience.getAttribute('aria-pressed'), 'true');
  await page.getByRole('link', { name: 'Open in Compare' }).click();
  await page.getByRole('heading', { level: 1, name: /Compare/ }).waitFor();
  const variantB = page.getByRole('group', { name: 'Variant B' });
  assert.equal(await variantB.getByLabel('Controller', { exact: true }).inputValue(), 'fuzzy-experience');
  const table = page.getByRole('table', { name: /Metrics of the runs/ });
  for (const name of ['A: fuzzy-dynamics', 'B: fuzzy-experience']) {
    await table.getByRole('columnheader', { name }).waitFor({ timeout: RUN_TIMEOUT });
  }
  assert.deepEqual(problems, []);
  await context.close();
});

test('an imported engine and the text typed survive a reload and a visit to Simulate; a refused FLL keeps the engine', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/fuzzy', { width: 1440, height: 900 });
  await page.getByLabel('FLL or FIS file to import').setInputFiles(CORPUS_ENGINE);
  await importChosenFile(page);
  await page.getByText(/Showing the imported engine "linear_tip_calculator"/).waitFor();
  // The table's own links run a table, which is not shown now.
  assert.equal(await page.getByRole('link', { name: 'Simulate with this table' }).isVisible(), false);
  assert.match(page.url(), /engine=Engine\*_linear!_tip!_calculator~/);
  // An FLL with no rules is refused, said so, and the engine studied stays.
  const text = page.getByLabel('Engine text (FLL or FIS)');
  const noRules = (await readFile(CORPUS_ENGINE, 'utf8')).split('\n').filter((l) => !/^\s*rule:/.test(l)).join('\n');
  await text.fill(noRules);
  await page.getByRole('button', { name: 'Import FLL or FIS' }).click();
  await page.getByText(/The FLL could not be read: .*without rules.*The engine studied is unchanged\./).waitFor();
  await page.getByText(/Showing the imported engine "linear_tip_calculator"/).waitFor();
  // Reload: the engine from the link, the typed text from the tab's storage.
  await page.reload();
  await page.getByText(/Showing the imported engine "linear_tip_calculator"/).waitFor();
  assert.equal(await page.getByLabel('Engine text (FLL or FIS)').inputValue(), noRules);
  // To Simulate and back by the menu (a bare link): the same engine.
  await page.getByRole('link', { name: 'Use in Simulate' }).click();
  assert.equal(await page.getByLabel('Controller', { exact: true }).inputValue(), 'fuzzy-engine');
  await page.getByRole('navigation', { name: 'Lab sections' }).getByRole('link', { name: 'Fuzzy rules' }).click();
  await page.getByText(/Showing the imported engine "linear_tip_calculator"/).waitFor();
  assert.match(page.url(), /engine=Engine\*_linear!_tip!_calculator~/);
  assert.deepEqual(problems, []);
  await context.close();
});
