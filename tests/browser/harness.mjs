// Shared test harness: the real release binary (started by tests/run.sh, which exports
// SEAARMS_URL; started here on a free loopback port when it is not set) and real headless
// Chromium (Debian /usr/bin/chromium driven by playwright-core; no downloaded browsers).

import { chromium } from 'playwright-core';
import { spawn } from 'node:child_process';
import { mkdtempSync, mkdirSync, rmSync, existsSync, readFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, dirname, extname } from 'node:path';
import { fileURLToPath } from 'node:url';
import net from 'node:net';
import { DEAD_ZONE } from '../../web/input.js'; // the page's own constant (no browser globals at load)

const here = dirname(fileURLToPath(import.meta.url));
export const ROOT = join(here, '..', '..');
export const ARTIFACTS = join(here, 'artifacts');
export const INSTRUCTOR_TOKEN = process.env.SEAARMS_INSTRUCTOR_TOKEN || 'test-token';
mkdirSync(ARTIFACTS, { recursive: true });

export const CHROMIUM_ARGS = ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
  '--disable-background-networking', '--disable-component-update', '--disable-sync',
  '--use-angle=swiftshader', '--enable-unsafe-swiftshader'];

/** SEAARMS_WEB_FROM_DISK=1: the page's own files (web/) come from the working tree, with the
 * server's headers (CSP included), so front-end work needs no release rebuild (the binary
 * embeds web/). The tests themselves run without it, against the embedded files. */
const WEB_FROM_DISK = !!process.env.SEAARMS_WEB_FROM_DISK;
function webFile(pathname) {
  const rel = pathname === '/' ? 'index.html' : pathname === '/instructor' ? 'instructor.html'
    : pathname.startsWith('/replay/') ? 'replay.html'
    : pathname.startsWith('/web/') ? decodeURIComponent(pathname.slice(5)) : null;
  if (rel === null || rel.includes('..')) return null;
  const f = join(ROOT, 'web', rel);
  return existsSync(f) ? f : null;
}

/** A file of web/ as the server sends it: a page gets the shared head in place of its include
 * line, as server/src/assets.rs does. */
function fromDisk(file) {
  if (extname(file) !== '.html') return readFileSync(file);
  const head = readFileSync(join(ROOT, 'web', 'head.html'), 'utf8').trimEnd();
  return readFileSync(file, 'utf8').replace('<!--#include head.html-->', () => head);
}

/** In a page: the form controls (shown or not) with no accessible name (no label, aria-label,
 * title, placeholder or button text), as the start of their HTML. */
export const UNNAMED_CONTROLS = () => [...document.querySelectorAll('input, select, button, textarea')]
  .filter((e) => !([...(e.labels || [])].some((l) => l.textContent.trim()) || e.getAttribute('aria-label')
    || e.title || e.placeholder || (e.tagName === 'BUTTON' && e.textContent.trim())))
  .map((e) => e.outerHTML.slice(0, 80));

async function freePort() {
  return new Promise((resolve, reject) => {
    const s = net.createServer();
    s.listen(0, '127.0.0.1', () => { const p = s.address().port; s.close(() => resolve(p)); });
    s.on('error', reject);
  });
}

async function waitHealthy(url, ms = 20000) {
  const t0 = Date.now();
  while (Date.now() - t0 < ms) {
    try { const r = await fetch(`${url}/healthz`); if (r.ok) return; } catch { /* not yet */ }
    await new Promise((r) => setTimeout(r, 100));
  }
  throw new Error(`server at ${url} not healthy after ${ms} ms`);
}

