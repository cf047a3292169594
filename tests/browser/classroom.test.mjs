//! The instructor's classroom (issue 16 acceptance, browser part): two trainees who typed their
//! names on the start screen appear by name on the instructor's Classroom tab; one works the
//! dual-lift exercise to its end with the (scripted, fake) gamepad, and the instructor opens
//! that finished attempt from its history in the debrief page, where clicking an event marker
//! seeks the replay to the marker's time (± one frame) and 4× playback advances the replay
//! clock about four times faster than the wall clock (loosely: over 2×); a silent
//! fault reaches the session but not the trainee's page; an instructor's pause is shown to the
//! trainee as "Paused by the instructor" and the trainee's resume is refused (the clock stays
//! stopped) until the instructor resumes. Wire: CONTRACT/docs/api.md (attempts, replay socket,
//! roster fields, paused_by, silent faults).

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { readFile } from 'node:fs/promises';
import { server, startServer, openBrowser, until, untilDrawn, FAKE_GAMEPAD, workDualLift, INSTRUCTOR_TOKEN, ARTIFACTS, pressReady, openClassroom } from './harness.mjs';

const SHOTS = process.env.SEAARMS_SHOTS || ARTIFACTS;
const auth = { authorization: `Bearer ${INSTRUCTOR_TOKEN}` };

/** A trainee opens the page, types name and group on the start screen and starts `exercise`. */
async function startTrainee(url, name, group, exercise, opts = {}, query = '') {
  const b = await openBrowser(opts);
  await b.page.goto(`${url}/${query}`);
  await b.page.waitForSelector(`#start .ex[data-id="${exercise}"]`, { timeout: 15000 });
  // the name is required: free play without one is refused on the screen
  await b.page.fill('#start-name', '   ');
  await b.page.click('#start-free');
  assert.equal(await b.page.isVisible('#start-need'), true, 'a blank name is refused');
  await b.page.fill('#start-name', name);
  await b.page.fill('#start-group', group);
  await b.page.click(`#start .ex[data-id="${exercise}"]`);
  await b.page.click('#start-exercise');
  await until(b.page, (ex) => window.__seaarms?.hello?.exercise?.id === ex, exercise, 30000);
  const id = await untilDrawn(b.page, { timeout: 30000 });
  await pressReady(b.page);
  return { ...b, id };
}

async function summary(url, id) {
  return (await fetch(`${url}/api/sessions/${id}`, { headers: auth })).json();
}

