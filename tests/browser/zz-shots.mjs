import { startServer, openBrowser, until, untilDrawn, pressReady, FAKE_GAMEPAD, workDualLift, openClassroom } from './harness.mjs';
const out = (n) => `/tmp/look/${n}.png`;
const { url, stop } = await startServer();
const group = 'ROV-A';
const t = await openBrowser({ initScript: FAKE_GAMEPAD });
const p = t.page;
await p.goto(`${url}/`);
await p.waitForSelector('#start .ex[data-id="dual-lift"]');
await p.fill('#start-name', 'Ada Lovelace');
await p.fill('#start-group', group);
await p.screenshot({ path: out('t1-start') });
await p.click('#start .ex[data-id="dual-lift"]');
await p.click('#start-exercise');
await until(p, () => window.__seaarms?.hello?.exercise?.id === 'dual-lift', undefined, 30000);
await untilDrawn(p);
await pressReady(p);
await workDualLift(p);
await p.waitForSelector('#card:not([hidden]) [data-score]', { timeout: 30000 });
await p.waitForTimeout(800);
await p.screenshot({ path: out('t2-card') });
const debrief = await p.getAttribute('#card [data-act="debrief"]', 'href').catch(() => null);
await p.click('#card [data-act="again"]');
await p.waitForSelector('#task .task-ready:not([hidden])', { timeout: 8000 });
await p.waitForTimeout(500);
await p.screenshot({ path: out('t3-again') });
// the fault drill in pilot view
await p.goto(`${url}/?exercise=fault-diagnosis`);
await untilDrawn(p);
await pressReady(p);
await p.waitForTimeout(4000);
await p.screenshot({ path: out('t4-drill') });
// the debrief of the dual-lift attempt
if (debrief) {
  await p.goto(new URL(debrief, url).href);
  await p.waitForTimeout(5000);
  await p.screenshot({ path: out('t5-debrief') });
}
console.log('debrief', debrief, 'trainee errors', t.errors);
// instructor
const i = await openBrowser({ viewport: { width: 1400, height: 900 } });
await openClassroom(i.page, url, group);
await i.page.waitForTimeout(3000);
await i.page.screenshot({ path: out('i1-classroom'), fullPage: true });
await i.page.click('#instr-tabs [data-tab="sessions"]').catch((e) => console.log('no sessions tab', e.message));
await i.page.waitForTimeout(2500);
await i.page.screenshot({ path: out('i2-sessions') });
console.log('instructor errors', i.errors);
await t.close(); await i.close(); stop();
process.exit(0);
