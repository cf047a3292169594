//! A new trainee picks `dual-lift` on the start screen, sees the goal and the handles, drives
//! the fake gamepad through the page's own input path (the steps of exercises/dual-lift.json,
//! in the order of its autopilot script: left handle, right handle, closed loop, lift 0.2 m,
//! hold) and sees the completion card with the server's score (issue 15 item 5).

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { server, openBrowser, until, untilDrawn, pressReady, FAKE_GAMEPAD, workDualLift, ROOT, INSTRUCTOR_TOKEN, instructorAction } from './harness.mjs';

const SHOTS = process.env.SEAARMS_SHOTS || join(ROOT, 'tests', 'browser', 'artifacts');

test('dual-lift: start screen, task panel, handles, scripted gamepad through the steps, completion card', { timeout: 600000 }, async () => {
  const url = await server();
  const b = await openBrowser({ initScript: FAKE_GAMEPAD });
  const page = b.page;
  try {
    await page.goto(`${url}/`);
    // the start screen: name, the server's exercises with their goals, free play
    await page.waitForSelector('#start .ex[data-id="dual-lift"]', { timeout: 15000 });
    const list = await (await fetch(`${url}/api/exercises`)).json();
    const spec = list.exercises.find((e) => e.id === 'dual-lift');
    assert.ok((await page.innerText('#start')).includes(spec.goal), 'the goal is on the start screen');
    assert.equal(await page.isDisabled('#start-exercise'), true, 'nothing picked yet');
    await page.fill('#start-name', 'Ada');
    await page.click('#start .ex[data-id="dual-lift"]');
    await page.screenshot({ path: join(SHOTS, 'start-screen.png') });
    await page.click('#start-exercise');
    await until(page, () => window.__seaarms?.hello?.exercise?.id === 'dual-lift');
    await untilDrawn(page);
    // the attempt waits for "Ready": its clock reads 0 while the trainee reads the goal
    await page.waitForTimeout(1000);
    const waiting = await page.evaluate(() => window.__seaarms.lastState);
    assert.equal(waiting.awaiting_ready, true);
    assert.equal(waiting.exercise.elapsed_s, 0);
    assert.equal(await page.isVisible('#task .task-ready'), true);
    await pressReady(page);
    await until(page, () => window.__seaarms.lastState.exercise.elapsed_s > 0.2);
    assert.equal(await page.isVisible('#task .task-ready'), false);
    // the session carries the trainee's name (what the instructor sees)
    const sid = await page.evaluate(() => window.__seaarms.connection.session);
    const summary = await (await fetch(`${url}/api/sessions/${sid}`, { headers: { authorization: 'Bearer test-token' } })).json().catch(() => null);
    if (summary && summary.label !== undefined) assert.equal(summary.label, 'Ada');
    // the task panel: goal and steps; the handles drawn on the box
    assert.equal(await page.isVisible('#task'), true);
    const panel = await page.innerText('#task');
    assert.ok(panel.includes(spec.goal), 'goal in the task panel');
    for (const s of spec.steps) assert.ok(panel.includes(s.text), `step "${s.text}" listed`);
    const scene = await page.evaluate(() => window.__seaarms.drawnScene());
    // the two side bars and the lifting point over the centre of mass (handle 2, issue 27)
    assert.equal(scene.handles.length, 3, 'every handle drawn');
    const expected = await page.evaluate(() => {
      const st = window.__seaarms.lastState, h = window.__seaarms.hello.scene.handles_m;
      const { position: p, rotation: r } = st.object.pose;
      return h.map((v) => [0, 1, 2].map((k) => p[k] + r[k][0] * v[0] + r[k][1] * v[1] + r[k][2] * v[2]));
    });
    scene.handles.forEach((h, i) => assert.ok(Math.hypot(...h.at.map((v, k) => v - expected[i][k])) < 1e-6, `handle ${i} drawn at ${h.at}`));
    assert.equal(await page.evaluate(() => window.__seaarms.lastState.settings.control_mode), 'cartesian', 'the exercise set Cartesian mode');

    const steps = [];
    // the drawn capture cue (a handle's sphere lit while a jaw is within grasp range), sampled in the page
    await page.evaluate(() => {
      window.__cues = new Set();
      setInterval(() => window.__seaarms.drawnScene().handles.forEach((h, i) => { if (h.capture) window.__cues.add(`${i}:${h.capture}`); }), 20);
    });
    let shot = false;
    await workDualLift(page, async (ex) => {
      if (!steps.includes(ex.step)) steps.push(ex.step);
      if (!shot && ex.step === 4 && ex.readouts.some((r) => r.label === 'Hold' && r.value > 1.5)) {
        shot = true;
        await page.screenshot({ path: join(SHOTS, 'task-panel.png') });
      }
    });
    const cues = await page.evaluate(() => [...window.__cues].sort());
    assert.deepEqual(cues, ['0:left', '1:right'], 'each handle lit for its jaw before the grasp (and no other)');
    await page.waitForSelector('#card:not([hidden]) [data-score]', { timeout: 20000 });
    await page.waitForTimeout(300);
    await page.screenshot({ path: join(SHOTS, 'completion-card.png') });
    const token = await page.evaluate(() => JSON.parse(localStorage.getItem('seaarms.session')).control_token);
    const a = await (await fetch(`${url}/api/sessions/${sid}/assessment`, { headers: { authorization: `Bearer ${token}` } })).json();
    console.log(`dual-lift by gamepad: steps seen ${steps.join(',')}, score ${a.score.toFixed(1)}, passed ${a.passed}, time ${a.time_s.toFixed(1)} s`);
    assert.ok(a.done && a.completed, `the attempt completed: ${JSON.stringify(a.failed_because)}`);
    const card = await page.innerText('#card');
    assert.equal(await page.getAttribute('#card [data-score]', 'data-score'), String(Math.round(a.score)), 'the card shows the server\'s score');
    assert.match(card, a.passed ? /Passed/ : /Not passed/);
    for (const t of a.terms) assert.ok(card.includes(t.metric.split('_')[0]), `metric ${t.metric} on the card`);
    // the card links the finished attempt's debrief with no token in its URL; this browser's
    // session cookie opens it (issue 29 item 6)
    await page.waitForSelector('#card [data-act="debrief"]:not([hidden])', { timeout: 10000 });
    const attempt = (await (await fetch(`${url}/api/sessions/${sid}`, { headers: { authorization: `Bearer ${token}` } })).json()).attempts[0];
    assert.equal(await page.getAttribute('#card [data-act="debrief"]', 'href'), `/replay/${attempt}`);
    await page.goto(`${url}/replay/${attempt}`);
    await until(page, () => window.__seaarms?.hello && window.__seaarms.replay.duration_s > 0, undefined, 30000);
    assert.deepEqual(b.errors, []);
  } finally {
    await b.close();
  }
});

