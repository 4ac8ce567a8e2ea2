// Lessons: a lesson opened by its link puts its panel beside the real lab page; a student answers
// a question, then does a step on the Simulate page (edits a field by its label, the page runs)
// and sees the check turn from unmet to met with the measured value; the progress survives a
// reload and shows on the Lessons page; on the Logs page a replay the student starts is checked
// the same way.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { useLab, server, browser, openLab, screenshot } from './harness.mjs';

useLab();

const RUN_TIMEOUT = 90_000;
const TITLE = 'The entry into a cut, and the safety envelope';

test('a lesson opened by its link checks a run as it finishes and keeps the progress', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/lessons/entry-and-envelope');
  // The link opens the step's own page, with the lesson beside it.
  const panel = page.getByRole('complementary', { name: TITLE });
  await panel.waitFor();
  await page.getByRole('heading', { level: 1, name: /Simulate/ }).waitFor();
  assert.match(page.url(), /#\/simulate\?preset=maneerat-doc-2&/);
  await panel.getByRole('heading', { name: /^Step 1 of 2/ }).waitFor();

  // Hints open one at a time.
  const hint = panel.getByRole('button', { name: /^Show a hint/ });
  await hint.click();
  assert.equal(await panel.getByRole('listitem').count(), 1);
  assert.equal(await hint.textContent(), 'Show a hint (1 of 2 shown)');

  // A wrong answer is said to be wrong; the right one marks the step done.
  await panel.getByLabel(/^Nothing: it only logs/).check();
  await panel.getByRole('button', { name: 'Check my answer' }).click();
  await panel.getByText(/^Not this one/).waitFor();
  await panel.getByLabel(/^Clamp it between/).check();
  await panel.getByRole('button', { name: 'Check my answer' }).click();
  await panel.getByText('Right.').waitFor();
  await panel.getByRole('status').filter({ hasText: /^Step done\./ }).waitFor();

  // Step 2 sets up its own run: the tool enters each cut at 150 %.
  await panel.getByRole('button', { name: 'Next step' }).click();
  await panel.getByRole('heading', { name: /^Step 2 of 2: Enter gently/ }).waitFor();
  await page.waitForURL(/entry_override=150/);
  const checks = panel.getByRole('list', { name: 'Check of your run' });
  const aboveLimit = checks.getByRole('listitem').filter({ hasText: 'time above limit at most 0 s' });
  await aboveLimit.filter({ hasText: /^Not met: / }).waitFor({ timeout: RUN_TIMEOUT });
  assert.match(await aboveLimit.textContent(), /— measured [1-9][\d.]* s$/);
  assert.equal(await panel.getByRole('status').count(), 0);

  // The student lowers the entry override by its label; the page runs again and the check turns.
  const entry = page.getByRole('textbox', { name: /^Entry override/ });
  assert.equal(await entry.inputValue(), '150');
  await entry.fill('60');
  await aboveLimit.filter({ hasText: /^Met: / }).waitFor({ timeout: RUN_TIMEOUT });
  assert.match(await aboveLimit.textContent(), /^Met: time above limit at most 0 s — measured 0 s$/);
  await panel.getByRole('status').filter({ hasText: /^Step done\./ }).waitFor();
  await screenshot(page, 'lessons-panel');

  // A reload finds the lesson open at the same step, done, and the Lessons page counts it.
  await page.reload();
  const reloaded = page.getByRole('complementary', { name: TITLE });
  await reloaded.getByRole('heading', { name: /^Step 2 of 2/ }).waitFor();
  await reloaded.getByRole('status').filter({ hasText: /^Step done\./ }).waitFor();
  // The student raises the entry override again: the step stays done in the progress, but the
  // panel does not say "Step done" under a check the run shown fails.
  await page.getByRole('textbox', { name: /^Entry override/ }).fill('150');
  await aboveLimit.filter({ hasText: /^Not met: / }).waitFor({ timeout: RUN_TIMEOUT });
  await reloaded.getByRole('status')
    .filter({ hasText: /^You met this step earlier; the run now shown does not meet it\.$/ }).waitFor();
  assert.equal(await reloaded.getByText(/Step done/).count(), 0);
  await page.getByRole('navigation', { name: 'Lab sections' }).getByRole('link', { name: 'Lessons' }).click();
  const card = page.getByRole('listitem').filter({ has: page.getByRole('heading', { name: TITLE }) });
  await card.getByText('2 of 2 steps done').waitFor();
  assert.equal(await card.getByRole('progressbar').getAttribute('value'), '2');
  // Closing the lesson takes the panel away.
  await reloaded.getByRole('button', { name: 'Close the lesson' }).click();
  await reloaded.waitFor({ state: 'detached' });
  assert.deepEqual(problems, []);
  await context.close();
});

