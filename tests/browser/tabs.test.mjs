//! A second tab of the same trainee (trial finding, issue 15): it must not join as a second
//! trainee whose zero input fights the first tab's. It asks; "Watch" connects read-only and the
//! first tab keeps driving alone; "Take control" turns the first tab into the watcher.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { server, openBrowser, until, untilDrawn } from './harness.mjs';

/** Input sequence numbers the server applied (state frames' `input_seq`), sampled for `ms`. */
async function appliedSeqs(page, ms) {
  return page.evaluate(async (ms) => {
    const seen = [];
    const t0 = performance.now();
    while (performance.now() - t0 < ms) {
      seen.push(window.__seaarms.lastReceived.input_seq);
      await new Promise((r) => setTimeout(r, 20));
    }
    return seen;
  }, ms);
}

test('a second tab asks, watches without sending, and can take control', { timeout: 90000 }, async () => {
  const url = await server();
  const b = await openBrowser();
  try {
    const one = b.page;
    await one.goto(`${url}/?scenario=training`);
    await untilDrawn(one);
    assert.equal(await one.evaluate(() => window.__seaarms.hello.role), 'trainee');
    const session = await one.evaluate(() => window.__seaarms.connection.session);

    const two = await b.context.newPage();
    two.on('pageerror', (e) => b.errors.push(String(e)));
    await two.goto(`${url}/`);
    await two.waitForSelector('#tabs [data-choice="watch"]', { timeout: 10000 });
    assert.match(await two.innerText('#tabs'), /Another tab is driving this session/);
    await two.click('#tabs [data-choice="watch"]');
    await untilDrawn(two);
    assert.equal(await two.evaluate(() => window.__seaarms.hello.role), 'observer');
    assert.equal(await two.evaluate(() => window.__seaarms.connection.session), session, 'the same session');

    // tab one drives the elbow; the server applies only tab one's input sequence
    await one.keyboard.down('KeyE');
    await until(one, () => window.__seaarms.lastInput?.arms.left.axes[2] === 1);
    const seq0 = await one.evaluate(() => window.__seaarms.lastInput.seq);
    const q0 = await one.evaluate(() => window.__seaarms.lastState.arms.left.q[2]);
    const seen = await appliedSeqs(one, 1500);
    const seq1 = await one.evaluate(() => window.__seaarms.lastInput.seq);
    await one.keyboard.up('KeyE');
    const q1 = await one.evaluate(() => window.__seaarms.lastState.arms.left.q[2]);
    assert.equal(await two.evaluate(() => window.__seaarms.lastInput), null, 'the watching tab sent no input');
    // a second sender would show its own (small, restarted) sequence numbers in between
    assert.ok(seen.every((s, i) => s >= seq0 - 5 && s <= seq1 && (i === 0 || s >= seen[i - 1])), `applied seqs ${seen.join(',')} within tab one's ${seq0}…${seq1}`);
    assert.ok(Math.abs(q1 - q0) > 0.03, `the elbow moved ${q1 - q0} rad`);
    // the watching tab's session controls are off
    assert.equal(await two.isDisabled('#btn-reset'), true);

    // tab two takes control: tab one becomes the watcher
    await two.click('#tabs [data-choice="take"]');
    await until(two, () => window.__seaarms.hello?.role === 'trainee' && window.__seaarms.connection.open);
    await until(one, () => window.__seaarms.hello?.role === 'observer' && window.__seaarms.connection.open);
    assert.match(await one.innerText('#tabs'), /another tab drives/i);
    await two.keyboard.down('KeyE');
    await until(two, () => window.__seaarms.lastInput?.arms.left.axes[2] === 1);
    const seqTwo = await two.evaluate(() => window.__seaarms.lastInput.seq);
    const lastOne = await one.evaluate(() => window.__seaarms.lastInput.seq);
    await until(one, (s) => window.__seaarms.lastReceived.input_seq >= s, seqTwo);
    await two.keyboard.up('KeyE');
    assert.equal(await one.evaluate(() => window.__seaarms.lastInput.seq), lastOne, 'tab one stopped sending');
    assert.deepEqual(b.errors, []);
  } finally {
    await b.close();
  }
});
