// Trainee page: creates or resumes a session, draws it, sends input. No physics here.

import { Connection } from './connection.js';
import { Input, DEAD_ZONE, mapping } from './input.js';
import { TouchPad, touchDevice } from './touch.js';
import { TabGuard } from './tabs.js';
import { StartScreen } from './start.js';
import { TaskPanel } from './task.js';
import { mountViews, followVisibility } from './viewcontrols.js';
import { $, Banner, statusLoop } from './page.js';
import { messages, exercises, jointNames, sessionSummary, sessionProgress, sessionGhosts, attemptTrack } from './api.js';
import { Ghost, choiceLabel } from './ghost.js';
import { ForceCues } from './rumble.js';
import { jointTurnWords, frameRows } from './sticks.js';
const SPEEDS = [0.25, 0.5, 0.75, 1];
/** Screens this narrow stack the page (style.css has the same width). */
const NARROW_SCREEN = '(max-width: 700px)';

const { view, status, plots, controls: viewControls } = mountViews();
const banner = new Banner($('banner'));
const showBanner = (kind, text, ms = 0) => banner.show(kind, text, ms);
let selectedArm = localStorage.getItem('seaarms.arm') === 'right' ? 'right' : 'left';
let settings = { control_mode: 'joint', control_method: 'open', arm_speed: 1, hold_orientation: true };

const params = new URLSearchParams(location.search);
let lastEnded = null; // the last `ended` message ({reason, text}), for tests
let endedNote = null; // shown once the next session's hello arrives

/** Shows the join-code prompt; resolves with the code the trainee types. */
function askJoinCode(wrong) {
  const form = $('join');
  const field = $('join-code');
  $('join-error').hidden = !wrong;
  form.hidden = false;
  field.value = '';
  field.focus();
  return new Promise((resolve) => {
    form.onsubmit = (e) => {
      e.preventDefault();
      const code = field.value.trim();
      if (!code) return;
      form.hidden = true;
      field.blur();
      resolve(code);
    };
  });
}

const conn = new Connection({
  role: 'trainee',
  joinCode: params.get('join'),
  onJoinCode: askJoinCode,
  // an exercise still locked for this trainee (progression): back to the choice, saying why
  onLocked(b) { startScreen.note = b.error; chooseAndStart(); },
  onEnded(e) {
    // why the session ended (e.g. abandoned: no connection for the grace period), shown again
    // over the next session and on the start screen
    lastEnded = e;
    endedNote = `Your previous session ended: ${e.text}.`;
    startScreen.note = endedNote;
    status.message(endedNote);
  },
  onHello(h) {
    setRole(h.role, h.session);
    if (endedNote) { showBanner('info', `${endedNote} This is a new session.`, 8000); endedNote = null; }
    view.setHello(h);
    setExercise(h);
    refreshGhosts();
    settings = { ...h.settings };
    syncControls();
    plots.setSession(h.session, conn.session?.base);
    plots.setJoints(jointNames(h));
    touch.setJoints(jointNames(h));
    status.role(h.role);
    input.setServerLimit(h.max_messages_per_second);
    setScenarios(h.scenarios, h.scenario);
    renderHelp();
  },
  onState(s) {
    view.setState(s);
    followAttempt(s);
    followVisibility(view, s.visibility_m);
    if (driving) cues.update(s, selectedArm);
    followScenario(s);
    plots.add(s, selectedArm);
    if (s.settings.control_mode !== settings.control_mode || s.settings.control_method !== settings.control_method ||
        s.settings.arm_speed !== settings.arm_speed || s.settings.hold_orientation !== settings.hold_orientation) {
      settings = { ...s.settings };
      syncControls();
    }
  },
  onPong(ms) { status.latency(ms); },
  onMessage(m) {
    status.message(`✉ ${m.from}: ${m.text}`);
    showBanner('msg', `Message from ${m.from}: ${m.text}`, 15000);
  },
  onError(msg) { showBanner('error', msg, 6000); },
  onStatus(kind, text) {
    if (kind === 'ok') showBanner(null, '');
    else showBanner(kind, text);
  },
});

statusLoop(view, status, () => selectedArm, (s) => task.update(s.exercise, s.awaiting_ready, s.practice));

