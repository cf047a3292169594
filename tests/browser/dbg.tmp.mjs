import { openBrowser, until } from './harness.mjs';
const b = await openBrowser();
await b.page.goto(process.argv[2]);
await b.page.waitForTimeout(3000);
const a = await b.page.evaluate(() => ({r: window.__seaarms.framesRendered, s: window.__seaarms.connection.framesReceived, ms: window.__seaarms.renderMs, gl: (() => { const c = document.getElementById('canvas').getContext('webgl2'); const e = c.getExtension('WEBGL_debug_renderer_info'); return e ? c.getParameter(e.UNMASKED_RENDERER_WEBGL) : '?'; })() }));
await b.page.waitForTimeout(3000);
const z = await b.page.evaluate(() => ({r: window.__seaarms.framesRendered, s: window.__seaarms.connection.framesReceived, ms: window.__seaarms.renderMs}));
console.log(a, z, 'fps', (z.r-a.r)/3, 'recv', (z.s-a.s)/3);
await b.close();