/** Starts the release binary on a free loopback port with a temp data dir; returns {url, stop}. */
export async function startServer(extraArgs = []) {
  const bin = process.env.SEAARMS_BIN || join(ROOT, 'target', 'release', 'seaarms');
  if (!existsSync(bin)) throw new Error(`${bin} missing: run cargo build --release (tests/run.sh does)`);
  const port = await freePort();
  const dataDir = mkdtempSync(join(tmpdir(), 'seaarms-data-'));
  const args = ['--bind', `127.0.0.1:${port}`, '--data-dir', dataDir, '--instructor-token', INSTRUCTOR_TOKEN, ...extraArgs];
  // tests not about progression start any exercise directly; `--progression on` in extraArgs
  // turns it back on (progression.test.mjs)
  const env = { SEAARMS_PROGRESSION: 'off', ...process.env, RUST_LOG: 'warn' };
  const proc = spawn(bin, args, { env, stdio: ['ignore', 'ignore', 'inherit'] });
  proc.unref(); // a test file's process may exit while its server runs; 'exit' stops it
  // the server shuts down gracefully on SIGTERM and may still write its records while the
  // folder goes: retry the removal (ENOTEMPTY) rather than fail the test on that race
  const stop = () => { proc.kill(); rmSync(dataDir, { recursive: true, force: true, maxRetries: 20, retryDelay: 100 }); };
  process.on('exit', stop);
  const url = `http://127.0.0.1:${port}`;
  await waitHealthy(url);
  return { url, stop, proc };
}

let own = null;
/** Base URL of the server under test (starting one if tests/run.sh did not). */
export async function server() {
  if (process.env.SEAARMS_URL) return process.env.SEAARMS_URL;
  if (!own) own = await startServer();
  return own.url;
}

/**
 * A fresh browser (persistent context in a temp profile) and page. Any request that is not to
 * the loopback server is aborted and recorded in `offsite`; console errors and page errors are
 * recorded in `errors`.
 */
export async function openBrowser({ viewport = { width: 1280, height: 800 }, initScript, hasTouch = false, isMobile = false } = {}) {
  const profile = mkdtempSync(join(tmpdir(), 'seaarms-chromium-'));
  const context = await chromium.launchPersistentContext(profile, {
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    headless: true,
    // a fulfilled document loses its loopback address space; its WebSocket would be refused
    args: WEB_FROM_DISK ? [...CHROMIUM_ARGS, '--disable-features=LocalNetworkAccessChecks'] : CHROMIUM_ARGS,
    viewport,
    hasTouch,
    isMobile,
  });
  const offsite = [];
  const errors = [];
  await context.route('**/*', async (route) => {
    const u = new URL(route.request().url());
    if (WEB_FROM_DISK && u.hostname === '127.0.0.1') {
      const file = webFile(u.pathname);
      if (file) {
        const response = await route.fetch(); // the server's headers (a file new since the build: 404)
        const type = { '.js': 'text/javascript', '.css': 'text/css', '.html': 'text/html' }[extname(file)];
        const headers = { ...response.headers(), ...(type ? { 'content-type': type } : {}) };
        return route.fulfill({ status: 200, headers, body: fromDisk(file) });
      }
    }
    if (u.protocol === 'data:' || u.hostname === '127.0.0.1' || u.hostname === 'localhost') return route.continue();
    offsite.push(route.request().url());
    return route.abort();
  });
  if (initScript) await context.addInitScript(initScript);
  const page = context.pages()[0] || await context.newPage();
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  page.on('pageerror', (e) => errors.push(String(e)));
  const close = async () => {
    await context.close();
    rmSync(profile, { recursive: true, force: true });
  };
  return { context, page, offsite, errors, close };
}

/** Waits until `fn()` (evaluated in the page) is truthy; returns its value. */
export async function until(page, fn, arg, timeout = 15000) {
  const h = await page.waitForFunction(fn, arg, { timeout, polling: 50 });
  return h.jsonValue();
}

/**
 * Waits until the page (web/view.js debug hooks, `window.__seaarms`) has drawn more than
 * `states` state frames of the server's and, with `open` (the default), its socket is open
 * (the hello received); returns the page's session id (true when it has none).
 */