const startScreen = new StartScreen($('start'));
const task = new TaskPanel($('task'), $('card'), $('gauges'), {
  banner: showBanner,
  withdraw: (text) => banner.withdraw(text),
  tryAgain: () => conn.send(messages.reset()), // a new attempt (docs/exercises.md)
  diagnose: (answer) => conn.send(messages.diagnose(answer)), // fault drill
  ready: () => conn.send(messages.ready()), // the goal is read: the attempt's clock starts
  nextTitle: async () => (await nextOpen())?.title,
  next: async () => { const n = await nextOpen(); if (n) newSession({ exercise: n.id }); else chooseAndStart(); },
  choose: () => chooseAndStart(),
});
/** What the page was set up for by the last hello: {scenario, exercise id or null}. */
let setUpFor = null;

/** A hello's exercise: the task panel, the exercise's arm, plots off while training. */
function setExercise(h) {
  const ex = h.exercise || null;
  setUpFor = { scenario: h.scenario, exercise: ex?.id ?? null };
  const was = task.active;
  task.setExercise(ex, conn.session);
  // the list behind "next exercise" (the start screen fills it when it was shown)
  if (ex && !startScreen.exercises.length) exercises().then((l) => { startScreen.exercises = l; });
  if (ex && (ex.control?.arm === 'left' || ex.control?.arm === 'right')) setArm(ex.control.arm);
  // a fault drill is diagnosed from the line pressures: its plots are on (not on a phone)
  const drill = !!ex?.fault_drill;
  if (!!ex !== was || drill) {
    $('chk-plots').checked = (!ex || drill) && !matchMedia(NARROW_SCREEN).matches;
    $('chk-plots').dispatchEvent(new Event('change'));
    // an exercise starts with the work site in sight: no ellipsoids over the jaws (O shows them)
    $('chk-ell').checked = !ex;
    $('chk-ell').dispatchEvent(new Event('change'));
  }
  // an assessed exercise may allow only the vehicle's cameras (`"views": "pilot"`)
  const pilotOnly = ex?.views === 'pilot';
  view.viewports.setAllowedSets(pilotOnly ? ['pilot'] : ['engineering', 'pilot']);
  $('sel-views').querySelector('option[value="engineering"]').disabled = pilotOnly;
  $('sel-views').value = view.viewports.set;
  if (ex) view.frameWorkSiteSoon(); // once the first frame has placed the box and its handles
  view.viewports.dirty = true;
}

/** The ghost (web/ghost.js): none, the trainee's best or the reference operators' best attempt
 * at this exercise (GET /api/sessions/{id}/ghosts), drawn on the attempt's clock; off by
 * default, N toggles it. */
const ghost = new Ghost(view);
let ghostChoices = null;
/** What N turns on again. */
let ghostLast = 'best';
/** The newest frame was waiting for "Ready" (a new attempt starts waiting). */
let wasAwaiting = false;

/** Asks which attempts may be the ghost (on each hello and each new attempt: a finished one
 * may be the new best), then draws the chosen one. */
async function refreshGhosts() {
  const sel = $('sel-ghost');
  const s = conn.session;
  const ex = setUpFor?.exercise;
  ghostChoices = ex && s?.control_token ? await sessionGhosts(s.id, ex, s.control_token, s.base || '') : null;
  sel.disabled = !ghostChoices;
  for (const kind of ['best', 'reference']) {
    const o = sel.querySelector(`option[value="${kind}"]`);
    o.textContent = choiceLabel(kind, ghostChoices?.[kind]);
    o.disabled = !ghostChoices?.[kind];
  }
  if (!ghostChoices) sel.value = 'none';
  await applyGhost();
}

/** Draws the ghost the menu names (its track fetched once per attempt). */
async function applyGhost() {
  const which = $('sel-ghost').value;
  const c = which === 'none' ? null : ghostChoices?.[which];
  if (!c) { ghost.clear(); return; }
  if (ghost.attempt === c.attempt) return;
  const s = conn.session;
  const track = await attemptTrack(c.attempt, s.id, s.control_token);
  if ($('sel-ghost').value !== which) return; // changed meanwhile
  if (track) ghost.show(track);
  else { ghost.clear(); showBanner('error', 'The ghost could not be loaded.', 5000); }
}

