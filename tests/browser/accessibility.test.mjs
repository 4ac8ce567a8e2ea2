// Every page, as a keyboard, screen-reader or phone user meets it: axe-core finds no violation
// once the page shows its first results, and on a 390 px phone no page scrolls sideways.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { useLab, server, browser, openLab, axeViolations, documentWidth, screenshot } from './harness.mjs';

const LONG = 60_000;

useLab();

/** Every page of the navigation: its hash and what shows that its first results are in. */
const PAGES = [
  ['Home', '#/home', (page) => page.getByRole('list', { name: 'The force-control loop' }).waitFor()],
  ['Simulate', '#/simulate', (page) => page.getByRole('img', { name: 'Cutting force' }).waitFor({ timeout: LONG })],
  ['Compare', '#/compare', (page) => page.getByRole('table', { name: /Metrics of the runs/ }).getByRole('columnheader', { name: /^B: / }).waitFor({ timeout: LONG })],
  ['Tune', '#/tune', (page) => page.getByRole('button', { name: 'Teach-in' }).waitFor()],
  ['Hardware', '#/hardware', (page) => page.getByRole('heading', { level: 1, name: /^Hardware/ }).waitFor()],
  ['Logs', '#/logs', async (page) => {
    await page.getByRole('button', { name: /^Synthetic CNC export/ }).click();
    await page.getByRole('status').filter({ hasText: /^Loaded / }).waitFor({ timeout: LONG });
  }],
  ['Fuzzy rules', '#/fuzzy', (page) => page.getByRole('img', { name: 'Control surface U(E, EC)' }).waitFor({ timeout: LONG })],
  ['Machine', '#/plant', (page) => page.getByRole('img', { name: 'Cutting forces' }).waitFor({ timeout: LONG })],
  ['Signal chain', '#/signal', (page) => page.getByText(/\d second-order sections?/).first().waitFor({ timeout: LONG })],
  ['Learn', '#/learn', (page) => page.getByRole('heading', { level: 2 }).first().waitFor()],
  ['Lessons', '#/lessons', (page) => page.getByRole('progressbar').first().waitFor()],
];

/** Views that are no page of the navigation: a lesson open beside the lab page of its step. */
const VIEWS = [
  ['A lesson beside Simulate', '#/lessons/entry-and-envelope', async (page) => {
    await page.getByRole('complementary', { name: /safety envelope/ }).waitFor();
    await page.getByRole('img', { name: 'Cutting force' }).waitFor({ timeout: LONG });
  }],
];

test('the accessibility test covers every page of the navigation', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/home');
  const nav = page.getByRole('navigation', { name: 'Lab sections' }).getByRole('link');
  assert.deepEqual(await nav.allTextContents(), PAGES.map(([name]) => name));
  assert.deepEqual(problems, []);
  await context.close();
});

for (const [name, hash, ready] of [...PAGES, ...VIEWS]) {
  test(`${name}: axe-core finds no violation once the first results show`, async () => {
    const { page, problems, context } = await openLab(browser, server.url, hash, { width: 1280, height: 900 });
    await ready(page);
    const violations = await axeViolations(page);
    assert.deepEqual(violations, [], `${name} at 1280 px:\n${violations.join('\n')}`);
    assert.deepEqual(problems, []);
    await context.close();
  });

  test(`${name}: on a 390 px phone the page does not scroll sideways and axe-core finds nothing`, async () => {
    const { page, problems, context } = await openLab(browser, server.url, hash, { width: 390, height: 844 });
    await ready(page);
    const { scrollWidth, viewportWidth } = await documentWidth(page);
    if (scrollWidth > viewportWidth) await screenshot(page, `phone-${hash.slice(2)}`);
    assert.ok(scrollWidth <= viewportWidth, `${name} is ${scrollWidth} px wide in a ${viewportWidth} px viewport`);
    if (['Simulate', 'Compare'].includes(name)) {
      // The results (charts first) above the long form that made them.
      const [resultsTop, formTop] = await page.evaluate(() => [
        document.querySelector('.layout-two > .results').getBoundingClientRect().top,
        document.querySelector('.layout-two > form').getBoundingClientRect().top,
      ]);
      assert.ok(resultsTop < formTop, `${name}: results at ${resultsTop} px, the form at ${formTop} px`);
    }
    const violations = await axeViolations(page);
    assert.deepEqual(violations, [], `${name} at 390 px:\n${violations.join('\n')}`);
    assert.deepEqual(problems, []);
    await context.close();
  });
}

test('the skip link is the first tab stop and moves focus to the page', async () => {
  const { page, problems, context } = await openLab(browser, server.url, '#/simulate');
  await page.keyboard.press('Tab');
  const first = await page.evaluate(() => document.activeElement.textContent.trim());
  assert.equal(first, 'Skip to content');
  const hashBefore = await page.evaluate(() => location.hash);
  await page.keyboard.press('Enter');
  await page.waitForFunction(() => document.activeElement?.id === 'main');
  assert.equal(await page.evaluate(() => location.hash), hashBefore, 'the skip link keeps the page and its settings');
  assert.deepEqual(problems, []);
  await context.close();
});
