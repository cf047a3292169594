// The page's protocol module: every URL the pages request or link to and every WebSocket
// message they send or read, in one place (server/src/protocol.rs is the server's side;
// docs/api.md documents both). The other modules call these functions; none builds a URL or
// a wire message of its own. Nothing here touches the DOM or runs at load (the browser tests
// import the page's modules in Node).

const enc = encodeURIComponent;

/** The `authorization` header of a bearer token (none without a token). */
function auth(token) {
  return token ? { authorization: `Bearer ${token}` } : {};
}

/** A request to this server: `token` sent as a bearer token, `body` as JSON; GETs are never
 * answered from the browser's cache (the server's state changes under them). */
function call(method, path, { token, body } = {}) {
  const init = { method, headers: auth(token) };
  if (body !== undefined) {
    init.headers['content-type'] = 'application/json';
    init.body = JSON.stringify(body);
  }
  if (method === 'GET') init.cache = 'no-store';
  return fetch(path, init);
}

/** The JSON body of an answer, or null when it has none. */
export async function jsonOf(resp) {
  try { return await resp.json(); } catch { return null; }
}

/** Why an answer failed: the server's `error` text (every error body has one), else the status. */
async function errorOf(resp) {
  return (await jsonOf(resp))?.error || `HTTP ${resp.status}`;
}

// ---- URLs ------------------------------------------------------------------------------

/** A session's REST path; `base` is its replica's path prefix ('' on a single server,
 * docs/api.md "Replicas"). */
const sessionPath = (id, base = '') => `${base}/api/sessions/${enc(id)}`;
const withToken = (path, token) => (token ? `${path}?token=${enc(token)}` : path);

/** Links the pages show. None carries a token: the browser's cookies open them (the
 * instructor's sign-in, `signIn`; the trainee's session cookie, set when it was created). */
export const links = {
  /** A session's record as CSV. */
  sessionCsv: (id, base = '') => `${sessionPath(id, base)}/log.csv`,
  /** The debrief page of an attempt. */
  debrief: (attemptId) => `/replay/${enc(attemptId)}`,
  /** The class results (CSV of finished attempts), of one group or all. */
  resultsCsv: (group) => (group ? `/api/results.csv?${new URLSearchParams({ group })}` : '/api/results.csv'),
  /** A trainee's printable logbook page (the instructor's sign-in cookie opens its data). */
  logbook: (trainee, group) => `/logbook?${new URLSearchParams({ trainee, group: group || '' })}`,
  /** A trainee's logbook as CSV. */
  logbookCsv: (trainee, group) => `/api/logbook.csv?${new URLSearchParams({ trainee, group: group || '' })}`,
};

/** GET /api/signin: what this browser's cookies are ({instructor, trainee_sessions}), or null. */
export async function cookies() {
  try {
    const r = await call('GET', '/api/signin');
    return r.ok ? r.json() : null;
  } catch {
    return null;
  }
}

/** POST /api/signin: this browser signed in as the instructor (an HttpOnly cookie); the answer. */
export function signIn(token) {
  return call('POST', '/api/signin', { body: { token } });
}

/** WebSocket paths (see `wsUrl`). */
export const sockets = {
  /** A live session's socket, as its trainee or (`observer`) read-only; without a token
   * the cookies open it (the instructor's sign-in: no token in a URL, issue 29). */
  session: (id, token, { observer = false, base = '' } = {}) => {
    const q = [token ? `token=${enc(token)}` : '', observer ? 'role=observer' : ''].filter(Boolean).join('&');
    return `${base}/ws/sessions/${enc(id)}${q ? `?${q}` : ''}`;
  },
  /** The replay socket of a recorded attempt (without a token, the cookies open it). */
  replay: (attemptId, token) => withToken(`/ws/replay/${enc(attemptId)}`, token),
};

/** Absolute WebSocket URL on this page's origin (only the path and query of the server's
 * `ws_url` are used, so the page also works behind a TLS proxy or another host name). */
export function wsUrl(pathOrUrl) {
  const u = new URL(pathOrUrl, location.href);
  const proto = location.protocol === 'https:' ? 'wss:' : 'ws:';
  return `${proto}//${location.host}${u.pathname}${u.search}`;
}

// ---- REST ------------------------------------------------------------------------------

/** GET /healthz: whether the server answers. */
export function healthy() {
  return fetch('/healthz', { cache: 'no-store' }).then((r) => r.ok).catch(() => false);
}

/** POST /api/sessions (`body`: scenario or exercise, trainee, group, join_code); the answer. */
export function createSession(body) {
  return call('POST', '/api/sessions', { body });
}

/** GET /api/sessions/{id} with the session's control token or the instructor's; the answer. */
export function sessionSummary(id, token, base = '') {
  return call('GET', sessionPath(id, base), { token });
}

/** DELETE /api/sessions/{id}: ends the session. */
export function endSession(id, token, base = '') {
  return call('DELETE', sessionPath(id, base), { token });
}

/** GET `path` with `token`: its JSON, or null when refused or unreachable. */
async function jsonOrNull(path, token) {
  try {
    const r = await call('GET', path, { token });
    return r.ok ? await r.json() : null;
  } catch {
    return null;
  }
}

