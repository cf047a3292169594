//! Keyboard taps move a bounded, repeatable amount (issue 28 item 2): in real Chromium, ten
//! 100 ms taps of an axis key at 25 % and at 100 % arm speed, each measured from the streamed
//! state before and after (the arm at rest), move the same amount each time — spread under
//! 0.5° for a joint in joint mode, under 0.5 cm for the jaw in Cartesian mode — close to the
//! step the server's jog takes (2° of a joint, 1 cm of the jaw, × the arm speed;
//! sim::Operator::jog). Before, a 100 ms tap moved rotate 12–16° and identical taps at 25 %
//! moved 2.4–7.2°.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { server, openBrowser, until, untilDrawn } from './harness.mjs';

/** Until the left arm is at rest (every joint speed below 0.2 mrad/s over a 100 ms window). */
async function atRest(page) {
  await page.waitForTimeout(150);
  await until(page, () => window.__seaarms.lastState.arms.left.qd.every((v) => Math.abs(v) < 2e-4), undefined, 10000);
}

async function taps(page, key, n, measure) {
  const out = [];
  for (let k = 0; k < n; k++) {
    await atRest(page);
    const before = await page.evaluate(measure);
    await page.keyboard.down(key);
    await page.waitForTimeout(100);
    await page.keyboard.up(key);
    await page.waitForTimeout(400);
    await atRest(page);
    const after = await page.evaluate(measure);
    out.push([before, after]);
  }
  return out;
}

const spread = (v) => Math.max(...v) - Math.min(...v);
const mean = (v) => v.reduce((a, b) => a + b, 0) / v.length;

test('ten 100 ms taps move a joint and the jaw by the same amount each time, at 25 % and 100 %', { timeout: 240000 }, async () => {
  const url = await server();
  const b = await openBrowser();
  try {
    await b.page.goto(`${url}/?scenario=training`);
    await untilDrawn(b.page);
    await b.page.click('#view'); // focus the page, not a control
    for (const speed of [0.25, 1]) {
      await b.page.selectOption('#sel-speed', String(speed));
      await until(b.page, (s) => window.__seaarms.lastState.settings.arm_speed === s, speed);
      // joint mode: wrist pitch up (R), then rotate (U)
      await b.page.selectOption('#sel-mode', 'joint');
      await until(b.page, () => window.__seaarms.lastState.settings.control_mode === 'joint');
      await b.page.click('#view');
      for (const [key, j] of [['KeyR', 3], ['KeyU', 5]]) {
        const d = (await taps(b.page, key, 10, () => window.__seaarms.lastState.arms.left.q))
          .map(([a, c]) => ((c[j] - a[j]) * 180) / Math.PI);
        console.log(`speed ${speed}, joint ${j + 1}: ${d.map((x) => x.toFixed(3)).join(' ')}°`);
        assert.ok(spread(d) < 0.5, `joint ${j + 1} at ${speed}: spread ${spread(d)}°`);
        assert.ok(Math.abs(mean(d) - 2 * speed) < 0.2 * speed, `joint ${j + 1} at ${speed}: ${mean(d)}° per tap`);
      }
      // Cartesian mode, the arm base frame (the sticks' x is the world's): up (W is axis 2, vy;
      // E is axis 3, vz)
      await b.page.selectOption('#sel-mode', 'cartesian');
      await b.page.selectOption('#sel-frame', 'base');
      await until(b.page, () => window.__seaarms.lastState.settings.control_mode === 'cartesian');
      await b.page.click('#view');
      const d = (await taps(b.page, 'KeyE', 10, () => window.__seaarms.lastState.arms.left.pose.position))
        .map(([a, c]) => 100 * (c[2] - a[2]));
      console.log(`speed ${speed}, jaw up: ${d.map((x) => x.toFixed(3)).join(' ')} cm`);
      assert.ok(spread(d) < 0.5, `jaw at ${speed}: spread ${spread(d)} cm`);
      assert.ok(Math.abs(mean(d) - speed) < 0.2 * speed, `jaw at ${speed}: ${mean(d)} cm per tap`);
    }
    assert.deepEqual(b.errors, []);
  } finally {
    await b.close();
  }
});
