//! Ghosts in real Chromium (issue 30 item 5): a trainee works dual-lift to its end through the
//! page's own gamepad path, starts again and, during the live attempt, turns on the ghost "my
//! best" — the finished attempt is drawn see-through (the scene has its meshes, and pixels
//! around its jaw change against the frame before it was on), and it moves with the attempt's
//! clock: its drawn joint angles at two times are the server's track interpolated at those
//! times (computed here from GET /api/attempts/{id}/track), and they differ. The second attempt
//! is then finished too, and its debrief compares it with the first: the table shows both
//! attempts' scores (GET /api/attempts/{id}) and their difference B − A.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { server, openBrowser, until, untilDrawn, pressReady, FAKE_GAMEPAD, workDualLift, decodePng, ARTIFACTS } from './harness.mjs';

/** The track's joint angles at time t (linear between its samples, the last held). */
function trackQ(track, t) {
  const S = track.samples;
  let i = 0;
  while (i < S.length - 1 && S[i + 1].t <= t) i++;
  const a = S[i], b = S[Math.min(i + 1, S.length - 1)];
  const f = b.t > a.t ? Math.min(1, Math.max(0, (t - a.t) / (b.t - a.t))) : 0;
  return [0, 1].map((k) => a.arms[k].q.map((q, j) => q + f * (b.arms[k].q[j] - q)));
}

const maxDiff = (x, y) => Math.max(...x.flat().map((v, i) => Math.abs(v - y.flat()[i])));