test('an instructor\'s scenario or exercise switch takes effect on the trainee\'s page (issue 15 item 6)', { timeout: 90000 }, async () => {
  const url = await server();
  const b = await openBrowser();
  const page = b.page;
  const act = (id, body) => instructorAction(url, id, body);
  try {
    await page.goto(`${url}/?scenario=training`);
    await untilDrawn(page);
    const id = await page.evaluate(() => window.__seaarms.connection.session);
    const other = await page.evaluate(() => window.__seaarms.hello.scenarios.map((s) => s.name).find((n) => n !== 'training'));
    await act(id, { type: 'scenario', scenario: other });
    await until(page, (n) => window.__seaarms.hello.scenario === n && window.__seaarms.lastState.scenario === n, other);
    assert.equal(await page.inputValue('#sel-scenario'), other, 'the scenario menu shows the instructor\'s choice');
    assert.equal(await page.isVisible('#task'), false, 'no task panel outside exercises');
    await act(id, { type: 'scenario', scenario: 'dual-lift' });
    await until(page, () => window.__seaarms.hello.exercise?.id === 'dual-lift');
    await page.waitForSelector('#task:not([hidden])');
    assert.match(await page.innerText('#task'), /Cooperative lift|dual/i);
    assert.equal((await page.evaluate(() => window.__seaarms.drawnScene())).handles.length, 3);
    assert.equal(await page.evaluate(() => window.__seaarms.connection.session), id, 'the same session');
    assert.deepEqual(b.errors, []);
  } finally {
    await b.close();
  }
});

