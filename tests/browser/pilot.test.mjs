//! Seeing and driving as an ROV operator does (issue 28, the page's part): the pilot cameras
//! in murky water (lit panel in the lamps' cone, fog beyond; silt where the arm touches the
//! seabed), an exercise that allows only the pilot cameras, Cartesian sticks that follow the
//! active view (stick right moves the jaw right on that view), rumble on contact and slip,
//! and the phone's folded toolbar and scrolling task panel.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { server, openBrowser, until, untilDrawn, decodePng, FAKE_GAMEPAD, padDriver, ROOT, ARTIFACTS } from './harness.mjs';
import { rumbleFor, JAW_FORCE_FULL_N } from '../../web/rumble.js';

const rgbOf = (hex) => [(hex >> 16) & 255, (hex >> 8) & 255, hex & 255];
const dist = (a, b) => Math.hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
/** Mean colour of a (2r+1)² block of a decoded screenshot around (x, y) (CSS px = image px). */
function meanAt(img, x, y, r = 3) {
  const s = [0, 0, 0];
  let n = 0;
  for (let dy = -r; dy <= r; dy++) for (let dx = -r; dx <= r; dx++) {
    const i = 4 * (Math.round(y + dy) * img.width + Math.round(x + dx));
    for (let c = 0; c < 3; c++) s[c] += img.data[i + c];
    n++;
  }
  return s.map((v) => v / n);
}

/** Shows the pilot set's `name` view large (toolbar and the view's ⤢). */
async function pilotLarge(page, name = 'pilot') {
  await page.selectOption('#sel-views', 'pilot');
  await page.click(`.vp[data-view="${name}"] .vp-max`);
  await until(page, (n) => window.__seaarms.viewSet().single === n, name);
}

test('valve-turn through the pilot camera at 3 m visibility: the panel lit in the lamps\' cone, fog beyond (artifacts/pilot-view.png, copied to docs by hand)', { timeout: 90000 }, async () => {
  const url = await server();
  const b = await openBrowser();
  try {
    await b.page.goto(`${url}/?exercise=valve-turn`);
    await untilDrawn(b.page);
    await pilotLarge(b.page);
    await b.page.selectOption('#sel-visibility', '3');
    assert.equal((await b.page.evaluate(() => window.__seaarms.water())).visibility_m, 3);
    const n = await b.page.evaluate(() => window.__seaarms.framesRendered);
    await until(b.page, (k) => window.__seaarms.framesRendered > k + 5, n);
    const png = await b.page.screenshot({ path: join(ARTIFACTS, 'pilot-view.png') });
    const img = await decodePng(b.page, png);
    const { hello, panel, far } = await b.page.evaluate(() => {
      const h = window.__seaarms.hello;
      const p = h.scene.panel;
      // the panel's face 20 cm above the receptacle (plate, clear of the valve and the stab),
      // and the seabed 5 m ahead of the vehicle: past the visibility
      const face = [p.pose.position[0] - 0.005, p.pose.position[1] + 0.15, p.receptacle_m[2] + 0.2];
      // seabed points 4.5 m ahead across the view (the arms hide some of them)
      const far = [-1, -0.5, 0, 0.5, 1, 1.5, 2].map((y) => window.__seaarms.project('pilot', [4.5, y, h.seabed_z_m]));
      return { hello: h, panel: window.__seaarms.project('pilot', face), far };
    });
    const water = rgbOf(await b.page.evaluate(() => window.__seaarms.water().colour));
    const lit = meanAt(img, panel.x, panel.y);
    const inView = far.filter((p) => p.x > 300 && p.x < 1270 && p.y > 60 && p.y < 750);
    const beyond = inView.map((p) => meanAt(img, p.x, p.y)).sort((u, v) => dist(u, water) - dist(v, water))[0];
    console.log(`panel ${lit.map(Math.round)} at (${panel.x.toFixed(0)}, ${panel.y.toFixed(0)}), seabed 4.5 m ahead ${beyond.map(Math.round)} (best of ${inView.length}), water ${water}`);
    // the panel (yellow plate, #e8c547) stands out of the water: brighter and yellower
    assert.ok(dist(lit, water) > 60, `panel ${lit.map(Math.round)} too close to the water colour`);
    assert.ok(lit[0] > water[0] + 40 && lit[0] > lit[2], 'the panel is lit (red channel above the water\'s, yellow over blue)');
    // beyond the visibility the seabed is gone in the fog
    assert.ok(dist(beyond, water) < 20, `the seabed 4.5 m ahead ${beyond.map(Math.round)} is lost in the water ${water}`);
    assert.ok(hello.scene.panel, 'valve-turn has its panel');
    assert.deepEqual(b.errors, []);
  } finally {
    await b.close();
  }
});

