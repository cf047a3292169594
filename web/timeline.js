// The debrief page's timeline: a bar over the attempt's duration with a marker per recorded
// event (GET /api/attempts/{id} `events`: {t (s since the attempt's start), kind, actor,
// detail}; docs/api.md), coloured by what happened, the moments that cost points standing
// out; click a marker or the bar to seek, a playhead at the replay's time. Also the event
// list beside the view. Colours are CSS classes (style.css `.k-…`), positions set through
// the CSSOM (the page's CSP refuses style="" attributes).

import { esc } from './page.js';

/** Categories in legend order: [id, label, costs points]. */
export const CATEGORIES = [
  ['strike', 'strike', true], ['overload', 'overload', true], ['relief', 'relief valve', true],
  ['slip', 'slip', true], ['drop', 'drop', true], ['limit', 'joint limit', true], ['fault', 'fault', false],
  ['grasp', 'grasp', false], ['step', 'step done', false], ['instructor', 'instructor', false],
  ['trainee', 'trainee command', false],
];
const COSTS = new Set(CATEGORIES.filter((c) => c[2]).map((c) => c[0]));

/** An event's category (see CATEGORIES). */
export function eventCategory(e) {
  const k = e.kind === 'exercise' ? e.detail?.kind : e.kind;
  switch (k) {
    case 'strike': case 'obstacle': return 'strike';
    case 'overload': return 'overload';
    case 'relief': return 'relief';
    case 'slip': case 'slid_out': return 'slip';
    case 'drop': return 'drop';
    case 'limit': case 'end_stop': return 'limit';
    case 'fault': case 'clear_faults': return 'fault';
    case 'grasp': return 'grasp';
    case 'step': return 'step';
    default: return e.actor === 'instructor' ? 'instructor' : 'trainee';
  }
}

/** How long after the assessment's strike notice the core's `strike` record of the same
 * strike can come (s): the record waits for the impact's peak (sim::STRIKE_WINDOW_S, 0.2 s)
 * and the notice comes with the next 100 Hz sample. */
const SAME_STRIKE_S = 0.25;

/**
 * The events without the core's `strike` records that an exercise's own strike notice
 * (`exercise` events of kind `strike` or `obstacle`) already marks: one marker per strike.
 * In free play, with no notices, every strike record stays.
 */
export function oneMarkPerStrike(events) {
  const notices = events.filter((e) => e.kind === 'exercise' && ['strike', 'obstacle'].includes(e.detail?.kind)).map((e) => e.t);
  return events.filter((e) => e.kind !== 'strike' || !notices.some((t) => e.t - t >= -0.02 && e.t - t <= SAME_STRIKE_S));
}

/** A short line for an event. */
export function eventText(e) {
  const d = e.detail && typeof e.detail === 'object' ? e.detail : {};
  if (e.kind === 'exercise') return d.text || String(d.kind || 'exercise event');
  if (e.kind === 'grasp') return `grasp: ${String(d.state ?? '').replaceAll('_', ' ')}`;
  if (e.kind === 'strike' && d.partner) {
    const what = String(d.partner).replaceAll('-', ' ');
    return `${d.arm} arm struck the ${what} (${d.part}) at ${(+d.impact_speed_m_s).toFixed(2)} m/s, peak ${(+d.peak_force_n).toFixed(0)} N`;
  }
  if (e.kind === 'relief') return `relief valve opened${d.arm ? ` (${d.arm}${d.joint !== undefined ? ` joint ${+d.joint + 1}` : ''})` : ''}`;
  const who = e.actor ? `${e.actor}: ` : '';
  if (e.kind === 'fault' && d.fault) return `${who}fault ${d.fault}${d.arm ? ` (${d.arm} arm${d.joint !== undefined && d.joint !== null ? `, joint ${+d.joint + 1}` : ''})` : ''}${d.silent ? ', silent' : ''}`;
  const what = e.kind.replaceAll('_', ' ');
  const extra = Object.entries(d).filter(([, v]) => v !== null && typeof v !== 'object')
    .map(([k, v]) => `${k} ${v}`).join(', ');
  return `${who}${what}${extra ? ` (${extra})` : ''}`;
}