function followAttempt(s) {
  const awaiting = !!s.awaiting_ready;
  if (awaiting && !wasAwaiting && setUpFor?.exercise) refreshGhosts();
  wasAwaiting = awaiting;
}

/** The instructor may switch the session's scenario or exercise: the frames say so, and a
 * fresh hello (reconnecting to the same session) sets the page up for it. */
function followScenario(s) {
  if (!setUpFor || s.scenario === undefined) return;
  const exercise = s.exercise?.id ?? null;
  if (s.scenario === setUpFor.scenario && exercise === setUpFor.exercise) return;
  setUpFor = { scenario: s.scenario, exercise };
  showBanner('info', `The instructor switched this session to ${exercise || s.scenario}.`, 5000);
  conn.reconnect();
}

/** A new session (keeps the trainee's name and group; the old session is ended). */
function newSession(opts) {
  conn.restart({ ...opts, ...conn.who });
}

/** The next exercise open to the trainee (progression: their locks read again, as the attempt
 * just finished may have opened one), or null. */
async function nextOpen() {
  const s = conn.session;
  if (s?.control_token && !conn.observing) startScreen.setLocks(await sessionProgress(s.id, s.control_token, s.base || ''));
  return startScreen.next(task.spec?.id);
}

async function chooseAndStart() {
  // the trainee's curves so far, read with the running session's token (its trainee's)
  const s = conn.session;
  const progress = s?.control_token && !conn.observing ? () => sessionProgress(s.id, s.control_token, s.base || '') : null;
  const choice = await startScreen.choose(task.spec?.id, progress, !!progress);
  if (choice) conn.restart(choice);
}

function syncControls() {
  $('sel-mode').value = settings.control_mode === 'cartesian' && !settings.hold_orientation ? 'cartesian-free' : settings.control_mode;
  $('sel-method').value = settings.control_method;
  const sp = SPEEDS.reduce((a, b) => (Math.abs(b - settings.arm_speed) < Math.abs(a - settings.arm_speed) ? b : a));
  $('sel-speed').value = String(sp);
  $('sel-arm').value = selectedArm;
}

function sendSettings(patch) {
  settings = { ...settings, ...patch };
  conn.send(messages.settings(patch));
  syncControls();
}

function setArm(side) {
  selectedArm = side;
  localStorage.setItem('seaarms.arm', side);
  syncControls();
  touch.showArm(side);
  view.setSelectedArm(input.enabled ? side : null);
}

let paused = false;
const actions = {
  toggleMode: () => sendSettings({ control_mode: settings.control_mode === 'joint' ? 'cartesian' : 'joint' }),
  toggleMethod: () => sendSettings({ control_method: settings.control_method === 'open' ? 'closed' : 'open' }),
  speed(d) {
    const i = SPEEDS.indexOf(+$('sel-speed').value);
    sendSettings({ arm_speed: SPEEDS[Math.max(0, Math.min(SPEEDS.length - 1, i + d))] });
  },
  release: () => conn.send(messages.release()),
  reset: () => conn.send(messages.reset()),
  pause() {
    paused = view.drawn ? !view.drawn.paused : !paused;
    conn.send(paused ? messages.pause() : messages.resume());
  },
  layout: () => viewControls.layout(),
  ghost() {
    const sel = $('sel-ghost');
    if (sel.disabled) return;
    if (sel.value !== 'none') { ghostLast = sel.value; sel.value = 'none'; } else sel.value = ghostLast;
    applyGhost();
  },
  ellipsoids() { $('chk-ell').checked = !$('chk-ell').checked; $('chk-ell').dispatchEvent(new Event('change')); },
  workSite: () => view.frameWorkSite(),
  viewSet() {
    const next = view.viewports.set === 'pilot' ? 'engineering' : 'pilot';
    view.viewports.showSet(next);
    $('sel-views').value = view.viewports.set;
  },
  help(show) {
    const h = $('help');
    h.hidden = show === undefined ? !h.hidden : !show;
  },
};