test('a seabed touch in the pilot cameras raises a visible silt cloud', { timeout: 120000 }, async () => {
  const url = await server();
  const b = await openBrowser({ initScript: FAKE_GAMEPAD });
  try {
    await b.page.goto(`${url}/?scenario=training`);
    await untilDrawn(b.page);
    await b.page.evaluate(() => window.__connectPad());
    await pilotLarge(b.page, 'overview');
    await b.page.selectOption('#sel-visibility', '6');
    await b.page.selectOption('#sel-mode', 'cartesian');
    await until(b.page, () => window.__seaarms.lastState.settings.control_mode === 'cartesian');
    const { driveTo } = padDriver(b.page);
    const seabed = await b.page.evaluate(() => window.__seaarms.hello.seabed_z_m);
    // the left jaw over open seabed beside the box, then down
    await driveTo('left', (st) => [0.9, 1.05, seabed + 0.15], 0.03);
    await b.page.waitForTimeout(2500); // earlier puffs (if any) settle out of the picture
    const before = await b.page.evaluate(() => window.__seaarms.water());
    const png0 = await b.page.screenshot();
    const jaw = await b.page.evaluate(() => window.__seaarms.lastState.arms.left.pose.position);
    const at = await b.page.evaluate((p) => window.__seaarms.project('overview', p), [jaw[0], jaw[1], seabed]);
    await b.page.evaluate(() => { window.__pad.axes[3] = 1; }); // right stick down: vz −
    await until(b.page, () => window.__seaarms.water().siltEmitted > 0, undefined, 30000);
    await b.page.evaluate(() => { window.__pad.axes[3] = 0; });
    await b.page.waitForTimeout(700);
    const after = await b.page.evaluate(() => window.__seaarms.water());
    const png1 = await b.page.screenshot({ path: join(ARTIFACTS, 'pilot-silt.png') });
    const [i0, i1] = [await decodePng(b.page, png0), await decodePng(b.page, png1)];
    // pixels around the touch that changed; the jaw moved there too, so count only the silt's
    // sandy colour (#b3a27a: red over blue) newly present
    let silty = 0;
    for (let y = Math.round(at.y) - 60; y <= at.y + 60; y += 2) for (let x = Math.round(at.x) - 90; x <= at.x + 90; x += 2) {
      const k = 4 * (y * i1.width + x);
      const p0 = i0.data.slice(k, k + 3), p1 = i1.data.slice(k, k + 3);
      if (dist(p0, p1) > 25 && p1[0] > p1[2] + 15 && p1[1] > p1[2] && Math.abs(p1[0] - p1[1]) < 40) silty++; // not the orange arm
    }
    console.log(`silt particles: ${before.siltEmitted} → ${after.siltEmitted} emitted, ${after.siltAlive} alive; ${silty} sampled pixels turned sandy`);
    assert.ok(after.siltAlive > 50, `silt in the water (${after.siltAlive})`);
    assert.ok(silty > 20, `a visible silt cloud at the touch (${silty} sampled pixels turned sandy)`);
    assert.deepEqual(b.errors, []);
  } finally {
    await b.close();
  }
});

