// The status bar (Lim Fig. 4-80): per-arm Yoshikawa, isotropy, Hong, JLM; dual-arm measures;
// grasp state; control mode and method; arm speed; sim time; latency; warnings and messages.
// Every number is the server's, formatted here; the DOM is built once and only text changes.

import { GRASP_COLOURS } from './scene.js';
import { fmt } from './page.js';

const FIELDS = [
  ['left', 'L'], ['right', 'R'],
];

export class StatusBar {
  constructor(el) {
    this.el = el;
    const arm = (side, tag) => `<span class="grp" data-arm="${side}"><span class="k">${tag}</span>
      w <b data-f="${side}.yoshikawa"></b> iso <b data-f="${side}.isotropy"></b>
      Hong <b data-f="${side}.hong"></b> JLM <b data-f="${side}.jlm"></b></span>`;
    el.innerHTML = `${FIELDS.map(([s, t]) => arm(s, t)).join('')}
      <span class="grp"><span class="k">dual</span> w <b data-f="dual.yoshikawa">—</b> iso <b data-f="dual.isotropy">—</b> Hong <b data-f="dual.hong">—</b></span>
      <span class="grp"><span class="k">grasp</span> <span class="grasp-chip" data-f="graspchip"></span> <b data-f="grasp"></b></span>
      <span class="grp"><span class="k">mode</span> <b data-f="mode"></b>/<b data-f="method"></b> <span class="k">arm</span> <b data-f="arm"></b>
        <span class="k">speed</span> <b data-f="speed"></b></span>
      <span class="grp"><span class="k">t</span> <b data-f="t"></b> s <b data-f="paused"></b></span>
      <span class="grp"><span class="k">water</span> <b data-f="water"></b></span>
      <span class="grp" data-f="link"><span class="k">latency</span> <b data-f="latency">—</b> ms</span>
      <span class="grp"><span class="k">relief</span> <b data-f="relief">0</b></span>
      <span class="grp"><span class="k">role</span> <b data-f="role"></b> <b data-f="pad"></b></span>
      <span class="grp warn" data-f="warnings"></span>
      <span class="grp bad" data-f="faults"></span>
      <span class="grp" data-f="message"></span>`;
    this.f = {};
    for (const n of el.querySelectorAll('[data-f]')) this.f[n.dataset.f] = n;
    this.text = {};
  }

  set(name, value) {
    if (this.text[name] === value) return;
    this.text[name] = value;
    this.f[name].textContent = value;
  }

  update(state, ui) {
    for (const [side] of FIELDS) {
      const m = state.arms[side].measures;
      this.set(`${side}.yoshikawa`, fmt(m.yoshikawa));
      this.set(`${side}.isotropy`, fmt(m.isotropy));
      this.set(`${side}.hong`, fmt(m.hong));
      this.set(`${side}.jlm`, fmt(m.jlm));
    }
    const d = state.dual?.measures;
    this.set('dual.yoshikawa', d ? fmt(d.yoshikawa) : '—');
    this.set('dual.isotropy', d ? fmt(d.isotropy) : '—');
    this.set('dual.hong', d ? fmt(d.hong) : '—');
    if (this.text.grasp !== state.grasp) {
      const c = GRASP_COLOURS[state.grasp] ?? GRASP_COLOURS.free;
      this.f.graspchip.style.background = `#${c.toString(16).padStart(6, '0')}`;
    }
    this.set('grasp', state.grasp.replaceAll('_', ' '));
    this.set('mode', state.settings.control_mode === 'cartesian' && !state.settings.hold_orientation
      ? 'cartesian, translation only' : state.settings.control_mode);
    this.set('method', state.settings.control_method);
    this.set('speed', `${Math.round(state.settings.arm_speed * 100)} %`);
    this.set('arm', ui.arm);
    this.set('t', state.t.toFixed(2));
    this.set('paused', state.paused ? (state.paused_by === 'instructor' ? 'PAUSED by the instructor' : 'PAUSED') : '');
    this.set('relief', String(state.relief_events));
    this.set('water', waterText(state.current));
    this.set('warnings', state.warnings.length ? '⚠ ' + state.warnings.map(describeWarning).join(', ') : '');
    this.set('faults', state.faults.length ? 'faults: ' + state.faults.join(', ') : '');
  }

  latency(ms) { this.set('latency', ms.toFixed(1)); }
  /** The page's role; a replay has no live link to the server's clock, so no latency. */
  role(r) {
    this.set('role', r);
    this.f.link.hidden = r === 'replay';
  }
  /** The connected gamepad by its name (a browser's id is "name (vendor, product…)"); the
   * whole id in the tooltip. */
  pad(id) {
    this.set('pad', id ? `gamepad: ${padName(id)}` : '');
    this.f.pad.title = id || '';
  }
  message(text) { this.set('message', text); }
}

/** A gamepad id's name part, at most 32 characters (an ellipsis where it is cut). */
export function padName(id) {
  const name = id.replace(/\s*\(.*$/, '') || id;
  return name.length > 32 ? `${name.slice(0, 31)}…` : name;
}

/** The frame's `current` ({speed_m_s, heading_deg}, or null in air) as status text: where the
 * water flows, e.g. "0.50 m/s → 30°" (degrees from +x, ahead of the arms, towards +y). */
export function waterText(c) {
  if (!c) return 'in air';
  if (!(c.speed_m_s > 0)) return 'still';
  return `${c.speed_m_s.toFixed(2)} m/s → ${Math.round(c.heading_deg)}°`;
}

/** `near_singularity:left` → "near singularity (left)"; `near_joint_limit:right:3` → "… joint 4";
 *  `slip:left` → "load slipping in jaw (left)". */
export function describeWarning(w) {
  const [kind, arm, joint] = w.split(':');
  if (kind === 'slip') return `load slipping in jaw (${arm})`;
  if (kind === 'orientation_lost') return `jaw orientation not held: limit or singularity (${arm})`;
  const k = kind.replaceAll('_', ' ');
  if (joint !== undefined && /^\d+$/.test(joint)) return `${k} (${arm} joint ${+joint + 1})`;
  return arm ? `${k} (${arm})` : k;
}