export async function untilDrawn(page, { states = 2, open = true, timeout } = {}) {
  return until(page, ([n, o]) => {
    const w = window.__seaarms;
    if (!(w?.statesDrawn > n) || (o && !w.connection?.open)) return false;
    return w.connection?.session || true;
  }, [states, open], timeout);
}

/** Presses the task panel's "Ready" (an exercise attempt on the trainee's page waits for it;
 * docs/exercises.md) and waits until its clock runs. */
export async function pressReady(page) {
  await until(page, () => window.__seaarms.lastState?.awaiting_ready === true, undefined, 15000);
  await page.click('#task .task-ready');
  await until(page, () => window.__seaarms.lastState?.awaiting_ready === false, undefined, 15000);
}

/** RGB of a pixel in a PNG screenshot buffer (decoded by the page itself: no extra packages). */
export async function decodePng(page, png) {
  return page.evaluate(async (b64) => {
    const img = new Image();
    img.src = `data:image/png;base64,${b64}`;
    await img.decode();
    const c = document.createElement('canvas');
    c.width = img.width; c.height = img.height;
    const g = c.getContext('2d');
    g.drawImage(img, 0, 0);
    const d = g.getImageData(0, 0, img.width, img.height).data;
    return { width: img.width, height: img.height, data: Array.from(d) };
  }, png.toString('base64'));
}

export function hue([r, g, b]) {
  const mx = Math.max(r, g, b), mn = Math.min(r, g, b);
  if (mx === mn) return 0;
  let h;
  if (mx === r) h = ((g - b) / (mx - mn)) % 6;
  else if (mx === g) h = (b - r) / (mx - mn) + 2;
  else h = (r - g) / (mx - mn) + 4;
  return (h * 60 + 360) % 360;
}

export function sat([r, g, b]) {
  const mx = Math.max(r, g, b), mn = Math.min(r, g, b);
  return mx === 0 ? 0 : (mx - mn) / mx;
}

/** Classifies a lit colour sample by the page's palette (hue/brightness bands). */
export function classify(rgb) {
  const [r, g, b] = rgb;
  const v = Math.max(r, g, b), s = sat(rgb), h = hue(rgb);
  if (v < 45) return 'black';
  if (s < 0.18) return 'grey';
  if (h >= 190 && h <= 215 && s < 0.7) return 'lightblue';
  if (h >= 42 && h <= 62) return 'yellow';
  if (h >= 12 && h < 35) return 'orange';
  if (h < 10 || h > 345) return 'red';
  return 'other';
}

/** Creates a trainee session over the REST API (as the page does). */
/** The instructor page signed in with the instructor token, on the Classroom tab for `group`. */
export async function openClassroom(page, url, group) {
  await page.goto(`${url}/instructor`);
  await page.fill('#token', INSTRUCTOR_TOKEN);
  await page.click('#token-form button');
  await page.click('#instr-tabs [data-tab="classroom"]');
  await page.fill('#cls-group', group);
  await page.dispatchEvent('#cls-group', 'change');
}

export async function createSession(url, body = {}) {
  const r = await fetch(`${url}/api/sessions`, { method: 'POST', headers: { 'content-type': 'application/json' }, body: JSON.stringify(body) });
  if (!r.ok) throw new Error(`POST /api/sessions: ${r.status} ${await r.text()}`);
  return r.json();
}

/** An instructor's action on session `id` (POST /api/sessions/{id}/actions with the instructor
 * token); throws with the server's answer unless it succeeds. */
export async function instructorAction(url, id, body) {
  const r = await fetch(`${url}/api/sessions/${id}/actions`, {
    method: 'POST', headers: { 'content-type': 'application/json', authorization: `Bearer ${INSTRUCTOR_TOKEN}` }, body: JSON.stringify(body),
  });
  if (!r.ok) throw new Error(`action ${JSON.stringify(body)}: ${r.status} ${await r.text()}`);
}