/** The "m:ss.s" of a time in seconds. */
export function clock(t) {
  const m = Math.floor(t / 60);
  const s = t - 60 * m;
  return `${m}:${s.toFixed(1).padStart(4, '0')}`;
}

export class Timeline {
  /**
   * @param el the bar's container; list: element for the event list (or null)
   * @param seek(t) called with the time the user picked
   */
  constructor(el, list, seek) {
    this.el = el;
    this.list = list;
    this.seek = seek;
    this.duration = 0;
    this.events = [];
    el.innerHTML = `<div class="tl-track" title="click to seek"><div class="tl-done"></div><div class="tl-marks"></div>
      <div class="tl-head"></div></div><div class="tl-legend"></div>`;
    this.track = el.querySelector('.tl-track');
    this.done = el.querySelector('.tl-done');
    this.head = el.querySelector('.tl-head');
    this.marks = el.querySelector('.tl-marks');
    this.legend = el.querySelector('.tl-legend');
    this.track.addEventListener('click', (e) => {
      const m = e.target.closest('.tl-mark');
      if (m) { this.seek(+m.dataset.t); return; }
      const r = this.track.getBoundingClientRect();
      if (this.duration > 0 && r.width > 0) this.seek(Math.max(0, Math.min(1, (e.clientX - r.left) / r.width)) * this.duration);
    });
    list?.addEventListener('click', (e) => {
      const row = e.target.closest('[data-t]');
      if (row) this.seek(+row.dataset.t);
    });
  }

  /** The attempt's events (by t) and duration (s). */
  set(events, duration) {
    events = oneMarkPerStrike(events);
    this.events = events;
    this.duration = duration;
    const d = duration > 0 ? duration : 1;
    this.marks.innerHTML = events.map((e, i) => {
      const c = eventCategory(e);
      return `<button type="button" class="tl-mark k-${c}${COSTS.has(c) ? ' cost' : ''}" data-i="${i}" data-t="${e.t}" data-kind="${c}"
        title="${esc(`${clock(e.t)} — ${eventText(e)}`)}"></button>`;
    }).join('');
    for (const m of this.marks.children) m.style.left = `${(100 * Math.min(1, Math.max(0, +m.dataset.t / d))).toFixed(3)}%`;
    const count = {};
    for (const e of events) { const c = eventCategory(e); count[c] = (count[c] || 0) + 1; }
    this.legend.innerHTML = CATEGORIES.filter(([c]) => count[c]).map(([c, label, cost]) =>
      `<span class="tl-key${cost ? ' cost' : ''}"><span class="tl-sw k-${c}"></span>${esc(label)} ${count[c]}</span>`).join('')
      || '<span class="tl-key">no events recorded</span>';
    if (this.list) {
      this.list.innerHTML = events.length ? events.map((e) => {
        const c = eventCategory(e);
        return `<li class="ev${COSTS.has(c) ? ' cost' : ''}" data-t="${e.t}" title="seek to ${clock(e.t)}"><span class="tl-sw k-${c}"></span>
          <span class="ev-t">${clock(e.t)}</span> ${esc(eventText(e))}</li>`;
      }).join('') : '<li class="ev">no events recorded</li>';
    }
  }

  /** The replay's time (s): the playhead and the played part of the bar. */
  setTime(t) {
    const f = this.duration > 0 ? Math.max(0, Math.min(1, t / this.duration)) : 0;
    const pct = `${(100 * f).toFixed(3)}%`;
    if (this.head.style.left !== pct) {
      this.head.style.left = pct;
      this.done.style.width = pct;
    }
  }
}