test('the own-log lesson checks a replay the student starts on the sample export', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/lessons/own-log', { width: 1440, height: 1000 });
  const panel = page.getByRole('complementary', { name: 'Your own machine\'s log' });
  await panel.getByRole('heading', { name: /^Step 1 of 4/ }).waitFor();
  for (let step = 2; step <= 4; step += 1) {
    await panel.getByRole('button', { name: 'Next step' }).click();
    await panel.getByRole('heading', { name: new RegExp(`^Step ${step} of 4`) }).waitFor();
  }
  // The step's link opens the sample export with the threshold loop's replay set up.
  await page.waitForURL(/#\/logs\?sample=synthetic-kim-step-doc-export\.csv/);
  await page.getByRole('status').filter({ hasText: 'Loaded synthetic-kim-step-doc-export.csv' }).waitFor({ timeout: RUN_TIMEOUT });
  await panel.getByText(/^Each replay you finish on the .* page is checked here\.$/).waitFor();
  assert.equal(await page.getByLabel('Replay Threshold-proportional').isChecked(), true);
  assert.equal(await page.getByLabel('Replay PI with anti-windup').isChecked(), false);
  assert.equal(await page.getByLabel(/^Target value/).inputValue(), '10.4');

  // The threshold loop alone: the PI's replay is not measured, so the check is not met.
  await page.getByRole('button', { name: 'Replay', exact: true }).click();
  const checks = panel.getByRole('list', { name: 'Check of your run' });
  const changes = checks.getByRole('listitem').filter({ hasText: 'override changes of the PI with anti-windup replay' });
  await changes.filter({
    hasText: /^Not met: .* — measured not measured: no PI with anti-windup replay was done \(tick it and replay\)$/,
  }).waitFor({ timeout: RUN_TIMEOUT });

  // The student ticks the PI controller by its label and replays: the check turns, with the counts.
  await page.getByLabel('Replay PI with anti-windup').check();
  await page.getByRole('button', { name: 'Replay', exact: true }).click();
  await changes.filter({ hasText: /^Met: / }).waitFor({ timeout: RUN_TIMEOUT });
  assert.match(await changes.textContent(),
    /^Met: override changes of the PI with anti-windup replay below that of the Threshold-proportional replay — measured \d+ vs \d+ for the Threshold-proportional replay$/);
  await panel.getByRole('status').filter({ hasText: /^Step done\./ }).waitFor();
  assert.deepEqual(problems, []);
  await context.close();
});

