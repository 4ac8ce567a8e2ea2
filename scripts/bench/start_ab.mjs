// Two or more builds of the lab side by side, on a fresh page each, alternating round by round:
// when the page hands its first job to a worker, when that job is done, when the charts first
// draw and when the metrics show (Simulate; on Compare, until every worker is idle with the
// metrics shown), from navigation start; and the page's longest main-thread task until then. For an A/B of a change to
// how the page or its workers start, where a single build's numbers vary more than the change.
//
//   node scripts/bench/start_ab.mjs DIST_A,DIST_B[,…] ['#/simulate?preset=maneerat-doc-2'] [--rounds 6] [--throttle]
//
// Each DIST is a `trunk build --release` output directory (copy dist/ away between builds).
// --throttle: Chromium's 10 Mbit/s, 20 ms latency, cache disabled (as workers.mjs's throttled
// case). Each build is opened once first, unmeasured; then the medians of the rounds are printed
// per build, with every round's time to the metrics.
import { serveDist, launchBrowser } from '../../tests/browser/harness.mjs';

const args = process.argv.slice(2);
const option = (name) => args.indexOf(name);
const rounds = option('--rounds') >= 0 ? Number(args[option('--rounds') + 1]) : 6;
const throttle = option('--throttle') >= 0;
const positional = args.filter((a, i) => !a.startsWith('--') && !(i > 0 && args[i - 1] === '--rounds'));
const dists = (positional[0] ?? '').split(',').filter(Boolean);
const hash = positional[1] ?? '#/simulate?preset=maneerat-doc-2';
if (dists.length === 0) {
  console.error('start_ab: give the build directories, comma-separated');
  process.exit(2);
}

/** Installed before the app loads: the moments above, in the page's clock. */
function instrument() {
  window.cutlabStart = {};
  window.cutlabLongest = 0;
  new PerformanceObserver((list) => {
    for (const e of list.getEntries()) window.cutlabLongest = Math.max(window.cutlabLongest, e.duration);
  }).observe({ type: 'longtask', buffered: true });
  const at = (what) => { window.cutlabStart[what] ??= performance.now(); };
  const post = Worker.prototype.postMessage;
  Worker.prototype.postMessage = function (message, ...rest) {
    if (typeof message?.request === 'string' || typeof message?.log_job === 'string') at('posted');
    return post.call(this, message, ...rest);
  };
  const handler = Object.getOwnPropertyDescriptor(Worker.prototype, 'onmessage');
  Object.defineProperty(Worker.prototype, 'onmessage', {
    set(listener) {
      handler.set.call(this, (event) => {
        if (event.data?.kind === 'done') at('done');
        return listener(event);
      });
    },
    get() { return handler.get.call(this); },
  });
  new MutationObserver(() => {
    if (Number(document.querySelector('[data-trace-rows]')?.dataset.traceRows ?? 0) > 0) at('drawn');
    for (const row of document.querySelectorAll('table.metrics tbody tr')) {
      if (/Cycle time/.test(row.textContent) && /\d/.test(row.querySelector('td')?.textContent ?? '')) at('metrics');
    }
  }).observe(document, { subtree: true, childList: true, characterData: true, attributes: true });
}

const servers = [];
for (const dist of dists) servers.push(await serveDist(dist));
const browser = await launchBrowser();

async function once(server) {
  const context = await browser.newContext({ viewport: { width: 1280, height: 900 } });
  await context.addInitScript(instrument);
  const page = await context.newPage();
  if (throttle) {
    const cdp = await context.newCDPSession(page);
    await cdp.send('Network.enable');
    await cdp.send('Network.setCacheDisabled', { cacheDisabled: true });
    await cdp.send('Network.emulateNetworkConditions', { offline: false, latency: 20, downloadThroughput: 10e6 / 8, uploadThroughput: 10e6 / 8 });
  }
  await page.goto(server.url + hash);
  const done = hash.startsWith('#/compare')
    ? () => document.documentElement.dataset.busyWorkers === '0' && document.querySelectorAll('table.metrics tbody tr').length > 0
    : () => window.cutlabStart.metrics !== undefined;
  await page.waitForFunction(done, null, { timeout: 60_000 });
  const times = await page.evaluate(() => ({ ...window.cutlabStart, longest: window.cutlabLongest }));
  await context.close();
  return times;
}

try {
  const results = dists.map(() => []);
  for (const server of servers) await once(server);
  for (let round = 0; round < rounds; round += 1) {
    for (let i = 0; i < servers.length; i += 1) results[i].push(await once(servers[i]));
  }
  const median = (values) => {
    const sorted = values.filter(Number.isFinite).sort((a, b) => a - b);
    return sorted.length ? Math.round(sorted[Math.floor(sorted.length / 2)]) : NaN;
  };
  console.log(`${hash}${throttle ? ', throttled' : ''}, ${rounds} rounds, medians in ms from navigation start`);
  console.log('| build | first job posted | its answer | first chart points | metrics | longest task | metrics, every round |');
  console.log('|---|---:|---:|---:|---:|---:|---|');
  dists.forEach((dist, i) => {
    const m = (key) => median(results[i].map((r) => r[key]));
    const all = results[i].map((r) => Math.round(r.metrics)).join(', ');
    console.log(`| ${dist} | ${m('posted')} | ${m('done')} | ${m('drawn')} | ${m('metrics')} | ${m('longest')} | ${all} |`);
  });
} finally {
  await browser.close();
  for (const server of servers) await server.close();
}
