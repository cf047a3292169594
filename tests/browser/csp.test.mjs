//! The pages run under the server's Content-Security-Policy (issue 13): the trainee page, the
//! instructor dashboard, the workspace map and the debrief page load and work with no policy violation, the
//! legend swatches still get their colours (set through the CSSOM, not style="" attributes),
//! and the policy is really enforced: an injected inline script is blocked and reported, and
//! a cross-origin page cannot frame the simulator.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { server, openBrowser, until, UNNAMED_CONTROLS } from './harness.mjs';

/** Records every CSP violation the page reports (set before any page script runs). */
const WATCH_CSP = () => {
  window.__csp = [];
  document.addEventListener('securitypolicyviolation', (e) => {
    window.__csp.push(`${e.violatedDirective} ${e.blockedURI}`);
  });
};

/** Injects an inline script; returns whether it ran. */
async function inlineScriptRuns(page) {
  return page.evaluate(() => {
    const s = document.createElement('script');
    s.textContent = 'window.__injected = true;';
    document.head.append(s);
    return window.__injected === true;
  });
}

test('the pages work under the CSP, which blocks injected inline script', { timeout: 90000 }, async () => {
  const url = await server();
  const pages = [
    ['/?scenario=training', () => window.__seaarms?.statesDrawn > 3],
    ['/instructor', () => document.readyState === 'complete' && document.getElementById('token')],
    ['/web/workspace.html', () => window.__workspace?.doc],
    // the debrief page's modules load and run (without a token it says so and fetches nothing)
    ['/replay/no-such-attempt', () => window.__seaarms?.replay && !document.getElementById('rp-note').hidden],
  ];
  for (const [path, ready] of pages) {
    const b = await openBrowser({ initScript: WATCH_CSP });
    try {
      const resp = await b.page.goto(`${url}${path}`);
      assert.match(resp.headers()['content-security-policy'], /default-src 'self'/, path);
      await until(b.page, ready, undefined, 60000);
      assert.deepEqual(await b.page.evaluate(() => window.__csp), [], `${path}: no violation while working`);
      assert.deepEqual(b.errors, [], `${path}: console errors`);
      assert.deepEqual(await b.page.evaluate(UNNAMED_CONTROLS), [], `${path}: every control is named`);
      if (!path.startsWith('/web/')) {
        // the simulator's pages carry the one shared head (web/head.html, put in by the server):
        // one import map, the shared stylesheet and the shared module preloads, each once
        const head = await b.page.evaluate(() => ({
          maps: document.querySelectorAll('script[type="importmap"]').length,
          preloads: [...document.querySelectorAll('link[rel="modulepreload"]')].map((l) => new URL(l.href).pathname),
          sheets: [...document.styleSheets].map((s) => s.href && new URL(s.href).pathname),
        }));
        assert.equal(head.maps, 1, `${path}: import maps`);
        assert.ok(head.sheets.includes('/web/style.css'), `${path}: the shared stylesheet is applied`);
        for (const m of ['/static/three/three.module.js', '/web/view.js', '/web/connection.js', '/web/status.js']) {
          assert.equal(head.preloads.filter((x) => x === m).length, 1, `${path}: ${m} preloaded once`);
        }
        assert.equal(new Set(head.preloads).size, head.preloads.length, `${path}: a module preloaded twice`);
      }
      assert.equal(await inlineScriptRuns(b.page), false, `${path}: injected inline script must not run`);
      await until(b.page, () => window.__csp.length > 0, undefined, 5000);
      const v = await b.page.evaluate(() => window.__csp);
      assert.ok(v.every((x) => x.startsWith('script-src')), `${path}: ${v}`);
      if (path.startsWith('/?')) {
        // The legend swatches are coloured (CSSOM), not left blank by the policy.
        const colours = await b.page.evaluate(() =>
          [...document.querySelectorAll('#legend .sw')].map((el) => getComputedStyle(el).backgroundColor));
        assert.ok(colours.length >= 8, `swatches: ${colours.length}`);
        assert.ok(colours.every((c) => c !== 'rgba(0, 0, 0, 0)'), `swatch colours: ${colours}`);
      }
    } finally {
      await b.close();
    }
  }
});

test('another page cannot frame the simulator (frame-ancestors \'none\')', { timeout: 60000 }, async () => {
  const url = await server();
  const b = await openBrowser();
  try {
    // A blank parent page with no policy of its own: only the simulator's header can refuse.
    await b.page.goto('about:blank');
    await b.page.evaluate(async (src) => {
      const f = document.createElement('iframe');
      f.src = src;
      document.body.append(f);
      await new Promise((r) => { f.onload = r; setTimeout(r, 3000); });
    }, `${url}/`);
    // Chromium replaces a refused frame with its error page; an allowed one would show the
    // simulator's own URL.
    const child = b.page.frames().filter((f) => f !== b.page.mainFrame());
    assert.equal(child.length, 1);
    assert.match(child[0].url(), /^chrome-error:/, `the frame loaded ${child[0].url()}`);
  } finally {
    await b.close();
  }
});
