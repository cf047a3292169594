// Debrief page (/replay/{attempt}): one recorded attempt re-simulated by the server and
// streamed over the replay WebSocket (docs/api.md "Attempts and replay"), drawn with the same
// 3D views, plots and status bar as the trainee page; a timeline with the attempt's events
// (click a marker or the bar to seek), play/pause, speed 0.25×–8×, the current time, and the
// attempt's assessment card. The browser's cookies open it — the instructor's sign-in or the
// trainee's session cookie (a trainee sees its own attempts); a script may still pass
// `?token=`. No physics here: every frame is the server's.

import { Connection } from './connection.js';
import { assessmentHtml } from './assessment.js';
import { Timeline, clock } from './timeline.js';
import { mountViews } from './viewcontrols.js';
import { mountCompare } from './compare.js';
import { $, esc, Banner, statusLoop } from './page.js';
import * as api from './api.js';
const params = new URLSearchParams(location.search);
const attemptId = decodeURIComponent(location.pathname.split('/').filter(Boolean).pop() || '');
const token = params.get('token') || '';
/** A just-finished attempt reaches the database within about a second (the recorder's batch). */
const FETCH_TRIES = 8;
const FETCH_RETRY_MS = 750;
const OUTCOMES = {
  passed: 'Passed', failed: 'Not passed', abandoned: 'Abandoned (reset or switched before the end)',
  ended: 'Free play (ended)', interrupted: 'Interrupted (the server stopped)',
};

const { view, status, plots, controls: viewControls } = mountViews();
const timeline = new Timeline($('timeline'), $('rp-events'), (t) => seek(t));
let arm = 'left';
let attempt = null;
/** The replay's state as the server last reported it ({t, playing, speed, duration_s}). */
const rp = { t: 0, playing: false, speed: 1, duration_s: 0, seeks: 0 };
let conn = null;
const banner = new Banner($('banner'));

function note(text) {
  $('rp-note').textContent = text;
  $('rp-note').hidden = !text;
}

/** GET /api/attempts/{id} (metadata, assessment, events), retried while it is not recorded yet. */
async function fetchAttempt() {
  for (let i = 0; i < FETCH_TRIES; i++) {
    let r;
    try {
      r = await api.attempt(attemptId, token);
    } catch {
      r = null;
    }
    if (r?.ok) return r.json();
    if (r && r.status !== 404) {
      const b = await r.json().catch(() => null);
      throw new Error(b?.error || `HTTP ${r.status}`);
    }
    await new Promise((ok) => setTimeout(ok, FETCH_RETRY_MS));
  }
  throw new Error('no such attempt');
}

function showAttempt(a, title) {
  const who = a.trainee ? `${a.trainee}${a.group ? ` (${a.group})` : ''}` : '';
  const when = a.started_unix ? new Date(a.started_unix * 1000).toLocaleString() : '';
  $('rp-title').textContent = `${who || 'trainee'} · ${title}`;
  document.title = `seaarms — debrief: ${who || attemptId} · ${title}`;
  const outcome = OUTCOMES[a.outcome] || (a.outcome ? a.outcome : 'running');
  $('rp-card').innerHTML = a.assessment
    ? assessmentHtml(a.assessment, { title, verdict: a.outcome === 'passed' || a.outcome === 'failed' ? null : outcome })
    : `<div class="card-head"><span class="card-verdict">${esc(outcome)}</span></div>
       <p class="card-title">${esc(title)}${a.sim_seconds ? ` — ${a.sim_seconds.toFixed(1)} s` : ''}. No assessment (not an exercise, or not finished).</p>`;
  $('rp-card').insertAdjacentHTML('beforeend', `<p class="rp-meta">Started ${esc(when)} · attempt ${esc(a.id)} · session ${esc(a.session)}</p>`);
  if (a.practice) {
    const from = a.taken_over_from;
    $('rp-card').insertAdjacentHTML('beforeend', `<p class="rp-meta rp-practice">Practice attempt, taken over from attempt ${esc(from?.attempt || '?')} at ${(from?.t ?? 0).toFixed(1)} s: not counted in progress.</p>`);
  }
  $('rp-card').dataset.outcome = a.outcome || '';
  plots.setSession(a.session);
}

function renderTime() {
  $('rp-time').textContent = `${clock(rp.t)} / ${clock(rp.duration_s)}`;
  $('rp-time').title = `${rp.t.toFixed(2)} s of ${rp.duration_s.toFixed(2)} s`;
  $('rp-play').textContent = rp.playing ? '❚❚ Pause' : '▶ Play';
  timeline.setTime(rp.t);
}

function send(msg) {
  if (!conn?.send(msg)) banner.show('error', 'Not connected to the replay yet.', 3000);
}

function seek(t) {
  if (!conn) return;
  rp.seeks++;
  plots.reset();
  send(api.messages.seek(Math.max(0, Math.min(rp.duration_s, t))));
}

function togglePlay() {
  if (rp.playing) { send(api.messages.pause()); return; }
  if (rp.duration_s > 0 && rp.t >= rp.duration_s - 1e-6) seek(0); // at the end: from the start
  send(api.messages.play());
}

