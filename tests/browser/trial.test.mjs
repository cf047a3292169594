//! A trainee trial (issue 28's last acceptance): a scripted HUMAN-PACED operator, not the
//! autopilot, works all seven exercises one after another in one real Chromium, in the pilot
//! view set (the vehicle's pan-tilt camera active; the sticks follow it), through the page's
//! own controls only: the fake gamepad (FAKE_GAMEPAD) and keyboard taps.
//!
//! The operator follows each exercise file's `autopilot` plan as its instruction sheet
//! (GET /api/exercises/{id}: which arm, which handle / marker / zone / panel point, grip,
//! push until…), but executes it as a person would:
//! - it decides every DECIDE_MS (250 ms, a choice reaction time; the issue asks ≥ 150 ms) and
//!   holds its sticks in between;
//! - it reads only what the page shows: the state frames the page drew (`__seaarms.lastState`:
//!   jaw, box and panel positions, joint angles and speeds, line pressures — the plots'
//!   and gauges' numbers), the scene of the hello (markers, handles, zone, panel), the task
//!   panel's step and readouts, and the completion card;
//! - it moves at most two axes at a time, each at rest, slow (30 %) or full, and for the last
//!   millimetres or degrees a fine keyboard tap (Shift + axis key: a 0.3× jog);
//! - in Cartesian mode it looks through the ACTIVE view: the jaw and its goal are projected into
//!   that view (`__seaarms.project`), the on-screen offset (px, scaled to metres at the jaw's
//!   depth) is pushed on the left stick (right = screen right, up = screen up, as the page maps
//!   the camera frame) and the depth difference along the camera's axis on the right stick's ↕
//!   (up = away); jaw turns likewise in the camera's axes (right stick ↔ about screen up;
//!   LB/RB held + right stick: about screen right ↕ and about the view axis ↔).
//! Prints and writes (artifacts/trial.json) each exercise's pass, score and time from the
//! completion card; asserts every exercise passes.
//!
//! The operator also does what the exercise goals tell a trainee to watch: in the hot stab it
//! reads the task panel's side-load readout, stops pushing in at 40 % of the limit and corrects
//! across the view until it falls below 20 %, and it does not turn the wrist against the
//! receptacle once the stab is in (the stab-depth readout above 0); carrying the stab it goes
//! slow over the last 8 cm to a point; near the seabed (25 cm) it brings a jaw down slowly.
//!
//! Part of `bash tests/run.sh`, on a server of its own (`startServer`: the shared server of the
//! suite may still be stepping other files' sessions, and the operator is paced by wall time).
//! Each exercise may be tried up to three times (TRIES), as a trainee in a practice session
//! would: the check fails when an exercise fails every try. Measured 2026-11-28 on a quiet machine (load < 2.5): 7 of
//! 7 at the first try in two runs in a row (3 min 40 s each); on a machine loaded by other
//! builds (load 5–9) 2–3 of 7 failed at the first try (real-time pacing: frames late and in
//! bursts, the operator overshoots). `cd tests/browser && node --test trial.test.mjs` runs it
//! alone (`TRIAL_ONLY=a,b` for a subset; `TRIAL_DEBUG=1|2` logs each action or decision).
//! Screenshots: artifacts/trial-valve-turn-pilot.png (jaw on the T-bar),
//! artifacts/trial-pick-and-place-pilot.png (jaw closed on the box's lifting point).

import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { writeFileSync } from 'node:fs';
import { join } from 'node:path';
import { startServer, openBrowser, until, untilDrawn, pressReady, FAKE_GAMEPAD, stick, handleWorld, ARTIFACTS } from './harness.mjs';
import { KEY_AXES } from '../../web/input.js';

/** The operator's decision interval (ms). */
const DECIDE_MS = 250;
/** Intent (stick units) below which an axis rests; below FULL it is slow (30 %), else full. */
const REST = 0.08, FULL = 0.6, SLOW = 0.3;
/** When the strongest intent is below this (and above 0.01) the operator taps (Shift: fine). */
const TAP = 0.25;
/** A second axis is moved only when its intent is at least this share of the first's (a
 * person pushes one axis and adds a clearly needed second one, not every small component).
 * 0.3, not 0.4: in the pilot view (tilted 18° down) a straight rise is screen-up with 0.31 of
 * "toward"; at 0.4 that depth share was dropped, and raising the hot stab 15 cm on screen-up
 * alone carried it 4.6 cm toward the panel, into the receptacle's mouth before it was lined up
 * (side load 770 N). */
const SECOND = 0.3;
/** The plan's gains (server/core/src/exercise/autopilot.rs: full stick beyond 10 cm, 0.2 rad,
 * 10°), the intent a person forms from an error. */
const MOVE_GAIN_PER_M = 10, ATT_GAIN_PER_RAD = 5, JOINT_GAIN_PER_DEG = 0.1, LEVEL_GAIN_PER_RAD = 5;
/** A `move` with an attitude is there within this turn (rad; the autopilot's 0.02 is 1.1°,
 * below what a tap resolves — 0.6° — with a reaction time; 2° is a person's "square"). */
const ATT_TOL_RAD = 0.035;
/** A jaw off its goal by this much on screen (m) is lined up before it is pushed in depth. */
const LINE_UP = 0.003;
/** How far ahead (s) the operator leads a moving jaw from its seen speed: 0 (off). A lead of
 * half or one decision made the moves worse on a loaded machine, where the real-time server's
 * frames come in bursts and the speed seen over 250 ms is noise. */
const LEAD_S = 0;
/** A `joint` step finishes with the joint this slow (rad/s), as the human-paced driver's. */
const JOINT_STILL = 0.05;
/** A full keyboard jog of a joint (°; sim::Operator::jog at full arm speed). */
const JOG_JOINT_DEG = 2;
/** The hot stab's side-load readout (task panel, share of its limit) at which the operator stops
 * pushing in and corrects first, and below which it pushes on again (a person watching a
 * climbing gauge eases off well before the limit, and waits for it to fall back). */
