// Instructor dashboard: sign in with the instructor token, list every session with its live
// summary (polls GET /api/sessions), observe one read-only in the same 3D view (observer
// WebSocket), and act on it (POST /api/sessions/{id}/actions).

import { View } from './view.js';
import { Connection } from './connection.js';
import { StatusBar, fmt } from './status.js';

const $ = (id) => document.getElementById(id);
const TOKEN_KEY = 'seaarms.instructor_token';
const POLL_MS = 1000;

let token = sessionStorage.getItem(TOKEN_KEY) || '';
let sessions = [];
let observed = null; // session id
let conn = null;
let view = null;
let status = null;
let pollTimer = null;

$('token').value = token;

function setListStatus(text, bad = false) {
  const el = $('list-status');
  el.textContent = text;
  el.className = bad ? 'bad' : '';
}

function banner(kind, text) {
  const b = $('banner');
  if (!text) { b.hidden = true; return; }
  b.className = kind === 'error' ? '' : kind;
  b.textContent = text;
  b.hidden = false;
}

const esc = (s) => String(s ?? '').replace(/[&<>"]/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;' }[c]));

/** Tolerant reading of a session summary (field names as the server sends them). */
function summary(s) {
  const sum = s.summary || s.state || s;
  const arms = sum.arms || {};
  const w = (side) => {
    const a = arms[side];
    const v = a?.measures?.yoshikawa ?? a?.yoshikawa ?? sum[`yoshikawa_${side}`];
    return v === undefined ? '—' : fmt(v, 3);
  };
  const mode = sum.settings ? `${sum.settings.control_mode}/${sum.settings.control_method}` : (sum.control_mode || '');
  const clients = s.clients ?? s.connections ?? (s.connected === undefined ? '' : (s.connected ? 'yes' : 'no'));
  return {
    id: s.id,
    label: s.label ?? '',
    scenario: s.scenario ?? sum.scenario ?? '',
    clients: typeof clients === 'object' ? JSON.stringify(clients) : clients,
    t: sum.t === undefined ? '' : Number(sum.t).toFixed(1),
    grasp: sum.grasp ?? '',
    mode,
    w: `${w('left')} / ${w('right')}`,
    warn: [...(sum.warnings || []), ...(sum.faults || [])].join(', '),
  };
}

function renderList() {
  const tb = document.querySelector('#sessions tbody');
  tb.innerHTML = sessions.map((s) => {
    const r = summary(s);
    return `<tr data-id="${esc(r.id)}" class="${r.id === observed ? 'open' : ''}"><td>${esc(r.id)}</td><td>${esc(r.label)}</td><td>${esc(r.scenario)}</td>
      <td>${esc(r.clients)}</td><td>${esc(r.t)}</td><td>${esc(r.grasp)}</td><td>${esc(r.mode)}</td><td>${esc(r.w)}</td>
      <td class="warn">${esc(r.warn)}</td><td><button data-open="${esc(r.id)}">${r.id === observed ? 'observing' : 'observe'}</button></td></tr>`;
  }).join('') || '<tr><td colspan="10">no sessions</td></tr>';
}

async function poll() {
  if (!token) return;
  try {
    const r = await fetch('/api/sessions', { headers: { authorization: `Bearer ${token}` }, cache: 'no-store' });
    if (r.status === 401 || r.status === 403) {
      setListStatus('Wrong instructor token.', true);
      sessions = [];
      renderList();
      return;
    }
    if (!r.ok) { setListStatus(`GET /api/sessions: HTTP ${r.status}`, true); return; }
    const body = await r.json();
    sessions = Array.isArray(body) ? body : body.sessions || [];
    setListStatus(`${sessions.length} session(s) · ${new Date().toLocaleTimeString()}`);
    renderList();
  } catch {
    setListStatus('Server unreachable; retrying…', true);
  }
}

function startPolling() {
  clearInterval(pollTimer);
  poll();
  pollTimer = setInterval(poll, POLL_MS);
}

$('token-form').addEventListener('submit', (e) => {
  e.preventDefault();
  token = $('token').value.trim();
  sessionStorage.setItem(TOKEN_KEY, token);
  startPolling();
});

document.querySelector('#sessions tbody').addEventListener('click', (e) => {
  const id = e.target?.dataset?.open;
  if (id) observe(id);
});

function observe(id) {
  if (conn) conn.close();
  observed = id;
  renderList();
  if (!view) {
    view = new View({ canvas: $('canvas'), viewportsEl: $('viewports'), legendEl: $('legend') });
    status = new StatusBar($('status'));
    setInterval(() => { if (view.drawn) status.update(view.drawn, { arm: '—' }); }, 100);
    window.__seaarms = view.debugHooks({
      get observed() { return observed; },
      get connection() { return conn ? { session: observed, framesReceived: conn.framesReceived, open: !!conn.ws && conn.gotHello } : null; },
      statusText() { return $('status').innerText; },
    });
  }
  $('instr-actions').hidden = false;
  $('obs-title').textContent = `session ${id}`;
  $('act-csv').href = `/api/sessions/${encodeURIComponent(id)}/log.csv`;
  conn = new Connection({
    role: 'observer', sessionId: id, token,
    onHello(h) { view.setHello(h); status.role(h.role); if (h.scenario) $('act-scenario').value = h.scenario; },
    onState(s) { view.setState(s); },
    onPong(ms) { status.latency(ms); },
    onMessage(m) { status.message(`✉ ${m.from}: ${m.text}`); },
    onError(msg) { banner('error', msg); },
    onStatus(kind, text) { banner(kind, kind === 'ok' ? '' : text); },
  });
  conn.start();
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
    if (v !== '') body.value = +v;
  }
  if (type === 'message') body.text = $('act-text').value;
  const out = $('act-result');
  try {
    const r = await fetch(`/api/sessions/${encodeURIComponent(observed)}/actions`, {
      method: 'POST', headers: { 'content-type': 'application/json', authorization: `Bearer ${token}` }, body: JSON.stringify(body),
    });
    let b = null;
    try { b = await r.json(); } catch { /* empty body */ }
    out.textContent = r.ok ? `${type}: ok` : `${type}: ${b?.error || 'HTTP ' + r.status}`;
    out.className = r.ok ? '' : 'bad';
    if (r.ok && type === 'message') $('act-text').value = '';
  } catch {
    out.textContent = `${type}: server unreachable`;
    out.className = 'bad';
  }
}

for (const b of document.querySelectorAll('#instr-actions button[data-act]')) {
  b.addEventListener('click', () => act(b.dataset.act));
}

(async () => {
  try {
    const r = await fetch('/api/scenarios');
    if (!r.ok) throw new Error();
    const body = await r.json();
    const list = Array.isArray(body) ? body : body.scenarios || [];
    $('act-scenario').innerHTML = list.map((s) => {
      const name = typeof s === 'string' ? s : s.name || s.id;
      return `<option value="${esc(name)}">${esc(name)}</option>`;
    }).join('');
  } catch { /* no scenarios endpoint */ }
})();

if (token) startPolling();
const want = new URLSearchParams(location.search).get('session');
if (want && token) observe(want);
