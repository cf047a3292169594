//! Phones and tablets (trial findings, issue 15): a phone viewport shows a usable 3D view, the
//! help overlay closes by touch, and on a touch tablet the on-screen sticks drive an arm
//! through the page's one input path.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { server, openBrowser, until, untilDrawn, decodePng, ARTIFACTS } from './harness.mjs';

const PHONE = { viewport: { width: 390, height: 844 }, hasTouch: true, isMobile: true };
const TABLET = { viewport: { width: 1024, height: 768 }, hasTouch: true };

test('phone 390×844: a 3D view with non-zero size and a non-blank picture; help closes by touch', { timeout: 60000 }, async () => {
  const url = await server();
  const b = await openBrowser(PHONE);
  try {
    await b.page.goto(`${url}/?scenario=training`);
    await untilDrawn(b.page, { open: false });
    await until(b.page, () => window.__seaarms.framesRendered > 2);
    const views = await b.page.evaluate(() => window.__seaarms.viewports().filter((v) => v.visible));
    assert.ok(views.length >= 1, 'a view is shown');
    const v = views[0];
    assert.ok(v.rect.width > 300 && v.rect.height > 250, `view ${v.name} is ${v.rect.width}×${v.rect.height} px`);
    assert.ok(v.rect.left >= 0 && v.rect.right <= 390 + 1, 'the view fits the screen width');
    const png = await b.page.screenshot({ path: join(ARTIFACTS, 'phone.png') });
    const img = await decodePng(b.page, png);
    // distinct colours inside the view's rectangle (a blank canvas has one or two)
    const distinct = new Set();
    for (let y = Math.ceil(v.rect.top) + 20; y < v.rect.bottom - 2; y += 3) {
      for (let x = Math.ceil(v.rect.left) + 2; x < v.rect.right - 2; x += 3) {
        const i = 4 * (y * img.width + x);
        distinct.add(img.data.slice(i, i + 3).join(','));
      }
    }
    assert.ok(distinct.size > 100, `the view's picture has ${distinct.size} colours`);
    // help: opened and closed by taps (no keyboard on a phone)
    await b.page.tap('#btn-help');
    assert.equal(await b.page.isVisible('#help'), true);
    await b.page.tap('#help [data-close]');
    assert.equal(await b.page.isVisible('#help'), false, 'the close button closes the help');
    await b.page.tap('#btn-help');
    assert.equal(await b.page.isVisible('#help'), true);
    await b.page.touchscreen.tap(195, 830); // the status bar, outside the overlay
    assert.equal(await b.page.isVisible('#help'), false, 'a tap outside closes the help');
    assert.deepEqual(b.errors, []);
  } finally {
    await b.close();
  }
});

/** Drags a finger (CDP touch events, as a touch screen sends them) from `a` to `b` and holds. */
async function touchDrag(cdp, a, b, id = 1) {
  const point = (p) => [{ x: p.x, y: p.y, id, radiusX: 8, radiusY: 8, force: 1 }];
  await cdp.send('Input.dispatchTouchEvent', { type: 'touchStart', touchPoints: point(a) });
  for (let k = 1; k <= 5; k++) {
    const p = { x: a.x + (b.x - a.x) * k / 5, y: a.y + (b.y - a.y) * k / 5 };
    await cdp.send('Input.dispatchTouchEvent', { type: 'touchMove', touchPoints: point(p) });
  }
}

test('tablet 1024×768 with touch: the on-screen sticks and buttons drive the selected arm', { timeout: 90000 }, async () => {
  const url = await server();
  const b = await openBrowser(TABLET);
  try {
    await b.page.goto(`${url}/?scenario=training`);
    await untilDrawn(b.page);
    assert.equal(await b.page.isVisible('#touch .stick[data-stick="left"]'), true, 'sticks shown on a touch screen');
    // right arm by its on-screen button (RB, through the pad's button edges)
    await b.page.tap('#touch [data-btn="5"]');
    await until(b.page, () => window.__seaarms.selectedArm === 'right');
    const before = await b.page.evaluate(() => ({ q: window.__seaarms.lastState.arms.right.q, left: window.__seaarms.lastState.arms.left.q,
      limits: window.__seaarms.hello.arms[1].model.joints[0].limits }));
    // left stick to the side: swing (joint 1), away from its nearer limit
    const [lo, hi] = before.limits || [-1, 1];
    const dir = before.q[0] - lo > hi - before.q[0] ? -1 : 1;
    const box = await b.page.locator('#touch .stick[data-stick="left"]').boundingBox();
    const c = { x: box.x + box.width / 2, y: box.y + box.height / 2 };
    const cdp = await b.context.newCDPSession(b.page);
    await touchDrag(cdp, c, { x: c.x + dir * box.width * 0.6, y: c.y });
    await until(b.page, (d) => Math.sign(window.__seaarms.lastInput?.arms.right.axes[0]) === d && Math.abs(window.__seaarms.lastInput.arms.right.axes[0]) > 0.8, dir);
    await b.page.waitForTimeout(1500);
    await cdp.send('Input.dispatchTouchEvent', { type: 'touchEnd', touchPoints: [] });
    await until(b.page, () => window.__seaarms.lastInput.arms.right.axes.every((v) => v === 0));
    const after = await b.page.evaluate(() => ({ q: window.__seaarms.lastState.arms.right.q, left: window.__seaarms.lastState.arms.left.q }));
    await b.page.screenshot({ path: join(ARTIFACTS, 'tablet-touch.png') });
    const dq = after.q[0] - before.q[0];
    assert.ok(dir * dq > 0.05, `right swing moved ${dq} rad in the state frames (wanted sign ${dir})`);
    for (let i = 0; i < 6; i++) assert.ok(Math.abs(after.left[i] - before.left[i]) < 0.01, `left arm joint ${i + 1} stayed`);
    // the grip buttons are held like a trigger: "close" sends grip −1 while held
    const close = await b.page.locator('#touch [data-btn="7"]').boundingBox();
    const at = { x: close.x + close.width / 2, y: close.y + close.height / 2 };
    await cdp.send('Input.dispatchTouchEvent', { type: 'touchStart', touchPoints: [{ ...at, id: 2 }] });
    await until(b.page, () => window.__seaarms.lastInput.arms.right.grip === -1);
    await cdp.send('Input.dispatchTouchEvent', { type: 'touchEnd', touchPoints: [] });
    await until(b.page, () => window.__seaarms.lastInput.arms.right.grip === 0);
    assert.deepEqual(b.errors, []);
  } finally {
    await b.close();
  }
});