/** GET /api/sessions/{id}/progress: the session's trainee's learning curves on every
 * exercise (docs/api.md), or null. */
export function sessionProgress(id, token, base = '') {
  return jsonOrNull(`${sessionPath(id, base)}/progress`, token);
}

/** GET /api/sessions/{id}/ghosts?exercise=: the attempts that may be drawn as the ghost on
 * `exercise` and compared with ({best, reference, attempts}, docs/api.md), or null. Without a
 * token the browser's cookie opens it. */
export function sessionGhosts(id, exercise, token, base = '') {
  return jsonOrNull(`${sessionPath(id, base)}/ghosts?${new URLSearchParams({ exercise })}`, token);
}

/** GET /api/attempts/{id}/track?session=: an attempt's poses at 10 Hz for drawing it as a ghost
 * (`session`: the asking trainee's session, which opens its own attempts and the reference
 * operators'), or null. */
export function attemptTrack(id, session, token) {
  return jsonOrNull(`/api/attempts/${enc(id)}/track?${new URLSearchParams({ session })}`, token);
}

/** GET /api/sessions/{id}/assessment: the session's exercise assessment, or null. */
export function sessionAssessment(id, token, base = '') {
  return jsonOrNull(`${sessionPath(id, base)}/assessment`, token);
}

/** Ended sessions the instructor's list asks for at first, and each "older" adds. */
export const ENDED_PAGE = 50;

/** GET /api/sessions with the instructor token: every live session and the `ended` newest
 * stored ones (the answer's `X-Next-Before` says whether there are older); the answer. */
export function listSessions(token, ended = ENDED_PAGE) {
  return call('GET', `/api/sessions?ended=${ended}`, { token });
}

/** POST /api/sessions/{id}/actions (an instructor's action); resolves {ok, error}. */
export async function sessionAction(id, body, token, base = '') {
  try {
    const r = await call('POST', `${sessionPath(id, base)}/actions`, { token, body });
    return { ok: r.ok, error: r.ok ? null : await errorOf(r) };
  } catch {
    return { ok: false, error: 'server unreachable' };
  }
}

/** GET /api/scenarios: the scenario list ([{name, description}] or names), or null when the
 * server cannot say. */
export async function scenarios() {
  try {
    const r = await call('GET', '/api/scenarios');
    if (!r.ok) return null;
    const body = await r.json();
    return Array.isArray(body) ? body : body.scenarios || [];
  } catch {
    return null;
  }
}

let catalogueBody = null;
/** GET /api/exercises, asked once per page and shared: {exercises, progression} (no
 * exercises when the server has none or cannot say; a failed ask is asked again next time). */
export function catalogue() {
  catalogueBody ??= call('GET', '/api/exercises')
    .then((r) => (r.ok ? r.json() : Promise.reject(new Error(`HTTP ${r.status}`))))
    .catch(() => { catalogueBody = null; return { exercises: [] }; });
  return catalogueBody;
}

/** The exercises of GET /api/exercises ([] when none or unknown). */
export function exercises() {
  return catalogue().then((b) => b.exercises || []);
}

/** GET/PUT/DELETE /api/unlocks (instructor): each exercise open or locked for a trainee;
 * `on`: unlock `exercise` (true), lock it again (false), or only read (undefined). */
export async function unlocks(trainee, group, token, exercise, on) {
  const q = new URLSearchParams({ trainee, group: group || '' });
  let r;
  if (on === undefined) r = await call('GET', `/api/unlocks?${q}`, { token });
  else if (on) r = await call('PUT', '/api/unlocks', { token, body: { trainee, group: group || '', exercise } });
  else { q.set('exercise', exercise); r = await call('DELETE', `/api/unlocks?${q}`, { token }); }
  const b = await jsonOf(r);
  if (!r.ok) throw new Error(b?.error || `HTTP ${r.status}`);
  return b;
}

/** GET /api/attempts/{id} (metadata, assessment, events); the answer. */
export function attempt(id, token) {
  return call('GET', `/api/attempts/${enc(id)}`, { token });
}

/** POST /api/attempts/{id}/take-over {t}: a new session whose first attempt is a practice
 * attempt from the attempt's replayed state at `t` s; the answer (as `createSession`'s). */
export function takeOver(id, t, token) {
  return call('POST', `/api/attempts/${enc(id)}/take-over`, { token, body: { t } });
}

/** GET /api/attempts filtered by `filter` ({trainee, exercise, group, limit}); the list, or
 * throws with the server's reason. */
export async function attempts(filter, token) {
  const r = await call('GET', `/api/attempts?${new URLSearchParams(filter)}`, { token });
  if (!r.ok) throw new Error(await errorOf(r));
  return (await r.json()).attempts || [];
}

/** GET /api/progress: a class's proficiency on `exercise` (instructor; `group` optional):
 * {exercise, benchmark, trainees: [curve]} (docs/api.md). */
