//! Speed: the page decodes every 60 Hz state frame and draws the newest one each animation
//! frame without growing memory (60 s here; `node soak.mjs 600` runs the 10-minute soak).

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { server, soak } from './harness.mjs';

test('decoding and drawing keep up with the frame rate without growing memory', { timeout: 120000 }, async () => {
  const url = await server();
  const r = await soak(url, 60, { every: 15 });
  console.log(`heap ${r.heapStartMB.toFixed(2)} → ${r.heapEndMB.toFixed(2)} MB (max ${r.heapMaxMB.toFixed(2)}), DOM nodes ${r.nodesStart} → ${r.nodesEnd}, ` +
    `received ${r.receivedHz.toFixed(1)} Hz of ${r.frameHz}, drawn ${r.drawnHz.toFixed(1)} Hz, rendered ${r.renderedHz.toFixed(1)} fps`);
  // the server skips frames for a client that is slow to take them (latest state wins); on a
  // loaded 2-core machine a few are skipped, so 80 % is the floor
  assert.ok(r.receivedHz > 0.8 * r.frameHz, `decoded ${r.receivedHz} frames/s of ${r.frameHz}`);
  // a CPU rasterizer (SwiftShader here) draws at most 15 fps by design (view.js); GPUs at rAF rate
  assert.ok(r.drawnHz > 8, `drew ${r.drawnHz} states/s`);
  assert.ok(r.heapEndMB - r.heapStartMB < 3, `heap grew ${r.heapEndMB - r.heapStartMB} MB in ${r.seconds} s`);
  assert.ok(r.nodesEnd - r.nodesStart < 200, `DOM grew ${r.nodesEnd - r.nodesStart} nodes`);
  assert.deepEqual(r.errors, []);
});
