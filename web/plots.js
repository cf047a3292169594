// Live plots of what Lim plotted after the fact (Figs 4-6 to 4-40): line pressures P_in/P_out
// of a chosen actuator, joint angles, contact and internal forces, manipulability over time.
// Fixed-size ring buffers (no growth); sampled at 20 Hz from the latest state; redrawn at 5 Hz.

import uPlot from 'uplot';
import { jointNames, links } from './api.js';

const WINDOW_S = 30;
const SAMPLE_HZ = 20;
const N = WINDOW_S * SAMPLE_HZ;
const COLOURS = ['#ff6b6b', '#ffd43b', '#69db7c', '#4dabf7', '#da77f2', '#ffa94d', '#e9ecef'];

class Series {
  constructor(k) {
    this.k = k;
    this.len = 0;
    this.cols = Array.from({ length: k + 1 }, () => new Float64Array(N));
    this.view = null;
  }

  push(values) {
    if (this.len === N) {
      for (const c of this.cols) c.copyWithin(0, 1);
      this.len = N - 1;
    }
    for (let i = 0; i < values.length; i++) this.cols[i][this.len] = Number.isFinite(values[i]) ? values[i] : 0;
    this.len++;
  }

  data() { return this.cols.map((c) => c.subarray(0, this.len)); }
  clear() { this.len = 0; }
}

/** A titled plot of `labels` appended to `el`: {plot, s (its Series), div, yLabel}. */
function makePlot(el, title, labels, yLabel, width) {
  const h = document.createElement('h4');
  h.textContent = title;
  el.appendChild(h);
  const div = document.createElement('div');
  el.appendChild(div);
  return chart(div, labels, yLabel, width);
}

/** A plot of `labels` drawn in `div` (emptied first). */
function chart(div, labels, yLabel, width) {
  div.replaceChildren();
  const opts = {
    width, height: 150,
    legend: { show: true, live: false },
    cursor: { show: false },
    scales: { x: { time: false } },
    axes: [
      { stroke: '#9cc3e6', grid: { stroke: '#1f3a55' }, label: 't (s)', labelSize: 14, size: 30 },
      { stroke: '#9cc3e6', grid: { stroke: '#1f3a55' }, label: yLabel, labelSize: 14, size: 50 },
    ],
    series: [{}, ...labels.map((l, i) => ({ label: l, stroke: COLOURS[i % COLOURS.length], width: 1.2, points: { show: false } }))],
  };
  const s = new Series(labels.length);
  const plot = new uPlot(opts, s.data(), div);
  return { plot, s, div, yLabel, labels };
}

export class Plots {
  constructor(el) {
    this.el = el;
    const w = Math.max(300, (el.clientWidth || 420) - 12);
    const ctl = document.createElement('div');
    ctl.innerHTML = `<label>actuator <select id="plot-arm"><option>left</option><option>right</option></select>
      <select id="plot-joint" aria-label="actuator joint"></select></label>
      <a id="csv-link" href="#" download>session CSV</a>`;
    el.appendChild(ctl);
    this.armSel = ctl.querySelector('#plot-arm');
    this.jointSel = ctl.querySelector('#plot-joint');
    this.csv = ctl.querySelector('#csv-link');
    this.armSel.addEventListener('change', () => this.clearSelected());
    this.jointSel.addEventListener('change', () => this.clearSelected());
    this.pressure = makePlot(el, 'Line pressures (kPa) — Lim Figs 4-7, 4-30', ['P_in', 'P_out'], 'kPa', w);
    this.joints = jointNames(null);
    this.jointOptions();
    this.angles = makePlot(el, 'Joint angles (deg), selected arm — Fig 4-6', this.joints, 'deg', w);
    this.forces = makePlot(el, 'Contact and internal forces (N) — Figs 4-34, 4-39', ['|F| left', '|F| right', 'Fint x', 'Fint y', 'Fint z'], 'N', w);
    this.manip = makePlot(el, 'Manipulability (Yoshikawa) — §4.3', ['left', 'right', 'dual'], 'w', w);
    this.all = [this.pressure, this.angles, this.forces, this.manip];
    this.lastSample = -Infinity;
    this.lastT = null;
    this.visible = true;
    this.redrawTimer = setInterval(() => this.redraw(), 200);
    new ResizeObserver(() => {
      const ww = Math.max(300, el.clientWidth - 12);
      for (const p of this.all) p.plot.setSize({ width: ww, height: 150 });
    }).observe(el);
  }

  /** The CSV link of session `id` (`base`: its replica's path prefix, docs/api.md). */
  setSession(id, base = '') {
    this.csv.href = links.sessionCsv(id, base);
  }

  /** The joints' names (the hello's model, web/api.js jointNames): the actuator menu and the
   * joint-angle plot's series. */
  setJoints(names) {
    if (names.join() === this.joints.join()) return;
    this.joints = names;
    this.jointOptions();
    const a = this.angles;
    a.plot.destroy();
    const i = this.all.indexOf(a);
    this.angles = chart(a.div, names, a.yLabel, a.plot.width);
    this.all[i] = this.angles;
  }

  jointOptions() {
    const j = this.jointSel.value;
    this.jointSel.replaceChildren(...this.joints.map((n, i) => new Option(`${i + 1} ${n}`, String(i))));
    if (j) this.jointSel.value = j;
  }

  clearSelected() { this.pressure.s.clear(); }

  /** Empties every plot (a replay's seek: the next frame starts a new trace). */
  reset() {
    for (const p of this.all) p.s.clear();
    this.lastT = null;
    this.lastSample = -Infinity;
    this.dirty = true;
  }

  /** Called for every state frame; samples at SAMPLE_HZ of sim time. */
  add(state, arm) {
    const t = state.t;
    if (this.lastT !== null && t < this.lastT) for (const p of this.all) p.s.clear(); // reset
    this.lastT = t;
    if (t - this.lastSample < 1 / SAMPLE_HZ && t >= this.lastSample) return;
    this.lastSample = t;
    const pa = state.arms[this.armSel.value];
    const j = +this.jointSel.value;
    this.pressure.s.push([t, pa.p_in[j] / 1000, pa.p_out[j] / 1000]);
    const a = state.arms[arm];
    this.angles.s.push([t, ...a.q.map((v) => v * 180 / Math.PI)]);
    const fl = state.arms.left.contact_force_n, fr = state.arms.right.contact_force_n, fi = state.internal_force_n;
    this.forces.s.push([t, Math.hypot(...fl), Math.hypot(...fr), fi[0], fi[1], fi[2]]);
    this.manip.s.push([t, state.arms.left.measures.yoshikawa, state.arms.right.measures.yoshikawa,
      state.dual ? state.dual.measures.yoshikawa : 0]); // dual: 0 unless both jaws hold
    this.dirty = true;
  }

  redraw() {
    if (!this.dirty || !this.visible) return;
    this.dirty = false;
    for (const p of this.all) p.plot.setData(p.s.data());
  }
}