test('an exercise with "views": "pilot" (valve-turn) offers no orbit, top, front or side view', { timeout: 60000 }, async () => {
  const url = await server();
  const b = await openBrowser();
  try {
    await b.page.goto(`${url}/?exercise=valve-turn`);
    await untilDrawn(b.page);
    const vs = await b.page.evaluate(() => window.__seaarms.viewSet());
    assert.deepEqual(vs.allowed, ['pilot']);
    assert.equal(vs.set, 'pilot');
    assert.equal(await b.page.isDisabled('#sel-views option[value="engineering"]'), true);
    await b.page.keyboard.press('KeyC'); // the view-set key cannot bring them back
    await b.page.keyboard.press('KeyV');
    const shown = await b.page.evaluate(() => window.__seaarms.viewports().filter((v) => v.visible).map((v) => v.name));
    const engineering = ['top', 'front', 'side', 'persp'];
    assert.ok(shown.length > 0 && shown.every((n) => !engineering.includes(n)), `views shown: ${shown}`);
    for (const n of engineering) assert.equal(await b.page.isVisible(`.vp[data-view="${n}"]`), false, `${n} hidden`);
    // the work site (the panel) is framed
    const ws = await b.page.evaluate(() => window.__seaarms.workSite());
    assert.ok(ws && Math.max(...ws.max.map((v, i) => v - ws.min[i])) > 0.2, `work site box spans the panel: ${JSON.stringify(ws)}`);
    assert.deepEqual(b.errors, []);
  } finally {
    await b.close();
  }
});

/** Clip-space projection of world point p with a camera's world matrix and projection
 * (column-major 4×4, as three.js stores them): NDC x, y. */
function ndc(cam, p) {
  const w = cam.world, P = cam.projection;
  // camera ← world for a rigid world matrix: Rᵀ (p − t)
  const d = [p[0] - w[12], p[1] - w[13], p[2] - w[14]];
  const c = [0, 1, 2].map((i) => w[4 * i] * d[0] + w[4 * i + 1] * d[1] + w[4 * i + 2] * d[2]);
  const clip = [0, 1, 2, 3].map((r) => P[r] * c[0] + P[4 + r] * c[1] + P[8 + r] * c[2] + P[12 + r]);
  return [clip[0] / clip[3], clip[1] / clip[3]];
}

test('stick right in Cartesian mode (camera frame) moves the jaw right on the active view, for every camera', { timeout: 240000 }, async () => {
  const url = await server();
  const b = await openBrowser({ initScript: FAKE_GAMEPAD });
  try {
    await b.page.goto(`${url}/?scenario=training`);
    await untilDrawn(b.page);
    await b.page.evaluate(() => window.__connectPad());
    await b.page.selectOption('#sel-mode', 'cartesian');
    await until(b.page, () => window.__seaarms.lastState.settings.control_mode === 'cartesian');
    assert.equal(await b.page.inputValue('#sel-frame'), 'camera', 'the camera frame is the default');
    const cams = [['engineering', 'top'], ['engineering', 'front'], ['engineering', 'side'], ['engineering', 'persp'],
      ['pilot', 'pilot'], ['pilot', 'wrist-left'], ['pilot', 'wrist-right'], ['pilot', 'overview']];
    for (const [set, name] of cams) {
      await b.page.selectOption('#sel-views', set);
      await b.page.click(`.vp[data-view="${name}"]`); // a click (no drag) makes it the active view
      await until(b.page, (n) => window.__seaarms.viewSet().active === n, name);
      const cam = await b.page.evaluate((n) => window.__seaarms.cameraOf(n), name);
      const p0 = await b.page.evaluate(() => window.__seaarms.lastState.arms.left.pose.position);
      await b.page.evaluate(() => { window.__pad.axes[0] = 1; });
      await b.page.waitForTimeout(700);
      await b.page.evaluate(() => { window.__pad.axes[0] = 0; });
      await b.page.waitForTimeout(400);
      const p1 = await b.page.evaluate(() => window.__seaarms.lastState.arms.left.pose.position);
      // the jaw's projection with the camera as it was when the stick went right (a wrist camera
      // rides on the jaw: its picture of the jaw itself never moves)
      const [x0, y0] = ndc(cam, p0), [x1, y1] = ndc(cam, p1);
      const dx = (x1 - x0) * cam.rect.width / 2, dy = (y1 - y0) * cam.rect.height / 2;
      console.log(`${name}: jaw moved ${(100 * Math.hypot(...p1.map((v, i) => v - p0[i]))).toFixed(1)} cm, on screen dx ${dx.toFixed(1)} px, dy ${dy.toFixed(1)} px`);
      assert.ok(dx > 3, `${name}: the jaw moved right on screen (dx ${dx.toFixed(1)} px)`);
      assert.ok(dx > 2 * Math.abs(dy), `${name}: mostly right (dx ${dx.toFixed(1)}, dy ${dy.toFixed(1)} px)`);
      // back again, so every camera starts from about the same posture
      await b.page.evaluate(() => { window.__pad.axes[0] = -1; });
      await b.page.waitForTimeout(700);
      await b.page.evaluate(() => { window.__pad.axes[0] = 0; });
      await b.page.waitForTimeout(400);
    }
    assert.deepEqual(b.errors, []);
  } finally {
    await b.close();
  }
});