const SIDE_EASE = 0.4, SIDE_RESUME = 0.2;
/** Carrying the hot stab, within this of a plan point (m) every axis is at most slow. */
const STAB_NEAR_M = 0.08;
/** A jaw this close over the seabed (m) is brought down slowly (each axis at most slow): the
 * goals say "without striking the seabed", and a full push down overshoots: reach-targets'
 * marker E is 7 cm over the seabed, and a full push from 19 cm over it carried the jaw to 2.6 cm
 * over it (fingers on the seabed) on a loaded machine with the caution at 15 cm. */
const SEABED_CAUTION_M = 0.25;
/** Wall time (s) one exercise's operator may take before it gives up (below the test's timeout, so
 * that an operator never keeps working a page the next exercise has taken over). */
const TRIAL_WALL_S = 210;
/** Tries an exercise gets (a practice session's): each is reported, and a retry is a signal
 * to look into. The fault drill's fault is drawn from the OS for each attempt; until
 * 2026-11-28 the operator missed the air fault's slow spin-up at the page's drawn frame rate
 * and ran out of the drill's 120 s (it now also reads the wrist pitch's stop, and stops
 * shuttling when the fault is due). */
const TRIES = 3;
const EXERCISES = ['familiarisation', 'reach-targets', 'dual-lift', 'valve-turn', 'hot-stab', 'fault-diagnosis', 'pick-and-place'];

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const norm = (v) => Math.hypot(...v);
const sub = (a, b) => a.map((x, i) => x - b[i]);
const dot = (a, b) => a.reduce((s, x, i) => s + x * b[i], 0);
const clampNorm = (v) => { const n = norm(v); return n > 1 ? v.map((x) => x / n) : v; };

/** Rotation matrix (rows) of a rotation vector (Rodrigues). */
function rotvecToMatrix(r) {
  const th = norm(r);
  if (th < 1e-12) return [[1, 0, 0], [0, 1, 0], [0, 0, 1]];
  const [x, y, z] = r.map((v) => v / th), c = Math.cos(th), s = Math.sin(th), C = 1 - c;
  return [[c + x * x * C, x * y * C - z * s, x * z * C + y * s], [y * x * C + z * s, c + y * y * C, y * z * C - x * s], [z * x * C - y * s, z * y * C + x * s, c + z * z * C]];
}
/** Rotation vector of A·Bᵀ (the turn from B to A, world frame). */
function rotationError(A, B) {
  const M = [0, 1, 2].map((i) => [0, 1, 2].map((j) => A[i][0] * B[j][0] + A[i][1] * B[j][1] + A[i][2] * B[j][2]));
  const c = Math.max(-1, Math.min(1, (M[0][0] + M[1][1] + M[2][2] - 1) / 2));
  const th = Math.acos(c);
  const v = [M[2][1] - M[1][2], M[0][2] - M[2][0], M[1][0] - M[0][1]];
  const s = norm(v);
  if (th < 1e-9 || s < 1e-12) return [0, 0, 0];
  return v.map((x) => (x / s) * th);
}

/** The human-paced operator on one page. */
class Operator {
  constructor(page, log) {
    this.page = page;
    this.log = log;
    this.hello = null;
    this.side = 'left';
    this.z0 = null; // the box's resting height at the start (what "lifted by h" is measured from)
    this.stats = { decisions: 0, taps: 0, maxAxes: 0, intervalsMs: [] };
    this.lastDecision = 0;
    /** Per joint, the turn rate (°/s) seen at full and at slow deflection: a first guess,
     * raised to what the joint shows (the wrist rotate turns at ~140 °/s at full stick). */
    this.rates = Array.from({ length: 6 }, () => ({ full: 40, slow: 12 }));
    this.held = null;
    this.easing = false; // holding off the push while the side-load readout falls back
    this.deadline = Infinity; // Date.now() past which every loop stops (TRIAL_WALL_S)
  }

  async begin() {
    this.hello = await this.page.evaluate(() => window.__seaarms.hello);
    const st = await this.state();
    this.z0 = st.object.pose.position[2];
  }

  async state() { return this.page.evaluate(() => window.__seaarms.lastState); }

  /** Waits for the next decision instant (DECIDE_MS after the last one). */
  async pace() {
    const now = Date.now();
    const wait = this.lastDecision + DECIDE_MS - now;
    if (wait > 0) await sleep(wait);
    const t = Date.now();
    if (this.lastDecision) this.stats.intervalsMs.push(t - this.lastDecision);
    this.lastDecision = t;
    this.stats.decisions++;
  }

  /** Sets the fake pad: `axes` [a0..a3], `buttons` {index: value}; everything else at rest. */
  async setPad(axes, buttons) {
    await this.page.evaluate(([a, b]) => {
      const p = window.__pad;
      for (let i = 0; i < 4; i++) p.axes[i] = a[i];
      for (let i = 0; i < p.buttons.length; i++) window.__setButton(i, b[i] ?? 0);
    }, [axes, buttons]);
  }

  /** Sticks at rest (the grip triggers too, unless `grip` is given). */
  async rest(grip = 0) { await this.sticks([0, 0, 0, 0, 0, 0], grip); }

