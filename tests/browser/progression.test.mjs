//! Progression in real Chromium (issue 30 item 4; docs/exercises.md "Progression"), on a server
//! of its own with `--progression on`: a new trainee's start screen shows the exercises whose
//! `requires` are not met with a lock and the reason, and they cannot be chosen; once in a
//! session, the "Exercises" screen gives the trainee's own state in the requirement; the
//! instructor unlocks reach-targets for them in the Classroom (their history's exercises), and
//! the trainee's screen then shows it open ("unlocked by your instructor") and it starts.
//! `cd tests/browser && SEAARMS_WEB_FROM_DISK=1 SEAARMS_BIN=<release binary> node --test
//! progression.test.mjs`.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { startServer, openBrowser, until, untilDrawn, ARTIFACTS, openClassroom } from './harness.mjs';

const SHOTS = process.env.SEAARMS_SHOTS || ARTIFACTS;
const ex = (id) => `#start .ex[data-id="${id}"]`;

test('progression: locks and reasons on the start screen; the instructor unlocks; it starts', { timeout: 180000 }, async () => {
  const srv = await startServer(['--progression', 'on']);
  const url = srv.url;
  const tag = Math.random().toString(36).slice(2, 7);
  const name = `Pat ${tag}`;
  const group = `prog-${tag}`;
  const t = await openBrowser({ viewport: { width: 1280, height: 1000 } });
  const instr = await openBrowser({ viewport: { width: 1280, height: 1000 } });
  const p = t.page;
  try {
    // a new browser: familiarisation open; reach-targets locked, with the reason, not choosable
    await p.goto(`${url}/`);
    await p.waitForSelector(ex('reach-targets'), { timeout: 15000 });
    await until(p, (s) => document.querySelector(s)?.classList.contains('locked'), ex('reach-targets'));
    assert.equal(await p.isDisabled(`${ex('reach-targets')} input`), true, 'a locked exercise cannot be chosen');
    assert.match(await p.textContent(`${ex('reach-targets')} .ex-lock`), /needs: proficiency in Joint familiarisation/);
    assert.match(await p.textContent(`${ex('hot-stab')} .ex-lock`), /needs: proficiency in Turn a panel valve/);
    assert.equal(await p.isDisabled(`${ex('familiarisation')} input`), false);
    assert.equal(await p.getAttribute(ex('familiarisation'), 'data-lock'), 'open');
    assert.equal(await p.isVisible('#start-locked'), true, 'the screen says how exercises open');
    await p.click(ex('reach-targets'), { force: true }); // a click on a locked card selects nothing
    assert.equal(await p.isDisabled('#start-exercise'), true);
    await p.screenshot({ path: join(SHOTS, 'progression-new-trainee.png') });

    // the trainee starts familiarisation
    await p.fill('#start-name', name);
    await p.fill('#start-group', group);
    await p.click(ex('familiarisation'));
    await p.click('#start-exercise');
    await until(p, () => window.__seaarms?.hello?.exercise?.id === 'familiarisation', undefined, 30000);
    await untilDrawn(p, { timeout: 30000 });

    // their own screen: reach-targets locked, their state in familiarisation given
    await p.click('#btn-exercises');
    await until(p, (s) => /you: not started yet/.test(document.querySelector(s)?.textContent || ''), `${ex('reach-targets')} .ex-lock`);
    assert.equal(await p.isDisabled(`${ex('reach-targets')} input`), true);
    await p.screenshot({ path: join(SHOTS, 'progression-own-locks.png') });
    await p.click('#start-back');

    // the instructor unlocks reach-targets for this trainee in the Classroom
    const ip = instr.page;
    await openClassroom(ip, url, group);
    const nameButton = `#roster button[data-history="${name}"]`;
    await ip.waitForSelector(nameButton, { timeout: 15000 });
    await ip.click(nameButton);
    const row = (id) => `#unlocks tr[data-exercise="${id}"]`;
    await ip.waitForSelector(`${row('reach-targets')}[data-status="locked"]`, { timeout: 15000 });
    assert.match(await ip.textContent(row('reach-targets')), /Joint familiarisation \(not started\)/);
    assert.equal(await ip.getAttribute(row('familiarisation'), 'data-status'), 'open');
    await ip.click(`${row('reach-targets')} button[data-unlock="1"]`);
    await ip.waitForSelector(`${row('reach-targets')}[data-status="unlocked"]`, { timeout: 15000 });
    assert.equal(await ip.textContent(`${row('reach-targets')} button`), 'Lock again');
    // the others stay locked for them
    assert.equal(await ip.getAttribute(row('pick-and-place'), 'data-status'), 'locked');
    await ip.screenshot({ path: join(SHOTS, 'progression-classroom-unlock.png') });

    // the trainee's screen shows it open, and it starts
    await p.click('#btn-exercises');
    await until(p, (s) => document.querySelector(s)?.dataset.lock === 'unlocked', ex('reach-targets'));
    assert.equal(await p.isDisabled(`${ex('reach-targets')} input`), false);
    assert.match(await p.textContent(`${ex('reach-targets')} .ex-lock`), /unlocked by your instructor/);
    assert.equal(await p.getAttribute(ex('pick-and-place'), 'data-lock'), 'locked');
    await p.screenshot({ path: join(SHOTS, 'progression-unlocked.png') });
    await p.click(ex('reach-targets'));
    await p.click('#start-exercise');
    await until(p, () => window.__seaarms?.hello?.exercise?.id === 'reach-targets', undefined, 30000);
    await untilDrawn(p, { timeout: 30000 });
    assert.deepEqual(t.errors.filter((e) => !/favicon/.test(e)), [], 'no console errors on the trainee page');
    assert.deepEqual(t.offsite, []);
  } finally {
    await t.close();
    await instr.close();
    srv.stop();
  }
});
