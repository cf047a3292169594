// Operator input: the Gamepad API (standard mapping) with a keyboard fallback covering the
// same functions, and on touch screens the on-screen sticks (web/touch.js, a virtual pad in
// the same mapping, sampled here like a real one). Sampled and sent at a steady SEND_HZ (below the server's
// `hello.max_messages_per_second`, see setServerLimit) with increasing sequence numbers:
// {"type":"input","seq":n,"arms":{"left":{"axes":[6],"grip":g},"right":{...}},"object":[6]?}.
// Joint mode: axis i drives joint i of the selected arm. Cartesian mode: the same axes are
// [vx, vy, vz, wx, wy, wz] of its end-effector. Closed loop: they drive the object instead.

import { messages } from './api.js';

/** Input messages per second (at most; lowered to stay under the server's message limit). */
export const SEND_HZ = 50;
/** Dead zone of sticks and triggers: |v| below it reads 0, above it is rescaled to [0, 1]. */
export const DEAD_ZONE = 0.12;
/** Other messages per second the page sends besides input (the 1 Hz latency ping). */
const OTHER_MESSAGES_HZ = 1;

/** A key held this long (ms) drives its axis continuously; a shorter tap is only the jog
 * sent when it went down (a bounded, repeatable move whatever the tap's length: 2° of a joint,
 * or 1 cm / 2° of the jaw, times the arm speed; sim::Operator::jog). */
export const TAP_HOLD_MS = 250;
/** Keyboard: each pair drives axis i (+, −). */
export const KEY_AXES = [
  ['KeyQ', 'KeyA'], ['KeyW', 'KeyS'], ['KeyE', 'KeyD'], ['KeyR', 'KeyF'], ['KeyT', 'KeyG'], ['KeyU', 'KeyJ'],
];
/** Keys with an action in `onPress` (besides the axes and the grip). */
const ACTION_KEYS = new Set(['Digit1', 'Digit2', 'KeyM', 'KeyL', 'Minus', 'Equal', 'KeyB', 'KeyI', 'KeyP', 'KeyV', 'KeyH',
  'KeyO', 'KeyK', 'KeyC', 'KeyN']);
/** Keys that change only this page's view. */
const VIEW_KEYS = new Set(['KeyV', 'KeyH', 'KeyO', 'KeyK', 'KeyC', 'KeyN']);
/** Keys that drive the pan-tilt camera while held: [pan +/−, tilt +/−, zoom +/−]. */
const CAMERA_KEYS = [['ArrowLeft', 'ArrowRight'], ['ArrowUp', 'ArrowDown'], ['PageUp', 'PageDown']];
/** Standard-mapping buttons: LB, RB (arm select; held: the right stick drives the wrist) and
 * L3 (held: the right stick and the d-pad drive the pan-tilt camera). */
const LB = 4, RB = 5, L3 = 10;
export const CART_NAMES = ['vx', 'vy', 'vz', 'wx', 'wy', 'wz'];

/** Gamepad (standard mapping) → axis i: [source, sign]. Sources: axes a0..a3, d-pad pairs. */
export const PAD_AXES = [
  { label: 'left stick X', get: (p) => p.axes[0] ?? 0 },
  { label: 'left stick Y (up = +)', get: (p) => -(p.axes[1] ?? 0) },
  { label: 'right stick Y (up = +)', get: (p) => -(p.axes[3] ?? 0) },
  { label: 'd-pad up / down', get: (p) => btn(p, 12) - btn(p, 13) },
  { label: 'right stick X', get: (p) => p.axes[2] ?? 0 },
  { label: 'd-pad right / left', get: (p) => btn(p, 15) - btn(p, 14) },
];

/** The documented mapping (also in README "Keyboard and gamepad"), as the help overlay shows
 * it: [function, gamepad, keyboard] rows, the axes named by `joints` (web/api.js jointNames). */
export function mapping(joints) {
  const axes = PAD_AXES.map((pad, i) => [`Axis ${i + 1}: ${joints[i]}${i ? '' : ' (joint)'} / ${CART_NAMES[i]}${i ? '' : ' (Cartesian)'}`,
    pad.label, KEY_AXES[i].map((k) => k.slice(3)).join(' / ')]);
  return [...axes, ...MAPPING];
}

