//! A (fake) gamepad drives the selected arm through the page's own input path: the page sends
//! steady 50 Hz input with increasing sequence numbers, the server's streamed q changes, and the
//! drawn arm follows.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { server, openBrowser, until, untilDrawn, FAKE_GAMEPAD, ARTIFACTS } from './harness.mjs';

test('a gamepad stick moves a joint: streamed q changes and the drawn arm moves', { timeout: 60000 }, async () => {
  const url = await server();
  const b = await openBrowser({ initScript: FAKE_GAMEPAD });
  try {
    await b.page.goto(`${url}/?scenario=training`);
    await untilDrawn(b.page);
    await b.page.evaluate(() => window.__connectPad());
    await until(b.page, () => window.__seaarms.statusText().includes('Fake pad'));
    // the status bar names the pad (not a cut-off id); the whole id is its tooltip
    const padField = await b.page.$eval('#status [data-f="pad"]', (e) => ({ text: e.textContent, title: e.title }));
    assert.deepEqual(padField, { text: 'gamepad: Fake pad', title: 'Fake pad (STANDARD GAMEPAD)' });
    const before = await b.page.evaluate(() => ({
      q: window.__seaarms.lastState.arms.left.q, drawnQ: window.__seaarms.drawnJointAngles()[0],
      jaw: window.__seaarms.drawnJawCentres()[0], limits: window.__seaarms.hello.arms[0].model.joints[0].limits,
      seq: window.__seaarms.lastInput?.seq ?? 0,
    }));
    // swing (joint 1, left stick X) away from its nearer limit
    const [lo, hi] = before.limits || [-1, 1];
    const dir = before.q[0] - lo > hi - before.q[0] ? -1 : 1;
    await b.page.evaluate((d) => { window.__pad.axes[0] = d; }, dir);
    await until(b.page, (d) => window.__seaarms.lastInput?.arms.left.axes[0] === d, dir);
    const tSend = Date.now();
    await b.page.waitForTimeout(1500);
    await b.page.evaluate(() => { window.__pad.axes[0] = 0; });
    const after = await b.page.evaluate(() => ({
      q: window.__seaarms.lastState.arms.left.q, drawnQ: window.__seaarms.drawnJointAngles()[0],
      jaw: window.__seaarms.drawnJawCentres()[0], seq: window.__seaarms.lastInput.seq,
      inputSeq: window.__seaarms.lastState.input_seq,
    }));
    await b.page.screenshot({ path: join(ARTIFACTS, 'gamepad-moved.png') });
    // every hydraulic cylinder's rod end is drawn on the arm: within the cylinder's sideways
    // mounting offset (7.5 cm, web/arms.js) plus its rod radius of the link polyline, not
    // beyond a short link's end (the 0.25 m pitch link) or past the jaw
    const rods = await b.page.evaluate(() => window.__seaarms.drawnRods());
    const toSegment = (p, a, c) => {
      const d = c.map((v, i) => v - a[i]), w = p.map((v, i) => v - a[i]);
      const t = Math.max(0, Math.min(1, (w[0] * d[0] + w[1] * d[1] + w[2] * d[2]) / Math.max(1e-12, d[0] ** 2 + d[1] ** 2 + d[2] ** 2)));
      return Math.hypot(...w.map((v, i) => v - t * d[i]));
    };
    rods.forEach(({ links, rodEnds }, arm) => rodEnds.forEach((e, k) => {
      const off = Math.min(...links.slice(1).map((c, i) => toSegment(e, links[i], c)));
      assert.ok(off < 0.09, `arm ${arm} cylinder ${k + 1}: rod end ${off.toFixed(3)} m off the links`);
    }));
    const dq = after.q[0] - before.q[0];
    assert.ok(dir * dq > 0.05, `swing moved ${dq} rad (wanted sign ${dir})`);
    for (let i = 1; i < 6; i++) assert.ok(Math.abs(after.q[i] - before.q[i]) < Math.abs(dq), `joint ${i + 1} moved less than the swing`);
    assert.ok(Math.abs(after.drawnQ[0] - before.drawnQ[0]) > 0.05, 'drawn swing angle changed');
    const moved = Math.hypot(...after.jaw.map((v, i) => v - before.jaw[i]));
    assert.ok(moved > 0.03, `drawn jaws moved ${moved} m`);
    // steady input stream with increasing sequence numbers, applied by the server
    // 50 Hz nominal; the achieved rate is printed, not asserted (it is a timing figure)
    const rate = (after.seq - before.seq) / ((Date.now() - tSend) / 1000 + 0.5);
    console.log(`input messages: ${rate.toFixed(1)} per second (50 Hz nominal)`);
    assert.ok(after.seq > before.seq + 1, `the page kept sending inputs (${after.seq - before.seq})`);
    assert.ok(after.inputSeq > before.seq, 'server applied the page\'s input seq');
    // the page's dead zone: a small stick deflection sends 0
    await b.page.evaluate(() => { window.__pad.axes[0] = 0.08; });
    await b.page.waitForTimeout(100);
    assert.equal(await b.page.evaluate(() => window.__seaarms.lastInput.arms.left.axes[0]), 0);
    await b.page.evaluate(() => { window.__pad.axes[0] = 0; });
    assert.deepEqual(b.errors, []);
  } finally {
    await b.close();
  }
});

