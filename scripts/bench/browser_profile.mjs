// What the browser lab's main-thread tasks are made of, from a Chromium trace of one first load:
// every task over --min-ms (default 30) with the trace events inside it and the CPU profile's
// samples inside it (self time per function, and the time under each of the app's own frames).
//
//   trunk build --release --offline
//   # The same module with its function names kept (Trunk's wasm-opt strips them):
//   rm -rf /tmp/named && cp -r dist /tmp/named && sed -i 's/ integrity="[^"]*"//g' /tmp/named/index.html
//   wasm-bindgen --target web --no-typescript --out-name cutlab-web --out-dir /tmp/wb \
//     target/wasm32-unknown-unknown/web-release/cutlab-web.wasm
//   wasm-opt --output=$(ls /tmp/named/*_bg.wasm) -Oz -g /tmp/wb/cutlab-web_bg.wasm
//   node scripts/bench/browser_profile.mjs --dist /tmp/named [--hash '#/compare?variants=4'] \
//        [--min-ms 30] [--top 25] [--trace out.json] [--no-samples] [--settle-ms 2000]
//
// The sampling profiler slows V8's compiles (it logs each compiled function), so its tasks run
// longer than without it; --no-samples times the tasks as they run unprofiled (trace events only).
//
// The page is loaded once, and the trace stops once the default run's metrics table shows its
// savings (every column of it on Compare), so the first tasks, the runs and the first draws are in.
import { writeFile } from 'node:fs/promises';
import { join, resolve } from 'node:path';
import { root, launchBrowser, serveDist } from '../../tests/browser/harness.mjs';

const arg = (name, fallback) => {
  const i = process.argv.indexOf(name);
  return i > 0 ? process.argv[i + 1] : fallback;
};
const dist = resolve(arg('--dist', join(root, 'dist')));
const hash = arg('--hash', '#/simulate');
const minMs = Number(arg('--min-ms', 30));
const top = Number(arg('--top', 25));
const tracePath = arg('--trace', null);
// Pages without a metrics table (Signal chain, Fuzzy rules, Hardware, …): trace until the network
// is idle and this many milliseconds more, instead of until the run's savings show.
const settleMs = process.argv.includes('--settle-ms') ? Number(arg('--settle-ms', 2000)) : null;
// Without the sampling profiler (whose code logging slows V8's compiles), the trace events alone
// time the tasks as they run without a profiler.
const sampling = !process.argv.includes('--no-samples');

const server = await serveDist(dist);
const url = `${server.url}${hash}`;

const categories = [
  'toplevel', 'devtools.timeline', 'disabled-by-default-devtools.timeline', 'v8', 'v8.execute',
  'v8.wasm', 'disabled-by-default-v8.wasm.detailed', 'blink.user_timing', 'loading',
  ...(sampling ? ['disabled-by-default-v8.cpu_profiler', 'disabled-by-default-v8.cpu_profiler.hires'] : []),
];
const browser = await launchBrowser();
let trace;
try {
  const context = await browser.newContext({ viewport: { width: 1280, height: 900 } });
  const page = await context.newPage();
  const problems = [];
  page.on('console', (m) => { if (m.type() === 'error') problems.push(m.text()); });
  page.on('pageerror', (e) => problems.push(e.message));
  await browser.startTracing(page, { categories });
  await page.goto(url);
  const columns = hash.includes('compare') ? Number(/variants=(\d)/.exec(hash)?.[1] ?? 2) : 1;
  if (settleMs !== null) {
    // A page without a metrics table: its load, then a fixed window for what it starts itself.
    await page.waitForLoadState('networkidle', { timeout: 120_000 });
    await page.waitForTimeout(settleMs);
  } else await page.waitForFunction((n) => {
    const rows = [...document.querySelectorAll('table.metrics tbody tr')].filter((r) => /Saving vs/.test(r.textContent));
    return rows.length === 2 && rows.every((r) => {
      const cells = [...r.querySelectorAll('td')];
      return cells.length === n && cells.every((c) => /\d/.test(c.textContent));
    });
  }, columns, { timeout: 120_000 });
  trace = JSON.parse((await browser.stopTracing()).toString());
  if (problems.length) console.error('console errors:', problems);
} finally {
  await browser.close();
  await server.close();
}
if (tracePath) await writeFile(tracePath, JSON.stringify(trace));