/** The rest of the mapping: [function, gamepad, keyboard]. */
const MAPPING = [
  ['Grip: close / open', 'RT (close) / LT (open)', 'Z (close) / X (open)'],
  ['Select left / right arm', 'LB / RB', '1 / 2'],
  ['Control mode joint ↔ Cartesian', 'Y', 'M'],
  ['Open ↔ closed loop', 'X', 'L'],
  ['Arm speed − / +', '—', '- / ='],
  ['Release (open both jaws)', 'B', 'B'],
  ['Initial position (reset)', 'Back / Select', 'I'],
  ['Pause / resume', 'Start', 'P'],
  ['Slow (30 %) while held', 'A', 'Shift'],
  ['Tap an axis key: a fixed step (2° of a joint, or 1 cm / 2° of the jaw, × arm speed); hold it to move', '—', 'tap / hold'],
  ['Wrist on the right stick (analog pitch ↕, rotate ↔) while held', 'LB or RB held', '—'],
  ['Pan-tilt camera: pan ↔, tilt ↕ / zoom', 'L3 held + right stick / + d-pad ↑↓', 'arrows / PgUp PgDn'],
  ['Engineering ↔ pilot cameras', '—', 'C'],
  ['Work-site view', '—', 'K'],
  ['Ellipsoids on / off', '—', 'O'],
  ['Four views ↔ one view', '—', 'V'],
  ['Ghost (an earlier attempt) on / off', '—', 'N'],
  ['Help overlay', '—', '? or H'],
];

function btn(p, i) { const b = p.buttons[i]; return b ? (typeof b === 'object' ? b.value : b) : 0; }
function pressed(p, i) { const b = p.buttons[i]; return !!b && (typeof b === 'object' ? b.pressed || b.value > 0.5 : b > 0.5); }

/** Input types that take typed text (keys there are the user's text, not arm commands). A
 * focused checkbox, button or closed menu leaves the keys to the arms. */
const TEXT_INPUT_TYPES = new Set(['text', 'search', 'email', 'password', 'number', 'url', 'tel']);

/** Whether a key event's target is a text field (or an editable element). */
export function isTextEntry(t) {
  if (!t || !t.tagName) return false;
  if (t.isContentEditable || t.tagName === 'TEXTAREA') return true;
  return t.tagName === 'INPUT' && TEXT_INPUT_TYPES.has((t.type || 'text').toLowerCase());
}

/** Scaled radial dead zone on a value in [−1, 1]. */
export function deadZone(v) {
  const a = Math.abs(v);
  if (!(a > DEAD_ZONE)) return 0;
  return Math.sign(v) * Math.min(1, (a - DEAD_ZONE) / (1 - DEAD_ZONE));
}

/**
 * Cartesian axes [vx vy vz wx wy wz] from the stick's frame into the world frame the server
 * takes: `R` is the stick frame's rotation (rows, world ← stick) or null (the world's own axes).
 * The camera frame's R (web/app.js stickFrame) has columns [screen right, screen up, into the
 * screen], so stick right moves the jaw right on that view, stick up moves it up and the right
 * stick's up pushes it away; the rotations turn about the same axes. Clamped to [−1, 1] each.
 */
export function toWorld(axes, R) {
  if (!R) return axes;
  const out = axes.slice();
  for (const o of [0, 3]) {
    for (let r = 0; r < 3; r++) out[o + r] = R[r][0] * axes[o] + R[r][1] * axes[o + 1] + R[r][2] * axes[o + 2];
  }
  // a diagonal command keeps its size in stick units, no axis beyond full speed
  for (const o of [0, 3]) {
    const m = Math.max(1, ...out.slice(o, o + 3).map(Math.abs));
    for (let r = 0; r < 3; r++) out[o + r] /= m;
  }
  return out;
}

export class Input {
  /**
   * @param conn Connection (send)
   * @param ui {arm(): 'left'|'right', setArm(side), mode(): 'joint'|'cartesian',
   *            method(): 'open'|'closed', actions: {toggleMode, toggleMethod, speed(d), release,
   *            reset, pause, layout, help}}
   */
  constructor(conn, ui) {
    this.conn = conn;
    this.ui = ui;
    this.seq = 0;
    this.keys = new Set();
    this.keyDownAt = new Map(); // axis key → when it went down (ms)
    this.padIndex = null;
    this.prevButtons = new Map(); // per pad index: its buttons at the last sample (edges)
    this.virtualPads = []; // standard-mapping pads drawn on the page (web/touch.js)
    this.last = null; // last message sent, for tests and the status bar
    this.enabled = true;
    window.addEventListener('keydown', (e) => this.onKey(e, true));
    window.addEventListener('keyup', (e) => this.onKey(e, false));
    window.addEventListener('blur', () => { this.keys.clear(); this.keyDownAt.clear(); });
    window.addEventListener('gamepadconnected', (e) => { this.padIndex = e.gamepad.index; ui.onPad?.(e.gamepad.id); });
    window.addEventListener('gamepaddisconnected', (e) => { if (this.padIndex === e.gamepad.index) this.padIndex = null; ui.onPad?.(null); });
    this.sendHz = SEND_HZ;
    this.timer = setInterval(() => this.tick(), 1000 / this.sendHz);
  }

