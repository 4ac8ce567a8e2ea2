// Where an edit's time goes. Simulate on a preset; once the first run and its savings are done,
// K_p is edited and timed until the new run's first points are drawn (the first animation frame
// whose force chart differs) and until that run has finished.
//
//   trunk build --release --offline
//   # one build, traced: each main-thread and worker task from the edit on, with its messages
//   node scripts/bench/edit_trace.mjs [--preset maneerat-doc-2] [--min-ms 1] [--trace out.json]
//        [--dist DIR] [--samples]
//   # builds side by side, untraced, alternating (copy dist/ away between builds):
//   node scripts/bench/edit_trace.mjs --dists /tmp/ab/A,/tmp/ab/B --rounds 6 [--preset …]
import { writeFile } from 'node:fs/promises';
import { launchBrowser, serveDist } from '../../tests/browser/harness.mjs';

const arg = (name, fallback) => {
  const i = process.argv.indexOf(name);
  return i > 0 ? process.argv[i + 1] : fallback;
};
const preset = arg('--preset', 'maneerat-doc-2');
const minMs = Number(arg('--min-ms', 1));
const tracePath = arg('--trace', null);
const dists = arg('--dists', null)?.split(',');
const rounds = Number(arg('--rounds', 1));
const dist = arg('--dist', undefined);
// The sampling profiler's categories (build the module with names kept, as
// scripts/bench/browser_profile.mjs's header shows, and pass it as --dist).
const samples = process.argv.includes('--samples');
const BUSY = /Running|teach cut|closed loop|Searching/;

/** One fresh page of `baseUrl`: the edit's times, and the trace when `traced`. */
async function editRound(browser, baseUrl, traced) {
  const context = await browser.newContext({ viewport: { width: 1280, height: 900 } });
  const page = await context.newPage();
  await page.goto(`${baseUrl}#/simulate?preset=${preset}`);
  await page.getByRole('table').first().waitFor({ timeout: 60_000 });
  await page.waitForFunction((busy) => ![...document.querySelectorAll('[role=status]')]
    .some((e) => new RegExp(busy).test(e.textContent)), BUSY.source, { timeout: 60_000 });
  await page.waitForTimeout(1000);
  const field = page.getByLabel('K_p (% per %)');
  if (traced) await browser.startTracing(page, { categories: ['toplevel', 'devtools.timeline',
    'disabled-by-default-devtools.timeline', 'v8.execute', 'blink.user_timing', 'v8.wasm',
    ...(samples ? ['disabled-by-default-v8.cpu_profiler', 'disabled-by-default-v8.cpu_profiler.hires'] : [])] });
  const times = await field.evaluate((input, busy) => new Promise((resolve) => {
    const chart = document.querySelector('canvas[aria-label="Cutting force"]') ?? document.querySelector('canvas');
    const before = chart.toDataURL();
    const running = () => [...document.querySelectorAll('[role=status]')].some((e) => new RegExp(busy).test(e.textContent));
    performance.mark('edit');
    const started = performance.now();
    let firstDrawn = null;
    let seenRunning = false;
    const frame = () => requestAnimationFrame(() => {
      const now = performance.now();
      if (firstDrawn === null && chart.toDataURL() !== before) firstDrawn = now - started;
      if (running()) seenRunning = true;
      if (firstDrawn !== null && seenRunning && !running()) resolve({ firstDrawn, done: now - started });
      else frame();
    });
    input.value = input.value === '0.8' ? '0.7' : '0.8';
    input.dispatchEvent(new Event('input', { bubbles: true }));
    frame();
  }), BUSY.source);
  const trace = traced ? JSON.parse((await browser.stopTracing()).toString()) : null;
  await context.close();
  return { ...times, trace };
}

function printTasks(trace) {
  const events = trace.traceEvents ?? trace;
  const names = new Map();
  for (const e of events) if (e.ph === 'M' && e.name === 'thread_name') names.set(`${e.pid}:${e.tid}`, e.args.name);
  const thread = (e) => names.get(`${e.pid}:${e.tid}`) ?? '?';
  const t0 = events.find((e) => e.name === 'edit')?.ts ?? 0;
  const rel = (ts) => ((ts - t0) / 1000).toFixed(1).padStart(7);
  for (const e of events.filter((e) => e.ts >= t0 && /Main|Worker/.test(thread(e))).sort((a, b) => a.ts - b.ts)) {
    if (e.name === 'RunTask' && e.ph === 'X' && e.dur >= minMs * 1000) {
      console.log(`${rel(e.ts)} ms  task ${(e.dur / 1000).toFixed(1).padStart(6)} ms  ${thread(e)}`);
    } else if (/PostMessage|^EventDispatch$|FireAnimationFrame|^Paint$/.test(e.name) && e.ph === 'X') {
      console.log(`${rel(e.ts)} ms    ${e.name}${e.args?.data?.type ? ` (${e.args.data.type})` : ''} ${(e.dur / 1000).toFixed(1)} ms  ${thread(e)}`);
    }
  }
}

const browser = await launchBrowser();
try {
  if (dists) {
    const servers = await Promise.all(dists.map((d) => serveDist(d)));
    const results = dists.map(() => []);
    for (let r = 0; r < rounds; r++) {
      for (let i = 0; i < dists.length; i++) results[i].push(await editRound(browser, servers[i].url, false));
    }
    await Promise.all(servers.map((s) => s.close()));
    const median = (xs) => { const s = [...xs].sort((a, b) => a - b); return s[Math.floor(s.length / 2)]; };
    console.log(`| build (${preset}, ${rounds} alternating rounds) | edit → first points drawn, median (all) | edit → run done, median (all) |`);
    console.log('|---|---|---|');
    dists.forEach((d, i) => {
      const f = results[i].map((x) => x.firstDrawn);
      const done = results[i].map((x) => x.done);
      console.log(`| ${d} | ${median(f).toFixed(0)} ms (${f.map((x) => x.toFixed(0)).join(' ')}) | ${median(done).toFixed(0)} ms (${done.map((x) => x.toFixed(0)).join(' ')}) |`);
    });
  } else {
    const server = await serveDist(dist);
    const { firstDrawn, done, trace } = await editRound(browser, server.url, true);
    await server.close();
    console.log(`edit → first points drawn ${firstDrawn.toFixed(1)} ms, run done ${done.toFixed(1)} ms (traced)`);
    if (tracePath) await writeFile(tracePath, JSON.stringify(trace));
    printTasks(trace);
  }
} finally {
  await browser.close();
}
