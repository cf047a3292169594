// Instructor dashboard: sign in with the instructor token, list every session with its live
// summary (polls GET /api/sessions), observe one read-only in the same 3D view (observer
// WebSocket), and act on it (POST /api/sessions/{id}/actions); the Classroom tab
// (web/classroom.js) shows the same summaries as a roster by trainee name, with attempt
// histories, a comparison on one exercise and the class results export.

import { View } from './view.js';
import { followVisibility } from './viewcontrols.js';
import { Connection } from './connection.js';
import { StatusBar } from './status.js';
import { Classroom, faultText } from './classroom.js';
import { $, esc, fmt, note, Banner, statusLoop } from './page.js';
import * as api from './api.js';
const TOKEN_KEY = 'seaarms.instructor_token';
const POLL_MS = 1000;
/** Default size of each fault when the value box is empty (server ranges in README). */
const FAULT_DEFAULTS = { supply_drop: 3.0e6, stuck_valve: 0.5, leak: 5e-10, air: 0.3 };

let token = sessionStorage.getItem(TOKEN_KEY) || '';
let sessions = [];
let observed = null; // session id
let observedBase = ''; // path prefix of the observed session's replica ('' on a single server)
let conn = null;
let view = null;
let status = null;
let pollTimer = null;

$('token').value = token;

function setListStatus(text, bad = false) {
  note($('list-status'), text, bad);
}

const banner = new Banner($('banner'));

/** One row of GET /api/sessions: {id, status, label, scenario, sim_seconds, grasp?, paused?,
 * trainees?, measures?: [left, right], overload_count, faults?, recording: 'ok'|'failed'}. */
function summary(s) {
  const w = (i) => (s.measures && s.measures[i] ? fmt(s.measures[i].yoshikawa, 3) : '—');
  return {
    id: s.id,
    status: s.status || 'live',
    label: s.trainee ?? s.label ?? '',
    scenario: s.scenario ?? '',
    clients: s.status === 'ended' ? (s.end_reason || 'ended')
      : `${s.trainees ?? 0} trainee(s)${s.awaiting_ready ? ', waiting for Ready' : s.paused ? ', paused' : ''}`,
    t: s.sim_seconds === undefined ? '' : Number(s.sim_seconds).toFixed(1),
    grasp: s.grasp ?? '',
    w: `${w(0)} / ${w(1)}`,
    recordingFailed: s.recording === 'failed',
    warn: [s.recording === 'failed' ? 'recording failed (record incomplete)' : '', ...(s.faults || []).map(faultText),
      s.overload_count ? `${s.overload_count} overload(s)` : ''].filter(Boolean).join(', '),
  };
}

function renderList() {
  const tb = document.querySelector('#sessions tbody');
  tb.innerHTML = sessions.map((s) => {
    const r = summary(s);
    // an ended session links its record: the newest attempts' debriefs and the CSV
    const btn = r.status === 'live' ? `<button data-open="${esc(r.id)}">${r.id === observed ? 'observing' : 'observe'}</button>`
      : `${(s.attempts || []).slice(0, 3).map((a, i) => `<a href="${esc(api.links.debrief(a))}" target="_blank" rel="noopener">debrief${i ? ` ${i + 1}` : ''}</a>`).join(' ')}
        <a href="${esc(api.links.sessionCsv(r.id))}" download>CSV</a>`;
    return `<tr data-id="${esc(r.id)}" data-status="${esc(r.status)}" class="${[r.id === observed ? 'open' : '', r.recordingFailed ? 'rec-failed' : ''].join(' ').trim()}"><td>${esc(r.id)}</td><td>${esc(r.status)}</td><td>${esc(r.label)}</td>
      <td>${esc(r.scenario)}</td><td>${esc(r.clients)}</td><td>${esc(r.t)}</td><td>${esc(r.grasp)}</td><td>${esc(r.w)}</td>
      <td class="warn">${esc(r.warn)}</td><td>${btn}</td></tr>`;
  }).join('') || '<tr><td colspan="10">no sessions</td></tr>';
}

