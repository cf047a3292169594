// What every page shares (trainee, instructor, debrief, workspace map): `$`, HTML escaping,
// the number formats, the banner over the view and the status bar's 10 Hz refresh. Nothing
// here touches the DOM at load (the browser tests import the page's modules in Node).

/** The element with id `id`. */
export const $ = (id) => document.getElementById(id);

/** Text made safe for innerHTML, inside elements and inside quoted attributes of either kind
 * (`&`, `<`, `>`, `"` and `'` escaped); null and undefined read as empty. */
export function esc(s) {
  return String(s ?? '').replace(/[&<>"']/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;', "'": '&#39;' }[c]));
}

/** A measure to `digits` decimals: null reads ∞ (the server writes an infinite value, e.g.
 * the condition number at a singularity, as null), another non-finite value —. */
export function fmt(v, digits = 4) {
  if (v === null || v === undefined) return '∞';
  if (!Number.isFinite(v)) return '—';
  return v.toFixed(digits);
}

/** A number to `digits` decimals, or — when absent. */
/** A padlock (SVG, drawn in the text's colour: no emoji font needed), for locked exercises. */
export const LOCK_ICON = '<svg class="lock-icon" viewBox="0 0 10 12" width="10" height="12" aria-hidden="true">'
  + '<path d="M2.5 5V3.5a2.5 2.5 0 0 1 5 0V5" fill="none" stroke="currentColor" stroke-width="1.3"/>'
  + '<rect x="1" y="5" width="8" height="6.5" rx="1" fill="currentColor"/></svg>';

export function fixed(v, digits = 1) {
  return Number.isFinite(v) ? Number(v).toFixed(digits) : '—';
}

/** A number for an assessment card: integers as such, others to 3 significant digits; — when
 * absent. */
export function num(v) {
  if (v === null || v === undefined) return '—';
  if (!Number.isFinite(v)) return String(v);
  return Number.isInteger(v) ? String(v) : Number(v.toPrecision(3)).toString();
}

/** A one-line status note: `text` in `el`, marked bad (style.css `.bad`) or not. */
export function note(el, text, bad = false) {
  el.textContent = text;
  el.className = bad ? 'bad' : '';
}

/** The banner over the view (#banner): errors, notices and messages, kept or timed. */
export class Banner {
  constructor(el) {
    this.el = el;
    this.timer = null;
  }

  /** Shows `text` in style `kind` ('error', 'info', 'msg'; style.css) for `ms` (0: until the
   * next one); no text hides the banner. */
  show(kind, text, ms = 0) {
    clearTimeout(this.timer);
    if (!text) { this.el.hidden = true; return; }
    this.el.className = kind === 'error' ? '' : kind || '';
    this.el.textContent = text;
    this.el.hidden = false;
    if (ms) this.timer = setTimeout(() => { this.el.hidden = true; }, ms);
  }

  /** Hides the banner if it still shows `text` (a notice that no longer applies). */
  withdraw(text) {
    if (!this.el.hidden && this.el.textContent === text) this.show(null, '');
  }
}

/** How often the status bar is refreshed (Hz). */
export const STATUS_HZ = 10;

/** Refreshes `status` (web/status.js) from `view`'s newest drawn state STATUS_HZ times a
 * second (its text changes only when values do); `arm()` names the selected arm, `also(state)`
 * runs after each refresh. */
export function statusLoop(view, status, arm, also = null) {
  return setInterval(() => {
    const s = view.drawn;
    if (!s) return;
    status.update(s, { arm: arm() });
    also?.(s);
  }, 1000 / STATUS_HZ);
}
