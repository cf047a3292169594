//! The trainee page loads from the release binary with no network beyond loopback, renders the
//! arms and the object within 2 s, shows four viewports, and its status bar shows the server's
//! numbers.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { server, openBrowser, until, untilDrawn, decodePng, classify, ARTIFACTS } from './harness.mjs';

const COMMON = { timeout: 60000 };

test('page loads offline, renders the arms and the object; reports the first-frame time', COMMON, async () => {
  const url = await server();
  const b = await openBrowser();
  try {
    await b.page.goto(`${url}/?scenario=training`);
    await untilDrawn(b.page, { states: 3, open: false });
    await until(b.page, () => window.__seaarms.framesRendered > 3);
    const t = await b.page.evaluate(() => {
      const nav = performance.getEntriesByType('navigation')[0];
      return { firstFrame: window.__seaarms.firstFrameAt, firstArms: window.__seaarms.firstStateFrameAt, domContentLoaded: nav.domContentLoadedEventEnd };
    });
    console.log(`first rendered frame ${t.firstFrame.toFixed(0)} ms, first frame with the arms ${t.firstArms?.toFixed(0)} ms after navigation`);
    // Speed is reported, not asserted (timed assertions fail on a busy CI machine): the
    // figure goes to the test log and the closing note.
    assert.ok(Number.isFinite(t.firstFrame) && Number.isFinite(t.firstArms), 'a first frame was rendered');

    // hide the translucent ellipsoids so the object's own colour is sampled
    await b.page.uncheck('#chk-ell');
    await b.page.waitForTimeout(200);
    const png = await b.page.screenshot({ path: join(ARTIFACTS, 'trainee.png') });
    const img = await decodePng(b.page, png);
    const px = (x, y) => { const i = 4 * (Math.round(y) * img.width + Math.round(x)); return img.data.slice(i, i + 3); };
    const counts = {};
    const distinct = new Set();
    for (let y = 60; y < img.height - 60; y += 3) {
      for (let x = 0; x < img.width; x += 3) {
        const c = px(x, y);
        counts[classify(c)] = (counts[classify(c)] || 0) + 1;
        distinct.add(c.join(','));
      }
    }
    assert.ok(distinct.size > 200, `screenshot looks blank (${distinct.size} colours)`);
    assert.ok((counts.orange || 0) > 200, `arm colour (orange) pixels: ${JSON.stringify(counts)}`);
    // the object's centre in the perspective view: its drawn colour for the current grasp state
    const s = await b.page.evaluate(() => {
      const st = window.__seaarms.lastState;
      return { grasp: st.grasp, at: window.__seaarms.project('persp', st.object.pose.position), colour: window.__seaarms.drawnObjectColour() };
    });
    const expected = { free: 'grey', one_on_surface: 'black', one_lifted: 'lightblue', one_holding_other_contact: 'red', both_holding: 'yellow' }[s.grasp];
    const around = [];
    for (let dy = -3; dy <= 3; dy += 3) for (let dx = -3; dx <= 3; dx += 3) around.push(classify(px(s.at.x + dx, s.at.y + dy)));
    assert.ok(around.filter((c) => c === expected).length >= 5, `object at ${JSON.stringify(s.at)} should look ${expected}: ${around}`);
    assert.deepEqual(b.offsite, [], 'requests beyond loopback');
    assert.deepEqual(b.errors, [], 'console errors');
  } finally {
    await b.close();
  }
});

