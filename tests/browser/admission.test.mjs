// Session admission as the trainee page meets it (docs/api.md "Sessions"): a class join code
// from `?join=CODE` or typed into the page's prompt after a 403, and a clear message on a 429
// (per-client creation limit, with Retry-After). Each test starts its own release binary with
// the flags under test (tests/run.sh's shared server has no join code).

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { startServer, createSession, openBrowser, untilDrawn, ARTIFACTS } from './harness.mjs';

const CODE = 'reef-7341';
/** Console lines the browser logs for the deliberately refused POST /api/sessions. */
const refused = (status) => (e) => !new RegExp(`status of ${status}`).test(e);

test('join code: ?join=CODE creates a session; without it the prompt asks and the typed code starts one', { timeout: 90000 }, async () => {
  const srv = await startServer(['--join-code', CODE]);
  const a = await openBrowser();
  const b = await openBrowser();
  try {
    // The server really refuses a creation without the code (so frames below prove the code was sent).
    const bare = await fetch(`${srv.url}/api/sessions`, { method: 'POST', headers: { 'content-type': 'application/json' }, body: '{}' });
    assert.equal(bare.status, 403);

    await a.page.goto(`${srv.url}/?scenario=training&join=${encodeURIComponent(CODE)}`);
    await untilDrawn(a.page);
    assert.equal(await a.page.isHidden('#join'), true, 'no prompt when the URL carries the code');
    assert.deepEqual(a.errors, []);

    await b.page.goto(`${srv.url}/?scenario=training`);
    await b.page.waitForSelector('#join', { state: 'visible', timeout: 10000 });
    assert.equal(await b.page.isHidden('#join-error'), true, 'no "wrong code" line before a code was tried');
    assert.equal(await b.page.evaluate(() => window.__seaarms.connection.session), undefined, 'no session yet');
    await b.page.screenshot({ path: join(ARTIFACTS, 'join-prompt.png') });

    // A wrong code: asked again, with the "not accepted" line.
    await b.page.fill('#join-code', 'wrong-code');
    await b.page.click('#join button[type="submit"]');
    await b.page.waitForSelector('#join-error', { state: 'visible', timeout: 10000 });
    assert.equal(await b.page.isVisible('#join'), true);
    await b.page.screenshot({ path: join(ARTIFACTS, 'join-prompt-wrong.png') });

    await b.page.fill('#join-code', CODE);
    await b.page.click('#join button[type="submit"]');
    await untilDrawn(b.page);
    assert.equal(await b.page.isHidden('#join'), true, 'prompt gone once the session runs');
    const id = await b.page.evaluate(() => window.__seaarms.connection.session);
    const list = await (await fetch(`${srv.url}/api/sessions`, { headers: { authorization: `Bearer ${process.env.SEAARMS_INSTRUCTOR_TOKEN || 'test-token'}` } })).json();
    assert.ok(list.some((s) => s.id === id && s.status === 'live'), `session ${id} is live on the server`);
    assert.deepEqual(b.errors.filter(refused(403)), []);
    assert.deepEqual([...a.offsite, ...b.offsite], []);
  } finally {
    await a.close();
    await b.close();
    srv.stop();
  }
});

test('too many new sessions from one client: 429 gives a clear message with the retry time', { timeout: 60000 }, async () => {
  // One creation allowed at once, then one a minute: the REST creation below uses it up.
  const srv = await startServer(['--session-burst', '1', '--sessions-per-minute', '1']);
  const b = await openBrowser();
  try {
    await createSession(srv.url, { label: 'uses the burst' });
    await b.page.goto(`${srv.url}/?scenario=training`);
    await b.page.waitForFunction(() => /too many new sessions/i.test(document.querySelector('#banner').textContent), undefined, { timeout: 10000 });
    const text = await b.page.textContent('#banner');
    const secs = Number(/retrying in (\d+) s/i.exec(text)?.[1]);
    // Retry-After of a 1-per-minute bucket just emptied: between 1 and 60 s.
    assert.ok(secs >= 1 && secs <= 60, `banner gives the Retry-After wait: ${text}`);
    assert.deepEqual(b.errors.filter(refused(429)), []);
    assert.deepEqual(b.offsite, []);
  } finally {
    await b.close();
    srv.stop();
  }
});