test('keyboard fallback: arm select, joint keys and grip', { timeout: 60000 }, async () => {
  const url = await server();
  const b = await openBrowser();
  try {
    await b.page.goto(`${url}/?scenario=training`);
    await untilDrawn(b.page);
    await b.page.keyboard.press('Digit2');
    assert.equal(await b.page.evaluate(() => window.__seaarms.selectedArm), 'right');
    const q0 = await b.page.evaluate(() => window.__seaarms.lastState.arms.right.q);
    await b.page.keyboard.down('KeyE'); // elbow +
    await b.page.keyboard.down('KeyX'); // open the jaw
    await until(b.page, () => window.__seaarms.lastInput?.arms.right.axes[2] === 1 && window.__seaarms.lastInput.arms.right.grip === 1);
    await b.page.waitForTimeout(1200);
    await b.page.keyboard.up('KeyE');
    await b.page.keyboard.up('KeyX');
    const q1 = await b.page.evaluate(() => window.__seaarms.lastState.arms.right.q);
    assert.ok(Math.abs(q1[2] - q0[2]) > 0.03, `right elbow moved ${q1[2] - q0[2]} rad`);
    await until(b.page, () => window.__seaarms.lastInput.arms.right.axes.every((v) => v === 0));
    // help overlay
    await b.page.keyboard.press('Shift+Slash');
    assert.equal(await b.page.isVisible('#help'), true);
    await b.page.keyboard.press('KeyH');
    assert.equal(await b.page.isVisible('#help'), false);
    await b.page.keyboard.press('Digit1');
    assert.deepEqual(b.errors, []);
  } finally {
    await b.close();
  }
});

test('the keyboard keeps driving after clicking a checkbox or a menu (trial finding, issue 15)', { timeout: 60000 }, async () => {
  const url = await server();
  const b = await openBrowser();
  try {
    await b.page.goto(`${url}/?scenario=training`);
    await untilDrawn(b.page);
    const held = async (what) => {
      await b.page.keyboard.down('KeyE');
      try {
        await until(b.page, () => window.__seaarms.lastInput?.arms.left.axes[2] === 1, undefined, 3000);
      } catch { assert.fail(`after ${what}, holding E did not send elbow + (focus on ${await b.page.evaluate(() => document.activeElement?.id)})`); }
      await b.page.keyboard.up('KeyE');
      await until(b.page, () => window.__seaarms.lastInput.arms.left.axes[2] === 0);
    };
    await b.page.click('#chk-poly');
    await b.page.click('#chk-poly');
    await held('clicking the polytopes checkbox');
    // focus left on a checkbox and a button (e.g. reached with Tab) does not take the keys
    await b.page.focus('#chk-ell');
    await held('focusing the ellipsoids checkbox');
    await b.page.focus('#btn-layout');
    await held('focusing a button');
    // a focused menu does not take the letter either (no type-ahead to "cartesian" on C/E…)
    await b.page.focus('#sel-mode');
    await held('focusing the control-mode menu');
    assert.equal(await b.page.inputValue('#sel-mode'), 'joint');
    assert.deepEqual(b.errors, []);
  } finally {
    await b.close();
  }
});