const input = new Input(conn, {
  arm: () => selectedArm,
  setArm,
  mode: () => settings.control_mode,
  method: () => settings.control_method,
  actions,
  onPad: (id) => status.pad(id),
  camera: (pan, tilt, zoom) => view.viewports.panTilt.command(pan, tilt, zoom),
  stickFrame: () => stickFrame(),
});

/** The frame the Cartesian sticks move the jaw in (toolbar "Sticks", kept per browser):
 * the active view's camera, the vehicle, or the selected arm's base (web/sticks.js). */
let stickFrameName = ['camera', 'vehicle', 'base'].includes(localStorage.getItem('seaarms.stickFrame'))
  ? localStorage.getItem('seaarms.stickFrame') : 'camera';
$('sel-frame').value = stickFrameName;
$('sel-frame').addEventListener('change', (e) => { stickFrameName = e.target.value; localStorage.setItem('seaarms.stickFrame', stickFrameName); });
function stickFrame() {
  return frameRows(stickFrameName, view.viewports.activeCamera(), view.hello, selectedArm);
}

/** Rumble and the jaw-force / line-pressure gauge (web/rumble.js). */
const cues = new ForceCues(() => input.pads(), $('gauges'));

/** How long the joint-mode note shows every axis after it changed (ms). */
const NOTE_UNFOLDED_MS = 8000;
/** A joint whose top speed is above this (rad/s, 86°/s) is marked fast in the note. */
const FAST_JOINT_RAD_S = 1.5;
/** On screen: what the sticks do now — Cartesian: the frame they follow; joint mode: which
 * way each axis turns the jaw in the active view (web/sticks.js). */
