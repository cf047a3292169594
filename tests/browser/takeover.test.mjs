//! "Take over from here" (issue 30 item 5): a trainee drives an exercise attempt with the fake
//! gamepad and abandons it, opens its debrief (the browser's session cookie opens it), seeks to
//! t = 2 s, clicks "Take over from here": the trainee page opens on the new live practice
//! attempt, waiting for Ready, and the joint angles (and every other number of the arms'
//! state) of its frame equal the debrief's frame at t exactly; after Ready its clock runs on
//! from t. Both read from the pages' own state (web/view.js debug hooks).

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { server, openBrowser, until, untilDrawn, pressReady, FAKE_GAMEPAD, ROOT, INSTRUCTOR_TOKEN } from './harness.mjs';

const SHOTS = process.env.SEAARMS_SHOTS || join(ROOT, 'tests', 'browser', 'artifacts');

/** The arms' state numbers of a frame: q, q̇, line pressures of both arms. */
const armState = (s) => ['left', 'right'].map((a) => ({ q: s.arms[a].q, qd: s.arms[a].qd, p_in: s.arms[a].p_in, p_out: s.arms[a].p_out }));

test('take over from here: the live practice attempt starts at the debrief frame, bit for bit', { timeout: 240000 }, async () => {
  const url = await server();
  const b = await openBrowser({ initScript: FAKE_GAMEPAD });
  const page = b.page;
  try {
    await page.goto(`${url}/?exercise=reach-targets`);
    await until(page, () => window.__seaarms?.hello?.exercise?.id === 'reach-targets');
    await untilDrawn(page);
    await pressReady(page);
    // drive: the left stick pushed for about 3 s of the attempt
    await page.evaluate(() => { window.__connectPad(); window.__pad.axes[0] = 0.7; window.__pad.axes[1] = -0.5; });
    await until(page, () => window.__seaarms.lastState.t > 3.2, undefined, 20000);
    await page.evaluate(() => { window.__pad.axes[0] = 0; window.__pad.axes[1] = 0; });
    const stored = await page.evaluate(() => JSON.parse(localStorage.getItem('seaarms.session')));
    // abandon it: the session ends (as a trainee who leaves)
    const del = await fetch(`${url}/api/sessions/${stored.id}`, { method: 'DELETE', headers: { authorization: `Bearer ${stored.control_token}` } });
    assert.ok(del.ok, `DELETE: ${del.status}`);
    let attempt = null;
    for (let i = 0; i < 50 && !attempt?.outcome; i++) {
      const r = await fetch(`${url}/api/attempts?session=${stored.id}`, { headers: { authorization: `Bearer ${INSTRUCTOR_TOKEN}` } });
      attempt = (await r.json()).attempts[0];
      if (!attempt?.outcome) await new Promise((ok) => setTimeout(ok, 200));
    }
    assert.equal(attempt.outcome, 'abandoned');

    // the debrief, opened by this browser's cookie; seek to 2 s (→ twice)
    await page.goto(`${url}/replay/${attempt.id}`);
    await until(page, () => window.__seaarms?.hello && window.__seaarms.replay.duration_s > 0, undefined, 30000);
    await until(page, () => !document.getElementById('rp-takeover').disabled);
    await page.keyboard.press('ArrowRight');
    // (the simulation's clock sums 1 ms steps: 1 s within rounding)
    await until(page, () => Math.abs(window.__seaarms.replay.t - 1) < 1e-6 && Math.abs(window.__seaarms.lastState?.t - 1) < 1e-6, undefined, 30000);
    await page.keyboard.press('ArrowRight');
    await until(page, () => Math.abs(window.__seaarms.replay.t - 2) < 1e-6 && Math.abs(window.__seaarms.lastState?.t - 2) < 1e-6, undefined, 30000);
    const atT = await page.evaluate(() => window.__seaarms.lastState);
    assert.notDeepEqual(atT.arms.left.q, [0, 0, 0, 0, 0, 0]);
    await page.screenshot({ path: join(SHOTS, 'takeover-debrief.png') });

    // take over: the trainee page opens on the practice attempt, waiting for Ready
    await Promise.all([page.waitForURL(`${url}/`, { timeout: 30000 }), page.click('#rp-takeover')]);
    await until(page, () => window.__seaarms?.lastState?.practice && window.__seaarms.connection?.open, undefined, 30000);
    const first = await page.evaluate(() => window.__seaarms.lastState);
    assert.equal(first.awaiting_ready, true);
    assert.equal(first.practice.attempt, attempt.id);
    assert.equal(first.practice.t, 2);
    assert.equal(first.t, atT.t);
    assert.deepEqual(armState(first), armState(atT), 'the live frame equals the debrief frame at t');
    assert.deepEqual(first.object.pose, atT.object.pose);
    assert.equal(await page.isVisible('#task .task-practice'), true);
    assert.match(await page.innerText('#task .task-practice'), /Practice from attempt .* at 2\.0 s/);
    const now = await page.evaluate(() => JSON.parse(localStorage.getItem('seaarms.session')));
    assert.notEqual(now.id, stored.id, 'the new session is the stored one');
    await page.screenshot({ path: join(SHOTS, 'takeover-live.png') });
    // Ready: the clock runs on from t
    await pressReady(page);
    await until(page, () => window.__seaarms.lastState.t > 2.3, undefined, 15000);
    assert.deepEqual(b.errors, []);
    assert.deepEqual(b.offsite, []);
  } finally {
    await b.close();
  }
});
