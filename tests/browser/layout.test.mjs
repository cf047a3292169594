//! The pages leave the 3D views room on a 1024×768 screen (a small laptop or a tablet) and at
//! 1280×800: with the side panels open (the trainee's plots; the debrief's card, events and
//! plots) the view is at least 400 px wide, and the legend stays inside the perspective view's
//! corner with its entries inside its box (nothing cut off or spilling over another view); no
//! view's title runs under its ⤢ button; the trainee's "Sticks follow …" note stays on the
//! view it describes (it ran over into the next view at 1280×800).

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { server, openBrowser, until, untilDrawn, decodePng, instructorAction, ARTIFACTS } from './harness.mjs';

const PAGES = [
  ['trainee', '/?scenario=training', () => window.__seaarms?.statesDrawn > 2 && !document.getElementById('plots').hidden],
  // the debrief page lays out its panels and views before any attempt is loaded
  ['debrief', '/replay/no-such-attempt', () => window.__seaarms?.replay && document.querySelector('#plots .uplot')],
];

for (const [width, height] of [[1024, 768], [1280, 800]]) {
  for (const [name, path, ready] of PAGES) {
    test(`${name} page at ${width}×${height}: the views keep room, the legend fits its corner`, { timeout: 60000 }, async () => {
      const url = await server();
      const b = await openBrowser({ viewport: { width, height } });
      try {
        await b.page.goto(`${url}${path}`);
        await until(b.page, ready, undefined, 30000);
        if (name === 'trainee') await until(b.page, () => document.getElementById('sticks-note')?.closest('.vp.active'), 'sticks note on the active view');
        await b.page.waitForTimeout(300);
        await b.page.screenshot({ path: join(ARTIFACTS, `layout-${name}-${width}.png`) });
        const m = await b.page.evaluate(() => {
          const r = (sel) => document.querySelector(sel).getBoundingClientRect().toJSON();
          const legend = document.getElementById('legend');
          return {
            view: r('#view'), persp: r('.vp[data-view="persp"]'), legend: r('#legend'),
            legendShown: getComputedStyle(legend).display !== 'none',
            note: document.getElementById('sticks-note') ? r('#sticks-note') : null, active: r('.vp.active'),
            overflow: legend.scrollWidth - legend.clientWidth,
            // each view's title against its own "one large view" button
            titles: [...document.querySelectorAll('.vp')].map((v) => {
              const t = v.querySelector('.vp-title').getBoundingClientRect(), bt = v.querySelector('.vp-max').getBoundingClientRect();
              const range = document.createRange();
              range.selectNodeContents(v.querySelector('.vp-title'));
              const text = range.getBoundingClientRect(); // the words themselves, however they wrap
              return { view: v.dataset.view, clash: text.right > bt.left && text.top < bt.bottom && t.top < bt.bottom };
            }),
          };
        });
        for (const t of m.titles) assert.equal(t.clash, false, `${name}: the ${t.view} view's title runs under its ⤢ button`);
        assert.ok(m.view.width >= 400, `${name}: the 3D view is ${m.view.width} px wide`);
        assert.ok(m.legendShown, `${name}: legend shown`);
        const { legend: l, persp: d } = m;
        assert.ok(l.left >= d.left && l.right <= d.right && l.top >= d.top && l.bottom <= d.bottom,
          `${name}: legend ${JSON.stringify(l)} outside the perspective view ${JSON.stringify(d)}`);
        assert.ok(m.overflow <= 1, `${name}: the legend's entries spill ${m.overflow} px out of its box`);
        if (name === 'trainee') {
          const { note: n, active: v } = m;
          assert.ok(n.width > 50 && n.left >= v.left && n.right <= v.right && n.top >= v.top && n.bottom <= v.bottom,
            `the sticks note ${JSON.stringify(n)} runs out of the active view ${JSON.stringify(v)}`);
        }
        assert.deepEqual(b.errors, []);
      } finally {
        await b.close();
      }
    });
  }
}

