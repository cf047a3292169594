import { openBrowser, until } from './harness.mjs';
const b = await openBrowser();
await b.context.addInitScript(() => {
  const OrigWS = window.WebSocket;
  window.__msgBytes = 0; window.__msgN = 0; window.__parseMs = 0;
  window.WebSocket = class extends OrigWS { constructor(...a) { super(...a); this.addEventListener('message', (e) => { window.__msgBytes += e.data.length; window.__msgN++; const t = performance.now(); JSON.parse(e.data); window.__parseMs += performance.now() - t; }); } };
});
await b.page.goto(process.argv[2] + '?maxfps=20');
await b.page.waitForTimeout(3000);
const r = await b.page.evaluate(async () => {
  const gaps = []; let last = performance.now();
  await new Promise((res) => { const id = setInterval(() => { const n = performance.now(); gaps.push(n - last); last = n; if (gaps.length >= 100) { clearInterval(id); res(); } }, 20); });
  gaps.sort((a, b) => a - b);
  return { n: window.__msgN, avgBytes: window.__msgBytes / window.__msgN, parseMsPerMsg: window.__parseMs / window.__msgN, gapMedian: gaps[50], gap90: gaps[90], gapMax: gaps[99], renderMs: window.__seaarms.renderMs };
});
console.log(r);
await b.close();