setInterval(() => {
  const el = $('sticks-note');
  const vp = view.viewports;
  const camTitle = vp.view(vp.active).title.replace(/ \(.*$/, '');
  let html;
  if (settings.control_mode === 'cartesian' || settings.control_method === 'closed') {
    const name = { camera: `the ${camTitle} view`, vehicle: 'the vehicle (x ahead, y left, z up)', base: `the ${selectedArm} arm's base` }[stickFrameName];
    html = `<b>Sticks follow</b> ${name}: left stick ↔ right/left, ↕ up/down; right stick ↕ ${stickFrameName === 'camera' ? 'away/toward' : 'z'}`;
  } else {
    const words = view.drawn ? jointTurnWords(view.drawn.arms[selectedArm], vp.activeCamera()) : null;
    const names = jointNames(view.hello);
    const pad = ['L stick ↔', 'L stick ↕', 'R stick ↕', 'd-pad ↕ (LB/RB + R stick ↕)', 'R stick ↔', 'd-pad ↔ (LB/RB + R stick ↔)'];
    // a joint much faster than the rest (the Magnum's wrist rotate, 150°/s, Lim Table 1-1) says so
    const fast = (j) => {
      const v = view.hello?.arms?.[0]?.model?.joints?.[j]?.max_velocity;
      return v > FAST_JOINT_RAD_S ? ` <i>(fast: ${Math.round((v * 180) / Math.PI)}°/s)</i>` : '';
    };
    html = `<b>Joint mode</b> in ${camTitle}: ` + (words ? words.map((w, i) => `<span class="li">${pad[i]} +: ${names[i]} ${w}${fast(i)}</span>`).join(' ') : '');
  }
  // the joint-mode list is long: shown whole for a while after it changes (mode, view, arm,
  // or a direction that flipped with the posture), then folded to its first words
  if (el.dataset.html !== html) { el.dataset.html = html; el.dataset.since = Date.now(); }
  const folded = settings.control_mode === 'joint' && settings.control_method !== 'closed' && Date.now() - el.dataset.since > NOTE_UNFOLDED_MS;
  const shown = folded ? `<b>Joint mode</b> in ${camTitle} (axes: ? or H)` : html;
  if (el.dataset.shown !== shown) { el.dataset.shown = shown; el.innerHTML = shown; }
  // it sits on the view it describes, within that view's bounds
  const host = vp.view(vp.active).el;
  if (el.parentElement !== host) host.appendChild(el);
}, 250);

// a phone: the toolbar folds to one row; "☰ Controls" opens it with every control reachable
$('btn-tools').addEventListener('click', () => {
  const open = !document.body.classList.contains('tools-open');
  document.body.classList.toggle('tools-open', open);
  $('btn-tools').setAttribute('aria-expanded', String(open));
});

// on-screen sticks: shown on touch screens (?touch=1 / ?touch=0 override), a toolbar toggle
const touch = new TouchPad($('view'));
input.addVirtualPad(touch.pad);
touch.visible = params.has('touch') ? params.get('touch') === '1' : touchDevice();
touch.showArm(selectedArm);
$('chk-touch').checked = touch.visible;
$('chk-touch').addEventListener('change', (e) => { touch.visible = e.target.checked; });

$('sel-arm').addEventListener('change', (e) => setArm(e.target.value));
$('sel-mode').addEventListener('change', (e) => sendSettings(e.target.value === 'joint' ? { control_mode: 'joint' }
  : { control_mode: 'cartesian', hold_orientation: e.target.value === 'cartesian' }));
$('sel-method').addEventListener('change', (e) => sendSettings({ control_method: e.target.value }));
$('sel-speed').addEventListener('change', (e) => sendSettings({ arm_speed: +e.target.value }));
$('btn-reset').addEventListener('click', actions.reset);
$('btn-pause').addEventListener('click', actions.pause);
$('btn-release').addEventListener('click', actions.release);
$('btn-help').addEventListener('click', () => actions.help());
// the overlay closes by its button or a tap outside it (touch screens have no ? key)
$('help').addEventListener('click', (e) => { if (e.target.closest('[data-close]')) actions.help(false); });
document.addEventListener('pointerdown', (e) => {
  if (!$('help').hidden && !e.target.closest('#help, #btn-help')) actions.help(false);
});
$('btn-new').addEventListener('click', () => {
  const sc = $('sel-scenario').value;
  newSession(sc ? { scenario: sc } : {});
});
$('btn-exercises').addEventListener('click', () => chooseAndStart());
$('sel-ghost').addEventListener('change', (e) => { if (e.target.value !== 'none') ghostLast = e.target.value; applyGhost(); });
// keep keyboard focus on the page after using a menu or a checkbox (web/input.js also
// ignores focus on anything but text fields)
for (const el of document.querySelectorAll('#toolbar select, #toolbar input[type=checkbox]')) el.addEventListener('change', () => el.blur());
/** The pause button and the instructor's pause: a trainee cannot lift it (the server refuses
 * a resume, and its error is shown as a banner), so the button is off and says why. */
setInterval(() => {
  const st = view.drawn;
  const byInstructor = !!st?.paused && st.paused_by === 'instructor';
  const b = $('btn-pause');
  b.textContent = st?.paused ? 'Resume' : 'Pause';
  b.disabled = !driving || byInstructor;
  b.title = byInstructor ? 'Paused by the instructor: only the instructor can resume' : 'Pause / resume (P)';
  $('paused-note').hidden = !byInstructor;
}, 250);

function renderHelp() {
  $('help').innerHTML = `<button type="button" class="help-close" data-close aria-label="Close help">✕ Close</button><h3>Keyboard and gamepad</h3>
<p>The selected arm (toolbar, <kbd>1</kbd>/<kbd>2</kbd>, LB/RB) follows the sticks. Joint mode: axis i drives
joint i's valve. Cartesian mode: the axes are the end-effector velocity [vx vy vz wx wy wz] in the frame chosen under "Sticks":
the camera frame (default: the active view — the last one you pointed at, outlined — so stick right moves the jaw
right on that view, stick up moves it up, the right stick's up pushes it away), the vehicle frame (x ahead, y left,
z up) or the arm's base frame. Joint mode: the note at the top of the view says which way each axis turns the jaw in
the active view. Hold LB or RB (arm select) for an analog wrist on the right stick.
Closed loop: the axes move the object; both jaws grip together. Dead zone ${Math.round(DEAD_ZONE * 100)} % on sticks and triggers;
input is sent at ${input.sendHz} Hz.</p>
<table><tr><th>Function</th><th>Gamepad (standard mapping)</th><th>Keyboard</th></tr>
${mapping(jointNames(view.hello)).map(([f, g, k]) => `<tr><td>${f}</td><td>${g}</td><td><kbd>${k}</kbd></td></tr>`).join('')}</table>
<p>Views: <b>engineering</b> (top, front, side, perspective: drag to orbit) or <b>pilot cameras</b> (the vehicle's pan-tilt
camera — drag it or hold L3 and use the right stick or the arrow keys — the wrist cameras and a fixed overview, in
water of the visibility set in the toolbar). The wheel zooms toward the cursor; <kbd>K</kbd> or "Work site" frames
the exercise's work site; ⤢ or double-click shows one large view.</p>
<p>Touch screens: "sticks" in the toolbar shows on-screen sticks — the left stick and the right stick are the
gamepad's, the buttons beside them select the arm (L arm / R arm) and open or close the jaw, the arrows are the d-pad.
On a phone, "☰ Controls" opens the toolbar. Press <kbd>?</kbd> to close.</p>`;
}

/** The scenario menu from `hello.scenarios` ([{name, description}], the server's list). */
function setScenarios(list, current) {
  const sel = $('sel-scenario');
  sel.replaceChildren(...list.map(({ name, description }) => Object.assign(new Option(name, name), { title: description })));
  // an exercise (or any scenario the menu does not list) is shown as the current one
  if (!list.some((x) => x.name === current)) sel.append(new Option(current, current));
  sel.value = current;
}

/** Controls that change the session: off while this tab only watches. */
const DRIVING_CONTROLS = ['sel-mode', 'sel-method', 'sel-speed', 'btn-reset', 'btn-pause', 'btn-release'];

/** Trainee (drives, sends input) or observer (this browser's other tab drives). */
let driving = false;
function setRole(role, session) {
  driving = role === 'trainee';
  tabs.driving(driving ? session : null);
  input.enabled = driving;
  view.setSelectedArm(driving ? selectedArm : null);
  touch.visible = driving && $('chk-touch').checked;
  for (const id of DRIVING_CONTROLS) $(id).disabled = !driving;
  document.body.classList.toggle('observing', !driving);
  if (!driving) watchUntilTaken('Watching: another tab drives this session.');
  else tabs.hide();
}

async function watchUntilTaken(text) {
  await tabs.watching(text);
  tabs.take(conn.session.id);
  conn.setObserving(false);
}

const tabs = new TabGuard($('tabs'), {
  // another tab took control: watch from here (setRole shows how to take it back)
  onTakenOver: () => conn.setObserving(true),
});

/** Starts or resumes this browser's session; asks first if another tab drives it. */
async function start() {
  const stored = Connection.stored();
  const named = params.get('exercise') ? { exercise: params.get('exercise') }
    : params.get('scenario') ? { scenario: params.get('scenario') } : null;
  if (stored && await conn.stillLive(stored)) {
    // a link to another exercise or scenario starts that one (the stored session is ended),
    // unless another tab drives the stored one
    const wanted = named && (named.exercise || named.scenario);
    if (wanted && !(await tabs.anotherDriving(stored.id))) {
      const r = await sessionSummary(stored.id, stored.control_token).catch(() => null);
      const runs = r?.ok ? (await r.json()).scenario : null;
      if (runs && runs !== wanted) {
        conn.session = stored;
        newSession(named);
        return;
      }
    }
    // resume this browser's session (unless another tab drives it and the trainee watches)
    if (await tabs.anotherDriving(stored.id)) {
      if (await tabs.choose() === 'take') tabs.take(stored.id);
      else conn.observing = true;
    }
    conn.start(named || {});
    return;
  }
  // a new trainee: the start screen, unless the URL names a scenario or an exercise
  conn.start(named || await startScreen.choose());
}

renderHelp();
syncControls();
// a phone: one large view, plots off (both can be switched back in the toolbar)
if (matchMedia(NARROW_SCREEN).matches) {
  actions.layout();
  $('chk-plots').checked = false;
  $('chk-plots').dispatchEvent(new Event('change'));
}
start();

window.__seaarms = view.debugHooks(() => conn, {
  get lastInput() { return input.last; },
  get selectedArm() { return selectedArm; },
  get ended() { return lastEnded; },
  /** The ghost: its attempt, time, meshes, drawn joint angles and tool points (web/ghost.js). */
  ghost() { return ghost.debug(); },
  get ghostChoices() { return ghostChoices; },
});
