// The task panel of an exercise (docs/exercises.md): the goal, the steps with ticks, the
// current step's live readouts (value against target), timer, progress and counters, from
// the hello's `exercise` and each state frame's `exercise`; banners for counted events
// (`last_event`); and the completion card with the score and each metric against its
// threshold (GET /api/sessions/{id}/assessment). Every number is the server's.

import { fmt, esc } from './status.js';

/** Event kinds shown as a warning banner (the rest, e.g. `step`, as information). */
const BAD_EVENTS = new Set(['strike', 'obstacle', 'drop', 'overload', 'relief', 'limit', 'fault']);
const COUNTERS = [['strikes', 'strikes'], ['drops', 'drops'], ['overloads', 'overloads'], ['relief', 'relief'], ['limit_hits', 'limit hits']];

/** "metric_name_unit" → "metric name (unit)" for the card. */
export function metricLabel(m) {
  const units = { _s: 's', _n: 'N', _m: 'm', _m_s3: 'm/s³', _deg: '°', _nm: 'N·m' };
  for (const [suffix, unit] of Object.entries(units).sort((a, b) => b[0].length - a[0].length)) {
    if (m.endsWith(suffix)) return `${m.slice(0, -suffix.length).replaceAll('_', ' ')} (${unit})`;
  }
  return m.replaceAll('_', ' ');
}

/** A number for the card: integers as such, others to 3 significant digits. */
function num(v) {
  if (v === null || v === undefined) return '—';
  if (!Number.isFinite(v)) return String(v);
  return Number.isInteger(v) ? String(v) : Number(v.toPrecision(3)).toString();
}

/** The fault drill's answers (FaultKind::NAMES in the core) and their labels. */
const DIAGNOSES = [['supply_drop', 'Supply pressure drop'], ['stuck_valve', 'Stuck valve'],
  ['leak', 'Internal leak'], ['air', 'Air in the oil']];

export class TaskPanel {
  /**
   * @param panel element of the panel (#task); card: element of the completion card
   * @param ui {banner(kind, text, ms), tryAgain(), next(), choose()}
   */
  constructor(panel, card, ui) {
    this.panel = panel;
    this.card = card;
    this.ui = ui;
    this.spec = null;
    this.lastEvent = null;
    this.shownDone = false;
    this.session = null;
  }

  get active() { return !!this.spec; }

  /** A new hello: `exercise` (the file) or null (free play or a case study). */
  setExercise(spec, session) {
    this.spec = spec;
    this.session = session;
    this.lastEvent = null;
    this.shownDone = false;
    this.step = -1;
    this.card.hidden = true;
    this.panel.hidden = !spec;
    if (!spec) { this.panel.replaceChildren(); return; }
    this.panel.innerHTML = `<h3 class="task-title">${esc(spec.title)}</h3>
      <p class="task-goal">${esc(spec.goal)}</p>
      <div class="task-bar"><span class="task-fill"></span></div>
      <div class="task-time"><span class="k">time</span> <b data-t="elapsed">0.0</b> / ${Math.round(spec.time_limit_s)} s
        <span class="k">score</span> <b data-t="score">—</b></div>
      <ol class="task-steps">${spec.steps.map((s, i) => `<li data-step="${i}">${esc(s.text)}</li>`).join('')}</ol>
      <div class="task-readouts"></div>
      <div class="task-counters">${COUNTERS.map(([k, label]) => `<span data-c="${k}">${label} <b>0</b></span>`).join('')}</div>
      ${spec.fault_drill ? `<div class="task-diagnose"><p>Name the fault:</p>${DIAGNOSES.map(([a, label]) =>
        `<button type="button" data-answer="${a}">${label}</button>`).join(' ')}</div>` : ''}`;
    for (const b of this.panel.querySelectorAll('[data-answer]')) {
      b.addEventListener('click', () => {
        this.ui.diagnose?.(b.dataset.answer);
        for (const o of this.panel.querySelectorAll('[data-answer]')) o.disabled = true;
        b.classList.add('chosen');
      });
    }
    this.fill = this.panel.querySelector('.task-fill');
    this.readouts = this.panel.querySelector('.task-readouts');
    this.items = [...this.panel.querySelectorAll('[data-step]')];
    this.t = Object.fromEntries([...this.panel.querySelectorAll('[data-t]')].map((n) => [n.dataset.t, n]));
    this.counters = Object.fromEntries([...this.panel.querySelectorAll('[data-c]')].map((n) => [n.dataset.c, n]));
  }