test('the log a student opens in own-log stays open through the next steps and a reload', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/lessons/own-log', { width: 1440, height: 1000 });
  const panel = page.getByRole('complementary', { name: 'Your own machine\'s log' });
  await panel.getByRole('heading', { name: /^Step 1 of 4/ }).waitFor();
  // Step 1 names the button the Logs page shows; the student presses it.
  const button = page.getByRole('button', { name: /^Synthetic CNC export: 60 ms RMS currents/ });
  const task = await panel.getByText(/^Open the sample export/).textContent();
  assert.ok(task.includes(`press "${await button.textContent()}"`), task);
  await button.click();
  const loaded = page.getByRole('status').filter({ hasText: 'Loaded synthetic-kim-step-doc-export.csv' });
  await loaded.waitFor({ timeout: RUN_TIMEOUT });
  // Step 2: the log is still open; the student analyses the spindle current grouped by phase.
  await panel.getByRole('button', { name: 'Next step' }).click();
  await panel.getByRole('heading', { name: /^Step 2 of 4/ }).waitFor();
  await page.getByRole('heading', { level: 1, name: /Machine logs/ }).waitFor();
  await loaded.waitFor();
  assert.match(page.url(), /#\/logs\?sample=synthetic-kim-step-doc-export\.csv/);
  await page.getByLabel('Column', { exact: true }).selectOption({ label: 'S_Strom [A]' });
  await page.getByLabel('Statistics per label of').selectOption({ label: 'Phase' });
  // (The address names the column and grouping where they differ from the page's own picks.)
  await page.waitForTimeout(500);
  // Step 3, "in the same analysis": the same address, column and grouping.
  const analysed = page.url();
  await panel.getByRole('button', { name: 'Next step' }).click();
  await panel.getByRole('heading', { name: /^Step 3 of 4/ }).waitFor();
  assert.equal(page.url(), analysed);
  await page.getByRole('table').getByText('Schnitt 5 mm').first().waitFor({ timeout: RUN_TIMEOUT });
  assert.equal(await page.getByLabel('Column', { exact: true }).inputValue(), 'S_Strom [A]');
  // A reload keeps it, and so does the lesson's own link.
  await page.reload();
  await page.getByRole('status').filter({ hasText: 'Loaded synthetic-kim-step-doc-export.csv' }).waitFor({ timeout: RUN_TIMEOUT });
  assert.equal(await page.getByLabel('Statistics per label of').inputValue(), 'Phase');
  await page.goto(`${server.url}#/lessons/own-log`);
  await page.waitForURL(/#\/logs\?sample=synthetic-kim-step-doc-export\.csv/);
  await page.getByRole('status').filter({ hasText: 'Loaded synthetic-kim-step-doc-export.csv' }).waitFor({ timeout: RUN_TIMEOUT });
  assert.deepEqual(problems, []);
  await context.close();
});

for (const viewport of [{ width: 390, height: 844 }, { width: 1024, height: 768 }]) {
  test(`at ${viewport.width} px the lesson stays in sight while the student edits the page`, async () => {
    const { page, problems, context } = await openLab(browser, server.url, '#/lessons/entry-and-envelope', viewport);
    const panel = page.getByRole('complementary', { name: TITLE });
    await panel.getByRole('heading', { name: /^Step 1 of 2/ }).waitFor();
    const inView = async () => {
      const box = await panel.boundingBox();
      return box.y >= 0 && box.y < viewport.height && box.y + box.height <= viewport.height + 1;
    };
    assert.equal(await inView(), true, 'panel in the window at the top of the page');
    // Far down the page, at a field the student edits, it is still there.
    const entry = page.getByRole('textbox', { name: /^Entry override/ });
    await entry.scrollIntoViewIfNeeded();
    await page.mouse.wheel(0, 3000);
    assert.equal(await inView(), true, 'panel in the window further down');
    const box = await panel.boundingBox();
    assert.ok(box.height <= viewport.height * 0.5, `the panel leaves the page room: ${box.height} px`);
    // Shrunk, it keeps the step, its task and its check, and grows back.
    const toggle = panel.getByRole('button', { name: 'Shrink the lesson' });
    await toggle.click();
    const grow = panel.getByRole('button', { name: 'Show the whole lesson' });
    assert.equal(await grow.getAttribute('aria-expanded'), 'false');
    await panel.getByRole('heading', { name: /^Step 1 of 2/ }).waitFor();
    assert.equal(await panel.getByText(/^The lab puts a safety envelope/).isVisible(), true);
    assert.equal(await panel.getByRole('button', { name: /^Show a hint/ }).isVisible(), false);
    assert.ok((await panel.boundingBox()).height < box.height);
    await grow.click();
    await panel.getByRole('button', { name: /^Show a hint/ }).waitFor();
    await screenshot(page, `lessons-panel-${viewport.width}`);
    assert.deepEqual(problems, []);
    await context.close();
  });
}

test('at 1280 px the docked lesson sits beside the page, clear of the navigation, and stays in sight', async () => {
  const viewport = { width: 1280, height: 800 };
  const { page, problems, context } = await openLab(browser, server.url, '#/lessons/entry-and-envelope', viewport);
  const panel = page.getByRole('complementary', { name: TITLE });
  await panel.getByRole('heading', { name: /^Step 1 of 2/ }).waitFor();
  // Docked (not the narrow window's bar): its shrink toggle is hidden.
  assert.equal(await panel.getByRole('button', { name: 'Shrink the lesson' }).isVisible(), false);
  // At least 4 px from every pill of the navigation, and below the header it sits in.
  const clear = (a, b, gap) => a.x + a.width + gap <= b.x || b.x + b.width + gap <= a.x
    || a.y + a.height + gap <= b.y || b.y + b.height + gap <= a.y;
  const box = await panel.boundingBox();
  const pills = await page.getByRole('navigation', { name: 'Lab sections' }).getByRole('link').all();
  assert.ok(pills.length > 5);
  for (const pill of pills) {
    const p = await pill.boundingBox();
    assert.ok(clear(box, p, 4), `the panel ${JSON.stringify(box)} touches "${await pill.textContent()}" ${JSON.stringify(p)}`);
  }
  const header = await page.getByRole('banner').boundingBox();
  assert.ok(box.y >= header.y + header.height, `panel top ${box.y} inside the header (to ${header.y + header.height})`);
  assert.ok(box.y + box.height <= viewport.height, `at the top of the page the panel runs out of the window: ${JSON.stringify(box)}`);
  // Beside the page, not over it.
  const main = await page.getByRole('main').boundingBox();
  assert.ok(main.x + main.width <= box.x, `the page (to ${main.x + main.width}) runs under the panel (from ${box.x})`);
  // Far down the page, at a field the student edits, it is still in the window.
  await page.getByRole('textbox', { name: /^Entry override/ }).scrollIntoViewIfNeeded();
  await page.mouse.wheel(0, 3000);
  const scrolled = await panel.boundingBox();
  assert.ok(scrolled.y >= 0 && scrolled.y + scrolled.height <= viewport.height + 1, `scrolled: ${JSON.stringify(scrolled)}`);
  await screenshot(page, 'lessons-panel-1280');
  assert.deepEqual(problems, []);
  await context.close();
});

test('an unknown lesson is said so, and every control of the list is named', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/lessons/no-such-lesson');
  await page.getByRole('alert').filter({ hasText: /no lesson named .no-such-lesson./ }).waitFor();
  const links = page.getByRole('main').getByRole('listitem').getByRole('link');
  assert.equal(await links.count(), 10);
  for (const bar of await page.getByRole('progressbar').all()) {
    assert.match(await bar.getAttribute('aria-label'), /^Progress in /);
  }
  await page.getByRole('button', { name: 'Download progress (JSON)' }).waitFor();
  assert.deepEqual(problems, []);
  await context.close();
});
