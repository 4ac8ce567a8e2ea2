// The Hardware page: a fake WebSerial port bridged through this process to a real
// `cutlab device --stdio` (connect, handshake, teach cut, arm, commands and acknowledgements,
// unplug, the device's fallback, recordings after a reload, export read back by the core's log
// reader); the virtual device with injected faults (counters, both watchdogs, a reload mid-run);
// and a browser without WebSerial, where the virtual device runs in a worker of its own.
//
// The device binary is the one `cargo test --features cli,charts` builds (scripts/test's native
// step, before the browser tests); if it is missing, it is built here.
import { test, before } from 'node:test';
import assert from 'node:assert/strict';
import { spawn, execFileSync } from 'node:child_process';
import { readFile, writeFile, mkdir } from 'node:fs/promises';
import { join } from 'node:path';
import { useLab, server, browser, artifacts, screenshot, watchLongTasks, nativeCli } from './harness.mjs';

let cutlab;
before(() => {
  cutlab = nativeCli();
});
useLab();

const LONG = 60_000;

/**
 * A fresh context whose pages run `init` before the app, open at `hash`; returns
 * { page, problems, context } like harness.openLab.
 */
async function openWith(hash, init, setup = async () => {}) {
  const context = await browser.newContext({ viewport: { width: 1280, height: 900 }, acceptDownloads: true });
  if (init) await context.addInitScript(init);
  await setup(context);
  const page = await context.newPage();
  const problems = [];
  page.on('console', (msg) => {
    if (msg.type() === 'error') problems.push(`console error: ${msg.text()}`);
  });
  page.on('pageerror', (err) => problems.push(`uncaught exception: ${err.message}`));
  await page.goto(server.url + hash);
  await page.getByRole('navigation', { name: 'Lab sections' }).waitFor();
  return { page, problems, context };
}

/** The number in the counters table's row `name`. */
async function counter(page, name) {
  const row = page.getByRole('table', { name: 'Link counters' }).getByRole('row', { name });
  return Number((await row.getByRole('cell').textContent()).trim());
}

/** Waits until the counter `name` satisfies `ok`. */
async function waitForCounter(page, name, ok, timeout = LONG) {
  const until = Date.now() + timeout;
  for (;;) {
    const value = await counter(page, name);
    if (ok(value)) return value;
    if (Date.now() > until) throw new Error(`${name} stayed at ${value}`);
    await page.waitForFunction(() => new Promise((r) => requestAnimationFrame(() => r(true))));
  }
}

/** `error` with the page's event log appended: a wait that timed out says what the link did. */
async function withEventLog(page, error) {
  const log = await page.getByRole('region', { name: 'Events' }).innerText({ timeout: 2000 }).catch(() => '(no event log)');
  error.message += `\nThe page's events:\n${log}`;
  return error;
}

/** Confirms the dialog the button `opener` opens, checking it names the limits. */
async function confirm(page, opener, confirmName, mentions) {
  await page.getByRole('button', { name: opener }).click();
  const dialog = page.getByRole('dialog');
  await dialog.waitFor();
  const text = await dialog.textContent();
  for (const m of mentions) assert.match(text, m);
  await dialog.getByRole('button', { name: confirmName }).click();
  await dialog.waitFor({ state: 'hidden' });
}