test('rumble: magnitudes follow the jaw force, slip and strikes (pure)', () => {
  const arm = (f, slipping = false, relief = false) => ({ contact_force_n: [f, 0, 0], slipping, relief_open: [relief, false, false, false, false, false] });
  assert.deepEqual(rumbleFor(arm(0), false), { strong: 0, weak: 0 });
  const half = rumbleFor(arm(JAW_FORCE_FULL_N / 2), false), full = rumbleFor(arm(2 * JAW_FORCE_FULL_N), false);
  assert.ok(half.strong > 0 && half.strong < full.strong && full.strong === 1, 'strong motor scales with the jaw force, capped at 1');
  assert.ok(rumbleFor(arm(0, true), false).weak > 0, 'slip buzzes the weak motor');
  assert.ok(rumbleFor(arm(0, false, true), false).weak > 0, 'an open relief valve buzzes the weak motor');
  assert.deepEqual(rumbleFor(arm(0), true), { strong: 1, weak: 1 }, 'a strike is a full jolt');
});

test('a spy on the pad\'s vibrationActuator.playEffect sees rumble on contact and on slip', { timeout: 180000 }, async () => {
  const url = await server();
  const spy = () => {
    window.__effects = [];
    const t = setInterval(() => {
      if (!window.__pad) return;
      clearInterval(t);
      window.__pad.vibrationActuator = { playEffect: (type, p) => { window.__effects.push({ type, ...p }); return Promise.resolve('complete'); } };
    }, 0);
  };
  const b = await openBrowser({ initScript: `(${FAKE_GAMEPAD})(); (${spy})();` });
  try {
    await b.page.goto(`${url}/?scenario=training`);
    await untilDrawn(b.page);
    await b.page.evaluate(() => window.__connectPad());
    await b.page.selectOption('#sel-mode', 'cartesian');
    await until(b.page, () => window.__seaarms.lastState.settings.control_mode === 'cartesian');
    const seen = { contact: false, slip: false };
    const { setSticks, selectArm, grab } = padDriver(b.page, () => {});
    await selectArm('right');
    await grab('right'); // one jaw, not squared: the hanging box twists out of it when lifted
    // lift with the one jaw: the jaw loads the box (contact force: the strong motor), then the
    // box's moment slips the grip (the weak motor)
    // every drawn frame is checked for the slip (it may last a few frames only)
    await b.page.evaluate(() => { window.__slipWatch = setInterval(() => { if (window.__seaarms.lastState?.arms.right.slipping) window.__slipSeen = true; }, 5); });
    const t0 = Date.now();
    while (Date.now() - t0 < 45000 && !seen.slip) {
      await setSticks([0, 0, 0.6]);
      await b.page.waitForTimeout(200);
      seen.slip = await b.page.evaluate(() => !!window.__slipSeen);
    }
    await b.page.waitForTimeout(300); // the slip's rumble follows its frame
    await setSticks([0, 0, 0]);
    const effects = await b.page.evaluate(() => window.__effects);
    const weak = effects.filter((e) => e.weakMagnitude >= 0.8).length;
    seen.contact = effects.some((e) => e.strongMagnitude > 0);
    console.log(`effects: ${effects.length} (${effects.filter((e) => e.strongMagnitude > 0).length} with the strong motor, ${weak} slip buzzes); slip in the frames: ${seen.slip}`);
    assert.ok(effects.every((e) => e.type === 'dual-rumble'));
    assert.ok(seen.contact, 'rumble on contact (the strong motor: a jaw force above 3 % of the clamp force)');
    assert.ok(seen.slip, 'the one-jaw lift slipped');
    assert.ok(weak > 0, 'rumble on slip (weak motor)');
    assert.deepEqual(b.errors, []);
  } finally {
    await b.close();
  }
});

