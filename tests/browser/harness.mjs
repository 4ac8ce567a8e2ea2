// Shared set-up for the browser tests: serves the release build in dist/ on a free loopback port,
// drives Debian's Chromium through playwright-core, and records every console error and uncaught
// exception so each test can fail on them.
import { before, after } from 'node:test';
import { createServer } from 'node:http';
import { gzipSync } from 'node:zlib';
import { readFile, mkdir } from 'node:fs/promises';
import { createRequire } from 'node:module';
import { execFileSync } from 'node:child_process';
import { existsSync } from 'node:fs';
import { extname, join, normalize, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
export const root = join(here, '..', '..');
const require = createRequire(join(root, 'scripts', 'node', 'package.json'));
const { chromium } = require('playwright-core');

const dist = join(root, 'dist');
export const artifacts = join(root, 'artifacts', 'browser');

const types = {
  '.html': 'text/html; charset=utf-8',
  '.js': 'text/javascript; charset=utf-8',
  '.wasm': 'application/wasm',
  '.css': 'text/css; charset=utf-8',
  '.svg': 'image/svg+xml',
  '.json': 'application/json',
  '.csv': 'text/csv; charset=utf-8',
  '.txt': 'text/plain; charset=utf-8',
  '.fll': 'text/plain; charset=utf-8',
};

/** The served build (`{ url, close }`) and the browser of the test file that called [useLab],
 * set before its first test. Exports are live bindings: a file imports them and reads them in
 * its tests. */
export let server;
export let browser;

/** Serves dist/ and launches Chromium before the calling test file's tests, and closes both
 * after them. Each test file runs in a process of its own, so each has its own. */
export function useLab() {
  before(async () => {
    server = await serveDist();
    browser = await launchBrowser();
  });
  after(async () => {
    await browser?.close();
    await server?.close();
  });
}

/** Serves dist/ (or another build's `directory`) on 127.0.0.1 at a free port; resolves to
 * { url, close }. Files go compressed to a browser that accepts it, as a web server hosting the lab
 * sends them (README, "Hosting the lab"; the modules are a fifth to a third of their size
 * compressed, which is what a throttled link's measurement must see): the release build's brotli
 * file (`name.br`, written by scripts/precompress.mjs), else gzip, made once on the first request
 * where the build has no `name.gz`. */
export async function serveDist(directory = dist) {
  const compressed = new Map();
  const encodings = [
    ['br', '.br', null],
    ['gzip', '.gz', (body) => gzipSync(body, { level: 9 })],
  ];
  const server = createServer(async (req, res) => {
    try {
      const path = decodeURIComponent(new URL(req.url, 'http://x').pathname);
      const file = normalize(join(directory, path.endsWith('/') ? path + 'index.html' : path));
      if (!file.startsWith(directory)) throw new Error('outside dist');
      const body = await readFile(file);
      const headers = { 'content-type': types[extname(file)] ?? 'application/octet-stream', vary: 'accept-encoding' };
      const accepted = (req.headers['accept-encoding'] ?? '').split(',').map((e) => e.trim().split(';')[0]);
      for (const [encoding, suffix, make] of encodings) {
        if (!accepted.includes(encoding)) continue;
        const key = file + suffix;
        if (!compressed.has(key)) {
          compressed.set(key, await readFile(key).catch(() => (make ? make(body) : null)));
        }
        const sent = compressed.get(key);
        if (sent === null) continue;
        headers['content-encoding'] = encoding;
        res.writeHead(200, headers);
        res.end(sent);
        return;
      }
      res.writeHead(200, headers);
      res.end(body);
    } catch {
      res.writeHead(404, { 'content-type': 'text/plain' });
      res.end('not found');
    }
  });
  await new Promise((resolve) => server.listen(0, '127.0.0.1', resolve));
  const { port } = server.address();
  return { url: `http://127.0.0.1:${port}/`, close: () => new Promise((r) => server.close(r)) };
}

/** Launches headless Chromium with the flags this closed network needs. */
export async function launchBrowser() {
  return chromium.launch({
    executablePath: '/usr/bin/chromium',
    args: [
      '--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
      '--disable-background-networking', '--disable-component-update', '--disable-sync',
    ],
  });
}

/**
 * Opens the lab at `hash` in a fresh page of `browser` (a high-DPI screen with
 * `deviceScaleFactor` 2); returns { page, problems, context }, where
 * `problems` collects console errors and uncaught exceptions for the test to assert empty.
 */
export async function openLab(browser, baseUrl, hash = '', viewport = { width: 1280, height: 720 }, deviceScaleFactor = 1) {
  const context = await browser.newContext({ viewport, deviceScaleFactor });
  const page = await context.newPage();
  const problems = [];
  page.on('console', (msg) => {
    if (msg.type() === 'error') problems.push(`console error: ${msg.text()}`);
  });
  page.on('pageerror', (err) => problems.push(`uncaught exception: ${err.message}`));
  await page.goto(baseUrl + hash);
  // The app is mounted once the navigation landmark exists.
  await page.getByRole('navigation', { name: 'Lab sections' }).waitFor();
  return { page, problems, context };
}

/** What the stand-in for a worker with a bug throws. */
export const WORKER_BUG = 'worker bug for the test';

/**
 * Opens the lab at `hash` in a fresh page whose first computation worker is a stand-in that
 * reports ready and throws on its first request (a bug in the worker); the workers after it load
 * the real module. The browser reports one core, so the pool has one worker and the first request
 * is the stand-in's (with two, started as the page loads, either could be asked first). Returns
 * { page, problems, context, served }: `problems` as [openLab]'s but for the stand-in's own error,
 * `served()` how many worker scripts were served.
 */
export async function openLabWithThrowingWorker(browser, baseUrl, hash) {
  const context = await browser.newContext({ viewport: { width: 1280, height: 720 } });
  await context.addInitScript(() => {
    Object.defineProperty(Navigator.prototype, 'hardwareConcurrency', { get: () => 1 });
  });
  let served = 0;
  await context.route(/cutlab-worker\.js$/, (route) => {
    served += 1;
    if (served > 1) return route.continue();
    return route.fulfill({
      contentType: 'text/javascript',
      body: `var wasm_bindgen = function () { self.onmessage = function () { throw new Error('${WORKER_BUG}'); }; self.postMessage({ kind: 'ready' }); };`,
    });
  });
  const page = await context.newPage();
  const problems = [];
  page.on('console', (msg) => {
    if (msg.type() === 'error' && !msg.text().includes(WORKER_BUG)) problems.push(msg.text());
  });
  page.on('pageerror', (err) => problems.push(err.message));
  await page.goto(baseUrl + hash);
  return { page, problems, context, served: () => served };
}

/** The canvas's pixels as a data URL, to detect a redraw. */
export async function canvasPixels(locator) {
  return locator.evaluate((canvas) => canvas.toDataURL());
}

/** Waits until the canvas shows something other than `before` (no fixed sleeps). */
export async function waitForRedraw(locator, before, timeout = 10_000) {
  const handle = await locator.elementHandle();
  await locator.page().waitForFunction(
    ([canvas, old]) => canvas.toDataURL() !== old,
    [handle, before],
    { timeout },
  );
}

/**
 * Starts recording the page's long tasks (main-thread work over 50 ms, as the browser itself
 * measures them); the returned function gives the longest so far, in ms (0 if none).
 */
export async function watchLongTasks(page) {
  await page.evaluate(() => {
    window.cutlabLongTasks = [];
    new PerformanceObserver((list) => {
      for (const entry of list.getEntries()) window.cutlabLongTasks.push(entry.duration);
    }).observe({ type: 'longtask' });
  });
  return async () => Math.max(0, ...(await page.evaluate(() => window.cutlabLongTasks)));
}

/** Saves a screenshot under artifacts/browser/ (git-ignored). */
export async function screenshot(page, name) {
  await mkdir(artifacts, { recursive: true });
  await page.screenshot({ path: join(artifacts, `${name}.png`), fullPage: true });
}

/** The native `cutlab` CLI the tests compare the browser with: the one `cargo test --features
 * cli,charts` builds (scripts/test's native step, before the browser tests), built here if missing. */
export function nativeCli() {
  const cutlab = join(root, 'target', 'debug', 'cutlab');
  if (!existsSync(cutlab)) {
    execFileSync('cargo', ['build', '--features', 'cli', '--bin', 'cutlab'], { cwd: root, stdio: 'inherit' });
  }
  return cutlab;
}

/**
 * Runs axe-core (scripts/node's pinned copy) on the page as it is now; resolves to its
 * violations, each as one line: rule, impact, help and the first few offending elements.
 */
export async function axeViolations(page) {
  if (!(await page.evaluate(() => Boolean(window.axe)))) {
    await page.addScriptTag({ path: require.resolve('axe-core/axe.min.js') });
  }
  const violations = await page.evaluate(async () => {
    const result = await window.axe.run(document);
    return result.violations.map((v) => ({
      id: v.id,
      impact: v.impact,
      help: v.help,
      targets: v.nodes.slice(0, 5).map((n) => n.target.join(' ')),
    }));
  });
  return violations.map((v) => `${v.id} (${v.impact}): ${v.help} — ${v.targets.join(', ')}`);
}

/** How wide the document is against the viewport, in CSS px: { scrollWidth, viewportWidth }. */
export async function documentWidth(page) {
  return page.evaluate(() => ({
    scrollWidth: document.scrollingElement.scrollWidth,
    viewportWidth: window.innerWidth,
  }));
}