test('a ghost of my best attempt is drawn during a live attempt, and the debrief compares two attempts', { timeout: 900000 }, async () => {
  const url = await server();
  const b = await openBrowser({ initScript: FAKE_GAMEPAD });
  const page = b.page;
  try {
    await page.goto(`${url}/?exercise=dual-lift`);
    await untilDrawn(page);
    const { session, token } = await page.evaluate(() => {
      const s = JSON.parse(localStorage.getItem('seaarms.session'));
      return { session: s.id, token: s.control_token };
    });
    const auth = { headers: { authorization: `Bearer ${token}` } };
    const ghosts = async () => (await fetch(`${url}/api/sessions/${session}/ghosts?exercise=dual-lift`, auth)).json();
    // nothing to show yet: the menu is there, without a best attempt
    await until(page, () => window.__seaarms.ghostChoices !== undefined && window.__seaarms.ghostChoices !== null);
    assert.equal(await page.inputValue('#sel-ghost'), 'none', 'off by default');
    assert.equal(await page.evaluate(() => window.__seaarms.ghostChoices.best), null);

    // the first attempt, to its end
    await pressReady(page);
    await workDualLift(page);
    await page.waitForSelector('#card:not([hidden]) [data-score]', { timeout: 30000 });
    let g;
    for (let i = 0; i < 40 && !(g = await ghosts()).best; i++) await page.waitForTimeout(250);
    assert.ok(g.best, `the finished attempt is the best: ${JSON.stringify(g)}`);
    const first = g.best.attempt;
    console.log(`first attempt ${first}: score ${g.best.score.toFixed(1)}, ${g.best.sim_seconds.toFixed(1)} s`);

    // try again: a new attempt, waiting for Ready; the menu now offers "my best"; the last
    // attempt's notice (e.g. "Done: …", shown 4 s) does not carry over into it
    const notice = await page.evaluate(() => { const e = document.getElementById('banner'); return e.hidden ? null : e.textContent; });
    await page.click('#card [data-act="again"]');
    // the task panel has taken the new attempt (its Ready button is back)
    await page.waitForSelector('#task .task-ready:not([hidden])', { timeout: 5000 });
    const left = await page.evaluate(() => { const e = document.getElementById('banner'); return e.hidden ? null : e.textContent; });
    console.log(`notice when trying again: ${JSON.stringify(notice)}; after: ${JSON.stringify(left)}`);
    assert.ok(left === null || left !== notice, `the finished attempt's notice ${JSON.stringify(notice)} is withdrawn (shown: ${JSON.stringify(left)})`);
    await pressReady(page);
    await until(page, (a) => window.__seaarms.ghostChoices?.best?.attempt === a, first);
    await page.uncheck('#chk-ell').catch(() => {});
    // the frame before: no ghost; wait until the best attempt's arms have moved off the start
    const track = await (await fetch(`${url}/api/attempts/${first}/track?session=${session}`, auth)).json();
    const moved = track.samples.findIndex((s) => maxDiff(s.arms.map((a) => a.q), track.samples[0].arms.map((a) => a.q)) > 0.3);
    assert.ok(moved > 0, 'the best attempt moves');
    const tMove = track.samples[moved].t + 1;
    await until(page, (t) => window.__seaarms.lastState.t > t, tMove, 60000);
    // small clips of the persp view where the ghost's jaws will be (the track's tool points
    // now), before and after it is turned on: a full screenshot decoded in the page takes longer
    // than the ghost stays put
    const tNow = await page.evaluate(() => window.__seaarms.lastState.t);
    const s0 = track.samples[Math.min(track.samples.length - 1, Math.round(tNow * 10))];
    const clips = [];
    for (const arm of s0.arms) {
      const at = await page.evaluate((p) => window.__seaarms.project('persp', p), arm.pose.slice(0, 3));
      clips.push({ x: Math.min(1240, Math.max(0, Math.round(at.x) - 20)), y: Math.min(760, Math.max(0, Math.round(at.y) - 20)), width: 40, height: 40 });
    }
    const before = [];
    for (const clip of clips) before.push(await page.screenshot({ clip }));
    await page.screenshot({ path: join(ARTIFACTS, 'ghost-off.png') });
    assert.equal((await page.evaluate(() => window.__seaarms.ghost())).meshes, 0, 'no ghost meshes while off');
    await page.selectOption('#sel-ghost', 'best');
    await until(page, (a) => window.__seaarms.ghost().attempt === a && window.__seaarms.ghost().t !== null, first);
    const on = await page.evaluate(() => ({ ghost: window.__seaarms.ghost(), t: window.__seaarms.lastState.t }));
    const after = [];
    for (const clip of clips) after.push(await page.screenshot({ clip }));
    assert.ok(on.ghost.meshes >= 20, `the scene has the ghost's meshes (${on.ghost.meshes})`);
    await page.screenshot({ path: join(ARTIFACTS, 'ghost-on.png') });
    // pixels around the ghost's jaws change (the live arms have not moved: no input)
    let changed = 0, probed = 0;
    for (let k = 0; k < clips.length; k++) {
      const [img0, img1] = [await decodePng(page, before[k]), await decodePng(page, after[k])];
      for (let i = 0; i < img0.data.length; i += 4) {
        probed++;
        if ([0, 1, 2].some((c) => Math.abs(img0.data[i + c] - img1.data[i + c]) > 12)) changed++;
      }
    }
    console.log(`ghost on at t = ${on.t.toFixed(2)} s (drawn at ${on.ghost.t.toFixed(2)} s): ${on.ghost.meshes} meshes; ${changed} of ${probed} pixels around its jaws changed`);
    assert.ok(changed >= 50, `the ghost shows in the persp view (${changed} of ${probed} pixels changed)`);

    // it moves with the clock, as the track says
    const at = async () => page.evaluate(() => window.__seaarms.ghost());
    const g1 = on.ghost;
    // a later time at which the track's pose differs from this one (the best attempt may
    // pause a moment, e.g. while a jaw closes), or its end
    const later = track.samples.find((s) => s.t > g1.t + 0.5 && maxDiff(trackQ(track, s.t), g1.q) > 0.05) || track.samples.at(-1);
    await until(page, (t) => window.__seaarms.ghost().t > t, later.t, 60000);
    const g2 = await at();
    for (const s of [g1, g2]) {
      const d = maxDiff(s.q, trackQ(track, s.t));
      assert.ok(d < 1e-9, `the ghost at t = ${s.t} is the track there (max |Δq| ${d})`);
    }
    console.log(`ghost at t = ${g1.t.toFixed(2)} s and ${g2.t.toFixed(2)} s (track ${track.duration_s.toFixed(1)} s): max |Δq| ${maxDiff(g1.q, g2.q).toFixed(4)} rad`);
    assert.ok(maxDiff(g1.q, g2.q) > 1e-3, 'the ghost moved between the two times');
    // N toggles it off and on
    await page.keyboard.press('n');
    await until(page, () => window.__seaarms.ghost().attempt === null);
    await page.keyboard.press('n');
    await until(page, (a) => window.__seaarms.ghost().attempt === a, first);

    // the second attempt, to its end (from open loop, as the first: the settings carry over
    // from the first attempt's closed loop); its debrief compares it with the first
    await page.selectOption('#sel-method', 'open');
    await until(page, () => window.__seaarms.lastState.settings.control_method === 'open');
    await workDualLift(page);
    await page.waitForSelector('#card:not([hidden]) [data-score]', { timeout: 30000 });
    for (let i = 0; i < 40 && (g = await ghosts()).attempts.length < 2; i++) await page.waitForTimeout(250);
    const second = g.attempts[0].attempt;
    assert.notEqual(second, first);
    const score = async (id) => (await (await fetch(`${url}/api/attempts/${id}`, auth)).json()).score;
    const [sa, sb] = [await score(second), await score(first)];
    await page.goto(`${url}/replay/${second}`);
    await page.waitForSelector('#rp-compare:not([hidden])', { timeout: 30000 });
    await page.selectOption('#sel-compare', first);
    await page.waitForSelector('#rp-compare-table tr[data-metric="score"]');
    const row = await page.evaluate(() => ({ ...document.querySelector('#rp-compare-table tr[data-metric="score"]').dataset }));
    console.log(`debrief of ${second} (score ${sa.toFixed(2)}) against ${first} (score ${sb.toFixed(2)}): ${JSON.stringify(row)}`);
    assert.equal(Number(row.a), sa, 'A is this attempt\'s score');
    assert.equal(Number(row.b), sb, 'B is the other attempt\'s score');
    assert.ok(Math.abs(Number(row.diff) - (sb - sa)) < 1e-9, 'the difference B − A');
    assert.equal(row.better, sb > sa ? 'B' : sb < sa ? 'A' : '=');
    const table = await page.innerText('#rp-compare-table');
    assert.match(table, /score/);
    await until(page, (a) => window.__seaarms.ghost()?.attempt === a && window.__seaarms.ghost().meshes > 0, first, 30000);
    await page.click('#rp-play');
    await page.waitForTimeout(2500);
    await page.screenshot({ path: join(ARTIFACTS, 'ghost-debrief.png') });
    const dg = await page.evaluate(() => ({ ghost: window.__seaarms.ghost(), t: window.__seaarms.replay.t }));
    assert.ok(dg.ghost.t > 0.5, `the debrief's ghost follows the replay's clock (t ${dg.ghost.t})`);
    assert.deepEqual(b.errors, []);
  } finally {
    await b.close();
  }
});
