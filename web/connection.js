// Session and WebSocket connection (protocol: server/src/protocol.rs). Creates or resumes a
// trainee session (id + token kept in localStorage), or joins one read-only as an observer,
// or plays a recorded attempt (role `replay`: the replay socket of docs/api.md);
// reconnects with exponential backoff after a drop or a server restart; measures latency with
// ping/pong. Latest state wins: only the newest frame is kept for drawing. A session that ended
// says so with an `ended` message ({reason, text}) before the close; the page never reads
// meaning out of error texts. Session creation (docs/api.md): 403 = the class join code is
// missing or wrong (asked for through `onJoinCode`), 429 = too many sessions from this client
// (retried after `Retry-After`), 503 = the server is full or cannot record (retried).

import * as api from './api.js';

const STORE_KEY = 'seaarms.session';
const BACKOFF_MS = [500, 1000, 2000, 4000, 8000];
/** Retry delay after a 503 on session creation, or a 429 without `Retry-After` (ms). */
const CREATE_RETRY_MS = 10000;


export class Connection {
  /**
   * @param opts {role: 'trainee'|'observer'|'replay', sessionId?, token?, joinCode?, onHello,
   *              onState, onMessage, onError, onEnded({reason, text}), onStatus(kind, text),
   *              onPong(ms), onJoinCode(wrong: boolean) → Promise<string> (the class join code),
   *              replay: {path (WebSocket path with its token), refused (text)}, onReplay(msg)}
   */
  constructor(opts) {
    this.opts = opts;
    this.role = opts.role || 'trainee';
    this.ws = null;
    this.session = null; // {id, control_token, ws_url}
    this.hello = null;
    this.latest = null;
    this.framesReceived = 0;
    this.attempt = 0;
    this.closedByUs = false;
    this.latencyMs = null;
    this.gotHello = false;
    this.pingTimer = null;
    this.retryTimer = null;
    this.joinCode = opts.joinCode || null;
    this.ended = null; // the `ended` message of the current session, once received
    this.observing = false; // a trainee's tab watching its session read-only (web/tabs.js)
    /** What each server message does (web/api.js `dispatch`). */
    this.handlers = {
      hello: (msg) => {
        this.hello = msg;
        this.gotHello = true;
        this.attempt = 0;
        this.status('ok', '');
        this.opts.onHello?.(msg);
      },
      state: (msg) => {
        this.latest = msg;
        this.framesReceived++;
        this.opts.onState?.(msg);
      },
      pong: (msg) => {
        this.latencyMs = performance.now() - msg.t;
        this.opts.onPong?.(this.latencyMs);
      },
      message: (msg) => this.opts.onMessage?.(msg),
      error: (msg) => {
        this.lastError = msg.message;
        this.opts.onError?.(msg.message);
      },
      ended: (msg) => { this.ended = msg; },
      replay: (msg) => this.opts.onReplay?.(msg),
    };
  }

  /** The trainee session stored by this browser ({id, control_token, ws_url}), if any. */
  static stored() {
    try { return JSON.parse(localStorage.getItem(STORE_KEY) || 'null'); } catch { return null; }
  }

  /** Keeps the created session `s` (the answer of POST /api/sessions or of a take-over:
   * {id, control_token, ws_url, base}) as this browser's trainee session, which the trainee
   * page resumes, with the trainee's name and group (`who`) it was created for; returns what
   * it stored. */
  static store(s, who = {}) {
    const session = { id: s.id, control_token: s.control_token, ws_url: s.ws_url, base: s.base || '', ...Connection.whoOf(who) };
    localStorage.setItem(STORE_KEY, JSON.stringify(session));
    return session;
  }

  /** The trainee's name and group in `o` (a stored session or a creation body), those given. */
  static whoOf(o) {
    return { ...(o?.trainee ? { trainee: o.trainee } : {}), ...(o?.group ? { group: o.group } : {}) };
  }

  /** The trainee's name and group this page's sessions are for: those it created its session
   * with, or those stored with the session it resumed (so a link, "Next" or "New session"
   * after a reload still records under the trainee's name). */
  get who() {
    return { ...Connection.whoOf(this.session), ...Connection.whoOf(this.createOpts) };
  }

  /** Reconnects to the same session (a fresh hello, e.g. after the instructor changed its
   * scenario). */
  reconnect() { this.setObserving(this.observing); }

  /** Reconnects to the same session read-only (`true`) or as its trainee (`false`). */
  setObserving(v) {
    this.observing = v;
    if (!this.session) return;
    this.close();
    this.open();
  }

  status(kind, text) { this.opts.onStatus?.(kind, text); }

