// The task panel of an exercise (docs/exercises.md): the goal, the steps with ticks, the
// current step's live readouts (value against target), timer, progress and counters, from
// the hello's `exercise` and each state frame's `exercise`; banners for counted events
// (`last_event`); and the completion card with the score and each metric against its
// threshold (GET /api/sessions/{id}/assessment, web/assessment.js) and a link to the
// attempt's debrief (/replay/{attempt}). Every number is the server's.

import { fmt, esc } from './page.js';
import { assessmentHtml, benchmarkHtml } from './assessment.js';
import * as api from './api.js';

/** Event kinds shown as a warning banner (the rest, e.g. `step`, as information). */
const BAD_EVENTS = new Set(['strike', 'obstacle', 'drop', 'overload', 'relief', 'limit', 'fault']);
const COUNTERS = [['strikes', 'strikes'], ['slips', 'slips'], ['drops', 'drops'], ['overloads', 'overloads'], ['relief', 'relief'], ['limit_hits', 'limit hits']];
/** The scored metrics' names in the cost line (the rest by their metric name). */
const COST_LABELS = {
  time_s: 'time', slips: 'slips', seabed_strikes: 'seabed strikes', obstacle_strikes: 'obstacle strikes',
  joint_limit_hits: 'limit hits', sparc: 'unsmooth motion', path_ratio: 'indirect path', mean_jlm: 'posture near limits',
  mean_yoshikawa: 'posture (manipulability)', peak_side_load_n: 'stab side load', overloads: 'overloads',
  relief_events: 'relief valve', drops: 'drops', peak_internal_force_n: 'internal force', idle_s: 'idle time',
};

/** The fault drill's answers (FaultKind::NAMES in the core) and their labels. */
const DIAGNOSES = [['supply_drop', 'Supply pressure drop'], ['stuck_valve', 'Stuck valve'],
  ['leak', 'Internal leak'], ['air', 'Air in the oil']];

/** A goal's first sentence (up to its first `.` or `:` followed by a space). */
const firstSentence = (text) => text.split(/(?<=[.:])\s/)[0];

export class TaskPanel {
  /**
   * @param panel element of the panel (#task); card: element of the completion card
   * @param gauges the force and pressure gauges (#gauges): docked in the panel, under the
   *   clock, while there is a task (next to it, not over a camera view), else back in the view
   * @param ui {banner(kind, text, ms), withdraw(text), tryAgain(), next(), choose()}
   */
  constructor(panel, card, gauges, ui) {
    this.panel = panel;
    this.card = card;
    this.gauges = gauges;
    this.gaugesHome = gauges.parentElement;
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
    if (!spec) { this.panel.replaceChildren(); this.gaugesHome.append(this.gauges); return; }
    this.panel.innerHTML = `<h3 class="task-title">${esc(spec.title)}</h3>
      ${spec.fault_drill ? `<details class="task-goal" open><summary>${esc(firstSentence(spec.goal))}</summary>${esc(spec.goal.slice(firstSentence(spec.goal).length).trim())}</details>`
        : `<p class="task-goal">${esc(spec.goal)}</p>`}
      <p class="task-practice" hidden></p>
      <button type="button" class="task-ready" data-act="ready" hidden title="Start the attempt's clock (Enter)">Ready — start</button>
      <div class="task-bar"><span class="task-fill"></span></div>
      <div class="task-time"><span class="k">time</span> <b data-t="elapsed">0.0</b> / ${Math.round(spec.time_limit_s)} s
        <span class="k">score</span> <b data-t="score">—</b></div>
      ${spec.fault_drill ? `<div class="task-diagnose"><p>Name the fault:</p>${DIAGNOSES.map(([a, label]) =>
        `<button type="button" data-answer="${a}">${label}</button>`).join(' ')}</div>` : ''}
      <ol class="task-steps">${spec.steps.map((s, i) => `<li data-step="${i}">${esc(s.text)}</li>`).join('')}</ol>
      <div class="task-readouts"></div>
      <div class="task-counters">${COUNTERS.map(([k, label]) => `<span data-c="${k}">${label} <b>0</b></span>`).join('')}</div>
      <div class="task-costs" title="Points each penalty takes off the score so far (a completed attempt scores 100 less these)"></div>
`;
    // the instruments right under the clock (and the drill's answers), above the steps: in
    // view without scrolling at 1280×800 however long the goal and the steps are
    this.panel.querySelector('.task-steps').before(this.gauges);
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
    this.costs = this.panel.querySelector('.task-costs');
    this.readyBtn = this.panel.querySelector('.task-ready');
    this.readyBtn.addEventListener('click', () => this.ui.ready?.());
    this.costsText = '';
  }