/** Ended sessions the list shows (the newest; "Older sessions" shows more). */
let endedShown = api.ENDED_PAGE;
$('more-sessions').addEventListener('click', () => { endedShown += api.ENDED_PAGE; poll(); });

async function poll() {
  if (!token) return;
  try {
    const r = await api.listSessions(token, endedShown);
    if (r.status === 401 || r.status === 403) {
      setListStatus('Wrong instructor token.', true);
      sessions = [];
      renderList();
      return;
    }
    if (!r.ok) { setListStatus(`GET /api/sessions: HTTP ${r.status}`, true); return; }
    const body = await r.json();
    sessions = Array.isArray(body) ? body : body.sessions || [];
    $('more-sessions').hidden = !r.headers.get('x-next-before');
    setListStatus(`${sessions.length} session(s) · ${new Date().toLocaleTimeString()}`);
    renderList();
    classroom.render(sessions);
  } catch {
    setListStatus('Server unreachable; retrying…', true);
  }
}

function startPolling() {
  clearInterval(pollTimer);
  poll();
  pollTimer = setInterval(poll, POLL_MS);
}

/** Signs this browser in (the cookie that opens the debrief and download links, which carry
 * no token in their URLs); false, with the reason shown, when the server refuses. */
async function signIn() {
  try {
    const r = await api.signIn(token);
    if (r.ok) return true;
    setListStatus(r.status === 403 ? 'Wrong instructor token.' : `sign in: HTTP ${r.status}`, true);
  } catch (err) {
    setListStatus(`sign in: ${err.message}`, true);
  }
  return false;
}

$('token-form').addEventListener('submit', async (e) => {
  e.preventDefault();
  token = $('token').value.trim();
  sessionStorage.setItem(TOKEN_KEY, token);
  if (!(await signIn())) return;
  classroom.exportLink();
  startPolling();
});

document.querySelector('#sessions tbody').addEventListener('click', (e) => {
  const id = e.target?.dataset?.open;
  if (id) observe(id);
});

/** The observed session's water current as the current fields' placeholders (the values to type
 * over), or "in air". */
function showCurrent(c) {
  const [speed, heading] = c ? [c.speed_m_s.toFixed(2), String(Math.round(c.heading_deg))] : ['in air', '—'];
  if ($('act-cur-speed').placeholder !== speed) $('act-cur-speed').placeholder = speed;
  if ($('act-cur-heading').placeholder !== heading) $('act-cur-heading').placeholder = heading;
}

function observe(id) {
  if (conn) conn.close();
  observed = id;
  renderList();
  if (!view) {
    view = new View({ canvas: $('canvas'), viewportsEl: $('viewports'), legendEl: $('legend') });
    status = new StatusBar($('status'));
    statusLoop(view, status, () => '—');
    window.__seaarms = view.debugHooks(() => conn, {
      get observed() { return observed; },
    });
  }
  $('instr-actions').hidden = false;
  $('view-hint').hidden = true;
  const who = sessions.find((s) => s.id === id);
  const name = who?.trainee || who?.label;
  $('obs-title').textContent = name ? `${name}${who.group ? ` (${who.group})` : ''} · session ${id}` : `session ${id}`;
  // another replica's session: its URLs carry that replica's prefix (docs/api.md "Replicas")
  observedBase = who?.base || '';
  $('act-csv').href = api.links.sessionCsv(id, observedBase);
  conn = new Connection({
    // the sign-in cookie opens the socket: the instructor token stays out of its URL
    role: 'observer', sessionId: id, token: null, base: observedBase,
    onHello(h) { view.setHello(h); status.role(h.role); if (h.scenario) $('act-scenario').value = h.scenario; },
    onState(s) { view.setState(s); followVisibility(view, s.visibility_m); showCurrent(s.current); },
    onPong(ms) { status.latency(ms); },
    onMessage(m) { status.message(`✉ ${m.from}: ${m.text}`); },
    onError(msg) { banner.show('error', msg); },
    onStatus(kind, text) { banner.show(kind, kind === 'ok' ? '' : text); },
  });
  conn.start();
}

