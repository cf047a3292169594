//! A scripted grasp, driven through the page's own input path (a fake gamepad in Cartesian
//! mode, steered by a proportional controller in this test that reads the streamed state),
//! turns the object from neutral to black (one jaw holds it on the seabed), light blue (lifted)
//! and yellow (both jaws hold it), and the page draws those colours.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { server, openBrowser, until, untilDrawn, FAKE_GAMEPAD, padDriver, decodePng, classify, ARTIFACTS } from './harness.mjs';

const COLOUR_NAME = { free: 'grey', one_on_surface: 'black', one_lifted: 'lightblue', one_holding_other_contact: 'red', both_holding: 'yellow' };

test('scripted grasp: object turns black, light blue, yellow as drawn', { timeout: 420000 }, async () => {
  const url = await server();
  const b = await openBrowser({ initScript: FAKE_GAMEPAD });
  const page = b.page;
  const seen = [];
  const snap = async (name) => {
    // One frame: its grasp state, drawn colour, dual measures and status text together (in open
    // loop the arms fight through the box, and the friction grip may drop it moments later).
    const st = await page.evaluate(() => { const s = window.__seaarms.lastState; return { grasp: s.grasp, dual: s.dual, text: window.__seaarms.statusText(), colour: window.__seaarms.drawnObjectColour(), at: window.__seaarms.project('persp', s.object.pose.position) }; });
    const png = await page.screenshot({ path: join(ARTIFACTS, `grasp-${name}.png`) });
    const img = await decodePng(page, png);
    const votes = {};
    for (let dy = -4; dy <= 4; dy += 2) for (let dx = -4; dx <= 4; dx += 2) {
      const i = 4 * (Math.round(st.at.y + dy) * img.width + Math.round(st.at.x + dx));
      const c = classify(img.data.slice(i, i + 3));
      votes[c] = (votes[c] || 0) + 1;
    }
    return { ...st, votes };
  };
  const { setSticks, selectArm, grab } = padDriver(page, (st) => { if (!seen.includes(st.grasp)) seen.push(st.grasp); });
  try {
    await page.goto(`${url}/?scenario=training`);
    await untilDrawn(page);
    await page.uncheck('#chk-ell'); // sample the object's own colour, not through an ellipsoid
    await page.evaluate(() => window.__connectPad());
    const first = await snap('free');
    assert.equal(first.grasp, 'free');
    assert.equal(first.colour, 0xb4b4b4);
    // Cartesian mode (gamepad Y), left arm (LB), open the jaw (LT)
    await page.evaluate(() => { window.__setButton(3, 1); });
    await until(page, () => window.__seaarms.lastState.settings.control_mode === 'cartesian');
    await page.evaluate(() => { window.__setButton(3, 0); window.__setButton(4, 1); window.__setButton(6, 1); });
    await page.waitForTimeout(1000);
    await page.evaluate(() => { window.__setButton(4, 0); window.__setButton(6, 0); });

    // squared jaw: this one jaw lifts the box by its end handle (the grip's torsion limit
    // would let the hanging box turn out of a jaw left as the Cartesian moves happened to
    // leave it; padDriver's squareJaw)
    await grab('left', { square: true });
    await until(page, () => window.__seaarms.lastState.grasp === 'one_on_surface', undefined, 20000);
    await page.waitForTimeout(300);
    const black = await snap('one_on_surface');
    // lift: +vz, jaw kept closed
    await setSticks([0, 0, 0.6]);
    await until(page, () => window.__seaarms.lastState.grasp === 'one_lifted', undefined, 30000);
    await setSticks([0, 0, 0]);
    await page.waitForTimeout(300);
    const blue = await snap('one_lifted');
    // right arm (RB); the left jaw, now sent grip 0, stays closed on its handle
    await selectArm('right');
    await grab('right');
    await until(page, () => window.__seaarms.lastState.grasp === 'both_holding', undefined, 20000);
    await page.waitForTimeout(300);
    const yellow = await snap('both_holding');
    await page.check('#chk-ell'); // the picture for docs/screenshot.png: dual ellipsoid on the object
    await page.waitForTimeout(500);
    await page.screenshot({ path: join(ARTIFACTS, 'showcase.png') });
    await page.evaluate(() => { window.__setButton(7, 0); });
    const dual = yellow; // the frame in which both jaws held
    console.log(`grasp states seen: ${seen.join(' → ')}`);
    for (const s of [black, blue, yellow]) {
      assert.equal(s.colour, { one_on_surface: 0x000000, one_lifted: 0x7fd4ff, both_holding: 0xffd700 }[s.grasp], `${s.grasp} material colour`);
      assert.ok((s.votes[COLOUR_NAME[s.grasp]] || 0) >= 8, `${s.grasp} drawn ${JSON.stringify(s.votes)} at ${JSON.stringify(s.at)}`);
    }
    assert.ok(dual.dual, 'dual ellipsoid present while both hold');
    assert.ok(dual.text.includes(dual.dual.measures.yoshikawa.toFixed(4)), 'dual measures in the status bar');
    assert.deepEqual(b.errors, []);
  } finally {
    await b.close();
  }
});
