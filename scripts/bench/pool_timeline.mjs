// When the page hands each job to a computation worker and when the worker answers, timed in the
// page from navigation start: which worker, which job, and what it asked (`runs` with how many
// calibrations it carries, so a teach cut made again shows; `references`, the savings' search).
//
//   node scripts/bench/pool_timeline.mjs '#/compare?preset=kim-circular-taper&variants=4' [--ms 4000]
//
// CUTLAB_DIST=<directory> serves another build than dist/. Prints one JSON line per message.
import { serveDist, launchBrowser } from '../../tests/browser/harness.mjs';

const hash = process.argv[2] ?? '#/compare?preset=kim-circular-taper&variants=4';
const watchMs = Number(process.argv[process.argv.indexOf('--ms') + 1]) || 4000;

/** Installed before the app loads: every request posted to a worker and every answer. */
function instrument() {
  window.cutlabPoolLog = [];
  const workerIds = new WeakMap();
  let workers = 0;
  const idOf = (worker) => {
    if (!workerIds.has(worker)) workerIds.set(worker, ++workers);
    return workerIds.get(worker);
  };
  const post = Worker.prototype.postMessage;
  Worker.prototype.postMessage = function (message, ...rest) {
    if (typeof message?.request === 'string') {
      const request = JSON.parse(message.request);
      const what = request.kind === 'runs' ? `runs, ${request.calibrations.length} calibrations` : request.kind;
      window.cutlabPoolLog.push({ ms: Math.round(performance.now()), worker: idOf(this), job: message.job, sent: what });
    }
    return post.call(this, message, ...rest);
  };
  const handler = Object.getOwnPropertyDescriptor(Worker.prototype, 'onmessage');
  Object.defineProperty(Worker.prototype, 'onmessage', {
    set(listener) {
      const worker = this;
      handler.set.call(this, (event) => {
        const kind = event.data?.kind;
        if (kind === 'done' || kind === 'failed') {
          window.cutlabPoolLog.push({ ms: Math.round(performance.now()), worker: idOf(worker), job: event.data.job, answered: kind });
        }
        return listener(event);
      });
    },
    get() { return handler.get.call(this); },
  });
}

const server = await serveDist(process.env.CUTLAB_DIST);
const browser = await launchBrowser();
try {
  const context = await browser.newContext({ viewport: { width: 1280, height: 900 } });
  await context.addInitScript(instrument);
  const page = await context.newPage();
  await page.goto(server.url + hash);
  await page.waitForTimeout(watchMs);
  for (const entry of await page.evaluate(() => window.cutlabPoolLog)) console.log(JSON.stringify(entry));
  await context.close();
} finally {
  await browser.close();
  await server.close();
}
