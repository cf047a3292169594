//! Phones and tablets (trial findings, issue 15): a phone viewport shows a usable 3D view, the
//! help overlay closes by touch, and on a touch tablet the on-screen sticks drive an arm
//! through the page's one input path.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { server, openBrowser, until, decodePng, ARTIFACTS } from './harness.mjs';

const PHONE = { viewport: { width: 390, height: 844 }, hasTouch: true, isMobile: true };
const TABLET = { viewport: { width: 1024, height: 768 }, hasTouch: true };

test('phone 390×844: a 3D view with non-zero size and a non-blank picture; help closes by touch', { timeout: 60000 }, async () => {
  const url = await server();
  const b = await openBrowser(PHONE);
  try {
    await b.page.goto(`${url}/`);
    await until(b.page, () => window.__seaarms?.statesDrawn > 2 && window.__seaarms.framesRendered > 2);
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