test('phone 390×844: every toolbar control reachable from the folded toolbar; every task step visible by scrolling the panel only', { timeout: 60000 }, async () => {
  const url = await server();
  const b = await openBrowser({ viewport: { width: 390, height: 844 }, hasTouch: true, isMobile: true });
  try {
    await b.page.goto(`${url}/?exercise=familiarisation`); // 7 steps, the most
    await untilDrawn(b.page);
    await b.page.tap('#btn-tools');
    const hidden = await b.page.evaluate(() => [...document.querySelectorAll('#toolbar select, #toolbar input, #toolbar button')].filter((e) => {
      const r = e.getBoundingClientRect();
      if (r.width < 4 || r.height < 4) return true;
      if (r.left < 0 || r.right > innerWidth + 0.5 || r.top < 0 || r.bottom > innerHeight) return true;
      const hit = document.elementFromPoint(r.left + r.width / 2, r.top + r.height / 2);
      return !(hit === e || e.contains(hit) || hit?.closest('label')?.contains(e));
    }).map((e) => e.id));
    await b.page.screenshot({ path: join(ARTIFACTS, 'phone-toolbar.png') });
    assert.deepEqual(hidden, [], 'toolbar controls out of reach');
    await b.page.tap('#btn-tools'); // fold it again
    const steps = await b.page.evaluate(async () => {
      const panel = document.getElementById('task');
      const out = [];
      for (const li of panel.querySelectorAll('[data-step]')) {
        li.scrollIntoView({ block: 'nearest' });
        await new Promise((r) => requestAnimationFrame(r));
        const r = li.getBoundingClientRect(), p = panel.getBoundingClientRect();
        out.push({ inPanel: r.top >= p.top - 0.5 && r.bottom <= p.bottom + 0.5, onScreen: r.top >= 0 && r.bottom <= innerHeight,
          pageScrolled: document.scrollingElement.scrollTop });
      }
      return out;
    });
    await b.page.screenshot({ path: join(ARTIFACTS, 'phone-task.png') });
    assert.equal(steps.length, 7, 'familiarisation has 7 steps');
    steps.forEach((s, i) => {
      assert.ok(s.inPanel && s.onScreen, `step ${i + 1} visible in the panel (${JSON.stringify(s)})`);
      assert.equal(s.pageScrolled, 0, 'the page itself did not scroll');
    });
    const help = await b.page.evaluate(() => document.getElementById('help').textContent);
    assert.match(help, /on-screen sticks/);
    assert.deepEqual(b.errors, []);
  } finally {
    await b.close();
  }
});
