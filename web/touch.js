// On-screen touch controls for tablets and phones: two virtual sticks, a d-pad, grip and arm
// buttons. They are a virtual gamepad in the standard mapping (the same `axes` and `buttons`
// layout as the Gamepad API), which web/input.js samples exactly like a real pad: one input
// path, one sender. Pointer events, so a finger, a pen or a mouse all work.

import { jointNames } from './api.js';

/** Standard-mapping button indices used here (web/input.js MAPPING). */
const BUTTON = { LB: 4, RB: 5, LT: 6, RT: 7, UP: 12, DOWN: 13, LEFT: 14, RIGHT: 15 };

/** Shortest press of an on-screen button (ms): longer than a few input samples (web/input.js
 * samples at SEND_HZ = 50 Hz), so a quick tap is never missed between two. */
const MIN_PRESS_MS = 120;

/** Whether the device's main pointer is coarse (a finger) or it has a touch screen. */
export function touchDevice() {
  return matchMedia('(pointer: coarse)').matches || (navigator.maxTouchPoints || 0) > 0;
}

export class TouchPad {
  /** @param container element the controls are drawn in (positioned, e.g. #view) */
  constructor(container) {
    this.pad = {
      id: 'on-screen sticks', index: -1, connected: true, mapping: 'standard', timestamp: 0,
      axes: [0, 0, 0, 0],
      buttons: Array.from({ length: 17 }, () => ({ pressed: false, touched: false, value: 0 })),
    };
    this.el = document.createElement('div');
    this.el.id = 'touch';
    this.el.hidden = true;
    this.el.innerHTML = `
      <div class="stick" data-stick="left"><span class="knob"></span></div>
      <div class="tpad tpad-left">
        <button type="button" data-btn="${BUTTON.LB}" class="arm-btn">L arm</button>
        <button type="button" data-btn="${BUTTON.RB}" class="arm-btn">R arm</button>
        <button type="button" data-btn="${BUTTON.LT}">open</button>
        <button type="button" data-btn="${BUTTON.RT}">close</button>
      </div>
      <div class="tpad tpad-right">
        <button type="button" data-btn="${BUTTON.UP}">▲</button>
        <button type="button" data-btn="${BUTTON.LEFT}">◀</button>
        <button type="button" data-btn="${BUTTON.RIGHT}">▶</button>
        <button type="button" data-btn="${BUTTON.DOWN}">▼</button>
      </div>
      <div class="stick" data-stick="right"><span class="knob"></span></div>`;
    container.appendChild(this.el);
    this.setJoints(jointNames(null));
    for (const s of this.el.querySelectorAll('.stick')) this.bindStick(s, s.dataset.stick === 'left' ? 0 : 2);
    for (const b of this.el.querySelectorAll('[data-btn]')) this.bindButton(b, +b.dataset.btn);
  }

  /** Names what each control drives (web/input.js PAD_AXES: axis i is joint i, or the i-th
   * of vx vy vz wx wy wz), the joints by `names` (web/api.js jointNames: the hello's model). */
  setJoints(names) {
    const title = (sel, text) => { this.el.querySelector(sel).title = text; };
    title('[data-stick="left"]', `left stick: ${names[0]} ↔, ${names[1]} ↕`);
    title('[data-stick="right"]', `right stick: ${names[2]} ↕, ${names[4]} ↔`);
    title(`[data-btn="${BUTTON.UP}"]`, `${names[3]} + / wx +`);
    title(`[data-btn="${BUTTON.DOWN}"]`, `${names[3]} − / wx −`);
    title(`[data-btn="${BUTTON.RIGHT}"]`, `${names[5]} + / wz +`);
    title(`[data-btn="${BUTTON.LEFT}"]`, `${names[5]} − / wz −`);
  }

  get visible() { return !this.el.hidden; }

  set visible(v) {
    this.el.hidden = !v;
    if (!v) this.releaseAll();
  }

  /** Marks the selected arm's button (the page's arm selection, whatever changed it). */
  showArm(side) {
    this.el.querySelector(`[data-btn="${BUTTON.LB}"]`).classList.toggle('on', side === 'left');
    this.el.querySelector(`[data-btn="${BUTTON.RB}"]`).classList.toggle('on', side === 'right');
  }

  releaseAll() {
    this.pad.axes.fill(0);
    for (const b of this.pad.buttons) { b.pressed = false; b.value = 0; }
    for (const k of this.el.querySelectorAll('.knob')) k.style.transform = '';
    for (const b of this.el.querySelectorAll('[data-btn]')) b.classList.remove('held');
  }

  /** A stick writes axes[first] (x, right +) and axes[first + 1] (y, down +), as a pad's. */
  bindStick(el, first) {
    const knob = el.querySelector('.knob');
    let id = null;
    const move = (e) => {
      const r = el.getBoundingClientRect();
      const radius = r.width / 2;
      let x = (e.clientX - (r.left + radius)) / radius;
      let y = (e.clientY - (r.top + r.height / 2)) / radius;
      const n = Math.hypot(x, y);
      if (n > 1) { x /= n; y /= n; }
      this.pad.axes[first] = x;
      this.pad.axes[first + 1] = y;
      knob.style.transform = `translate(${x * radius}px, ${y * radius}px)`;
    };
    const end = (e) => {
      if (e.pointerId !== id) return;
      id = null;
      this.pad.axes[first] = 0;
      this.pad.axes[first + 1] = 0;
      knob.style.transform = '';
    };
    el.addEventListener('pointerdown', (e) => {
      if (id !== null) return;
      id = e.pointerId;
      el.setPointerCapture(e.pointerId);
      e.preventDefault();
      move(e);
    });
    el.addEventListener('pointermove', (e) => { if (e.pointerId === id) move(e); });
    el.addEventListener('pointerup', end);
    el.addEventListener('pointercancel', end);
  }

  /** A button is held while a pointer is down on it. */
  bindButton(el, index) {
    const set = (v) => {
      this.pad.buttons[index].value = v;
      this.pad.buttons[index].pressed = v > 0.5;
      el.classList.toggle('held', v > 0.5);
    };
    let downAt = 0;
    let timer = null;
    // a quick tap stays pressed for MIN_PRESS_MS so the input sampler sees it
    const up = () => { timer = setTimeout(() => set(0), Math.max(0, MIN_PRESS_MS - (performance.now() - downAt))); };
    el.addEventListener('pointerdown', (e) => {
      el.setPointerCapture(e.pointerId);
      e.preventDefault();
      clearTimeout(timer);
      downAt = performance.now();
      set(1);
    });
    el.addEventListener('pointerup', up);
    el.addEventListener('pointercancel', up);
    el.addEventListener('contextmenu', (e) => e.preventDefault()); // a long press is a hold
  }
}