// The fake WebSerial: navigator.serial.requestPort() gives a port whose readable stream is fed by
// the test (window.__fakeSerial.push) and whose writable stream hands every chunk to the test
// (cutlabSerialWrite); window.__fakeSerial.unplug() makes it fail as an unplugged USB adapter does.
const fakeSerial = () => {
  const state = { controller: null, opened: null, unplugged: false };
  const toBase64 = (bytes) => {
    let s = '';
    for (const b of bytes) s += String.fromCharCode(b);
    return btoa(s);
  };
  class FakePort extends EventTarget {
    constructor() {
      super();
      this.readable = null;
      this.writable = null;
    }
    getInfo() {
      return { usbVendorId: 0x1209, usbProductId: 0xc0de };
    }
    async open(options) {
      state.unplugged = false;
      state.opened = {
        baudRate: options.baudRate, dataBits: options.dataBits, stopBits: options.stopBits,
        parity: options.parity, flowControl: options.flowControl, bufferSize: options.bufferSize,
      };
      this.readable = new ReadableStream({ start: (c) => { state.controller = c; } });
      this.writable = new WritableStream({
        write: (chunk) => window.cutlabSerialWrite(toBase64(chunk)),
      });
      await window.cutlabSerialOpened(JSON.stringify(state.opened));
    }
    async close() {
      // Closing a port whose cable is out reaches nothing.
      if (!state.unplugged) await window.cutlabSerialClosed();
    }
  }
  const port = new FakePort();
  const serial = new EventTarget();
  serial.requestPort = async () => port;
  serial.getPorts = async () => [port];
  Object.defineProperty(Navigator.prototype, 'serial', { get: () => serial, configurable: true });
  window.__fakeSerial = {
    push(b64) {
      const bin = atob(b64);
      const bytes = new Uint8Array(bin.length);
      for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
      state.controller?.enqueue(bytes);
    },
    unplug() {
      state.unplugged = true;
      state.controller?.error(new DOMException('The device has been lost.', 'NetworkError'));
      port.dispatchEvent(new Event('disconnect'));
    },
  };
};

/** `cutlab protocol decode` of `bytes`: the frames as objects. */
function decode(bytes) {
  const out = execFileSync(cutlab, ['protocol', 'decode'], { input: bytes, maxBuffer: 1 << 28 });
  return out.toString().trim().split('\n').map((l) => JSON.parse(l));
}

/**
 * The node end of the fake port: each opening of the port starts a `cutlab device --stdio`
 * child; its stdout goes to the page in batches (one evaluate at a time), the page's writes go
 * to its stdin, and both directions are kept for decoding.
 */
class Bridge {
  constructor(args) {
    this.args = args;
    this.page = null;
    this.sessions = [];
  }

  get current() {
    return this.sessions[this.sessions.length - 1];
  }

  open(json) {
    const session = {
      opened: JSON.parse(json), toDevice: [], fromDevice: [], log: '', pending: [], unplugged: false,
      device: spawn(cutlab, this.args),
    };
    this.sessions.push(session);
    session.device.stderr.on('data', (d) => { session.log += d.toString(); });
    session.device.stdout.on('data', (d) => {
      if (session.unplugged) return;
      session.fromDevice.push(d);
      session.pending.push(d);
    });
    session.pump = (async () => {
      while (!session.unplugged) {
        if (session.pending.length && this.page) {
          const batch = Buffer.concat(session.pending).toString('base64');
          session.pending = [];
          await this.page.evaluate((b64) => window.__fakeSerial.push(b64), batch).catch(() => {});
        } else {
          await new Promise((r) => setTimeout(r, 10));
        }
      }
    })();
  }

  write(b64) {
    const session = this.current;
    if (!session || session.unplugged) return;
    const bytes = Buffer.from(b64, 'base64');
    session.toDevice.push(bytes);
    session.device.stdin.write(bytes);
  }

  /** The cable is out: nothing crosses any more (the device runs on, hearing nothing). */
  unplug() {
    if (this.current) this.current.unplugged = true;
  }

  /** Ends the current device (its input closes, as when the port is closed). */
  async close() {
    const session = this.current;
    if (!session) return;
    session.unplugged = true;
    session.device.stdin.end();
    await session.pump;
  }

  kill() {
    for (const s of this.sessions) {
      s.unplugged = true;
      s.device.kill();
    }
  }
}