export async function classProgress(exercise, group, token) {
  const q = new URLSearchParams({ exercise, ...(group ? { group } : {}) });
  const r = await call('GET', `/api/progress?${q}`, { token });
  if (!r.ok) throw new Error(await errorOf(r));
  return r.json();
}

/** GET /api/reference-operators (instructor): [{trainee, group, marked_unix}]. */
export async function referenceOperators(token) {
  const r = await call('GET', '/api/reference-operators', { token });
  if (!r.ok) throw new Error(await errorOf(r));
  return (await r.json()).reference_operators || [];
}

/** PUT /api/reference-operators (instructor): marks or unmarks a trainee; the new list. */
export async function markReference(trainee, group, reference, token) {
  const r = await call('PUT', '/api/reference-operators', { token, body: { trainee, group, reference } });
  if (!r.ok) throw new Error(await errorOf(r));
  return (await r.json()).reference_operators || [];
}

/** GET /api/logbook (instructor): a trainee's logbook {trainee, group, generated_unix,
 * exercises: [entry]} (docs/api.md). */
export async function logbook(trainee, group, token) {
  const q = new URLSearchParams({ trainee, group: group || '' });
  const r = await call('GET', `/api/logbook?${q}`, { token });
  if (!r.ok) throw new Error(await errorOf(r));
  return r.json();
}

/** PUT /api/signoffs (instructor): signs a trainee off on an exercise; the sign-off. */
export async function signOff(body, token) {
  const r = await call('PUT', '/api/signoffs', { token, body });
  if (!r.ok) throw new Error(await errorOf(r));
  return r.json();
}

/** DELETE /api/signoffs (instructor): revokes a trainee's sign-off on an exercise. */
export async function revokeSignoff(trainee, group, exercise, token) {
  const q = new URLSearchParams({ trainee, group: group || '', exercise });
  const r = await call('DELETE', `/api/signoffs?${q}`, { token });
  if (!r.ok) throw new Error(await errorOf(r));
}

/** POST /api/analysis (`body`: {robot, q, polytope?}); the analysis, or null. */
export async function analysis(body) {
  try {
    const r = await call('POST', '/api/analysis', { body });
    return r.ok ? await r.json() : null;
  } catch {
    return null;
  }
}

/** POST /api/studies/workspace-map; the map, or throws with the server's reason. */
export async function workspaceMap(body) {
  const r = await call('POST', '/api/studies/workspace-map', { body });
  if (!r.ok) throw new Error(await errorOf(r));
  return r.json();
}

// ---- WebSocket messages ----------------------------------------------------------------

/** Messages the page sends: on a session's socket (protocol.rs `ClientMessage`) and on a
 * replay's (docs/api.md "Attempts and replay": play, pause, seek, speed). */
export const messages = {
  /** Stick input: `arms` {left, right: {axes[6], grip}}, `object` the object's twist
   * sticks in closed loop (else absent). */
  input: (seq, arms, object) => (object ? { type: 'input', seq, arms, object } : { type: 'input', seq, arms }),
  /** A keyboard tap: `arm` moves a bounded amount along `axes` (six values in [−1, 1], world
   * frame in Cartesian mode) and stops (docs/api.md). */
  jog: (arm, axes) => ({ type: 'jog', arm, axes }),
  /** A change of settings ({control_mode, control_method, arm_speed, hold_orientation}, any
   * of them). */
  settings: (patch) => ({ type: 'settings', ...patch }),
  reset: () => ({ type: 'reset' }),
  release: () => ({ type: 'release' }),
  pause: () => ({ type: 'pause' }),
  resume: () => ({ type: 'resume' }),
  /** The fault drill's answer (a fault kind's name). */
  diagnose: (answer) => ({ type: 'diagnose', answer }),
  /** The trainee has read the goal: the exercise attempt's clock starts. */
  ready: () => ({ type: 'ready' }),
  /** Latency probe: the server answers `pong` with the same `t`. */
  ping: (t) => ({ type: 'ping', t }),
  play: () => ({ type: 'play' }),
  /** Replay: go to `t` (s since the attempt's start). */
  seek: (t) => ({ type: 'seek', t }),
  /** Replay: play at `value` × real time. */
  speed: (value) => ({ type: 'speed', value }),
};

/** The names of the joints of the model a `hello` carries for arm `i` (0 left, 1 right:
 * `arms[i].model.joints[j].name`, the robot file's names); "joint j" where the model names
 * none, or before the hello. */
export function jointNames(hello, i = 0) {
  const joints = hello?.arms?.[i]?.model?.joints;
  return Array.from({ length: joints?.length || 6 }, (_, j) => joints?.[j]?.name || `joint ${j + 1}`);
}

/** The server's messages the page reads (protocol.rs `ServerMessage`): `hello`, `state`,
 * `pong`, `message`, `error`, `ended`, and the replay socket's `replay`. Parses `text` and
 * calls `handlers[type](msg)`; a message that is not JSON or has no handler is ignored. */
export function dispatch(text, handlers) {
  let msg;
  try { msg = JSON.parse(text); } catch { return; }
  if (typeof msg?.type === 'string' && Object.hasOwn(handlers, msg.type)) handlers[msg.type](msg);
}