  /** For the browser tests: the session, frames received, latency, and whether it is open. */
  debugInfo() {
    return { session: this.session?.id, framesReceived: this.framesReceived, latencyMs: this.latencyMs, open: !!this.ws && this.gotHello };
  }

  /** Trainee: resume the stored session if the server still has it, else create one. */
  async start(createOpts = {}) {
    this.createOpts = createOpts;
    if (this.role === 'trainee') {
      const stored = Connection.stored();
      if (stored && stored.id && stored.control_token && await this.stillLive(stored)) {
        this.session = stored;
        this.resuming = true;
      } else {
        if (stored) localStorage.removeItem(STORE_KEY);
        if (!(await this.create())) return;
      }
    } else if (this.role === 'replay') {
      this.session = { id: this.opts.sessionId, ws_url: this.opts.replay.path };
    } else {
      const base = this.opts.base || '';
      this.session = { id: this.opts.sessionId, control_token: this.opts.token, base,
        ws_url: api.sockets.session(this.opts.sessionId, this.opts.token, { observer: true, base }) };
    }
    this.open();
  }

  /** GET /api/sessions/{id} with the control token: is the stored session still live? One
   * that ended while this page was away (e.g. abandoned, or interrupted when its replica
   * stopped) is reported through `onEnded`. Asked without the replica prefix, so any replica
   * answers: 421 means another replica holds it, live (docs/api.md "Replicas"). */
  async stillLive(stored) {
    try {
      const r = await api.sessionSummary(stored.id, stored.control_token);
      if (r.status === 421) return true;
      if (!r.ok) return false;
      const s = await r.json();
      const live = s.status === undefined || s.status === 'live';
      if (!live && s.end_reason && this.endedReported !== stored.id) {
        this.endedReported = stored.id;
        this.opts.onEnded?.({ type: 'ended', reason: null, text: s.end_reason, session: stored.id });
      }
      return live;
    } catch {
      return true; // server unreachable: try the socket, which retries with backoff
    }
  }

  /** POST /api/sessions; returns false (and retries later) when the server is full, busy or
   * down. A 403 (join code missing or wrong) asks `onJoinCode` for the code and tries again. */
  async create(extra = {}) {
    // the trainee's page: an exercise attempt waits for "Ready" (the goal is read first)
    const body = { wait_for_ready: true, ...this.createOpts, ...extra };
    if (this.joinCode) body.join_code = this.joinCode;
    let resp;
    try {
      resp = await api.createSession(body);
    } catch {
      this.status('error', 'Cannot reach the server; retrying…');
      this.scheduleRetry(() => this.start(this.createOpts));
      return false;
    }
    if (resp.status === 403 && resp.headers.get('content-type')?.includes('json')) {
      // a locked exercise (progression) is a 403 whose detail names what is missing
      const b = await api.jsonOf(resp.clone());
      if (b?.detail?.missing) {
        this.status('error', b.error);
        this.opts.onLocked?.(b);
        return false;
      }
    }
    if (resp.status === 403 && this.opts.onJoinCode) {
      this.status('info', this.joinCode ? 'Wrong class join code.' : 'This server needs the class join code.');
      this.joinCode = await this.opts.onJoinCode(!!this.joinCode);
      return this.create(extra);
    }
    if (resp.status === 429 || resp.status === 503) {
      const b = await api.jsonOf(resp);
      const secs = Number(resp.headers.get('retry-after'));
      const ms = secs > 0 ? secs * 1000 : CREATE_RETRY_MS;
      const why = resp.status === 429 ? 'Too many new sessions from this computer' : 'The server cannot start a session now';
      this.status('error', `${why}: ${b?.error || 'HTTP ' + resp.status}. Retrying in ${Math.round(ms / 1000)} s…`);
      clearTimeout(this.retryTimer);
      this.retryTimer = setTimeout(() => this.start(this.createOpts), ms);
      return false;
    }
    if (!resp.ok) {
      const b = await api.jsonOf(resp);
      this.status('error', `Could not create a session: ${b?.error || 'HTTP ' + resp.status}`);
      return false;
    }
    const s = await resp.json();
    this.session = Connection.store(s, body);
    this.resuming = false;
    this.observing = false; // a new session is this tab's to drive
    return true;
  }

  /** Ends the current session (DELETE /api/sessions/{id} with its control token, so it does
   * not linger live and empty) and starts a new one created with `opts` (the body of
   * POST /api/sessions, e.g. another scenario or exercise). */
  async restart(opts) {
    this.close();
    this.closedByUs = false;
    this.createOpts = { ...opts };
    localStorage.removeItem(STORE_KEY);
    const old = this.session;
    const watched = this.observing; // another tab drives that one: it stays
    this.session = null;
    this.hello = null;
    if (old?.control_token && !watched) {
      try {
        await api.endSession(old.id, old.control_token, old.base || '');
      } catch { /* unreachable: the server ends it after its grace period */ }
    }
    if (await this.create()) this.open();
  }