test('start screen: the name and group boxes show their whole placeholder, on a laptop and a phone', { timeout: 60000 }, async () => {
  const url = await server();
  for (const viewport of [{ width: 1024, height: 768 }, { width: 390, height: 844 }]) {
    const b = await openBrowser({ viewport });
    try {
      await b.page.goto(`${url}/`);
      await b.page.waitForSelector('#start-name', { timeout: 15000 });
      const boxes = await b.page.evaluate(() => ['start-name', 'start-group'].map((id) => {
        const el = document.getElementById(id);
        const cs = getComputedStyle(el);
        const ctx = document.createElement('canvas').getContext('2d');
        ctx.font = `${cs.fontSize} ${cs.fontFamily}`;
        const room = el.clientWidth - parseFloat(cs.paddingLeft) - parseFloat(cs.paddingRight);
        return { id, placeholder: el.placeholder, text: ctx.measureText(el.placeholder).width, room, right: el.getBoundingClientRect().right };
      }));
      for (const x of boxes) {
        assert.ok(x.text <= x.room, `${viewport.width} px: "${x.placeholder}" needs ${x.text.toFixed(0)} px, ${x.id} has ${x.room.toFixed(0)}`);
        assert.ok(x.right <= viewport.width, `${viewport.width} px: ${x.id} runs off the screen`);
      }
      assert.deepEqual(b.errors, []);
    } finally {
      await b.close();
    }
  }
});

test('a banner shown with the completion card is not hidden behind it', { timeout: 60000 }, async () => {
  const url = await server();
  const b = await openBrowser();
  try {
    await b.page.goto(`${url}/?scenario=training`);
    const id = await untilDrawn(b.page);
    // the card as the page shows it at the end of an exercise (its real content needs a whole
    // attempt: exercise.test.mjs), and a two-line banner (an instructor's message) over it
    await b.page.evaluate(() => {
      const card = document.getElementById('card');
      card.innerHTML = '<div class="card-head"><span class="card-verdict">Passed</span><span class="card-score">98<small>/100</small></span></div><table><tr><td>time (s)</td></tr></table>';
      card.hidden = false;
    });
    const text = 'Hold it at 20 cm for 5 s with the internal force under 500 N, then let go of the box gently on the seabed';
    await instructorAction(url, id, { type: 'message', text });
    await b.page.waitForFunction((t) => document.getElementById('banner').textContent.includes(t), text);
    const [banner, card] = await Promise.all(['#banner', '#card'].map((s) => b.page.$eval(s, (e) => e.getBoundingClientRect().toJSON())));
    await b.page.screenshot({ path: join(ARTIFACTS, 'banner-with-card.png') });
    const overlap = banner.left < card.right && card.left < banner.right && banner.top < card.bottom && card.top < banner.bottom;
    assert.equal(overlap, false, `banner ${JSON.stringify(banner)} overlaps the card ${JSON.stringify(card)}`);
    assert.deepEqual(b.errors, []);
  } finally {
    await b.close();
  }
});

test('the water current\'s arrow is drawn solid: its shaft stands out several pixels wide in the top view', { timeout: 60000 }, async () => {
  const url = await server();
  const b = await openBrowser();
  try {
    await b.page.goto(`${url}/?scenario=training`);
    const id = await untilDrawn(b.page);
    await instructorAction(url, id, { type: 'set_current', speed_m_s: 0.8, heading_deg: 30 });
    await until(b.page, () => window.__seaarms.drawnCurrent().visible);
    await b.page.click('.vp[data-view="top"] .vp-max');
    await b.page.waitForTimeout(500);
    const [tail, tip] = await b.page.evaluate(() => window.__seaarms.drawnCurrent().ends.map((p) => window.__seaarms.project('top', p)));
    const png = await b.page.screenshot({ path: join(ARTIFACTS, 'current-arrow-top.png') });
    const img = await decodePng(b.page, png);
    // across the shaft at 40 % of its length: the pixels of the arrow's colour (scene.js
    // CURRENT_COLOUR #5fd0ff, drawn unlit), within ±12 px of the axis
    const len = Math.hypot(tip.x - tail.x, tip.y - tail.y);
    assert.ok(len > 40, `the arrow is ${len} px long in the top view`);
    const [ux, uy] = [(tip.x - tail.x) / len, (tip.y - tail.y) / len];
    const [cx, cy] = [tail.x + 0.4 * (tip.x - tail.x), tail.y + 0.4 * (tip.y - tail.y)];
    let wide = 0;
    for (let k = -12; k <= 12; k++) {
      const x = Math.round(cx - uy * k), y = Math.round(cy + ux * k);
      const i = 4 * (y * img.width + x);
      const [R, G, B] = img.data.slice(i, i + 3);
      if (Math.hypot(R - 0x5f, G - 0xd0, B - 0xff) < 60) wide++;
    }
    assert.ok(wide >= 5, `the shaft is ${wide} px wide`);
    assert.deepEqual(b.errors, []);
  } finally {
    await b.close();
  }
});