/**
 * Init script: a fake standard-mapping gamepad. `navigator.getGamepads()` returns it once
 * `window.__connectPad()` has dispatched `gamepadconnected`; tests set `window.__pad.axes[i]`
 * and `window.__pad.buttons[i].value/pressed`.
 */
export const FAKE_GAMEPAD = () => {
  const buttons = Array.from({ length: 17 }, () => ({ pressed: false, touched: false, value: 0 }));
  const pad = { id: 'Fake pad (STANDARD GAMEPAD)', index: 0, connected: false, mapping: 'standard', timestamp: 0, axes: [0, 0, 0, 0], buttons };
  window.__pad = pad;
  Object.defineProperty(Navigator.prototype, 'getGamepads', { configurable: true, value: () => [pad.connected ? pad : null, null, null, null] });
  window.__connectPad = () => {
    pad.connected = true;
    const e = new Event('gamepadconnected');
    Object.defineProperty(e, 'gamepad', { value: pad });
    window.dispatchEvent(e);
  };
  window.__setButton = (i, v) => { buttons[i].value = v; buttons[i].pressed = v > 0.5; };
};

/** Stick value that comes out of the page's dead zone (web/input.js DEAD_ZONE) as `v`. */
export function stick(v) {
  const dz = DEAD_ZONE;
  if (Math.abs(v) < 1e-3) return 0;
  return Math.sign(v) * (dz + Math.min(1, Math.abs(v)) * (1 - dz));
}

/** JS heap (after a forced GC), DOM nodes, and the page's frame counters, via CDP. */
export async function sampleMemory(page, cdp) {
  await cdp.send('HeapProfiler.collectGarbage');
  const { metrics } = await cdp.send('Performance.getMetrics');
  const m = Object.fromEntries(metrics.map((x) => [x.name, x.value]));
  const c = await page.evaluate(() => ({ received: window.__seaarms.connection.framesReceived, drawn: window.__seaarms.statesDrawn, rendered: window.__seaarms.framesRendered, frameHz: window.__seaarms.hello.frame_hz }));
  return { t: Date.now(), heapMB: m.JSHeapUsedSize / 1048576, nodes: m.Nodes, listeners: m.JSEventListeners, ...c };
}

/** Runs the trainee page for `seconds` and reports heap growth and frame rates. */
export async function soak(url, seconds, { log = () => {}, every = 30 } = {}) {
  const b = await openBrowser();
  try {
    await b.page.goto(`${url}/?scenario=training`);
    await untilDrawn(b.page);
    const cdp = await b.context.newCDPSession(b.page);
    await cdp.send('Performance.enable');
    await b.page.waitForTimeout(5000); // warm up (JIT, plots filling their windows)
    const samples = [await sampleMemory(b.page, cdp)];
    const t0 = Date.now();
    while (Date.now() - t0 < seconds * 1000) {
      await b.page.waitForTimeout(Math.min(every * 1000, seconds * 1000 - (Date.now() - t0)));
      const s = await sampleMemory(b.page, cdp);
      samples.push(s);
      log(s);
    }
    const a = samples[0], z = samples[samples.length - 1];
    const dt = (z.t - a.t) / 1000;
    return {
      seconds: dt, samples, errors: b.errors,
      heapStartMB: a.heapMB, heapEndMB: z.heapMB, heapMaxMB: Math.max(...samples.map((s) => s.heapMB)),
      nodesStart: a.nodes, nodesEnd: z.nodes,
      receivedHz: (z.received - a.received) / dt, drawnHz: (z.drawn - a.drawn) / dt, renderedHz: (z.rendered - a.rendered) / dt,
      frameHz: z.frameHz,
    };
  } finally {
    await b.close();
  }
}

/** World position of handle `i` (0: the left arm's, 1: the right's) from the hello's scene
 * (`handles_m`, box frame; docs/exercises.md) and a state frame's box pose. */