  /**
   * Puts a chosen set of ≤ 2 quantised axis values (index → value in {±0.3, ±1}) on the pad:
   * axis 0 left stick ↔, 1 left stick ↕ (up +), 2 right stick ↕ (up +), 4 right stick ↔;
   * 3 and 5 (the wrist) on the right stick with the selected arm's shoulder button held (↕, ↔)
   * or, when the right stick is busy and the value is full, on the d-pad (↕, ↔).
   * `grip` < 0 closes (RT), > 0 opens (LT).
   */
  async sticks(v, grip = 0) {
    const axes = [0, 0, 0, 0];
    const buttons = {};
    const used = v.map((x, i) => [i, x]).filter(([, x]) => x !== 0);
    const rightBusy = used.some(([i]) => i === 2 || i === 4);
    for (const [i, x] of used) {
      if (i === 0) axes[0] = stick(x);
      else if (i === 1) axes[1] = -stick(x);
      else if (i === 2) axes[3] = -stick(x);
      else if (i === 4) axes[2] = stick(x);
      else if (rightBusy) { // d-pad: digital
        if (i === 3) buttons[x > 0 ? 12 : 13] = 1; else buttons[x > 0 ? 15 : 14] = 1;
      } else {
        buttons[this.side === 'left' ? 4 : 5] = 1;
        if (i === 3) axes[3] = -stick(x); else axes[2] = stick(x);
      }
    }
    if (grip < 0) buttons[7] = 1;
    if (grip > 0) buttons[6] = 1;
    await this.setPad(axes, buttons);
  }

  /** A tap of axis i (+ or −): the axis key for 80 ms, with Shift (`fine`, the default) a
   * 0.3× jog. */
  async tap(i, sign, fine = true) {
    const key = KEY_AXES[i][sign > 0 ? 0 : 1];
    await this.rest();
    if (fine) await this.page.keyboard.down('ShiftLeft');
    await this.page.keyboard.down(key);
    await sleep(80);
    await this.page.keyboard.up(key);
    if (fine) await this.page.keyboard.up('ShiftLeft');
    this.stats.taps++;
  }

  /**
   * One decision from a 6-axis intent (stick units, in the stick frame): a fine tap when
   * everything is small (not in closed loop, where a key drives the object while held), else
   * the strongest axis and, if clearly needed, a second one, each quantised to rest / slow /
   * full; the right stick's ↕/↔ and the wrist (shoulder + right stick) exclude each other,
   * unless the wrist value is full (d-pad).
   */
  async act(intent, { grip = 0, closed = false, canTap = true, linear = false } = {}) {
    const order = intent.map((x, i) => [i, x]).sort((a, b) => Math.abs(b[1]) - Math.abs(a[1]));
    const [i0, x0] = order[0];
    const q = (x) => (Math.abs(x) < REST ? 0 : Math.abs(x) < FULL ? SLOW * Math.sign(x) : Math.sign(x));
    if (Math.abs(x0) < 0.01) { await this.sticks([0, 0, 0, 0, 0, 0], grip); return 'rest'; }
    if (Math.abs(x0) < TAP && canTap && !closed) {
      // line up in the picture first, then push along the view: a tap goes to a screen axis
      // (left stick) while it is off by LINE_UP or more, to the depth axis only after
      const screen = order.find(([i, x]) => (i === 0 || i === 1) && Math.abs(x) >= LINE_UP * MOVE_GAIN_PER_M);
      const [i, x] = linear && screen ? screen : [i0, x0];
      await this.tap(i, Math.sign(x));
      return 'tap';
    }
    if (Math.abs(x0) < TAP && !closed && linear) { await this.sticks([0, 0, 0, 0, 0, 0], grip); return 'wait'; } // moving: let it come
    const out = [0, 0, 0, 0, 0, 0];
    out[i0] = closed ? (Math.abs(x0) < FULL ? SLOW * Math.sign(x0) : Math.sign(x0)) : q(x0);
    const wrist = (i) => i === 3 || i === 5, rs = (i) => i === 2 || i === 4;
    for (const [i, x] of order.slice(1)) {
      if (Math.abs(x) < Math.max(REST, SECOND * Math.abs(x0))) break;
      const clash = (wrist(i) && rs(i0) && Math.abs(q(x)) < 1) || (rs(i) && wrist(i0) && Math.abs(out[i0]) < 1);
      if (clash) continue;
      out[i] = q(x);
      break;
    }
    const n = out.filter((x) => x !== 0).length;
    this.stats.maxAxes = Math.max(this.stats.maxAxes, n);
    await this.sticks(out, grip);
    return out;
  }

  /** The active view's camera: axes (world) right, up, forward; position; scale. */
  async camera() {
    return this.page.evaluate(() => {
      const w = window.__seaarms;
      const name = w.viewSet().active;
      const c = w.cameraOf(name);
      const m = c.world;
      return { name, right: [m[0], m[1], m[2]], up: [m[4], m[5], m[6]], fwd: [-m[8], -m[9], -m[10]], pos: [m[12], m[13], m[14]], p5: c.projection[5], h: c.rect.height };
    });
  }

  /**
   * What a person sees of `goal` against `now` (world points) through the active view: the
   * on-screen offset (projected by the page, px) at the jaw's depth in metres (right, up) and
   * the depth difference along the view (away +), as [right, up, away] metres.
   */
  async seen(now, goal) {
    const cam = await this.camera();
    const [a, b] = await this.page.evaluate(([n, p, g]) => [window.__seaarms.project(n, p), window.__seaarms.project(n, g)], [cam.name, now, goal]);
    const depth = (p) => dot(sub(p, cam.pos), cam.fwd);
    const mPerPx = (2 * depth(now)) / (cam.p5 * cam.h);
    return { cam, v: [(b.x - a.x) * mPerPx, -(b.y - a.y) * mPerPx, depth(goal) - depth(now)] };
  }

  /** A world vector in the active camera's axes [right, up, away]. */
  static inCamera(cam, w) { return [dot(w, cam.right), dot(w, cam.up), dot(w, cam.fwd)]; }

  /** Where a plan's point reference is (world), from the page's frame and the hello's scene. */
  point(st, to) {
    const sc = this.hello.scene;
    if (to.handle !== undefined) return handleWorld(st, this.hello, Math.min(to.handle, sc.handles_m.length - 1));
    if (to.target !== undefined) return sc.targets.find((t) => t.id === to.target).position_m;
    if (to.zone !== undefined) { const z = sc.zones.find((x) => x.id === to.zone); return [z.center_m[0], z.center_m[1], this.hello.seabed_z_m]; }
    return to.point;
  }