test('a real device behind a fake serial port: handshake, teach cut, arm, acknowledgements, unplug, reconnect, recordings after a reload, export', async () => {
  // The device's watchdog, 4 s of device time at 4x, gives the page a second of wall time to
  // answer: a loaded machine holding the page up for a few tenths of a second does not trip it.
  const bridge = new Bridge(['device', '--stdio', '--scenario', 'maneerat-doc-1', '--time-scale', '4', '--watchdog-s', '4']);
  const { page, problems, context } = await openWith('#/hardware?preset=maneerat-doc-1', fakeSerial, async (ctx) => {
    await ctx.exposeFunction('cutlabSerialWrite', (b64) => bridge.write(b64));
    await ctx.exposeFunction('cutlabSerialOpened', (json) => bridge.open(json));
    await ctx.exposeFunction('cutlabSerialClosed', () => bridge.close());
  });
  bridge.page = page;
  try {
    // Connect with the serial settings typed beside the button.
    await page.getByLabel('Baud rate').fill('460800');
    await page.getByLabel('Parity').selectOption('even');
    await page.getByRole('button', { name: 'Connect to a serial port…' }).click();
    await page.getByText('Link state: streaming').waitFor({ timeout: LONG });
    const { opened } = bridge.current;
    assert.equal(opened.baudRate, 460800);
    assert.equal(opened.parity, 'even');
    assert.equal(opened.dataBits, 8);
    const identity = page.getByRole('definition');
    await page.getByText('Why: handshake complete: cutlab-emulator (maneerat-doc-1), protocol 2.0').waitFor();
    assert.ok(await identity.filter({ hasText: 'cutlab-emulator' }).count());
    assert.ok(await identity.filter({ hasText: /^2\.0$/ }).count());
    assert.ok(await identity.filter({ hasText: '1000 Hz' }).count());
    // A real port starts from reduce-only limits, and the machine's view of the feed hold shows.
    await page.getByRole('alert').filter({ hasText: /A real port: reduce-only limits, the highest override set to 100 %/ }).waitFor();
    assert.equal(await page.getByLabel(/Highest override/).inputValue(), '100');
    await page.getByRole('status', { name: 'Feed hold at the machine' }).filter({ hasText: 'none latched' }).waitFor();

    // Teach cut over the link: the next part, open loop, inside the reduce-only limit. The first
    // arming of this device names every commissioning check, and waits for each.
    await page.getByRole('button', { name: 'Teach cut…' }).click();
    const firstDialog = page.getByRole('dialog');
    await firstDialog.waitFor();
    assert.match(await firstDialog.textContent(), /100 %, 30 %, 100 %, 60 %/);
    const checks = firstDialog.getByRole('group', { name: /First arming of cutlab-emulator: the commissioning checks/ }).getByRole('checkbox');
    assert.equal(await checks.count(), 10);
    assert.ok(await firstDialog.getByRole('button', { name: 'Start the teach cut' }).isDisabled());
    await firstDialog.getByRole('checkbox', { name: /PMC diagnosis screen/ }).waitFor();
    for (let i = 0; i < 10; i += 1) await checks.nth(i).check();
    await firstDialog.getByRole('button', { name: 'Start the teach cut' }).click();
    await firstDialog.waitFor({ state: 'hidden' });
    await page.getByText('Link state: armed').waitFor();
    await page.getByText(/teach cut over the link \(part 1\): \d+ periods/).waitFor({ timeout: LONG });
    await page.getByText('Link state: streaming').waitFor();

    // Arm: the confirmation names the limits in force (this device is commissioned now: no
    // checks again).
    await confirm(page, 'Arm…', 'Arm now', [/Override 10–100 %/, /Overload: feed hold/, /falls back to 50 %/]);
    await page.getByText('Link state: armed').waitFor();
    await page.getByText(/If the link is lost now: after 4 s the device applies [\d.]+ %/).waitFor({ timeout: LONG });
    // Override commands reach the device and its acknowledgements come back.
    await waitForCounter(page, 'Commands acknowledged', (n) => n >= 6);
    await page.getByText(/Last acknowledgement: set-override #\d+: applied; override now [\d.]+ %/).waitFor({ timeout: LONG });
    const longestTask = await watchLongTasks(page);
    // A moment of the closed loop, then the cable comes out.
    await page.getByText(/recording “.*closed loop”: \d+ rows/).waitFor();
    await page.waitForFunction(() => /recording “.*closed loop”: (\d{4,}) rows/.test(document.body.innerText), null, { timeout: LONG });
    await screenshot(page, 'hardware-armed');
    bridge.unplug();
    await page.evaluate(() => window.__fakeSerial.unplug());
    await page.getByText('Link state: alarm').waitFor();
    await page.getByRole('alert').filter({ hasText: /link lost: .*unplugged|link lost: reading the port failed/ }).first().waitFor();
    assert.equal(await counter(page, 'Link losses (host watchdog, port lost)'), 1);
    await page.getByText(/the device applies its fallback override \(at most 50 %, never above the applied\) on its own/).first().waitFor();
    assert.ok((await longestTask()) < 200, `the page froze for ${await longestTask()} ms`);
    // The device, hearing nothing more, falls back on its own watchdog (4 s of device time).
    const first = bridge.current;
    const until = Date.now() + LONG;
    while (!/watchdog: nothing from the host/.test(first.log) && Date.now() < until) {
      await new Promise((r) => setTimeout(r, 50));
    }
    assert.match(first.log, /watchdog: nothing from the host for 4 s; fallback override [\d.]+ % \(the lower of the applied and the configured 50 %\)/);
    await bridge.close();

    // What crossed the line, decoded by the core's own tool: Arms and SetOverrides went out,
    // Acks with the applied value came back.
    const sent = decode(Buffer.concat(first.toDevice)).filter((f) => f.type);
    const received = decode(Buffer.concat(first.fromDevice)).filter((f) => f.type);
    assert.ok(sent.filter((f) => f.type === 'arm').length >= 2);
    const overrides = sent.filter((f) => f.type === 'set-override');
    assert.ok(overrides.length >= 5, `${overrides.length} set-override frames`);
    const acks = received.filter((f) => f.type === 'ack' && f.command === 'set-override');
    assert.ok(acks.length >= 5);
    assert.ok(acks.every((a) => a.result === 'applied' || a.result === 'limited'));
    assert.ok(acks.some((a) => overrides.some((o) => o.seq === a.seq)));

    // Plugged in again: Connect, without a reload (the lost port is closed already); the
    // calibration is kept.
    assert.ok(await page.getByRole('button', { name: 'Disconnect' }).isDisabled());
    await page.getByRole('button', { name: 'Connect to a serial port…' }).click();
    await page.getByText('Link state: streaming').waitFor({ timeout: LONG });
    assert.equal(bridge.sessions.length, 2);
    await page.getByText(/In use: teach cut over the link \(part 1\)/).waitFor();
    await page.getByRole('button', { name: 'Disconnect' }).click();
    await page.getByText('Link state: closed').waitFor();

    // The recordings survive a reload, intact.
    const listed = page.getByRole('table', { name: 'Stored recordings' });
    const loopRow = listed.getByRole('row').filter({ hasText: 'closed loop' });
    await loopRow.filter({ hasText: 'the link was lost' }).waitFor();
    const rowsBefore = Number(await loopRow.getByRole('cell').first().textContent());
    await page.reload();
    await page.getByRole('heading', { name: 'Recordings' }).waitFor();
    const teachRow = listed.getByRole('row').filter({ hasText: 'teach cut' });
    await teachRow.filter({ hasText: 'the part ended' }).waitFor();
    await loopRow.filter({ hasText: 'the link was lost' }).waitFor();
    assert.equal(Number(await loopRow.getByRole('cell').first().textContent()), rowsBefore);
    assert.equal(await page.getByRole('region', { name: 'Unfinished recordings' }).count(), 0);
    await screenshot(page, 'hardware-recordings');

    // Export, and read it back with the core's log reader.
    const [download] = await Promise.all([
      page.waitForEvent('download'),
      loopRow.getByRole('button', { name: /^Export .* as CSV$/ }).click(),
    ]);
    assert.match(download.suggestedFilename(), /^cutlab-recording-.*closed-loop\.csv$/);
    await mkdir(artifacts, { recursive: true });
    const file = join(artifacts, 'hardware-recording.csv');
    await writeFile(file, await readFile(await download.path()));
    const log = JSON.parse(execFileSync(cutlab, ['log', 'inspect', file, '--json']).toString());
    assert.equal(log.rows, rowsBefore);
    assert.equal(log.time_column, 'time [s]');
    assert.ok(Math.abs(log.sample_period_s - 0.001) < 1e-9);
    const role = (name) => log.columns.find((c) => c.name === name)?.role;
    assert.equal(role('S_I_U [A]'), 'phase-current');
    assert.equal(role('X_I_V [A]'), 'phase-current');
    assert.equal(role('S_speed [rpm]'), 'spindle-speed');
    assert.equal(role('feed [mm/min]'), 'feed');
    assert.equal(role('S_current_rms [A]'), 'rms-current');
    assert.equal(role('force estimate [N]'), 'force');
    assert.equal(role('phase'), 'label');
    // The Logs page opens the same file as a person would, with the same rows and roles.
    await page.goto(`${page.url().split('#')[0]}#/logs`);
    await page.getByLabel('Open log files').setInputFiles(file);
    await page.getByRole('status')
      .filter({ hasText: `Loaded hardware-recording.csv: ${rowsBefore} rows × ${log.columns.length} columns` })
      .waitFor({ timeout: LONG });
    await page.getByLabel('Analyse hardware-recording.csv').check();
    assert.equal(await page.getByRole('combobox', { name: 'force estimate [N]' }).inputValue(), 'force');
    assert.equal(await page.getByRole('combobox', { name: 'phase', exact: true }).inputValue(), 'label');
    assert.deepEqual(problems, []);
  } finally {
    bridge.kill();
    await context.close();
  }
});

test('the virtual device with injected faults: counters, the device watchdog, the host watchdog, and a reload mid-run', async () => {
  const { page, problems, context } = await openWith('#/hardware?preset=maneerat-doc-1');
  try {
    await page.getByLabel('Program (preset)').selectOption('maneerat-doc-1');
    await page.getByLabel('Time scale').fill('2');
    await page.getByLabel('Drop rate').fill('0.01');
    await page.getByLabel('Noise rate').fill('0.01');
    // The receiver stalls for 3 s inside the teach cut's part, longer than the device's 2 s
    // watchdog (2 s, not 0.5 s: at 2x the page has a second of wall time to answer each tick,
    // which a busy computer always gives, docs/hardware.md §6). The part starts when the teach
    // cut arms the device, about a second of device time after power-on here, and lasts 15 s;
    // the stall must begin after the arm, or the device never armed has no watchdog to trip.
    // At 10 s of device time, it leaves the test 4.5 s of wall time to confirm the teach cut
    // (at 6 s and 4x it left 1.2 s, which a loaded CI machine once missed), and it ends, with
    // the host's re-arm, well before the part's end.
    await page.getByLabel('Device watchdog').fill('2');
    await page.getByLabel('Receiver stall at').fill('10');
    await page.getByLabel('Receiver stall for').fill('3');
    await page.getByRole('button', { name: 'Start the virtual device' }).click();
    await page.getByText('Link state: streaming').waitFor({ timeout: LONG });
    const longestTask = await watchLongTasks(page);
    await confirm(page, 'Teach cut…', 'Start the teach cut', [/teach-cut overrides/]);
    // Lost and corrupted frames are counted as they happen.
    await waitForCounter(page, 'Samples lost (sequence gaps)', (n) => n > 10);
    await waitForCounter(page, 'Frames rejected (CRC, COBS, size)', (n) => n > 5);
    await waitForCounter(page, 'Bytes dropped (part of no frame)', (n) => n > 0);
    // The stall: the device falls back, the host sees it and re-arms; the teach cut, whose fit
    // would take the fallback's samples for the schedule's overrides, is abandoned and the page
    // says so.
    await waitForCounter(page, 'Device watchdog fallbacks', (n) => n >= 1);
    await page.getByText(/re-arming the device after its watchdog fallback/).first().waitFor();
    await page.getByText(/device back under the host's control/).first().waitFor({ timeout: LONG });
    await page.getByText(/teach cut abandoned: the device's watchdog fell back/).first().waitFor({ timeout: LONG });
    // Once the part ends (handed back), the teach cut runs again on the next part.
    await page.getByText(/the part ended: the device handed back/).first().waitFor({ timeout: LONG });
    await confirm(page, 'Teach cut…', 'Start the teach cut', [/teach-cut overrides/]);
    await page.getByText(/teach cut over the link/).first().waitFor({ timeout: LONG });
    await page.getByText('Link state: streaming').waitFor();
    await confirm(page, 'Arm…', 'Arm now', [/Overload/]);
    // A reload while the loop runs (two seconds of it in: 4000 samples at 2× real time): the
    // recording so far is offered afterwards.
    await page.waitForFunction(() => /recording “.*closed loop”: ([4-9]\d{3}|\d{5,}) rows/.test(document.body.innerText), null, { timeout: LONG });
    const shown = await page.getByText(/recording “.*closed loop”: \d+ rows/).textContent();
    const rowsShown = Number(shown.match(/: (\d+) rows/)[1]);
    assert.ok((await longestTask()) < 200, `the page froze for ${await longestTask()} ms`);
    await page.reload();
    const offered = page.getByRole('region', { name: 'Unfinished recordings' });
    await offered.waitFor({ timeout: LONG });
    const stored = Number((await offered.getByRole('listitem').first().textContent()).match(/(\d+) rows/)[1]);
    // At most a second of it is lost (the recording is stored every 0.5 s): 2000 samples at 2×
    // real time and 1 kHz.
    assert.ok(stored >= rowsShown - 2000 && stored > 0, `${stored} rows stored of ${rowsShown} shown`);
    await offered.getByRole('button', { name: /^Keep / }).click();
    await offered.waitFor({ state: 'detached' });
    const kept = page.getByRole('table', { name: 'Stored recordings' }).getByRole('row').filter({ hasText: /cut short: the page closed/ });
    await kept.waitFor();
    // Deleted, it is gone from the list, which is read back from the store.
    const recordings = await page.getByRole('table', { name: 'Stored recordings' }).getByRole('row').count();
    await kept.getByRole('button', { name: /^Delete / }).click();
    await kept.waitFor({ state: 'detached' });
    assert.equal(await page.getByRole('table', { name: 'Stored recordings' }).getByRole('row').count(), recordings - 1);

    // Again, to the host's watchdog: the virtual cable comes out at 26 s of device time, during
    // the closed loop's part. The teach cut's part ends about 16 s after power-on, and the
    // closed loop's (12–13 s long) must be armed before the cable comes out: 10 s of device time,
    // 5 s of wall time at 2x, for the test to confirm the arming.
    await page.getByLabel('Time scale').fill('2');
    await page.getByLabel('Cable pulled at').fill('26');
    await page.getByLabel('Host watchdog').fill('1');
    await page.getByRole('button', { name: 'Start the virtual device' }).click();
    await page.getByText('Link state: streaming').waitFor({ timeout: LONG });
    await confirm(page, 'Teach cut…', 'Start the teach cut', [/teach-cut overrides/]);
    await page.getByText(/teach cut over the link/).first().waitFor({ timeout: LONG });
    await page.getByText('Link state: streaming').waitFor();
    await confirm(page, 'Arm…', 'Arm now', [/alarms after 1 s without samples/]);
    await page.getByText('Link state: alarm').waitFor({ timeout: LONG });
    await page.getByRole('alert').filter({ hasText: 'host watchdog: no sample for 1 s while the part ran' }).waitFor();
    assert.equal(await counter(page, 'Link losses (host watchdog, port lost)'), 1);
    await page.getByRole('button', { name: 'Acknowledge the alarm' }).click();
    await page.getByText(/The alarm stays: the device is still silent/).waitFor();
    await screenshot(page, 'hardware-virtual-alarm');
    await page.getByRole('button', { name: 'Disconnect' }).click();
    await page.getByText('Link state: closed').waitFor();
    assert.deepEqual(problems, []);
  } catch (e) {
    throw await withEventLog(page, e);
  } finally {
    await context.close();
  }
});

test('without WebSerial the page says why and what works instead; the virtual device runs from a saved calibration, and Escape returns to the safe override', async () => {
  const { page, problems, context } = await openWith('#/hardware?preset=maneerat-doc-1', () => {
    delete Navigator.prototype.serial;
  });
  const note = page.getByRole('note');
  await note.getByRole('heading', { name: 'WebSerial is not available here' }).waitFor();
  assert.match(await note.textContent(), /this browser has no WebSerial \(Firefox and Safari/);
  assert.match(await note.textContent(), /the virtual device below/);
  assert.match(await note.textContent(), /cutlab host --port/);
  assert.ok(await page.getByRole('button', { name: 'Connect to a serial port…' }).isDisabled());
  // Before any link: no override reads as a 0 % feed hold, no round trip as 0 ms.
  await page.getByText('Override: no link open.').waitFor();
  const roundTrip = page.getByRole('table', { name: 'Link counters' }).getByRole('row', { name: /Command round trip/ });
  assert.match(await roundTrip.textContent(), /no command acknowledged yet/);

  // A calibration saved by the command line: the run needs no teach cut.
  await mkdir(artifacts, { recursive: true });
  const saved = join(artifacts, 'hardware-calibration.json');
  execFileSync(cutlab, ['sim', '--scenario', 'maneerat-doc-1', '--controller', 'fixed', '--save-calibration', saved]);
  // A calibration saved in this browser (as the Logs page saves it) is offered too.
  const savedText = JSON.parse(await readFile(saved, 'utf8'));
  await page.evaluate((file) => localStorage.setItem('cutlab-calibrations', JSON.stringify([
    { ...file, source: 'log teach.csv, spindle feedback' },
  ])), savedText);
  const savedList = page.getByLabel('Or one saved in this browser (Logs page)');
  await savedList.focus();
  await savedList.selectOption({ label: 'log teach.csv, spindle feedback' });
  await page.getByText('In use: saved in this browser: log teach.csv, spindle feedback').waitFor();

  const broken = join(artifacts, 'hardware-calibration-broken.json');
  await writeFile(broken, '{"format": "cutlab-calibration", "version": 1, "calibration": 3}');
  await page.getByLabel('Load a calibration file (cutlab-calibration JSON)').setInputFiles(broken);
  await page.getByText(/hardware-calibration-broken\.json: /).waitFor();
  // A version 1 file, saved before calibrations kept their load levels, is read, and the page
  // says it cannot tell what its lines rest on (the words of the fit's other front ends).
  const warnings = page.getByRole('list', { name: 'Calibration warnings' });
  const older = join(artifacts, 'hardware-calibration-v1.json');
  const v1 = structuredClone(savedText);
  v1.version = 1;
  delete v1.calibration.few_load_levels;
  await writeFile(older, JSON.stringify(v1));
  await page.getByLabel('Load a calibration file (cutlab-calibration JSON)').setInputFiles(older);
  await warnings.getByText(/^Warning: the calibration does not say how many load levels its lines rest on/).waitFor();
  await page.getByLabel('Load a calibration file (cutlab-calibration JSON)').setInputFiles(saved);
  await page.getByText(/In use: file hardware-calibration\.json .*spindle feedback/).waitFor();
  // Today's file knows its teach cut's levels: enough, nothing to warn of.
  assert.equal(savedText.version, 2);
  assert.deepEqual(savedText.calibration.few_load_levels, []);
  assert.equal(await warnings.getByRole('listitem').count(), 0);

  // The virtual device, as a real bridge's twin (no truth), is one click away.
  await page.getByLabel("Send the simulation's truth (off: a real bridge's twin)").uncheck();
  // At 2x the part (about 12 s of device time) leaves the test 6 s of wall time to press Escape
  // while it still runs, a loaded machine included.
  await page.getByLabel('Time scale').fill('2');
  // The device runs in a worker of its own (the page's module holds no plant), which the click
  // starts and Disconnect ends.
  const started = [];
  page.on('worker', (w) => started.push(w));
  await page.getByRole('button', { name: 'Start the virtual device' }).click();
  await page.getByText('Link state: streaming').waitFor({ timeout: LONG });
  assert.equal(started.length, 1, `workers started by the click: ${started.map((w) => w.url())}`);
  assert.ok(started[0].url().endsWith('/worker-loader.js'), `the device's worker: ${started[0].url()}`);
  assert.equal(await page.evaluate(() => document.documentElement.dataset.deviceWorker), 'on');
  const features = page.getByRole('definition').filter({ hasText: /^none$/ });
  await features.waitFor();
  await confirm(page, 'Arm…', 'Arm now', [/holding 150 N/]);
  await page.getByText('Link state: armed').waitFor();
  await page.waitForFunction(() => /recording “.*closed loop”: (\d{4,}) rows/.test(document.body.innerText), null, { timeout: LONG });
  // Escape: the safe override (the device's fallback, 50 %) at once.
  await page.keyboard.press('Escape');
  await page.getByText('Link state: streaming').waitFor();
  await page.getByText('Why: Escape pressed: the override held at 50 % (the safe value) until the part ends').waitFor();
  await page.getByText(/Override commanded 50\.0 %, applied 50\.0 %/).waitFor({ timeout: LONG });
  assert.ok(await page.getByRole('button', { name: 'Disarm (Esc)' }).isDisabled());
  await page.getByRole('table', { name: /Metrics of the run/ }).waitFor();
  // The calibration goes back out as a file the command line reads.
  const [download] = await Promise.all([
    page.waitForEvent('download'),
    page.getByRole('button', { name: 'Save the calibration (JSON)' }).click(),
  ]);
  assert.equal(download.suggestedFilename(), 'cutlab-calibration.json');
  const again = join(artifacts, 'hardware-calibration-again.json');
  await writeFile(again, await readFile(await download.path()));
  const run = execFileSync(cutlab, ['sim', '--scenario', 'maneerat-doc-1', '--controller', 'threshold', '--calibration', again]).toString();
  assert.match(run, /Cycle time/);
  const deviceWorkerClosed = started[0].waitForEvent('close', { timeout: LONG });
  await page.getByRole('button', { name: 'Disconnect' }).click();
  await page.getByText('Link state: closed').waitFor();
  await deviceWorkerClosed;
  assert.equal(await page.evaluate(() => document.documentElement.dataset.deviceWorker), undefined);
  // Started again and its cable pulled: the link is lost at once and that worker ends too.
  await page.getByRole('button', { name: 'Start the virtual device' }).click();
  await page.getByText('Link state: streaming').waitFor({ timeout: LONG });
  assert.equal(started.length, 2);
  const unpluggedClosed = started[1].waitForEvent('close', { timeout: LONG });
  await page.getByRole('button', { name: 'Pull the virtual cable' }).click();
  await page.getByText(/link lost: the virtual device's cable was pulled/).first().waitFor();
  await unpluggedClosed;
  assert.equal(await page.evaluate(() => document.documentElement.dataset.deviceWorker), undefined);
  assert.deepEqual(problems, []);
  await context.close();
});
