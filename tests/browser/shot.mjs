// Manual check: node shot.mjs URL [out.png] [wait_ms] — loads a page in headless Chromium,
// prints console errors and offsite requests, saves a screenshot into artifacts/.
import { openBrowser, ARTIFACTS } from './harness.mjs';
import { join } from 'node:path';
const [url, out = 'shot.png', wait = '3000'] = process.argv.slice(2);
const b = await openBrowser();
const t0 = Date.now();
await b.page.goto(url);
await b.page.waitForTimeout(+wait);
await b.page.screenshot({ path: join(ARTIFACTS, out) });
const info = await b.page.evaluate(() => window.__seaarms ? { frames: window.__seaarms.framesRendered, first: window.__seaarms.firstFrameAt, status: window.__seaarms.statusText?.() } : null);
console.log(JSON.stringify({ ms: Date.now() - t0, info, errors: b.errors, offsite: b.offsite }, null, 1));
await b.close();