  /** A plan's `until` condition, judged from what the page shows. */
  met(c, st) {
    const ex = st.exercise;
    switch (c.kind) {
      case 'object_height': { // the task panel's lift readout when it has one, else the box's rise
        const lift = Operator.liftReadout(st);
        return (lift ?? st.object.pose.position[2] - this.z0) >= c.height_m - (c.tolerance_m ?? 0.01);
      }
      case 'valve_angle': return Math.abs(st.panel.valve_angle_deg - c.angle_deg) <= (c.tolerance_deg ?? 1);
      case 'stab_seated': return st.panel?.stab_phase === 'seated';
      case 'object_resting': return norm(st.object.velocity.slice(0, 3)) < 0.01 && st.object.pose.position[2] - this.z0 < 0.02;
      case 'internal_force_below': return norm(st.internal_force_n) < c.force_n;
      case 'arms_still': return ['left', 'right'].every((s) => st.arms[s].qd.every((v) => Math.abs(v) <= c.max_joint_speed_rad_s));
      default: return ex.done;
    }
  }

  /** The task panel's readout whose label matches `re` ({label, value, target, unit}), or undefined. */
  static readout(st, re) { return st.exercise?.readouts.find((x) => re.test(x.label)); }

  /** The task panel's lift / height readout (m), or null. */
  static liftReadout(st) {
    const r = st.exercise?.readouts.find((x) => /lift|height/i.test(x.label));
    return r ? r.value * ({ cm: 0.01, mm: 0.001 }[r.unit] ?? 1) : null;
  }

  /** The object's levelling turn (world rotation vector intent), as the plan's `level`. */
  static level(st) {
    const r = st.object.pose.rotation, z = [r[0][2], r[1][2], r[2][2]];
    const w = [z[1], -z[0], 0].map((x) => x * LEVEL_GAIN_PER_RAD); // z × ẑ
    return clampNorm(w);
  }

  /** Decides every DECIDE_MS until `step(st)` returns 'done' or the time is up. */
  async loop(timeoutS, step) {
    const t0 = Date.now();
    while (Date.now() - t0 < timeoutS * 1000 && Date.now() < this.deadline) {
      await this.pace();
      const st = await this.state();
      if (st.exercise?.done) return 'exercise done';
      const r = await step(st, (Date.now() - t0) / 1000);
      if (r === 'done') return 'done';
    }
    return 'timeout';
  }