  /** A state frame's `exercise` (null outside exercises). */
  update(ex) {
    if (!this.spec || !ex) return;
    if (this.shownDone && !ex.done) this.restarted(); // "try again" (here or from another tab)
    if (ex.step !== this.step) {
      this.step = ex.step;
      this.items.forEach((li, i) => {
        li.classList.toggle('done', i < ex.step);
        li.classList.toggle('current', i === ex.step && !ex.done);
      });
    }
    this.fill.style.width = `${(100 * ex.progress).toFixed(1)}%`;
    this.t.elapsed.textContent = ex.elapsed_s.toFixed(1);
    this.t.score.textContent = Math.round(ex.score).toString();
    this.readouts.innerHTML = ex.readouts.map((r) => {
      const frac = r.target ? Math.max(0, Math.min(1, r.value / r.target)) : 0;
      return `<div class="readout"><span class="k">${esc(r.label)}</span> <b>${fmt(r.value, 3)}</b> / ${fmt(r.target, 3)} ${esc(r.unit)}
        <span class="ro-bar"><span class="ro-fill" data-w="${(100 * frac).toFixed(1)}"></span></span></div>`;
    }).join('');
    for (const f of this.readouts.querySelectorAll('.ro-fill')) f.style.width = `${f.dataset.w}%`;
    for (const [k] of COUNTERS) {
      const v = ex.counters[k] ?? 0;
      const b = this.counters[k].firstElementChild;
      if (b.textContent !== String(v)) b.textContent = String(v);
      this.counters[k].classList.toggle('bad', v > 0);
    }
    const e = ex.last_event;
    if (e && (!this.lastEvent || e.t !== this.lastEvent.t || e.kind !== this.lastEvent.kind)) {
      this.lastEvent = e;
      this.ui.banner(BAD_EVENTS.has(e.kind) ? 'error' : 'info', e.text, 4000);
    }
    if (ex.done && !this.shownDone) {
      this.shownDone = true;
      this.showCard(ex);
    }
  }

  /** The completion card, from the session's assessment. */
  async showCard(ex) {
    let a = null;
    try {
      const s = this.session;
      const r = await fetch(`/api/sessions/${encodeURIComponent(s.id)}/assessment`, {
        headers: { authorization: `Bearer ${s.control_token}` }, cache: 'no-store' });
      if (r.ok) a = await r.json();
    } catch { /* shown from the frame below */ }
    const score = a ? a.score : ex.score;
    const passed = a ? a.passed : ex.passed;
    const terms = a?.terms || [];
    const limits = a?.limits || [];
    const next = this.ui.nextTitle?.();
    this.card.innerHTML = `<div class="card-head ${passed ? 'pass' : 'fail'}">
        <span class="card-verdict">${passed ? 'Passed' : 'Not passed'}</span>
        <span class="card-score" data-score="${Math.round(score)}">${Math.round(score)}<small>/100</small></span></div>
      <p class="card-title">${esc(this.spec.title)} — ${a ? `${num(a.time_s)} s` : `${ex.elapsed_s.toFixed(1)} s`},
        ${a ? `${a.step_times_s.length} of ${a.steps_total}` : `${ex.step} of ${ex.steps}`} steps</p>
      ${a && a.failed_because.length ? `<ul class="card-why">${a.failed_because.map((w) => `<li>${esc(w)}</li>`).join('')}</ul>` : ''}
      ${terms.length ? `<table class="card-terms"><tr><th>metric</th><th>yours</th><th>good</th><th>poor</th><th>points</th></tr>
        ${terms.map((t) => `<tr><td>${esc(metricLabel(t.metric))}</td><td>${num(t.value)}</td><td>${num(t.good)}</td><td>${num(t.bad)}</td>
          <td>${(t.score * t.weight).toFixed(1)} / ${num(t.weight)}</td></tr>`).join('')}</table>` : ''}
      ${limits.length ? `<table class="card-limits"><tr><th>pass limit</th><th>yours</th><th>allowed</th><th></th></tr>
        ${limits.map((l) => `<tr class="${l.met ? 'ok' : 'bad'}"><td>${esc(metricLabel(l.metric))}</td><td>${num(l.value)}</td>
          <td>${l.max !== null && l.max !== undefined ? `≤ ${num(l.max)}` : ''}${l.min !== null && l.min !== undefined ? ` ≥ ${num(l.min)}` : ''}</td>
          <td>${l.met ? '✓' : '✗'}</td></tr>`).join('')}</table>` : ''}
      <div class="card-actions">
        <button type="button" data-act="again">Try again</button>
        ${next ? `<button type="button" data-act="next">Next: ${esc(next)}</button>` : ''}
        <button type="button" data-act="choose">All exercises</button>
        <button type="button" data-act="close">Close</button>
      </div>`;
    this.card.hidden = false;
    this.card.querySelector('[data-act="again"]').addEventListener('click', () => { this.card.hidden = true; this.ui.tryAgain(); });
    this.card.querySelector('[data-act="next"]')?.addEventListener('click', () => { this.card.hidden = true; this.ui.next(); });
    this.card.querySelector('[data-act="choose"]').addEventListener('click', () => { this.card.hidden = true; this.ui.choose(); });
    this.card.querySelector('[data-act="close"]').addEventListener('click', () => { this.card.hidden = true; });
  }

  /** After "try again" (the same session restarts the attempt). */
  restarted() {
    this.shownDone = false;
    this.lastEvent = null;
    this.step = -1;
    this.card.hidden = true;
  }
}