  /** A state frame's `exercise` (null outside exercises), whether the attempt waits for
   * the trainee's "Ready" (`awaiting_ready`: its clock stands until then), and `practice`
   * ({attempt, t} of a practice attempt taken over from a debrief, else absent). */
  update(ex, awaitingReady = false, practice = null) {
    if (!this.spec || !ex) return;
    const note = practice ? `Practice from attempt ${practice.attempt} at ${practice.t.toFixed(1)} s: the exercise goes on from there (steps done stay done, the clock runs on); not counted in your progress.` : '';
    const p = this.panel.querySelector('.task-practice');
    if (p && p.textContent !== note) {
      p.textContent = note;
      p.hidden = !note;
    }
    this.practice = practice;
    if (this.readyBtn.hidden === awaitingReady) {
      this.readyBtn.hidden = !awaitingReady;
      this.panel.classList.toggle('awaiting-ready', awaitingReady);
      if (awaitingReady) this.readyBtn.focus({ preventScroll: true });
      // a long goal (the fault drill's) folds once the clock runs: the answers stay in sight
      const goal = this.panel.querySelector('details.task-goal');
      if (goal) goal.open = awaitingReady;
    }
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
    const costs = (ex.costs || []).map((c) => `${COST_LABELS[c.metric] ?? c.metric.replaceAll('_', ' ')} −${c.points.toFixed(c.points < 10 ? 1 : 0)}`);
    const text = costs.length ? `costs: ${costs.join(' · ')}` : '';
    if (text !== this.costsText) {
      this.costsText = text;
      this.costs.textContent = text;
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
    const s = this.session;
    const a = await api.sessionAssessment(s.id, s.control_token, s.base || ''); // null: shown from the frame
    const next = await this.ui.nextTitle?.();
    const practice = this.practice ? `<p class="card-practice">Practice attempt (taken over at ${this.practice.t.toFixed(1)} s): not counted in your progress.</p>` : '';
    this.card.innerHTML = `${assessmentHtml(a, { title: this.spec.title, frame: ex })}${practice}
      <div class="card-actions">
        <button type="button" data-act="again">Try again</button>
        ${next ? `<button type="button" data-act="next">Next: ${esc(next)}</button>` : ''}
        <button type="button" data-act="choose">All exercises</button>
        <a class="card-debrief" data-act="debrief" hidden target="_blank" rel="noopener">Debrief ▶</a>
        <button type="button" data-act="close">Close</button>
      </div>`;
    this.card.hidden = false;
    this.card.querySelector('[data-act="again"]').addEventListener('click', () => { this.card.hidden = true; this.ui.tryAgain(); });
    this.card.querySelector('[data-act="next"]')?.addEventListener('click', () => { this.card.hidden = true; this.ui.next(); });
    this.card.querySelector('[data-act="choose"]').addEventListener('click', () => { this.card.hidden = true; this.ui.choose(); });
    this.card.querySelector('[data-act="close"]').addEventListener('click', () => { this.card.hidden = true; });
    // the reference operators' bands for this exercise (the trainee's progress carries them)
    api.sessionProgress(s.id, s.control_token, s.base || '').then((p) => {
      const bench = p?.exercises?.find((e) => e.exercise === this.spec.id)?.benchmark;
      const html = benchmarkHtml(a, bench);
      if (html && !this.card.hidden) this.card.querySelector('.card-actions')?.insertAdjacentHTML('beforebegin', html);
    });
    // the finished attempt: the session's newest (GET /api/sessions/{id} names its attempts,
    // newest first; a new one starts only with "try again")
    try {
      const r = await api.sessionSummary(s.id, s.control_token, s.base || '');
      const sum = r.ok ? await r.json() : null;
      const id = sum?.attempts?.[0] ?? sum?.attempt;
      const link = this.card.querySelector('[data-act="debrief"]');
      if (id && link) {
        link.href = api.links.debrief(id);
        link.hidden = false;
      }
    } catch { /* no link: the server cannot say which attempt */ }
  }

  /** After "try again" (the same session restarts the attempt). */
  restarted() {
    this.shownDone = false;
    // the last attempt's notice ("Done: …") does not carry into the new one
    if (this.lastEvent) this.ui.withdraw?.(this.lastEvent.text);
    this.lastEvent = null;
    this.step = -1;
    this.card.hidden = true;
  }
}