test('fault drill: the page offers the four answers and the server records the one clicked', { timeout: 90000 }, async () => {
  const url = await server();
  const b = await openBrowser();
  const page = b.page;
  try {
    await page.goto(`${url}/?exercise=fault-diagnosis`);
    await until(page, () => window.__seaarms?.hello?.exercise?.id === 'fault-diagnosis');
    await untilDrawn(page, { open: false });
    await pressReady(page);
    const buttons = await page.$$eval('#task [data-answer]', (bs) => bs.map((b) => b.dataset.answer));
    assert.deepEqual(buttons, ['supply_drop', 'stuck_valve', 'leak', 'air']);
    // at 1280×800 the answers are in sight without scrolling, beside the line-pressure plots
    // and the gauges the drill is diagnosed from (issue 28 item 6)
    const layout = await page.evaluate(() => ({
      answers: [...document.querySelectorAll('#task [data-answer]')].map((b) => b.getBoundingClientRect().bottom),
      plots: !document.getElementById('plots').hidden && document.getElementById('plots').getBoundingClientRect().height > 200,
      gauges: document.getElementById('gauges').getBoundingClientRect().bottom <= innerHeight,
      vh: innerHeight,
    }));
    assert.ok(layout.answers.every((y) => y <= layout.vh), `answers at ${layout.answers} of ${layout.vh}`);
    assert.ok(layout.plots && layout.gauges, JSON.stringify(layout));
    await page.click('#task [data-answer="leak"]');
    const sid = await page.evaluate(() => window.__seaarms.connection.session);
    let a = null;
    for (let i = 0; i < 50 && a?.diagnosis?.answer !== 'leak'; i++) {
      await page.waitForTimeout(100);
      a = await (await fetch(`${url}/api/sessions/${sid}/assessment`, { headers: { authorization: `Bearer ${INSTRUCTOR_TOKEN}` } })).json();
    }
    assert.equal(a.diagnosis.answer, 'leak', JSON.stringify(a));
    assert.equal(await page.isDisabled('#task [data-answer="air"]'), true, 'one answer only');
    // The hidden fault is never listed in the trainee's frames.
    const faults = await page.evaluate(() => window.__seaarms.lastState.faults);
    assert.deepEqual(faults, []);
  } finally {
    await b.close();
  }
});

test('a link to another exercise starts that exercise, not the stored session (found by the trainee trial), for the same trainee', { timeout: 60000 }, async () => {
  const url = await server();
  const b = await openBrowser();
  try {
    // the trainee types name and group on the start screen
    await b.page.goto(`${url}/`);
    await b.page.waitForSelector('#start .ex[data-id="reach-targets"]', { timeout: 15000 });
    await b.page.fill('#start-name', 'Grace Hopper');
    await b.page.fill('#start-group', 'link-test');
    await b.page.click('#start .ex[data-id="reach-targets"]');
    await b.page.click('#start-exercise');
    await until(b.page, () => window.__seaarms?.lastState?.exercise?.id === 'reach-targets', undefined, 20000);
    const first = await b.page.evaluate(() => JSON.parse(localStorage.getItem('seaarms.session')).id);
    await b.page.goto(`${url}/?exercise=valve-turn`);
    await until(b.page, () => window.__seaarms?.lastState?.exercise?.id === 'valve-turn', undefined, 20000);
    const second = await b.page.evaluate(() => JSON.parse(localStorage.getItem('seaarms.session')).id);
    assert.notEqual(second, first, 'a new session');
    const r = await fetch(`${url}/api/sessions/${first}`, { headers: { authorization: `Bearer ${INSTRUCTOR_TOKEN}` } });
    assert.equal((await r.json()).status, 'ended', 'the stored one was ended, not left live and empty');
    // the new page load knew the trainee only from the stored session: the new one is theirs
    const s2 = await (await fetch(`${url}/api/sessions/${second}`, { headers: { authorization: `Bearer ${INSTRUCTOR_TOKEN}` } })).json();
    assert.deepEqual([s2.trainee, s2.group], ['Grace Hopper', 'link-test'], 'recorded under the trainee who followed the link');
    // the same link again resumes it
    await b.page.goto(`${url}/?exercise=valve-turn`);
    await until(b.page, () => window.__seaarms?.lastState?.exercise?.id === 'valve-turn', undefined, 20000);
    assert.equal(await b.page.evaluate(() => JSON.parse(localStorage.getItem('seaarms.session')).id), second);
    assert.deepEqual(b.errors, []);
  } finally {
    await b.close();
  }
});