  url() {
    const s = this.session;
    const u = new URL(api.wsUrl(s.ws_url || api.sockets.session(s.id, s.control_token)));
    if (this.observing) u.searchParams.set('role', 'observer');
    return u.href;
  }

  open() {
    clearTimeout(this.retryTimer);
    this.closedByUs = false;
    this.gotHello = false;
    this.lastError = null;
    this.ended = null;
    let ws;
    try { ws = new WebSocket(this.url()); } catch (e) {
      this.status('error', `WebSocket: ${e.message}`);
      return;
    }
    this.ws = ws;
    this.status('info', this.attempt ? `Reconnecting (attempt ${this.attempt + 1})…` : 'Connecting…');
    ws.onopen = () => {
      // the replay socket has no ping (it is not a live link)
      if (this.role !== 'replay') this.pingTimer = setInterval(() => this.send(api.messages.ping(performance.now())), 1000);
    };
    ws.onmessage = (ev) => this.onMessage(ev.data);
    ws.onclose = (ev) => this.onClose(ev);
    ws.onerror = () => { /* onclose follows and handles it */ };
  }

  onMessage(text) { api.dispatch(text, this.handlers); }

  async onClose(ev) {
    clearInterval(this.pingTimer);
    this.ws = null;
    if (this.closedByUs) return;
    const why = this.lastError || ev.reason || '';
    if (!this.gotHello) {
      // Refused before hello: wrong token, ended session, or the server is down.
      const up = await api.healthy();
      if (!up) {
        this.status('error', 'Server unreachable; reconnecting…');
        this.scheduleRetry(() => this.open());
        return;
      }
      if (this.role === 'trainee' && this.resuming && this.session?.control_token
          && this.endedReported !== this.session.id && await this.stillLive(this.session)) {
        // still live on a replica the proxy cannot reach now: keep trying; once the others
        // declare it lost, stillLive reports it ended (interrupted) and a new one starts
        this.status('error', `Connection lost${why ? ' (' + why + ')' : ''}; reconnecting…`);
        this.scheduleRetry(() => this.open());
        return;
      }
      if (this.role === 'trainee') {
        this.status('info', `${this.resuming ? 'The stored session has ended' : 'Session refused'}${why ? ': ' + why : ''}. Starting a new session…`);
        localStorage.removeItem(STORE_KEY);
        this.resuming = false;
        if (this.hello || this.attempt > 3) await new Promise((r) => setTimeout(r, 1000));
        this.attempt++;
        if (await this.create()) this.open();
      } else if (this.role === 'replay') {
        this.status('error', `${this.opts.replay.refused}${why ? ': ' + why : ''}.`);
      } else {
        this.status('error', `Cannot observe this session${why ? ': ' + why : ' (ended, or wrong instructor token)'}.`);
      }
      return;
    }
    if (this.ended) {
      const ended = this.ended;
      this.opts.onEnded?.(ended);
      if (this.role === 'trainee') {
        this.status('info', `This session has ended (${ended.text}). Starting a new session…`);
        localStorage.removeItem(STORE_KEY);
        this.hello = null;
        await new Promise((r) => setTimeout(r, 1500));
        if (await this.create()) this.open();
      } else {
        this.status('error', `This session has ended (${ended.text}).`);
      }
      return;
    }
    this.status('error', `Connection lost${why ? ' (' + why + ')' : ''}; reconnecting…`);
    this.resuming = true;
    this.scheduleRetry(() => this.open());
  }

  scheduleRetry(fn) {
    const ms = BACKOFF_MS[Math.min(this.attempt, BACKOFF_MS.length - 1)];
    this.attempt++;
    clearTimeout(this.retryTimer);
    this.retryTimer = setTimeout(fn, ms);
  }

  send(obj) {
    if (this.ws && this.ws.readyState === WebSocket.OPEN && this.gotHello) {
      this.ws.send(JSON.stringify(obj));
      return true;
    }
    return false;
  }

  close() {
    this.closedByUs = true;
    clearTimeout(this.retryTimer);
    clearInterval(this.pingTimer);
    if (this.ws) {
      // a socket closed here says nothing more (a reopened one must not hear its close)
      this.ws.onmessage = null;
      this.ws.onclose = null;
      this.ws.close(1000, 'bye');
    }
    this.ws = null;
  }
}