/** POST /api/sessions/{id}/actions; resolves {ok, error}. */
function postAction(id, body) {
  return api.sessionAction(id, body, token, observedBase);
}

async function act(type) {
  if (!observed) return;
  const body = { type };
  if (type === 'scenario') body.scenario = $('act-scenario').value;
  if (type === 'fault') {
    body.fault = $('act-fault').value;
    body.arm = $('act-arm').value;
    if ($('act-joint').value !== '') body.joint = +$('act-joint').value;
    const v = $('act-value').value.trim();
    body.value = v === '' ? FAULT_DEFAULTS[body.fault] : +v;
    if ((body.fault === 'stuck_valve' || body.fault === 'leak') && body.joint === undefined) body.joint = 1;
    if ($('act-silent').checked) body.silent = true; // a diagnosis drill: the trainee is not told
    if ($('act-persistent').checked) body.persistent = true; // kept across the trainee's reset
  }
  if (type === 'message') body.text = $('act-text').value;
  if (type === 'set_current') {
    // Empty boxes mean 0; anything else goes as typed and the server checks it.
    const num = (id) => { const v = $(id).value.trim(); return v === '' ? 0 : Number(v); };
    body.speed_m_s = num('act-cur-speed');
    body.heading_deg = num('act-cur-heading');
  }
  if (type === 'set_visibility') {
    const v = $('act-visibility').value.trim();
    body.visibility_m = v === '' ? 6 : Number(v);
  }
  const out = $('act-result');
  const r = await postAction(observed, body);
  out.textContent = r.ok ? `${type}${body.silent ? ' (silent)' : ''}: ok` : `${type}: ${r.error}`;
  out.className = r.ok ? '' : 'bad';
  if (r.ok && type === 'message') $('act-text').value = '';
}

for (const b of document.querySelectorAll('#instr-actions button[data-act]')) {
  b.addEventListener('click', () => act(b.dataset.act));
}

(async () => {
  const list = await api.scenarios();
  if (!list) return; // no scenarios endpoint
  if (!list.some((s) => (typeof s === 'string' ? s : s.name) === 'training')) list.unshift({ name: 'training' });
  // Exercises are scenarios too (the trainee's page follows a switch to one).
  for (const e of await api.exercises()) list.push({ name: e.id, title: `exercise: ${e.title}` });
  $('act-scenario').innerHTML = list.map((s) => {
    const name = typeof s === 'string' ? s : s.name || s.id;
    return `<option value="${esc(name)}">${esc(s.title || name)}</option>`;
  }).join('');
})();

const classroom = new Classroom({
  token: () => token,
  observe: (id) => observe(id),
  act: postAction,
  observed: () => observed,
});

/** Sessions / Classroom tabs (the 3D view and the action bar stay below both). */
function showTab(name) {
  for (const b of document.querySelectorAll('#instr-tabs [data-tab]')) b.classList.toggle('on', b.dataset.tab === name);
  $('instr-list').hidden = name !== 'sessions';
  classroom.show(name === 'classroom');
  sessionStorage.setItem('seaarms.instructor_tab', name);
}
for (const b of document.querySelectorAll('#instr-tabs [data-tab]')) b.addEventListener('click', () => showTab(b.dataset.tab));
showTab(new URLSearchParams(location.search).get('tab') || sessionStorage.getItem('seaarms.instructor_tab') || 'sessions');

const want = new URLSearchParams(location.search).get('session');
if (token) {
  signIn().then((ok) => {
    if (!ok) return;
    startPolling();
    if (want) observe(want);
  });
}
