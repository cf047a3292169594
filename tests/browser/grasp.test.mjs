//! A scripted grasp, driven through the page's own input path (a fake gamepad in Cartesian
//! mode, steered by a proportional controller in this test that reads the streamed state),
//! turns the object from neutral to black (one jaw holds it on the seabed), light blue (lifted)
//! and yellow (both jaws hold it), and the page draws those colours.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { server, openBrowser, until, FAKE_GAMEPAD, stick, decodePng, classify, ARTIFACTS } from './harness.mjs';

// Handle grasp points in the object frame (server/core grasp: bars 3 cm above the top face at
// y = ±0.15, left arm at +y; capture radius 4 cm).
const HANDLE_Y = { left: 0.15, right: -0.15 };
const HANDLE_ABOVE_TOP_M = 0.03;
const COLOUR_NAME = { free: 'grey', one_on_surface: 'black', one_lifted: 'lightblue', one_holding_other_contact: 'red', both_holding: 'yellow' };

function handleWorld(state, hello, side) {
  const { position: p, rotation: r } = state.object.pose;
  const h = [0, HANDLE_Y[side], hello.object.size_m[2] / 2 + HANDLE_ABOVE_TOP_M];
  return [0, 1, 2].map((i) => p[i] + r[i][0] * h[0] + r[i][1] * h[1] + r[i][2] * h[2]);
}

test('scripted grasp: object turns black, light blue, yellow as drawn', { timeout: 420000 }, async () => {
  const url = await server();
  const b = await openBrowser({ initScript: FAKE_GAMEPAD });
  const page = b.page;
  const seen = [];
  const snap = async (name) => {
    const st = await page.evaluate(() => ({ grasp: window.__seaarms.lastState.grasp, colour: window.__seaarms.drawnObjectColour(), at: window.__seaarms.project('persp', window.__seaarms.lastState.object.pose.position) }));
    const png = await page.screenshot({ path: join(ARTIFACTS, `grasp-${name}.png`) });
    const img = await decodePng(page, png);
    const votes = {};
    for (let dy = -4; dy <= 4; dy += 2) for (let dx = -4; dx <= 4; dx += 2) {
      const i = 4 * (Math.round(st.at.y + dy) * img.width + Math.round(st.at.x + dx));
      const c = classify(img.data.slice(i, i + 3));
      votes[c] = (votes[c] || 0) + 1;
    }
    return { ...st, votes };
  };
  const setSticks = (v) => page.evaluate(([a0, a1, a3]) => { const p = window.__pad; p.axes[0] = a0; p.axes[1] = a1; p.axes[3] = a3; }, [stick(v[0]), -stick(v[1]), -stick(v[2])]);
  /** Cartesian P control of one arm's tool point to `target(state)` (world, m). */
  const driveTo = async (side, target, tol = 0.02, timeoutMs = 90000) => {
    const t0 = Date.now();
    let err = [1, 1, 1];
    while (Date.now() - t0 < timeoutMs) {
      const { st, hello } = await page.evaluate(() => ({ st: window.__seaarms.lastState, hello: window.__seaarms.hello }));
      if (!seen.includes(st.grasp)) seen.push(st.grasp);
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
  try {
    await page.goto(`${url}/?scenario=training`);
    await until(page, () => window.__seaarms?.statesDrawn > 2 && window.__seaarms.connection.open);
    await page.uncheck('#chk-ell'); // sample the object's own colour, not through an ellipsoid
    await page.evaluate(() => window.__connectPad());
    const first = await snap('free');
    assert.equal(first.grasp, 'free');
    assert.equal(first.colour, 0xb4b4b4);
    // Cartesian mode (gamepad Y), left arm (LB), open the jaw (LT)
    await page.evaluate(() => { window.__setButton(3, 1); });
    await until(page, () => window.__seaarms.lastState.settings.control_mode === 'cartesian');
    await page.evaluate(() => { window.__setButton(3, 0); window.__setButton(4, 1); window.__setButton(6, 1); });
    await page.waitForTimeout(1000);
    await page.evaluate(() => { window.__setButton(4, 0); window.__setButton(6, 0); });

    const above = (side, dz) => (st, hello) => { const h = handleWorld(st, hello, side); h[2] += dz; return h; };
    const selectArm = async (side) => {
      const btn = side === 'left' ? 4 : 5; // LB / RB
      await page.evaluate((i) => window.__setButton(i, 1), btn);
      await until(page, (s) => window.__seaarms.selectedArm === s, side);
      await page.evaluate((i) => window.__setButton(i, 0), btn);
    };
    /** Opens the jaw, brings the tool point onto its handle, closes; retries if it slips. */
    const grab = async (side) => {
      for (let attempt = 1; attempt <= 3; attempt++) {
        await page.evaluate(() => { window.__setButton(7, 0); window.__setButton(6, 1); }); // LT: open
        await page.waitForTimeout(900);
        await page.evaluate(() => { window.__setButton(6, 0); });
        await driveTo(side, above(side, 0.1), 0.03);
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
    await grab('left');
    await until(page, () => window.__seaarms.lastState.grasp === 'one_on_surface', undefined, 20000);
    await page.waitForTimeout(300);
    const black = await snap('one_on_surface');
    // lift: +vz, jaw kept closed
    await setSticks([0, 0, 0.6]);
    await until(page, () => window.__seaarms.lastState.grasp === 'one_lifted', undefined, 30000);
    await setSticks([0, 0, 0]);
    await page.waitForTimeout(300);
    const blue = await snap('one_lifted');
    // right arm (RB); the left jaw, now sent grip 0, stays closed on its handle
    await selectArm('right');
    await grab('right');
    await until(page, () => window.__seaarms.lastState.grasp === 'both_holding', undefined, 20000);
    await page.waitForTimeout(300);
    const yellow = await snap('both_holding');
    await page.check('#chk-ell'); // the picture for docs/screenshot.png: dual ellipsoid on the object
    await page.waitForTimeout(500);
    await page.screenshot({ path: join(ARTIFACTS, 'showcase.png') });
    await page.evaluate(() => { window.__setButton(7, 0); });
    const dual = await page.evaluate(() => ({ dual: window.__seaarms.lastState.dual, text: window.__seaarms.statusText() }));
    console.log(`grasp states seen: ${seen.join(' → ')}`);
    for (const s of [black, blue, yellow]) {
      assert.equal(s.colour, { one_on_surface: 0x000000, one_lifted: 0x7fd4ff, both_holding: 0xffd700 }[s.grasp], `${s.grasp} material colour`);
      assert.ok((s.votes[COLOUR_NAME[s.grasp]] || 0) >= 8, `${s.grasp} drawn ${JSON.stringify(s.votes)} at ${JSON.stringify(s.at)}`);
    }
    assert.ok(dual.dual, 'dual ellipsoid present while both hold');
    assert.ok(dual.text.includes(dual.dual.measures.yoshikawa.toFixed(4)), 'dual measures in the status bar');
    assert.deepEqual(b.errors, []);
  } finally {
    await b.close();
  }
});