  /** Keeps input (plus the ping) within the server's `max_messages_per_second` (hello). */
  setServerLimit(maxMessagesPerSecond) {
    const hz = Math.max(1, Math.min(SEND_HZ, maxMessagesPerSecond - OTHER_MESSAGES_HZ));
    if (!(hz > 0) || hz === this.sendHz) return;
    this.sendHz = hz;
    clearInterval(this.timer);
    this.timer = setInterval(() => this.tick(), 1000 / this.sendHz);
  }

  onKey(e, down) {
    if (isTextEntry(e.target)) return;
    if (e.ctrlKey || e.metaKey || e.altKey) return;
    if (down) {
      if (!this.keys.has(e.code)) {
        this.onPress(e);
        if (KEY_AXES.flat().includes(e.code)) {
          this.keyDownAt.set(e.code, performance.now());
          this.jogKey(e.code, e.shiftKey);
        }
      }
      this.keys.add(e.code);
    } else {
      this.keys.delete(e.code);
      this.keyDownAt.delete(e.code);
    }
    // the page's keys never reach a focused control (a menu would jump to the option
    // starting with the letter)
    if (KEY_AXES.flat().includes(e.code) || CAMERA_KEYS.flat().includes(e.code) || e.code === 'KeyZ' || e.code === 'KeyX' ||
        (e.target?.tagName === 'SELECT' && ACTION_KEYS.has(e.code))) e.preventDefault();
  }

  onPress(e) {
    const a = this.ui.actions;
    // a tab that only watches keeps the view keys (layout, help), not the session's
    if (!this.enabled && !VIEW_KEYS.has(e.code) && e.key !== '?' && e.key !== 'Escape') return;
    switch (e.code) {
      case 'Digit1': this.ui.setArm('left'); break;
      case 'Digit2': this.ui.setArm('right'); break;
      case 'KeyM': a.toggleMode(); break;
      case 'KeyL': a.toggleMethod(); break;
      case 'Minus': a.speed(-1); break;
      case 'Equal': a.speed(+1); break;
      case 'KeyB': a.release(); break;
      case 'KeyI': a.reset(); break;
      case 'KeyP': a.pause(); break;
      case 'KeyV': a.layout(); break;
      case 'KeyH': a.help(); break;
      case 'KeyO': a.ellipsoids?.(); break;
      case 'KeyK': a.workSite?.(); break;
      case 'KeyC': a.viewSet?.(); break;
      case 'KeyN': a.ghost?.(); break;
      default:
        if (e.key === '?') a.help();
        else if (e.key === 'Escape') a.help(false);
    }
  }

  /** A tap on an axis key: one jog of the selected arm (open loop; in closed loop the keys
   * drive the object continuously). Shift makes it fine (0.3×, as for the sticks). */
  jogKey(code, fine) {
    if (!this.enabled || this.ui.method() === 'closed') return;
    const i = KEY_AXES.findIndex((pair) => pair.includes(code));
    if (i < 0) return;
    const axes = [0, 0, 0, 0, 0, 0];
    axes[i] = (KEY_AXES[i][0] === code ? 1 : -1) * (fine ? 0.3 : 1);
    const world = this.ui.mode() === 'cartesian' ? toWorld(axes, this.ui.stickFrame?.()) : axes;
    this.conn.send(messages.jog(this.ui.arm(), world));
  }

  /** Whether an axis key counts as held (down for TAP_HOLD_MS or more). */
  held(code, now) {
    return this.keys.has(code) && now - (this.keyDownAt.get(code) ?? -Infinity) >= TAP_HOLD_MS;
  }