  /** Runs one plan action (exercises/*.json `autopilot`) at a human's pace. */
  async run(a) {
    const T = a.timeout_s ?? 30;
    switch (a.do) {
      case 'settings': {
        // the toolbar, as a trainee would (the exercise usually set them already)
        const st = await this.state();
        if (a.mode && st.settings.control_mode !== a.mode) await this.page.keyboard.press('KeyM');
        if (a.method && st.settings.control_method !== a.method) await this.page.keyboard.press('KeyL');
        if (a.mode || a.method) {
          await until(this.page, ([m, k]) => { const s = window.__seaarms.lastState.settings; return (!m || s.control_mode === m) && (!k || s.control_method === k); }, [a.mode, a.method], 5000);
        }
        return 'done';
      }
      case 'move': {
        await this.selectArm(a.arm);
        const want = a.attitude_rotvec ? rotvecToMatrix(a.attitude_rotvec) : null;
        const tol = a.tolerance_m ?? 0.01;
        let prev = null;
        const stepAt = (await this.state()).exercise.step;
        return this.loop(T, async (st) => {
          // the task panel ticked its step: what the move was for is done (a marker touched)
          if (st.exercise.step > stepAt) { await this.rest(); return 'done'; }
          const now = a.steer === 'object' ? st.object.pose.position : st.arms[a.arm].pose.position;
          const goal = sub(this.point(st, a.to), (a.offset_m ?? [0, 0, 0]).map((x) => -x));
          const { cam, v } = await this.seen(now, goal);
          // the hot stab in its receptacle (the task panel's stab-depth readout is above 0): the
          // receptacle lines it up, as what the jaw touches does — no turning the wrist against it
          const touching = st.arms[a.arm].contact || Operator.readout(st, /stab depth/i)?.value > 0;
          let att = want ? rotationError(want, st.arms[a.arm].pose.rotation) : [0, 0, 0];
          // squared to within ATT_TOL_RAD; in contact the jaw is turned by what it touches:
          // a person does not fight that with the wrist
          if (norm(sub(goal, now)) <= tol && (norm(att) <= ATT_TOL_RAD || touching)) { await this.rest(); return 'done'; }
          if (touching || norm(att) < ATT_TOL_RAD) att = [0, 0, 0];
          // a person sees the jaw moving and leads it: where it will be a decision from now
          // (the hydraulics carry on after the stick is let go)
          const t = Date.now();
          const vel = prev && t > prev.t ? sub(now, prev.p).map((x) => (x * 1000) / (t - prev.t)) : [0, 0, 0];
          prev = { t, p: now };
          const ahead = sub(v, Operator.inCamera(cam, vel).map((x) => x * LEAD_S));
          const moving = norm(vel) > 0.03;
          const lin = clampNorm(ahead.map((x) => x * MOVE_GAIN_PER_M));
          // near the seabed (the page draws it; the hello gives its height) a push that takes
          // the jaw down goes slow
          const down = lin[0] * cam.right[2] + lin[1] * cam.up[2] + lin[2] * cam.fwd[2] < 0;
          if (down && st.arms[a.arm].pose.position[2] - this.hello.seabed_z_m < SEABED_CAUTION_M) {
            for (let k = 0; k < 3; k++) lin[k] = Math.max(-SLOW, Math.min(SLOW, lin[k]));
          }
          // the side-load readout climbing while the stab goes in (the goal says: no side load
          // over its limit): stop pushing in and correct across the view first, until it has
          // fallen back; once the stab-depth readout is home (seated) there is no pushing in
          // to hold off (a pull back then unseated the stab)
          const side = Operator.readout(st, /side load/i), depth = Operator.readout(st, /stab depth/i);
          const home = depth && depth.value >= depth.target;
          const share = side && side.target > 0 && !home ? side.value / side.target : 0;
          if (share >= SIDE_EASE) this.easing = true;
          else if (share < SIDE_RESUME) this.easing = false;
          if (this.easing) lin[2] = Math.min(lin[2], 0);
          // carrying the stab (its readouts are on the task panel) the last STAB_NEAR_M to a
          // point go slow: a full rise overshot the line-up point by 2 cm with the stab's tip at
          // the receptacle's mouth (side load 380 N between two decisions)
          if (depth && !home && norm(sub(goal, now)) < STAB_NEAR_M) {
            for (let k = 0; k < 3; k++) lin[k] = Math.max(-SLOW, Math.min(SLOW, lin[k]));
          }
          const ang = a.level ? Operator.level(st) : clampNorm(att.map((x) => x * ATT_GAIN_PER_RAD));
          const did = await this.act([...lin, ...Operator.inCamera(cam, ang)], { closed: st.settings.control_method === 'closed', linear: true, canTap: !moving });
          const smax = process.env.TRIAL_DEBUG === '2' ? await this.page.evaluate(() => { if (!window.__smaxT) { window.__smax = 0; window.__smaxT = setInterval(() => { window.__smax = Math.max(window.__smax, window.__seaarms.lastState?.panel?.side_load_n ?? 0); }, 4); } const m = window.__smax; window.__smax = 0; return m; }) : 0;
          if (process.env.TRIAL_DEBUG === '2') console.log(`smax ${smax.toFixed(0)} move ${cam.name} ${JSON.stringify(a.to)}: t ${st.t.toFixed(2)} jaw ${now.map((x) => x.toFixed(3))} goal ${goal.map((x) => x.toFixed(3))} q ${st.arms[a.arm].q.map((x) => (x * 57.3).toFixed(1))} vel ${Operator.inCamera(cam, vel).map((x) => (100 * x).toFixed(1))} seen ${v.map((x) => (100 * x).toFixed(1))} cm, att ${(norm(att) * 57.3).toFixed(1)}° → ${JSON.stringify(did)} side ${st.panel?.side_load_n?.toFixed(0)} N, relief ${st.exercise.counters.relief}${this.easing ? ' (easing)' : ''}, ${st.panel?.stab_phase ?? ''}`);
          return null;
        });
      }
      case 'joint': {
        await this.selectArm(a.arm);
        const j = a.joint;
        return this.loop(T, async (st) => {
          const arm = st.arms[a.arm];
          const e = a.angle_deg - (arm.q[j] * 180) / Math.PI, qd = (arm.qd[j] * 180) / Math.PI;
          const rate = this.rates[j];
          // what the last held deflection turned the joint at: a person learns each axis's pace
          if (this.held?.j === j && this.held.level) rate[this.held.level] = Math.max(rate[this.held.level], Math.abs(qd));
          this.held = null;
          if (Math.abs(e) <= a.tolerance_deg && Math.abs(arm.qd[j]) <= JOINT_STILL) { await this.rest(); return 'done'; }
          // the deflection whose turn over one decision does not overshoot (the turn so far
          // coasts on for a moment: half a decision at the speed seen)
          const left = e - (qd * DECIDE_MS) / 2000;
          const step = (lvl) => (rate[lvl] * DECIDE_MS) / 1000;
          let did;
          if (Math.abs(left) > 1.2 * step('full')) did = 'full';
          else if (Math.abs(left) > 1.2 * step('slow')) did = 'slow';
          else if (Math.abs(qd) > 3) did = 'wait'; // still turning: let it come to rest first
          else did = 'tap';
          const intent = [0, 0, 0, 0, 0, 0];
          if (did === 'full' || did === 'slow') {
            intent[j] = Math.sign(left) * (did === 'full' ? 1 : SLOW);
            this.held = { j, level: did };
            await this.sticks(intent);
            this.stats.maxAxes = Math.max(this.stats.maxAxes, 1);
          } else if (did === 'wait') await this.rest();
          else await this.tap(j, Math.sign(e), Math.abs(e) < 2 * JOG_JOINT_DEG); // fine below two full jogs
          if (process.env.TRIAL_DEBUG === '2') console.log(`joint ${j}: e ${e.toFixed(2)}°, qd ${qd.toFixed(1)}°/s → ${did} (rates ${rate.full.toFixed(0)}/${rate.slow.toFixed(0)} °/s)`);
          return null;
        });
      }
      case 'grip': {
        await this.selectArm(a.arm);
        const close = a.close;
        const r = await this.loop(a.timeout_s ?? 3, async (st) => {
          const holds = st.arms[a.arm].holding || (st.exercise && st.exercise.step > this.stepAt);
          await this.sticks([0, 0, 0, 0, 0, 0], close ? -1 : 1);
          return close && holds ? 'done' : null;
        });
        await this.rest();
        return r;
      }
      case 'sticks': case 'object': {
        if (a.arm) await this.selectArm(a.arm);
        return this.loop(T, async (st) => {
          if (this.met(a.until, st)) { await this.rest(); return 'done'; }
          const cam = await this.camera();
          const w = a.do === 'object' ? a.velocity : a.axes;
          const ang = a.level ? Operator.level(st) : w.slice(3);
          await this.act([...Operator.inCamera(cam, w.slice(0, 3)), ...Operator.inCamera(cam, ang)], { closed: st.settings.control_method === 'closed' });
          return null;
        });
      }
      case 'wait': {
        await this.rest();
        // in closed loop with a lift readout and target on the panel, the wait is a hold:
        // keep the readout on its target (screen up/down on the left stick, slow)
        const r = await this.loop(a.s, async (st) => {
          const ro = st.exercise?.readouts.find((x) => /lift|height/i.test(x.label));
          if (st.settings.control_method !== 'closed' || !ro) return null;
          const e = (ro.target - ro.value) * ({ cm: 0.01, mm: 0.001 }[ro.unit] ?? 1);
          const cam = await this.camera();
          const up = Operator.inCamera(cam, [0, 0, Math.abs(e) < 0.01 ? 0 : 0.5 * Math.sign(e)]); // slow
          await this.act([...up, 0, 0, 0], { closed: true });
          return null;
        });
        return r === 'exercise done' ? r : 'done';
      }
      case 'wait_until':
        await this.rest();
        return this.loop(T, async (st) => (this.met(a.until, st) ? 'done' : null));
      case 'diagnose': return this.diagnose(a.arm);
      default: throw new Error(`plan action ${a.do} unknown to the operator`);
    }
  }