export function handleWorld(state, hello, i) {
  const { position: p, rotation: r } = state.object.pose;
  const h = hello.scene.handles_m[i];
  return [0, 1, 2].map((k) => p[k] + r[k][0] * h[0] + r[k][1] * h[1] + r[k][2] * h[2]);
}

/**
 * Drives the page's own input path with the fake gamepad (FAKE_GAMEPAD) in Cartesian mode:
 * a proportional controller in the test reads the streamed state and sets the sticks.
 * `onState(state)` sees every state the controller reads.
 */
export function padDriver(page, onState = () => {}) {
  // the controller works in world axes: the sticks in the vehicle frame (toolbar "Sticks";
  // the built-in vehicle's axes are the world's), not the default camera frame
  const setSticks = (v) => page.evaluate(([a0, a1, a3]) => {
    const f = document.getElementById('sel-frame');
    if (f.value !== 'vehicle') { f.value = 'vehicle'; f.dispatchEvent(new Event('change')); }
    const p = window.__pad; p.axes[0] = a0; p.axes[1] = a1; p.axes[3] = a3;
  }, [stick(v[0]), -stick(v[1]), -stick(v[2])]);
  /** Cartesian P control of one arm's tool point to `target(state, hello)` (world, m). */
  const driveTo = async (side, target, tol = 0.02, timeoutMs = 90000) => {
    const t0 = Date.now();
    let err = [1, 1, 1];
    while (Date.now() - t0 < timeoutMs) {
      const { st, hello } = await page.evaluate(() => ({ st: window.__seaarms.lastState, hello: window.__seaarms.hello }));
      onState(st);
      const tgt = target(st, hello);
      const ee = st.arms[side].pose.position;
      err = tgt.map((v, i) => v - ee[i]);
      if (Math.hypot(...err) < tol) break;
      // full speed (0.2 m/s) beyond 8 cm, proportional inside, at least 15 % near the goal
      const v = err.map((e) => { const f = Math.max(-1, Math.min(1, e / 0.08)); return Math.abs(f) < 0.15 ? Math.sign(f) * Math.max(Math.abs(f), Math.abs(e) > tol / 2 ? 0.15 : 0) : f; });
      await setSticks(v);
      await page.waitForTimeout(40);
    }
    await setSticks([0, 0, 0]);
    return Math.hypot(...err);
  };
  const above = (side, dz) => (st, hello) => { const h = handleWorld(st, hello, side === 'left' ? 0 : 1); h[2] += dz; return h; };
  const selectArm = async (side) => {
    const btn = side === 'left' ? 4 : 5; // LB / RB
    await page.evaluate((i) => window.__setButton(i, 1), btn);
    await until(page, (s) => window.__seaarms.selectedArm === s, side);
    await page.evaluate((i) => window.__setButton(i, 0), btn);
  };
  /**
   * Turns the jaw about the world vertical (d-pad right/left = ±wz) until its closing axis
   * (tool y, the rotation's second column) has no world-x part, within `tol` (rad). A box hung
   * from one handle (y = ±0.15 m off its centre) pulls a moment about world x; squared so, the
   * pads carry it as roll about the bar (limit N·s, 59 N·m) and not as torsion about the
   * closing axis (limit 2μNρ̄: 15.2 N·m static at the rated clamp, 10 N·m sliding;
   * server/core/src/grasp/grip.rs), which alone would slip under the box's 37 N·m (249 N wet
   * weight × 0.15 m).
   */
  const squareJaw = async (side, tol = 0.02, timeoutMs = 15000) => {
    const t0 = Date.now();
    let e = 1;
    while (Date.now() - t0 < timeoutMs) {
      const r = await page.evaluate((s) => window.__seaarms.lastState.arms[s].pose.rotation, side);
      // angle of the closing axis's horizontal part from the nearer of ±y; +wz turns it toward −x
      e = Math.atan2(r[0][1], r[1][1]);
      if (e > Math.PI / 2) e -= Math.PI; else if (e < -Math.PI / 2) e += Math.PI;
      if (Math.abs(e) < tol) break;
      const v = Math.sign(e) * Math.max(0.25, Math.min(1, Math.abs(e) / 0.3));
      await page.evaluate((x) => { window.__setButton(15, Math.max(0, x)); window.__setButton(14, Math.max(0, -x)); }, v);
      await page.waitForTimeout(40);
    }
    await page.evaluate(() => { window.__setButton(15, 0); window.__setButton(14, 0); });
    return Math.abs(e);
  };
  /**
   * Opens the jaw, brings the tool point onto its handle, closes (RT kept pressed); retries if
   * it slips. `square`: square the jaw (squareJaw) 10 cm above the handle first, for a lift by
   * this one jaw.
   */
  const grab = async (side, { square = false } = {}) => {
    for (let attempt = 1; attempt <= 3; attempt++) {
      await page.evaluate(() => { window.__setButton(7, 0); window.__setButton(6, 1); }); // LT: open
      await page.waitForTimeout(900);
      await page.evaluate(() => { window.__setButton(6, 0); });
      await driveTo(side, above(side, 0.1), 0.03);
      if (square) await squareJaw(side);
      const e = await driveTo(side, above(side, 0), 0.015);
      await page.waitForTimeout(400); // let the hydraulics settle
      const still = await page.evaluate((s) => window.__seaarms.lastState.arms[s].contact, side);
      if (e > 0.03 || !still) continue;
      await page.evaluate(() => { window.__setButton(7, 1); }); // RT: close (kept pressed)
      try {
        await until(page, (s) => window.__seaarms.lastState.arms[s].holding, side, 4000);
        return attempt;
      } catch { /* slipped out of the capture radius: open and try again */ }
    }
    throw new Error(`${side} jaw could not grab its handle`);
  };
  return { setSticks, driveTo, selectArm, grab, squareJaw };
}