test('four viewports, switchable to one large view', COMMON, async () => {
  const url = await server();
  const b = await openBrowser();
  try {
    await b.page.goto(`${url}/?scenario=training`);
    await untilDrawn(b.page, { states: 1, open: false });
    const four = await b.page.evaluate(() => window.__seaarms.viewports());
    assert.deepEqual(four.map((v) => v.name), ['top', 'front', 'side', 'persp']);
    for (const v of four) assert.ok(v.visible && v.rect.width > 200 && v.rect.height > 150, JSON.stringify(v));
    // the four quadrants do not overlap
    const [a, , , d] = four.map((v) => v.rect);
    assert.ok(a.right <= d.left + 3 && a.bottom <= d.top + 3);
    // the legend stays inside the perspective view's corner, covering no other view (here the
    // plots take 420 px, and the legend is wider than half of what is left)
    assert.equal(await b.page.isVisible('#plots'), true);
    const legend = await b.page.$eval('#legend', (e) => e.getBoundingClientRect().toJSON());
    assert.ok(legend.left >= d.left && legend.top >= d.top && legend.right <= d.right && legend.bottom <= d.bottom,
      `legend ${JSON.stringify(legend)} outside the perspective view ${JSON.stringify(d)}`);
    // where it wraps, no entry is split from its swatch or across lines
    const entries = await b.page.$$eval('#legend .li', (els) => els.map((e) => ({ text: e.textContent, lines: e.getClientRects().length, h: e.getBoundingClientRect().height })));
    assert.ok(entries.length >= 8, `legend entries: ${entries.length}`);
    const lineH = Math.min(...entries.map((e) => e.h));
    for (const e of entries) assert.ok(e.lines === 1 && e.h < 1.5 * lineH, `"${e.text}" spans lines: ${JSON.stringify(e)}`);
    await b.page.click('.vp[data-view="persp"] .vp-max');
    await b.page.waitForTimeout(100);
    const one = await b.page.evaluate(() => window.__seaarms.viewports());
    const big = one.find((v) => v.name === 'persp');
    assert.equal(one.filter((v) => v.visible).length, 1);
    assert.ok(big.rect.width > 1.8 * four[3].rect.width, 'large view is larger');
    await b.page.screenshot({ path: join(ARTIFACTS, 'single-view.png') });
    await b.page.keyboard.press('KeyV');
    await b.page.waitForTimeout(100);
    assert.equal((await b.page.evaluate(() => window.__seaarms.viewports())).filter((v) => v.visible).length, 4);
    assert.deepEqual(b.errors, []);
  } finally {
    await b.close();
  }
});

test('status bar shows the latest state frame\'s measures', COMMON, async () => {
  const url = await server();
  const b = await openBrowser();
  try {
    await b.page.goto(`${url}/?scenario=training`);
    await untilDrawn(b.page, { states: 1, open: false });
    await b.page.click('#btn-pause');
    await until(b.page, () => window.__seaarms.lastState.paused === true);
    await b.page.waitForTimeout(400); // the status bar refreshes at 10 Hz
    const { st, text } = await b.page.evaluate(() => ({ st: window.__seaarms.lastState, text: window.__seaarms.statusText() }));
    for (const side of ['left', 'right']) {
      const m = st.arms[side].measures;
      const tag = side === 'left' ? 'L' : 'R';
      const line = text.split('\n').find((l) => l.startsWith(tag + ' ')) || text;
      for (const k of ['yoshikawa', 'isotropy', 'hong', 'jlm']) {
        assert.ok(line.includes(m[k].toFixed(4)), `${side} ${k} ${m[k].toFixed(4)} not in "${line}"`);
      }
    }
    assert.ok(text.includes(st.grasp.replaceAll('_', ' ')), 'grasp state shown');
    assert.ok(text.includes(st.settings.control_mode) && text.includes(st.settings.control_method), 'control mode and method shown');
    assert.ok(text.includes(st.t.toFixed(2)), `sim time ${st.t.toFixed(2)} shown`);
    assert.ok(text.includes('PAUSED'));
    await until(b.page, () => window.__seaarms.connection.latencyMs !== null);
    assert.match(await b.page.evaluate(() => window.__seaarms.statusText()), /latency \d+\.\d ms/);
    await b.page.click('#btn-pause'); // resume
    await until(b.page, () => window.__seaarms.lastState.paused === false);
    assert.deepEqual(b.errors, []);
  } finally {
    await b.close();
  }
});
