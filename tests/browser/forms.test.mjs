// Forms show the values in use: a blank field's placeholder is what the run uses (the preset's),
// a unit is written once, the preset's full title is shown, every number field brings up a
// numeric keypad, and no message uses a command-line flag or Rust's range syntax.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { useLab, server, browser, openLab } from './harness.mjs';

useLab();

test('Simulate: blank fields show the preset\'s values, units once, the full title, numeric keypads', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/simulate?preset=kim-step-doc&controller=pi');
  const form = page.getByRole('form', { name: 'Run settings' });
  // Paper 003's DSP board: 0–255 %; its 2-flute Ø20 mm cutter at 1000 rpm.
  for (const [label, value] of [['Highest override', '255'], ['Spindle speed', '1000'], ['Tool diameter', '20'], ['Teeth', '2']]) {
    const field = form.getByLabel(label, { exact: false }).first();
    assert.equal(await field.inputValue(), '', `${label} is blank`);
    assert.equal(await field.getAttribute('placeholder'), value, `${label}'s placeholder`);
  }
  // A drop-down left at the preset's choice names the choice it stands for.
  const material = form.getByRole('combobox', { name: 'Work material' });
  assert.equal(await material.inputValue(), '');
  assert.equal(await material.locator('option:checked').textContent(), "The preset's: SM45C / AISI 1045 steel");
  const feedback = form.getByRole('combobox', { name: 'Force measured from' });
  assert.equal(await feedback.locator('option:checked').textContent(), "The preset's: Spindle current (paper 003)");
  const labels = await form.locator('label').allTextContents();
  assert.ok(labels.includes('Teeth'), `labels: ${labels.join(' | ')}`);
  for (const text of labels) assert.doesNotMatch(text, /\(teeth\)|× \(×\)/, text);
  await form.getByText(/^Depth steps 1→5 mm, SM45C · paper 003/).waitFor();
  const keypads = await form.locator('input[type="text"]').evaluateAll((inputs) => inputs.map((i) => i.getAttribute('inputmode')));
  assert.ok(keypads.length > 10);
  assert.deepEqual([...new Set(keypads)], ['decimal']);
  // A gain out of range: the range as a person reads it.
  await form.getByLabel('K_p (% per %)').fill('-5');
  const message = page.getByText(/^kp = -5 is outside/);
  await message.waitFor();
  assert.match(await message.textContent(), /^kp = -5 is outside 0–\d+ % per %$/);
  assert.doesNotMatch(await page.locator('main').textContent(), /\.\.=|--[a-z]/);
  assert.deepEqual(problems, []);
  await context.close();
});

test('a "paper 00x" mention opens that paper in the home page\'s reference list', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/learn');
  const mention = page.locator('main a', { hasText: /^paper 000$/i }).first();
  await mention.click();
  await page.getByRole('heading', { level: 1, name: /adaptive cutting-force control/ }).waitFor();
  assert.match(page.url(), /#\/home\/paper-000$/);
  const entry = page.locator('#paper-000');
  await page.waitForFunction(() => {
    const r = document.getElementById('paper-000')?.getBoundingClientRect();
    return r && r.top >= 0 && r.top < window.innerHeight;
  });
  assert.match(await entry.textContent(), /^Paper 000\./);
  assert.deepEqual(problems, []);
  await context.close();
});

test('Tune names each scenario by its title and rounds what it reports', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/tune');
  await page.getByRole('checkbox', { name: 'Depth steps 1→5 mm, SM45C (kim-step-doc)' }).waitFor();
  await page.getByRole('button', { name: 'What Depth steps 1→5 mm, SM45C means' }).click();
  await page.getByText('paper 003 (Kim, Kwon, Chu), Fig. 10').waitFor();
  assert.deepEqual(problems, []);
  await context.close();
});

test('a select\'s blank option names the preset\'s choice, also while another is chosen', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/simulate?preset=kim-step-doc&seed=1&feedback=feed&controller=pi');
  const form = page.getByRole('form', { name: 'Run settings' });
  const feedback = form.getByRole('combobox', { name: 'Force measured from' });
  assert.equal(await feedback.inputValue(), 'feed');
  assert.equal(await feedback.locator('option[value=""]').textContent(), "The preset's: Spindle current (paper 003)");
  assert.deepEqual(problems, []);
  await context.close();
});

test('a field\'s "?" is a small circle after its label, on every form', async () => {
  for (const hash of ['#/simulate?preset=kim-step-doc', '#/compare', '#/signal?preset=wang-10th-5hz', '#/plant?preset=kim-step-doc']) {
    const { page, problems, context } = await openLab(browser, server.url, hash);
    const toggles = page.locator('.field .help-toggle');
    await toggles.first().waitFor();
    const boxes = await toggles.evaluateAll((buttons) => buttons
      .filter((b) => b.offsetParent !== null)
      .map((b) => {
        const r = b.getBoundingClientRect();
        const label = b.parentElement.querySelector('label').getBoundingClientRect();
        return { width: r.width, height: r.height, afterLabel: r.top >= label.top - 1 };
      }));
    assert.ok(boxes.length > 0, hash);
    for (const box of boxes) {
      assert.ok(box.width < 2 * box.height && box.width < 40, `${hash}: ${JSON.stringify(box)}`);
      assert.ok(box.afterLabel, `${hash}: ${JSON.stringify(box)}`);
    }
    assert.deepEqual(problems, []);
    await context.close();
  }
});