test('classroom: named roster, attempt history → debrief (seek to a marker, 4× play), silent fault, instructor pause', { timeout: 480000 }, async () => {
  const url = await server();
  const tag = Math.random().toString(36).slice(2, 7);
  const group = `class-${tag}`;
  const [nameA, nameB] = [`Ada ${tag}`, `Brendan ${tag}`];
  const instr = await openBrowser({ viewport: { width: 1280, height: 900 } });
  const a = await startTrainee(url, nameA, group, 'dual-lift', { initScript: FAKE_GAMEPAD });
  // (B draws at 5 frames/s: less CPU taken from the replay's re-simulation on a loaded machine)
  const b = await startTrainee(url, nameB, group, 'reach-targets', {}, '?maxfps=5');
  const ip = instr.page;
  let debrief = null;
  try {
    // the sessions carry the names and the group typed on the start screen
    for (const [t, n] of [[a, nameA], [b, nameB]]) {
      const s = await summary(url, t.id);
      assert.equal(s.trainee, n);
      assert.equal(s.group, group);
    }
    assert.equal(await a.page.evaluate(() => localStorage.getItem('seaarms.trainee')), nameA, 'the name is remembered');

    // the instructor's Classroom tab lists both by name, in their group
    await openClassroom(ip, url, group);
    const row = (t) => `#roster tr[data-id="${t.id}"]`;
    await ip.waitForSelector(row(a), { timeout: 10000 });
    await ip.waitForSelector(row(b), { timeout: 10000 });
    assert.equal((await ip.textContent(`${row(a)} .cls-name`)).trim(), nameA);
    assert.equal((await ip.textContent(`${row(b)} .cls-name`)).trim(), nameB);
    assert.match(await ip.textContent(row(a)), /Cooperative lift/);
    assert.match(await ip.textContent(`${row(a)} td:nth-child(4)`), /^\d+\/5$/, 'step x/y of dual-lift\'s five');
    // issue 29: no token in a link (the sign-in cookie opens them); the export downloads
    assert.equal(await ip.getAttribute('#cls-export', 'href'), `/api/results.csv?group=${encodeURIComponent(group)}`);

    // Trainee A works dual-lift to its end with the gamepad (its completion card links the debrief)
    await workDualLift(a.page);
    await a.page.waitForSelector('#card:not([hidden]) [data-score]', { timeout: 20000 });
    const attemptA = (await summary(url, a.id)).attempts?.[0];
    assert.ok(attemptA, 'the session names its attempt');
    await a.page.waitForSelector('#card [data-act="debrief"]:not([hidden])', { timeout: 10000 });
    assert.equal(await a.page.getAttribute('#card [data-act="debrief"]', 'href'), `/replay/${attemptA}`);
    // issue 30: the card says where the reference operators' benchmark stands (none marked yet)
    await a.page.waitForSelector('#card [data-bench="none"]', { timeout: 10000 });
    assert.match(await a.page.textContent('#card [data-bench="none"]'), /No reference benchmark yet \(\d+ of the 5 reference operators' attempts it needs\)/);
    let recorded = null; // the recorder writes each second's batch: the attempt's end follows soon
    for (let i = 0; i < 100 && !recorded?.outcome; i++) {
      if (i) await new Promise((ok) => setTimeout(ok, 200));
      const r = await fetch(`${url}/api/attempts/${attemptA}`, { headers: auth });
      recorded = r.ok ? await r.json() : null;
    }
    assert.ok(recorded?.outcome === 'passed' || recorded?.outcome === 'failed', `finished: ${recorded?.outcome}`);
    assert.equal(recorded.replayable, true, recorded.replay_note);
    // "Export class results (CSV)" downloads in Chromium (it was a 403: the link passed
    // ?token= to a route that reads the header) with the finished attempt's row
    const [dl] = await Promise.all([ip.waitForEvent('download'), ip.click('#cls-export')]);
    assert.equal(await dl.failure(), null);
    const csv = await readFile(await dl.path(), 'utf8');
    assert.match(csv.split('\n')[0], /^trainee,group,exercise,attempt/, csv.slice(0, 200));
    assert.ok(csv.includes(attemptA), `the export lists ${attemptA}: ${csv}`);
    const hrefs = await ip.evaluate(() => [location.href, ...[...document.querySelectorAll('a[href]')].map((x) => x.href)]);
    for (const h of hrefs) assert.ok(!h.includes(INSTRUCTOR_TOKEN), `the instructor token in ${h}`);

    // the comparison on dual-lift (it follows the roster's exercise) has the trainee's score
    const cmpRow = `#compare tr[data-trainee="${nameA}"]`;
    await ip.waitForSelector(cmpRow, { timeout: 15000 });
    assert.equal(await ip.inputValue('#cmp-exercise'), 'dual-lift');
    assert.equal(await ip.textContent(`${cmpRow} td:nth-child(6)`), String(Math.round(recorded.score)), 'best score');
    assert.equal(await ip.textContent(`${cmpRow} td:nth-child(7)`), String(Math.round(recorded.score)), 'last score');
    // its proficiency (issue 30): one attempt is not proficiency (the LC-CUSUM needs twelve
    // passes at the default rates); the chart's value after one pass is ln(0.9/0.7) = 0.25
    const prof = await ip.textContent(`${cmpRow} td:nth-child(3)`);
    const chart = recorded.outcome === 'passed' ? '0.25/2.77' : '0.00/2.77';
    assert.equal(prof.replace(/\s+/g, ' ').trim(), `practising ${chart}`, prof);
    // reference operators (issue 30 item 1): the line under the table says no benchmark yet;
    // ticking A's "reference" box counts A's attempt toward it (and is stored: the API lists
    // A); unticking takes it back (the shared test server's other files see no reference)
    const benchCount = async () => +(/(\d+) finished attempts? by reference operators/.exec(await ip.textContent('#cmp-bench'))?.[1] ?? NaN);
    await until(ip, () => /No benchmark yet/.test(document.querySelector('#cmp-bench').textContent));
    const before = await benchCount();
    await ip.check(`${cmpRow} input.ref`);
    await until(ip, (n) => new RegExp(`No benchmark yet: ${n} finished attempts? by reference`).test(document.querySelector('#cmp-bench').textContent), before + 1, 10000);
    const refs = await (await fetch(`${url}/api/reference-operators`, { headers: auth })).json();
    assert.ok(refs.reference_operators.some((r) => r.trainee === nameA && r.group === group), JSON.stringify(refs));
    assert.equal(await ip.isChecked(`${cmpRow} input.ref`), true);
    await ip.uncheck(`${cmpRow} input.ref`);
    await until(ip, (n) => new RegExp(`No benchmark yet: ${n} finished attempts? by reference`).test(document.querySelector('#cmp-bench').textContent), before, 10000);

    // its history lists the attempt with its outcome and a debrief link (no token in it)
    await ip.click(`${row(a)} [data-history]`);
    const histRow = `#history tr[data-attempt="${attemptA}"]`;
    await ip.waitForSelector(`${histRow}[data-outcome="${recorded.outcome}"]`, { timeout: 20000 });
    assert.equal(await ip.textContent(`${histRow} td:nth-child(4)`), String(Math.round(recorded.score)), 'its score');
    assert.equal(await ip.getAttribute(`${histRow} a.debrief`, 'href'), `/replay/${attemptA}`);
    const [dp] = await Promise.all([instr.context.waitForEvent('page'), ip.click(`${histRow} a.debrief`)]);
    debrief = dp;
    const derrors = [];
    dp.on('pageerror', (e) => derrors.push(String(e)));
    dp.on('console', (m) => { if (m.type() === 'error') derrors.push(m.text()); });

    // the debrief page: the same four views, the replay's clock, the markers of the events
    await until(dp, () => window.__seaarms?.hello && window.__seaarms.replay.duration_s > 0, undefined, 30000);
    await untilDrawn(dp, { states: 0, open: false, timeout: 30000 });
    const info = await dp.evaluate(() => ({ views: window.__seaarms.viewports().length, hz: window.__seaarms.hello.frame_hz,
      d: window.__seaarms.replay.duration_s, events: window.__seaarms.attempt.events }));
    assert.equal(info.views, 4);
    // a replay has no live link: its status bar names the role and shows no latency
    const bar = await dp.evaluate(() => window.__seaarms.statusText());
    assert.match(bar, /role replay/);
    assert.doesNotMatch(bar, /latency/);
    assert.ok(info.d > 8, `the attempt lasted ${info.d} s`);
    const grasp = info.events.find((e) => e.kind === 'grasp' && e.t > 1);
    assert.ok(grasp, `a grasp event among ${JSON.stringify(info.events.map((e) => [e.kind, e.t]))}`);
    assert.ok(grasp.t < info.d, `grasp at ${grasp.t} s of ${info.d} s`);
    assert.equal(await dp.locator('.tl-mark').count(), info.events.length, 'one marker per event');
    assert.equal(await dp.getAttribute('#rp-card [data-score]', 'data-score'), String(Math.round(recorded.score)));
    assert.match(await dp.textContent('#rp-card'), recorded.outcome === 'passed' ? /Passed/ : /Not passed/);
    // pick the grasp's marker (a button: focused and pressed, since a marker a few ms away
    // may be drawn over it): the replay seeks there (± one frame)
    const frame = 1 / info.hz;
    const marker = `.tl-mark[data-kind="grasp"][data-t="${grasp.t}"]`;
    await dp.locator(marker).press('Enter');
    await until(dp, ([t, f]) => { const r = window.__seaarms.replay; return r.seeks === 1 && Math.abs(r.t - t) <= f + 1e-9; }, [grasp.t, frame]);
    assert.match(await dp.textContent('#rp-time'), /^\d+:\d\d\.\d \/ \d+:\d\d\.\d$/);
    // a click on the bar seeks too (to its fraction of the duration)
    const box = await dp.locator('.tl-track').boundingBox();
    await dp.mouse.click(box.x + box.width * 0.25, box.y + box.height - 2); // below the markers
    await until(dp, ([d, f]) => { const r = window.__seaarms.replay; return r.seeks === 2 && Math.abs(r.t - 0.25 * d) <= 0.01 * d + f; }, [info.d, frame]);
    await dp.locator(marker).press('Enter'); // back to the grasp
    await until(dp, ([t, f]) => Math.abs(window.__seaarms.replay.t - t) <= f + 1e-9, [grasp.t, frame]);
    // play at 4×: the replay's clock runs about four times the wall clock (loosely: over 2×)
    await dp.selectOption('#rp-speed', '4');
    await until(dp, () => window.__seaarms.replay.speed === 4);
    await dp.click('#rp-play');
    await until(dp, () => window.__seaarms.replay.playing);
    const s1 = await dp.evaluate(() => ({ t: window.__seaarms.replay.t, w: performance.now() }));
    await dp.waitForTimeout(1500);
    const s2 = await dp.evaluate(() => ({ t: window.__seaarms.replay.t, w: performance.now(), playing: window.__seaarms.replay.playing }));
    const rate = (s2.t - s1.t) / ((s2.w - s1.w) / 1000);
    console.log(`replay at 4×: ${(s2.t - s1.t).toFixed(2)} s of attempt in ${((s2.w - s1.w) / 1000).toFixed(2)} s wall (${rate.toFixed(2)}×)`);
    assert.ok(rate > 2, `4× playback ran at ${rate.toFixed(2)}×`);
    assert.ok(s2.t <= info.d + 1e-9);
    assert.match(await dp.textContent('#rp-play'), s2.playing ? /Pause/ : /Play/);
    // the screenshot: the five seconds up to the lift's step event (keyboard: Shift+← seeks −5 s),
    // played at 4× and paused there
    if (s2.playing) await dp.click('#rp-play');
    await until(dp, () => !window.__seaarms.replay.playing);
    const lift = info.events.filter((e) => e.kind === 'exercise').at(-2) ?? grasp;
    await dp.locator(`.tl-mark[data-t="${lift.t}"]`).first().click();
    await until(dp, (t) => Math.abs(window.__seaarms.replay.t - t) < 0.1, lift.t);
    await dp.keyboard.press('Shift+ArrowLeft');
    await until(dp, (t) => Math.abs(window.__seaarms.replay.t - Math.max(0, t - 5)) < 0.1, lift.t);
    await dp.click('#rp-play');
    await until(dp, (t) => window.__seaarms.replay.t >= t, lift.t, 20000);
    await dp.click('#rp-play');
    await until(dp, () => !window.__seaarms.replay.playing);
    await dp.waitForTimeout(500);
    await dp.screenshot({ path: join(SHOTS, 'debrief.png') });
    assert.deepEqual(derrors, []);


    // a silent fault on trainee B: the instructor sees it, the trainee's page shows nothing
    await ip.click(`${row(b)} [data-observe]`);
    await until(ip, (id) => window.__seaarms?.hello?.session === id, b.id);
    await untilDrawn(ip, { open: false });
    await ip.selectOption('#act-fault', 'leak');
    await ip.check('#act-silent');
    await ip.click('#instr-actions button[data-act="fault"]');
    await until(ip, () => /fault \(silent\): ok/.test(document.querySelector('#act-result').textContent));
    await ip.waitForFunction((r) => /leak/.test(document.querySelector(`${r} td.warn`).textContent), row(b), { timeout: 10000 });
    const sb = await summary(url, b.id);
    assert.ok((sb.faults || []).some((f) => typeof f === 'object' && f.silent), `the summary marks it silent: ${JSON.stringify(sb.faults)}`);
    const n0 = await b.page.evaluate(() => window.__seaarms.connection.framesReceived);
    await until(b.page, (n) => window.__seaarms.connection.framesReceived > n + 30, n0);
    const seen = await b.page.evaluate(() => ({ faults: window.__seaarms.lastState.faults, status: window.__seaarms.statusText(),
      banner: document.querySelector('#banner').hidden ? '' : document.querySelector('#banner').textContent }));
    assert.deepEqual(seen.faults, [], 'no fault in the trainee\'s frames');
    assert.doesNotMatch(seen.status, /leak|fault/i, 'nor on its status bar');
    assert.doesNotMatch(seen.banner, /leak|fault/i, 'nor in a banner');

    // the instructor pauses trainee B from the roster: the trainee sees why and cannot resume
    await ip.click(`${row(b)} .cls-acts button[data-act="pause"]`);
    await until(b.page, () => window.__seaarms.lastState.paused && window.__seaarms.lastState.paused_by === 'instructor');
    await b.page.waitForSelector('#paused-note:not([hidden])');
    assert.equal((await b.page.textContent('#paused-note')).trim(), 'Paused by the instructor');
    await until(b.page, () => document.getElementById('btn-pause').disabled);
    await ip.waitForSelector(`${row(b)}[data-paused="instructor"]`);
    const tStop = await b.page.evaluate(() => window.__seaarms.lastState.t);
    await b.page.keyboard.press('p'); // the trainee's pause key: a resume the server refuses
    await b.page.waitForFunction(() => /instructor/i.test(document.querySelector('#banner').textContent) && !document.querySelector('#banner').hidden, undefined, { timeout: 5000 });
    const n1 = await b.page.evaluate(() => window.__seaarms.connection.framesReceived);
    await until(b.page, (n) => window.__seaarms.connection.framesReceived > n + 20, n1);
    const after = await b.page.evaluate(() => ({ t: window.__seaarms.lastState.t, paused: window.__seaarms.lastState.paused }));
    assert.equal(after.paused, true, 'still paused');
    assert.equal(after.t, tStop, 'the clock stayed stopped');
    await ip.waitForSelector(`${row(b)} .cls-acts button[data-act="resume"]`);
    await b.page.screenshot({ path: join(SHOTS, 'trainee-paused-by-instructor.png') });
    await ip.screenshot({ path: join(SHOTS, 'classroom.png') }); // (the silent fault still listed)
    await ip.click('#instr-actions button[data-act="clear_faults"]');
    await ip.click(`${row(b)} .cls-acts button[data-act="resume"]`);
    await until(b.page, () => !window.__seaarms.lastState.paused);
    await until(b.page, () => document.getElementById('paused-note').hidden && !document.getElementById('btn-pause').disabled);

    // "New session" ends the old session first (it does not linger live and empty)
    await a.page.click('#btn-new');
    await until(a.page, (old) => window.__seaarms.connection.open && window.__seaarms.connection.session !== old, a.id, 20000);
    const old = await summary(url, a.id);
    assert.equal(old.status, 'ended', `the old session: ${JSON.stringify(old)}`);
    const fresh = await summary(url, await a.page.evaluate(() => window.__seaarms.connection.session));
    assert.equal(fresh.trainee, nameA, 'the new session keeps the name');
    assert.equal(fresh.group, group);

    // in the new session, A opens the exercises: the start screen draws A's learning curve
    // on dual-lift from the records of the earlier session (issue 30) — one point, filled
    // for a pass — and the state
    await a.page.click('#btn-exercises');
    const slot = '#start [data-progress="dual-lift"]:not([hidden])';
    await a.page.waitForSelector(slot, { timeout: 10000 });
    assert.match(await a.page.textContent(slot), new RegExp(`practising\\s*1 attempt, last ${Math.round(recorded.score)}`));
    assert.equal(await a.page.locator(`${slot} circle.${recorded.outcome === 'passed' ? 'pass' : 'fail'}`).count(), 1);
    assert.equal(await a.page.locator('#start .ex-progress:not([hidden])').count(), 1, 'no curve where there is no attempt');
    await a.page.locator(slot).scrollIntoViewIfNeeded();
    await a.page.screenshot({ path: join(SHOTS, 'start-progress.png') });
    // "Back to my session" closes it and keeps the session
    const kept = await a.page.evaluate(() => window.__seaarms.connection.session);
    await a.page.click('#start-back');
    await a.page.waitForSelector('#start', { state: 'hidden' });
    await a.page.waitForTimeout(500);
    assert.equal(await a.page.evaluate(() => window.__seaarms.connection.session), kept);

    for (const t of [a, b, instr]) assert.deepEqual(t.errors, [], 'console errors');
    for (const t of [a, b, instr]) assert.deepEqual(t.offsite, []);
  } finally {
    await debrief?.close();
    for (const t of [a, b]) await fetch(`${url}/api/sessions/${t.id}`, { method: 'DELETE', headers: auth }).catch(() => {});
    await a.close();
    await b.close();
    await instr.close();
  }
});

test('a session abandoned while the page was away: the page says why it ended when the trainee comes back', { timeout: 90000 }, async () => {
  const own = await startServer(['--abandon-grace-seconds', '1']); // its own server: a short grace
  const b = await openBrowser();
  try {
    await b.page.goto(`${own.url}/?scenario=training`);
    const id = await untilDrawn(b.page);
    // the tab goes away (its socket closes); the same browser comes back after the grace
    const page2 = await b.context.newPage();
    await b.page.close();
    let s = null;
    for (let i = 0; i < 100 && s?.status !== 'ended'; i++) {
      await new Promise((ok) => setTimeout(ok, 100));
      s = await (await fetch(`${own.url}/api/sessions/${id}`, { headers: auth })).json();
    }
    assert.equal(s.status, 'ended');
    assert.match(s.end_reason, /left|abandon/i);
    await page2.goto(`${own.url}/`);
    await page2.waitForSelector('#start .start-note');
    assert.equal(await page2.textContent('#start .start-note'), `Your previous session ended: ${s.end_reason}.`);
  } finally {
    await b.close();
    own.stop();
  }
});