/**
 * Works the `dual-lift` exercise to its end through the page's own input path (FAKE_GAMEPAD,
 * padDriver), in the order of the autopilot script of exercises/dual-lift.json: left handle,
 * right handle, closed loop (gamepad X; RT stays pressed so both jaws grip), lift the box to
 * the height readout's target and hold it there. `onExercise(ex)` is called (and awaited in
 * the lift loop) with the polled frames' `exercise`. Returns when the frame says done.
 */
export async function workDualLift(page, onExercise = () => {}) {
  const { setSticks, selectArm, grab } = padDriver(page, (st) => { if (st.exercise) onExercise(st.exercise); });
  await page.evaluate(() => window.__connectPad());
  await selectArm('left');
  await grab('left');
  await selectArm('right');
  await grab('right');
  await until(page, () => window.__seaarms.lastState.exercise.step >= 2, undefined, 20000);
  await page.evaluate(() => window.__setButton(2, 1));
  await until(page, () => window.__seaarms.lastState.settings.control_method === 'closed');
  await page.evaluate(() => window.__setButton(2, 0));
  await until(page, () => window.__seaarms.lastState.exercise.step >= 3, undefined, 20000);
  // lift and hold: proportional control of the height readout (right stick Y = vz)
  const t0 = Date.now();
  while (Date.now() - t0 < 150000) {
    const ex = await page.evaluate(() => window.__seaarms.lastState.exercise);
    await onExercise(ex);
    if (ex.done) break;
    // the lift readout (its unit is the server's: m or cm)
    const h = ex.readouts.find((r) => /lift|height/i.test(r.label));
    if (h) {
      const e = (h.target - h.value) * ({ cm: 0.01, mm: 0.001 }[h.unit] ?? 1); // m
      await setSticks([0, 0, Math.abs(e) < 0.004 ? 0 : Math.max(-0.5, Math.min(0.5, e / 0.06))]);
    }
    await page.waitForTimeout(50);
  }
  await setSticks([0, 0, 0]);
}