function connect() {
  let resumeAt = null; // after a dropped socket: where it was
  conn = new Connection({
    role: 'replay',
    sessionId: attemptId,
    replay: { path: api.sockets.replay(attemptId, token),
      refused: attempt?.outcome ? 'The replay was refused' : 'The attempt is still running; its replay opens when it ends' },
    onHello(h) {
      view.setHello(h);
      status.role('replay');
      if (h.exercise?.control?.arm === 'left' || h.exercise?.control?.arm === 'right') setArm(h.exercise.control.arm);
      rp.duration_s = h.replay?.duration_s ?? rp.duration_s;
      timeline.set(attempt?.events || [], rp.duration_s);
      $('rp-play').disabled = false;
      plots.setJoints(api.jointNames(h));
      if (resumeAt !== null && resumeAt > 0) { send(api.messages.seek(resumeAt)); }
      if (rp.speed !== 1) send(api.messages.speed(rp.speed));
      renderTime();
    },
    onState(s) {
      view.setState(s);
      plots.add(s, arm);
    },
    onReplay(m) {
      rp.t = m.t;
      rp.playing = m.playing;
      rp.speed = m.speed;
      rp.duration_s = m.duration_s;
      resumeAt = m.t;
      $('rp-speed').value = String(m.speed);
      renderTime();
    },
    onError(msg) { banner.show('error', msg, 6000); },
    onStatus(kind, text) { banner.show(kind === 'ok' ? null : kind, kind === 'ok' ? '' : text); },
  });
  conn.start();
}

function setArm(side) {
  arm = side;
  $('sel-arm').value = side;
}

/** "Take over from here": the replayed state at the time shown becomes a new live practice
 * attempt (POST /api/attempts/{id}/take-over), stored as this browser's trainee session, and
 * the trainee page opens on it. */
async function takeOver() {
  const b = $('rp-takeover');
  b.disabled = true;
  if (rp.playing) send(api.messages.pause());
  try {
    const r = await api.takeOver(attemptId, rp.t, token);
    if (!r.ok) throw new Error((await api.jsonOf(r))?.error || `HTTP ${r.status}`);
    // the practice session is the attempt's trainee's (the server names it so)
    Connection.store(await r.json(), { trainee: attempt?.trainee, group: attempt?.group });
    location.href = '/';
  } catch (e) {
    banner.show('error', `Cannot take over: ${e.message}`, 6000);
    b.disabled = false;
  }
}

/** The take-over button: enabled for a replayable exercise attempt, else says why not. */
function enableTakeOver(a) {
  const b = $('rp-takeover');
  const why = a.replayable === false ? 'This attempt cannot be replayed here, so it cannot be taken over'
    : !a.exercise ? 'Only an exercise attempt can be taken over' : '';
  b.disabled = !!why;
  if (why) b.title = why;
}

$('rp-takeover').addEventListener('click', takeOver);
$('rp-play').addEventListener('click', togglePlay);
$('rp-speed').addEventListener('change', (e) => { send(api.messages.speed(+e.target.value)); e.target.blur(); });
$('sel-arm').addEventListener('change', (e) => { setArm(e.target.value); plots.reset(); e.target.blur(); });
document.addEventListener('keydown', (e) => {
  if (e.target.closest?.('input, select, textarea')) return;
  if (e.key === ' ') { e.preventDefault(); togglePlay(); } else if (e.key === 'ArrowRight') seek(rp.t + (e.shiftKey ? 5 : 1));
  else if (e.key === 'ArrowLeft') seek(rp.t - (e.shiftKey ? 5 : 1));
  else if (e.key === 'v' || e.key === 'V') viewControls.layout();
});
statusLoop(view, status, () => arm);

(async () => {
  // No token and no cookie that could open it: say so rather than ask and be refused.
  const c = token ? null : await api.cookies();
  if (c && !c.instructor && !c.trainee_sessions) {
    note('This debrief opens for the instructor signed in on this browser, or on the browser that ran the session: open it from the instructor page or from your completion card.');
    return;
  }
  try {
    attempt = await fetchAttempt();
    // just finished: its end reaches the database with the recorder's next batch
    for (let i = 0; i < FETCH_TRIES && !attempt.outcome; i++) {
      await new Promise((ok) => setTimeout(ok, FETCH_RETRY_MS));
      attempt = await fetchAttempt();
    }
  } catch (e) {
    const who = /token/.test(e.message) ? ' It opens for the instructor signed in on this browser, or on the browser that ran the session.' : '';
    note(`Cannot open attempt ${attemptId}: ${e.message}.${who}`);
    return;
  }
  if (!attempt.outcome) note('This attempt is still running: the replay shows it up to the last recorded second.');
  let title = attempt.exercise || attempt.scenario || 'free play';
  if (attempt.exercise) {
    const ex = (await api.exercises()).find((e) => e.id === attempt.exercise);
    if (ex?.title) title = ex.title;
  }
  showAttempt(attempt, title);
  enableTakeOver(attempt);
  rp.duration_s = attempt.sim_seconds || 0;
  timeline.set(attempt.events || [], rp.duration_s);
  renderTime();
  if (attempt.replayable === false) {
    note(`This attempt cannot be replayed: ${attempt.replay_note || 'no reason given'}. Its events and assessment are shown.`);
    return;
  }
  connect();
  showCompare();
})();

/** The second attempt: its ghost and the side-by-side table (web/compare.js). */
let compare = null;
async function showCompare() {
  if (!attempt.exercise || !attempt.assessment) return;
  compare = await mountCompare({ view, select: $('sel-compare'), table: $('rp-compare-table'), attempt, token });
  $('rp-compare').hidden = !compare.choices;
}

window.__seaarms = view.debugHooks(() => conn, {
  get replay() { return { ...rp }; },
  get attempt() { return attempt; },
  /** The second attempt: the ghost drawn and the one chosen (web/compare.js). */
  ghost() { return compare ? compare.ghost.debug() : null; },
  get compared() { return compare?.chosen ?? null; },
});
