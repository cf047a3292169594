//! The per-trainee logbook (issue 30 item 7, browser part): the instructor opens a trainee's
//! logbook from the Classroom's attempt history ("Logbook"), signs off an exercise there and
//! the page shows the sign-off; the print stylesheet hides the toolbar and the buttons and
//! prints black on white; no request carries a token in its URL (the sign-in cookie opens the
//! page's data). Wire: docs/api.md "Logbook and sign-off".

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { server, openBrowser, createSession, INSTRUCTOR_TOKEN, ARTIFACTS, UNNAMED_CONTROLS, openClassroom } from './harness.mjs';

/** Records every CSP violation a page reports (as csp.test.mjs). */
const WATCH_CSP = () => {
  window.__csp = [];
  document.addEventListener('securitypolicyviolation', (e) => window.__csp.push(`${e.violatedDirective} ${e.blockedURI}`));
};

const SHOTS = process.env.SEAARMS_SHOTS || ARTIFACTS;

test('logbook: opened from the Classroom, signed off, printable, no token in a URL', { timeout: 120000 }, async () => {
  const url = await server();
  const tag = Math.random().toString(36).slice(2, 7);
  const group = `log-${tag}`;
  const name = `Ada ${tag}`;
  const s = await createSession(url, { trainee: name, group, exercise: 'reach-targets' });
  const instr = await openBrowser({ viewport: { width: 1280, height: 900 }, initScript: WATCH_CSP });
  const urls = [];
  instr.context.on('request', (r) => urls.push(r.url()));
  // console errors and uncaught errors of every page of the context (the logbook opens in a new tab)
  const errors = [];
  instr.context.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  instr.context.on('weberror', (e) => errors.push(String(e.error())));
  const ip = instr.page;
  try {
    await openClassroom(ip, url, group);
    const row = `#roster tr[data-id="${s.id}"]`;
    await ip.waitForSelector(row, { timeout: 10000 });
    await ip.click(`${row} .cls-name button`);
    await ip.waitForSelector('#cls-history:not([hidden])');
    await ip.screenshot({ path: join(SHOTS, 'logbook-classroom.png') });
    const href = await ip.getAttribute('#hist-logbook', 'href');
    assert.equal(href, `/logbook?${new URLSearchParams({ trainee: name, group })}`);
    // the attempt is recorded within the recorder's second; then the logbook has it
    const [lp] = await Promise.all([instr.context.waitForEvent('page'), ip.click('#hist-logbook')]);
    await lp.waitForLoadState();
    await lp.waitForSelector('#lb-table tr[data-exercise="reach-targets"]', { timeout: 10000 });
    assert.equal(await lp.textContent('#lb-name'), `${name} (${group})`);
    assert.match((await lp.evaluate(() => fetch(location.href).then((r) => r.headers.get('content-security-policy')))) || '', /default-src 'self'/);
    assert.deepEqual(await lp.evaluate(UNNAMED_CONTROLS), [], 'every control is named');
    const cells = await lp.$$eval('#lb-table tr[data-exercise="reach-targets"] td', (tds) => tds.map((t) => t.textContent.trim()));
    assert.equal(cells[3], '0 / 1', 'one attempt, running: none finished');
    assert.equal(cells[7], 'not started', 'no finished attempt: the proficiency state is not started');

    // sign off reach-targets: the page shows the assessor and the note, the API has it
    await lp.fill('#lb-assessor', 'R. Assessor');
    await lp.fill('#lb-note', 'observed on the simulator');
    await lp.click('#lb-table tr[data-exercise="reach-targets"] button[data-sign]');
    await lp.waitForSelector('#lb-table tr[data-exercise="reach-targets"] button[data-revoke]', { timeout: 10000 });
    const signed = await lp.textContent('#lb-table tr[data-exercise="reach-targets"] .lb-signoff');
    assert.match(signed, /R\. Assessor/);
    assert.match(signed, /observed on the simulator/);
    assert.match(signed, /^\d{4}-\d\d-\d\d \d\d:\d\d/, 'an ISO 8601 date');
    const api = await (await fetch(`${url}/api/logbook?${new URLSearchParams({ trainee: name, group })}`, {
      headers: { authorization: `Bearer ${INSTRUCTOR_TOKEN}` },
    })).json();
    const entry = api.exercises.find((e) => e.exercise === 'reach-targets');
    assert.equal(entry.signoff.assessor, 'R. Assessor');
    await lp.screenshot({ path: join(SHOTS, 'logbook-screen.png'), fullPage: true });

    // print: no toolbar, no buttons, black on white
    assert.equal(await lp.isVisible('#toolbar'), true);
    await lp.emulateMedia({ media: 'print' });
    assert.equal(await lp.isVisible('#toolbar'), false, 'the toolbar is not printed');
    assert.equal(await lp.isVisible('#lb-table button'), false, 'nor the sign-off buttons');
    const colours = await lp.evaluate(() => {
      const b = getComputedStyle(document.body);
      return [b.backgroundColor, b.color];
    });
    assert.deepEqual(colours, ['rgb(255, 255, 255)', 'rgb(0, 0, 0)']);
    await lp.screenshot({ path: join(SHOTS, 'logbook-print.png'), fullPage: true });

    // the cookie opened everything: no token in any URL
    const leaked = urls.filter((u) => u.includes(INSTRUCTOR_TOKEN) || /[?&]token=/.test(u));
    assert.deepEqual(leaked, []);
    assert.deepEqual(errors, []);
    assert.deepEqual(await lp.evaluate(() => window.__csp), [], 'no CSP violation');
  } finally {
    await instr.close();
  }
});