const events = trace.traceEvents ?? trace;
// The page's main thread: where the navigation to the lab started.
const start = events.find((e) => e.name === 'navigationStart' && e.args?.data?.documentLoaderURL?.startsWith(url.split('#')[0]));
if (!start) throw new Error('no navigation to the lab in the trace');
const main = { pid: start.pid, tid: start.tid };
const onMain = events.filter((e) => e.pid === main.pid && e.tid === main.tid);
const nav = start.ts;
const ms = (us) => (us / 1000).toFixed(1);

// The CPU profile: nodes and samples from the Profile/ProfileChunk events of the main thread's
// isolate (the chunks may sit on a profiler thread of the same process).
const nodes = new Map();
const samples = [];
for (const e of events.filter((e) => e.pid === main.pid && (e.name === 'Profile' || e.name === 'ProfileChunk'))) {
  const d = e.args?.data ?? {};
  if (e.name === 'Profile') { samples.clock = d.startTime; continue; }
  const p = d.cpuProfile ?? {};
  for (const n of p.nodes ?? []) nodes.set(n.id, n);
  let t = samples.length ? samples[samples.length - 1].ts : samples.clock;
  (p.samples ?? []).forEach((id, i) => {
    t += d.timeDeltas?.[i] ?? 0;
    samples.push({ id, ts: t });
  });
}
const nameOf = (n) => {
  const f = n.callFrame ?? {};
  const name = f.functionName || `(${f.url ? f.url.split('/').pop() : 'anonymous'})`;
  return name.length > 110 ? name.slice(0, 107) + '…' : name;
};
const stackOf = (id) => {
  const out = [];
  for (let n = nodes.get(id); n; n = nodes.get(n.parent)) out.push(nameOf(n));
  return out; // leaf first
};

// Tasks: the outermost task events (Chromium nests a RunTask and a ThreadControllerImpl::RunTask).
const isTask = (e) => e.ph === 'X' && (e.name === 'RunTask' || e.name === 'ThreadControllerImpl::RunTask');
const allTasks = onMain.filter(isTask).sort((a, b) => a.ts - b.ts || b.dur - a.dur);
const outer = [];
for (const e of allTasks) {
  const last = outer[outer.length - 1];
  if (!last || e.ts >= last.ts + last.dur) outer.push(e);
}
const tasks = outer.filter((e) => e.dur >= minMs * 1000);
console.log(`${url}: ${tasks.length} main-thread tasks ≥ ${minMs} ms (CPU samples: ${samples.length})`);
for (const task of tasks) {
  const end = task.ts + task.dur;
  console.log(`\n## task at ${ms(task.ts - nav)} ms after navigation start: ${ms(task.dur)} ms`);
  const inside = onMain.filter((e) => e.ph === 'X' && e !== task && e.ts >= task.ts && e.ts < end);
  const byName = new Map();
  for (const e of inside) byName.set(e.name, (byName.get(e.name) ?? 0) + (e.dur ?? 0));
  console.log('trace events inside (inclusive, nested ones counted in each):');
  for (const [name, dur] of [...byName].sort((a, b) => b[1] - a[1]).slice(0, 12)) console.log(`  ${ms(dur).padStart(7)} ms  ${name}`);
  const within = samples.filter((s) => s.ts >= task.ts && s.ts < end);
  const dt = within.length > 1 ? (within[within.length - 1].ts - within[0].ts) / (within.length - 1) : 0;
  const self = new Map();
  const total = new Map();
  for (const s of within) {
    const stack = stackOf(s.id);
    self.set(stack[0], (self.get(stack[0]) ?? 0) + dt);
    for (const f of new Set(stack)) total.set(f, (total.get(f) ?? 0) + dt);
  }
  console.log(`CPU samples inside: ${within.length} (every ${(dt / 1000).toFixed(2)} ms); self time:`);
  for (const [f, t] of [...self].sort((a, b) => b[1] - a[1]).slice(0, top)) console.log(`  ${ms(t).padStart(7)} ms  ${f}`);
  console.log("total time (self and callees) of the app's own functions:");
  for (const [f, t] of [...total].filter(([f]) => /cutlab/.test(f)).sort((a, b) => b[1] - a[1]).slice(0, top)) console.log(`  ${ms(t).padStart(7)} ms  ${f}`);
}