  async selectArm(side) {
    if (!side || side === 'both') return;
    this.side = side;
    const cur = await this.page.evaluate(() => window.__seaarms.selectedArm);
    if (cur !== side) {
      await this.page.keyboard.press(side === 'left' ? 'Digit1' : 'Digit2');
      await until(this.page, (s) => window.__seaarms.selectedArm === s, side, 3000);
    }
  }

  /** Holds `axes` (joint mode, one joint) for `n` decisions; returns the frames seen. */
  async hold(intent, n) {
    const seen = [];
    for (let k = 0; k < n; k++) {
      await this.pace();
      if (intent.some((x) => x)) await this.sticks(intent); else await this.rest();
      seen.push(await this.state());
    }
    return seen;
  }

  /**
   * The fault drill's tests, as its goal lists them, at a person's pace (each phase a whole
   * number of decisions), reading the joint angles and speeds and the line-pressure gauges
   * (the plots: the page's drawn frames, recorded as they come, 60 Hz):
   * 1. watch with the sticks centred (2 s): a joint that turns > 1° is jogged against its
   *    motion — one that does not answer (< 2°) has a stuck valve, one that does is a leak;
   *    then every joint is jogged out and back (0.5 s each): one that answers neither has a
   *    stuck valve (it sits at its stop);
   * 2. spin the wrist rotate at full stick (0.75 s): P_I + P_O (the supply) under 80 % of the
   *    nameplate 6.89 MPa is a supply drop; a spin-up slower than the healthy motor's (65 % of
   *    the steady speed within 40 ms of the first motion) is air;
   * 2b. jog the wrist pitch out and back at full stick (0.5 s each) and let go: a joint that
   *    keeps creeping after the stick is centred is air (the goal's "creep on after a stop"). Read
   *    off any drawn frame while it slows: the coast still to come over the speed then, a time
   *    constant, is 23–28 ms with healthy oil (the spool's 25 ms: leak and supply drop alike)
   *    and 75–146 ms with air (bulk modulus × 0.03 and × 0.02), from a core probe of the drill's
   *    posture at 1 kHz (2026-11-28); over 50 ms is air. Unlike the 40 ms spin-up reading it
   *    needs no frame at a given moment: the healthy stop is over within ~65 ms (perhaps no
   *    frame in it: no evidence), aerated oil creeps for 300–500 ms (several frames at 15 Hz);
   * 3. jog the shoulder, elbow and wrist pitch out and back, let them settle and watch the
   *    gauges 2 s: line pressures drifting by > 0.1 MPa are a leak; else the nearest symptom.
   * Thresholds are the autopilot's (server/core/src/exercise/autopilot.rs Diagnosis).
   */
  async diagnose(side) {
    await this.selectArm(side);
    const st0 = await this.state();
    if (st0.settings.control_mode !== 'joint') await this.run({ do: 'settings', mode: 'joint' });
    await this.page.evaluate((sd) => {
      window.__rec = [];
      let last = -1;
      window.__recTimer = setInterval(() => { const s = window.__seaarms.lastState; if (s && s.t !== last) { last = s.t; const a = s.arms[sd]; window.__rec.push({ t: s.t, qd5: a.qd[5], p5: a.p_in[5] + a.p_out[5], q3: a.q[3], qd3: a.qd[3] }); } }, 5);
    }, side);
    const q = (st) => st.arms[side].q.map((x) => (x * 180) / Math.PI);
    const drift = (a, b) => Math.max(...[0, 1, 2, 3, 4, 5].map((j) => Math.abs(b.arms[side].p_in[j] - a.arms[side].p_in[j]) + Math.abs(b.arms[side].p_out[j] - a.arms[side].p_out[j])));
    const answer = async (name, why) => {
      this.notes = why;
      await this.rest();
      await this.page.evaluate(() => clearInterval(window.__recTimer));
      await this.page.click(`#task [data-answer="${name}"]`);
      return 'done';
    };
    // 1. watch
    const a0 = await this.state();
    const watch = await this.hold([0, 0, 0, 0, 0, 0], 8);
    const a1 = watch.at(-1);
    let leakDrift = drift(a0, a1);
    const dq = q(a1).map((x, j) => x - q(a0)[j]);
    const jr = dq.map(Math.abs).indexOf(Math.max(...dq.map(Math.abs)));
    if (Math.abs(dq[jr]) > 1) {
      const dir = -Math.sign(dq[jr]);
      const b0 = q(await this.state())[jr];
      const axes = [0, 0, 0, 0, 0, 0]; axes[jr] = dir;
      const b1 = q((await this.hold(axes, 3)).at(-1))[jr];
      return answer((b1 - b0) * dir < 2 ? 'stuck_valve' : 'leak', `joint ${jr + 1} ran ${dq[jr].toFixed(1)}° with the sticks centred; jogged against it moved ${((b1 - b0) * dir).toFixed(1)}°`);
    }
    for (let j = 0; j < 6; j++) {
      const axes = [0, 0, 0, 0, 0, 0];
      const c0 = q(await this.state())[j];
      axes[j] = 1; const c1 = q((await this.hold(axes, 2)).at(-1))[j];
      axes[j] = -1; const c2 = q((await this.hold(axes, 2)).at(-1))[j];
      await this.hold([0, 0, 0, 0, 0, 0], 1);
      if (Math.abs(c1 - c0) < 2 && Math.abs(c2 - c1) < 2) return answer('stuck_valve', `joint ${j + 1} answered neither way (${(c1 - c0).toFixed(1)}°, ${(c2 - c1).toFixed(1)}°)`);
    }
    // 2. spin
    await this.hold([0, 0, 0, 0, 0, 0], 2);
    await this.page.evaluate(() => { window.__rec.length = 0; });
    await this.hold([0, 0, 0, 0, 0, 1], 3);
    const rec = await this.page.evaluate(() => window.__rec.slice());
    await this.hold([0, 0, 0, 0, 0, 0], 2);
    const steady = rec.at(-1).qd5;
    const tail = rec.filter((r) => r.t >= rec.at(-1).t - 0.2);
    const supply = tail.reduce((x, r) => x + r.p5, 0) / tail.length / 6.89e6;
    const start = rec.find((r) => Math.abs(r.qd5) > 0.05 * Math.abs(steady));
    const at40 = rec.find((r) => start && r.t >= start.t + 0.04);
    const lag = start && at40 ? at40.qd5 / steady : 1;
    if (supply < 0.8) return answer('supply_drop', `spin: P_I + P_O = ${(supply * 100).toFixed(0)} % of the supply`);
    if (lag < 0.65) return answer('air', `spin: ${(lag * 100).toFixed(0)} % of the steady speed 40 ms in`);
    // 2b. the wrist pitch's stop
    const stopTau = [];
    for (const dir of [1, -1]) {
      await this.page.evaluate(() => { window.__rec.length = 0; });
      await this.hold([0, 0, 0, dir, 0, 0], 2);
      const jog = await this.page.evaluate(() => window.__rec.slice());
      await this.page.evaluate(() => { window.__rec.length = 0; });
      await this.hold([0, 0, 0, 0, 0, 0], 3);
      const coast = await this.page.evaluate(() => window.__rec.slice());
      // which way the stick turned it (the joint-mode labels say; the frames show it)
      const sgn = Math.sign(jog.at(-1)?.qd3 ?? 0);
      const steadyPitch = Math.max(0, ...jog.map((r) => r.qd3 * sgn));
      const end = coast.at(-1)?.q3;
      const taus = coast.filter((r) => r.qd3 * sgn > 0.1 * steadyPitch && r.qd3 * sgn < 0.9 * steadyPitch).map((r) => (end - r.q3) / r.qd3);
      // no frame while it slowed: it stopped between two frames, as healthy oil does
      stopTau.push(taus.length && steadyPitch > 0.1 ? taus.sort((x, y) => x - y)[taus.length >> 1] : 0.025);
    }
    const tau = Math.max(...stopTau);
    if (tau > 0.05) return answer('air', `wrist pitch crept on after the stop: time constant ${stopTau.map((x) => (x * 1000).toFixed(0)).join(' and ')} ms (healthy ≈ 25 ms)`);
    // 3. leak test
    for (const j of [1, 2, 3]) {
      const axes = [0, 0, 0, 0, 0, 0];
      axes[j] = 1; await this.hold(axes, 1);
      axes[j] = -1; await this.hold(axes, 1);
    }
    await this.hold([0, 0, 0, 0, 0, 0], 3);
    const l0 = await this.state();
    const l1 = (await this.hold([0, 0, 0, 0, 0, 0], 8)).at(-1);
    leakDrift = Math.max(leakDrift, drift(l0, l1));
    const why = `supply ${(supply * 100).toFixed(0)} %, spin-up ${(lag * 100).toFixed(0)} %, pitch stop ${(tau * 1000).toFixed(0)} ms, gauge drift ${(leakDrift / 1e6).toFixed(2)} MPa`;
    if (leakDrift > 1e5) return answer('leak', why);
    const score = [[(1 - supply) / 0.2, 'supply_drop'], [Math.max((1 - lag) / 0.35, tau / 0.05), 'air'], [leakDrift / 1e5, 'leak']].sort((x, y) => y[0] - x[0]);
    return answer(score[0][1], `${why} (nearest)`);
  }
}

