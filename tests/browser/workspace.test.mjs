//! The workspace heat map (issue: manipulability studies) draws the server's map: the pixel
//! colours follow the server's numbers (brightest where the server's maximum is, grey where
//! the server says unreachable), with no request leaving localhost.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { server, openBrowser, ARTIFACTS } from './harness.mjs';

test('workspace heat map shows the server\'s Yoshikawa map', { timeout: 90000 }, async () => {
  const url = await server();
  const b = await openBrowser();
  try {
    await b.page.goto(`${url}/web/workspace.html`);
    await b.page.waitForFunction(() => window.__workspace?.doc, null, { timeout: 60000 });
    const info = await b.page.evaluate(() => {
      const { doc, measure, max } = window.__workspace;
      const grid = doc[measure];
      const nz = grid.length, nx = grid[0].length;
      const c = document.getElementById('map');
      const ctx = c.getContext('2d');
      const px = (ix, iz) => {
        const x = Math.floor((ix + 0.5) * c.width / nx), y = Math.floor(c.height - (iz + 0.5) * c.height / nz);
        return Array.from(ctx.getImageData(x, y, 1, 1).data.slice(0, 3));
      };
      let best = null, dead = null, reachable = 0;
      for (let iz = 0; iz < nz; iz++) for (let ix = 0; ix < nx; ix++) {
        const v = grid[iz][ix];
        if (v == null) { dead ??= [ix, iz]; continue; }
        reachable++;
        if (!best || v > grid[best[1]][best[0]]) best = [ix, iz];
      }
      return { max, reachable, cells: nx * nz, bestPx: px(...best), deadPx: dead ? px(...dead) : null, summary: doc.summary };
    });
    // Counts agree with the server's summary; the maximum is drawn in the ramp's top colour.
    assert.equal(info.reachable, info.summary.reachable);
    assert.ok(Math.abs(info.max - info.summary.max_yoshikawa.value) < 1e-12);
    assert.deepEqual(info.bestPx, [250, 230, 60], `brightest cell ${info.bestPx}`);
    if (info.deadPx) assert.deepEqual(info.deadPx, [60, 66, 72], 'unreachable cells are grey');
    assert.deepEqual(b.offsite, [], 'no request left localhost');
    await b.page.screenshot({ path: join(ARTIFACTS, 'workspace-map.png') });
  } finally {
    await b.close();
  }
});