  pad() {
    if (this.padIndex === null || !navigator.getGamepads) return null;
    const pads = navigator.getGamepads();
    const p = pads && pads[this.padIndex];
    return p && p.connected !== false ? p : null;
  }

  /** Adds a pad the page draws itself (touch sticks; a negative `index` of its own); it is
   * sampled like the Gamepad API's. */
  addVirtualPad(p) { this.virtualPads.push(p); }

  /** The connected gamepad and every virtual pad. */
  pads() {
    const p = this.pad();
    return p ? [p, ...this.virtualPads] : this.virtualPads;
  }

  /** Current [axes(6), grip] from the keyboard and the gamepad. */
  sample() {
    const axes = [0, 0, 0, 0, 0, 0];
    let grip = 0;
    const slowKey = this.keys.has('ShiftLeft') || this.keys.has('ShiftRight');
    const now = performance.now();
    // in closed loop the keys drive the object at once; in open loop a tap is a jog and the
    // axis follows only a held key
    const hold = (code) => (this.ui.method() === 'closed' ? this.keys.has(code) : this.held(code, now));
    KEY_AXES.forEach(([plus, minus], i) => { axes[i] += (hold(plus) ? 1 : 0) - (hold(minus) ? 1 : 0); });
    if (this.keys.has('KeyZ')) grip -= 1;
    if (this.keys.has('KeyX')) grip += 1;
    let slow = slowKey;
    const cam = CAMERA_KEYS.map(([plus, minus]) => (this.keys.has(plus) ? 1 : 0) - (this.keys.has(minus) ? 1 : 0));
    for (const p of this.pads()) {
      const v = PAD_AXES.map((m) => deadZone(m.get(p)));
      const rx = deadZone(p.axes[2] ?? 0), ry = -deadZone(p.axes[3] ?? 0);
      if (pressed(p, L3)) {
        // the right stick and the d-pad's up/down drive the camera, not the arm
        cam[0] -= rx; cam[1] += ry; cam[2] += v[3];
        v[2] = v[4] = v[3] = 0;
      } else if (pressed(p, LB) || pressed(p, RB)) {
        // analog wrist: the right stick's ↕ is pitch (axis 4), its ↔ rotate (axis 6)
        v[3] += ry; v[5] += rx;
        v[2] = v[4] = 0;
      }
      v.forEach((x, i) => { axes[i] += x; });
      grip += deadZone(btn(p, 6)) - deadZone(btn(p, 7)); // LT opens, RT closes
      if (pressed(p, 0)) slow = true;
      this.padButtons(p);
    }
    const k = slow ? 0.3 : 1;
    for (let i = 0; i < 6; i++) axes[i] = Math.max(-1, Math.min(1, axes[i] * k));
    this.ui.camera?.(...cam.map((c) => Math.max(-1, Math.min(1, c))));
    return { axes, grip: Math.max(-1, Math.min(1, grip)) };
  }

  /** Edge-triggered gamepad buttons. */
  padButtons(p) {
    const a = this.ui.actions;
    const now = p.buttons.map((_, i) => pressed(p, i));
    const prev = this.prevButtons.get(p.index) || []; // (getGamepads may return new objects)
    const edge = (i) => now[i] && !prev[i];
    if (edge(4)) this.ui.setArm('left');
    if (edge(5)) this.ui.setArm('right');
    if (edge(3)) a.toggleMode();
    if (edge(2)) a.toggleMethod();
    if (edge(1)) a.release();
    if (edge(8)) a.reset();
    if (edge(9)) a.pause();
    this.prevButtons.set(p.index, now);
  }

  tick() {
    if (!this.enabled) return;
    const sampled = this.sample();
    const { grip } = sampled;
    const axes = this.ui.mode() === 'cartesian' || this.ui.method() === 'closed' ? toWorld(sampled.axes, this.ui.stickFrame?.()) : sampled.axes;
    const arm = this.ui.arm();
    const still = [0, 0, 0, 0, 0, 0];
    let msg;
    if (this.ui.method() === 'closed') {
      msg = messages.input(this.seq + 1, { left: { axes: still, grip }, right: { axes: still, grip } }, axes);
    } else {
      const zero = { axes: still, grip: 0 };
      msg = messages.input(this.seq + 1, { left: zero, right: zero, [arm]: { axes, grip } });
    }
    if (this.conn.send(msg)) {
      this.seq++;
      this.last = msg;
    }
  }

  stop() { clearInterval(this.timer); }
}