let url, b, own;
const results = [];

before(async () => {
  own = await startServer();
  url = own.url;
  b = await openBrowser({ initScript: FAKE_GAMEPAD });
});
after(async () => {
  writeFileSync(join(ARTIFACTS, 'trial.json'), JSON.stringify({ decide_ms: DECIDE_MS, results }, null, 2));
  for (const r of results) console.log(`trial ${r.id}: ${r.passed ? 'PASSED' : 'NOT PASSED'} score ${r.score} time ${r.time_s} s (${r.decisions} decisions, ${r.taps} taps, ≤ ${r.maxAxes} axes, wall ${r.wall_s} s)${r.failed_because?.length ? ' — ' + r.failed_because.join('; ') : ''}`);
  await b?.close();
  own?.stop();
});

/** One exercise, as a new trainee: open it, pilot view, read the goal, Ready, work the plan. */
async function trial(id) {
  const page = b.page;
  const t0 = Date.now();
  // a new trainee on this browser (the page resumes a stored session whatever the URL names)
  await page.evaluate(() => localStorage.removeItem('seaarms.session')).catch(() => {});
  await page.goto(`${url}/?exercise=${id}`);
  await until(page, (x) => window.__seaarms?.hello?.exercise?.id === x, id);
  await untilDrawn(page);
  await page.evaluate(() => window.__connectPad());
  // the pilot cameras; the pan-tilt camera's view is the active one (a click on it)
  if (await page.inputValue('#sel-views') !== 'pilot') await page.selectOption('#sel-views', 'pilot');
  const r = await page.evaluate(() => window.__seaarms.viewports().find((v) => v.name === 'pilot').rect);
  await page.mouse.click(r.x + r.width / 2, r.y + r.height - 12);
  await until(page, () => window.__seaarms.viewSet().active === 'pilot', undefined, 5000);
  const goal = await page.innerText('#task .task-goal');
  const plan = (await (await fetch(`${url}/api/exercises/${id}`)).json()).autopilot;
  assert.ok(Array.isArray(plan) && plan.length, `${id}: the exercise's plan`);
  await pressReady(page);
  const op = new Operator(page);
  op.deadline = t0 + TRIAL_WALL_S * 1000;
  await op.begin();
  op.stepAt = 0;
  const actions = [];
  let shot = false;
  // a fault drill's goal says when the fault comes ("at a random moment in the first 15 s"):
  // the shuttle stops then (the operator did not read it until 2026-11-28 and shuttled the
  // whole plan, 80–110 s of the drill's 120)
  const faultBy = /(?:within|in the first) (\d+) s\b/.exec(goal)?.[1];
  assert.ok(id !== 'fault-diagnosis' || faultBy, `${id}: the goal says when the fault comes: ${goal}`);
  for (const a of plan) {
    if (Date.now() > op.deadline) break;
    op.stepAt = (await op.state()).exercise.step;
    if (faultBy && a.do === 'joint' && (await op.state()).exercise.elapsed_s > +faultBy + 1) continue;
    const ta = Date.now();
    const r = await op.run(a);
    const st = await op.state();
    const line = { do: a.do, to: a.to ?? a.joint ?? a.until?.kind ?? a.s, result: r, s: +((Date.now() - ta) / 1000).toFixed(1), step: st.exercise.step };
    actions.push(line);
    // a look at the work mid-trial, in the pilot views: the jaw on the T-bar; the jaw closed on
    // the box's lifting point
    if (!shot && ((id === 'valve-turn' && st.exercise.step >= 1) || (id === 'pick-and-place' && a.do === 'grip' && a.close))) {
      shot = true;
      await page.screenshot({ path: join(ARTIFACTS, `trial-${id}-pilot.png`) });
    }
    if (process.env.TRIAL_DEBUG) console.log(JSON.stringify({ ...line, q: st.arms[op.side].q.map((x) => +(x * 57.3).toFixed(1)), jaw: st.arms[op.side].pose.position.map((x) => +x.toFixed(3)), panel: st.panel, counters: st.exercise.counters }));
    if (r === 'exercise done') break;
  }
  // the plan ends on a hold and the task panel still counts it (a slip or a drift reset its
  // clock): a person keeps holding while the panel says "hold", up to 30 s more
  const last = plan.at(-1);
  const holdUntil = Date.now() + 30000;
  while (last?.do === 'wait' && Date.now() < Math.min(op.deadline, holdUntil) && !(await op.state()).exercise.done) {
    const r = await op.run(last);
    actions.push({ do: 'wait (hold on)', result: r, step: (await op.state()).exercise.step });
    if (r === 'exercise done') break;
  }
  await op.rest();
  // the plan is done; the last step may still be counting (a hold)
  const finished = await until(page, () => window.__seaarms.lastState.exercise.done, undefined, 15000).then(() => true, () => false);
  if (!finished) {
    // the plan ran out (its actions timed out) with the attempt unfinished: say where it stands
    const ex = await op.state().then((s) => s.exercise);
    const res = { id, goal, passed: false, score: Math.round(ex.score), time_s: +ex.elapsed_s.toFixed(1), decisions: op.stats.decisions, taps: op.stats.taps,
      maxAxes: op.stats.maxAxes, minIntervalMs: Math.min(...op.stats.intervalsMs), wall_s: +((Date.now() - t0) / 1000).toFixed(1),
      failed_because: [`unfinished at step ${ex.step + 1} of ${ex.steps} ("${ex.step_text}"), counters ${JSON.stringify(ex.counters)}`], actions };
    results.push(res);
    return res;
  }
  if (process.env.TRIAL_DEBUG) console.log(JSON.stringify(await op.state().then((s) => s.exercise)));
  await page.waitForSelector('#card:not([hidden]) [data-score]', { timeout: 20000 });
  // the completion card: verdict, score, time (the server's assessment, as the page shows it)
  const verdict = (await page.innerText('#card .card-verdict')).trim();
  const score = +(await page.getAttribute('#card [data-score]', 'data-score'));
  const title = await page.innerText('#card .card-title');
  const why = await page.$$eval('#card .card-why li', (l) => l.map((x) => x.textContent));
  const res = { id, goal, passed: verdict === 'Passed', score, time_s: +(title.match(/— ([\d.]+) s/)?.[1] ?? NaN),
    decisions: op.stats.decisions, taps: op.stats.taps, maxAxes: op.stats.maxAxes,
    minIntervalMs: Math.min(...op.stats.intervalsMs), wall_s: +((Date.now() - t0) / 1000).toFixed(1), failed_because: why, notes: op.notes, actions };
  results.push(res);
  return res;
}

for (const id of (process.env.TRIAL_ONLY ? process.env.TRIAL_ONLY.split(',') : EXERCISES)) {
  test(`trainee trial in pilot view: ${id}`, { timeout: TRIES * (TRIAL_WALL_S + 60) * 1000 }, async () => {
    let r = await trial(id);
    for (let k = 2; !r.passed && k <= TRIES; k++) {
      // another try, as a trainee in a practice session would have (each is reported)
      console.log(`try ${k - 1} of ${id} not passed (score ${r.score}: ${r.failed_because?.join('; ')}): trying again`);
      r = await trial(id);
      r.try = k;
    }
    console.log(JSON.stringify(r));
    assert.ok(r.maxAxes <= 2, 'two axes at a time at most');
    assert.ok(r.minIntervalMs >= 150, `decisions ≥ 150 ms apart (${r.minIntervalMs} ms)`);
    assert.ok(r.passed, `${id} passed (score ${r.score})`);
  });
}
