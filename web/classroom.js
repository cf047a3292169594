// The instructor's classroom view (issue 16 item 4, docs/api.md): the roster of live trainees
// by name from the session summaries the dashboard polls (GET /api/sessions: trainee, group,
// exercise {title, step, steps_total, progress, score}, warnings, paused_by), each with its
// pause/resume and observe buttons; a trainee's attempt history (GET /api/attempts?trainee=)
// with links to the debrief page and the CSV; a comparison of the trainees on one exercise
// (GET /api/attempts?exercise=: best/last score, best time, strikes, posture from the
// assessments' metrics); and the class results export (GET /api/results.csv?group=).
// With a trainee's history, each exercise open or locked for them (progression,
// GET /api/unlocks) with a control to unlock it for them or lock it again.

import { describeWarning } from './status.js';
import { $, esc, fixed as f, note, LOCK_ICON } from './page.js';
import * as api from './api.js';

/** How often an open history and the comparison are refetched (ms). */
const REFRESH_MS = 5000;
/** Most attempts asked for at once. */
const LIMIT = 500;
const OUTCOMES = { passed: 'passed', failed: 'not passed', abandoned: 'abandoned', ended: 'ended', interrupted: 'interrupted' };

/** Seabed plus obstacle strikes of an attempt's assessment (null when it has none). */
function strikes(a) {
  const m = a.assessment;
  if (!m) return null;
  return (m.seabed_strikes ?? 0) + (m.obstacle_strikes ?? 0);
}

/** One label of a summary's `faults` (strings, or {label, silent} objects). */
export function faultText(x) {
  if (typeof x === 'string') return x;
  const label = x.label ?? x.fault ?? x.kind ?? JSON.stringify(x);
  return x.silent ? `${label} (silent)` : label;
}

/** The comparison of one exercise's attempts: one row per trainee (and group), by best score. */
export function compareRows(attempts) {
  const by = new Map();
  for (const a of attempts) { // newest first (the API's order)
    if (a.outcome !== 'passed' && a.outcome !== 'failed') continue; // finished exercise attempts only
    const key = `${a.trainee ?? ''}\u0000${a.group ?? ''}`;
    if (!by.has(key)) by.set(key, { trainee: a.trainee ?? '', group: a.group ?? '', list: [] });
    by.get(key).list.push(a);
  }
  const mean = (xs) => (xs.length ? xs.reduce((s, x) => s + x, 0) / xs.length : null);
  return [...by.values()].map(({ trainee, group, list }) => {
    const passed = list.filter((a) => a.outcome === 'passed');
    const times = passed.map((a) => a.assessment?.time_s ?? a.sim_seconds).filter(Number.isFinite);
    return {
      trainee, group, attempts: list.length, passed: passed.length,
      best: Math.max(...list.map((a) => a.score ?? 0)),
      last: list[0].score ?? null,
      bestTime: times.length ? Math.min(...times) : null,
      strikes: strikes(list[0]),
      meanW: mean(list.map((a) => a.assessment?.mean_yoshikawa).filter(Number.isFinite)),
      meanJlm: mean(list.map((a) => a.assessment?.mean_jlm).filter(Number.isFinite)),
    };
  }).sort((a, b) => b.best - a.best || a.trainee.localeCompare(b.trainee));
}

/** The benchmark's line under the Compare table: what the reference operators set, or why there
 * is none yet (docs/exercises.md "Benchmarks"). */
export function benchmarkLine(b) {
  if (!b) return '';
  if (!b.applies) {
    return `No benchmark yet: ${b.reference_attempts} finished attempt${b.reference_attempts === 1 ? '' : 's'} by reference operators, ${b.min_reference_attempts} needed — tick "reference" for experienced operators.`;
  }
  const req = b.measures.filter((m) => m.required && m.benchmark)
    .map((m) => `${esc(m.metric === 'score' ? 'score' : m.metric.replaceAll('_', ' '))} ${m.higher_is_better ? '≥' : '≤'} ${fmtNum(m.line)} (${fmtNum(m.benchmark.mean)} ± ${fmtNum(m.benchmark.sd)})`);
  return `Benchmark from ${b.reference_attempts} reference attempts (${fmtNum(b.k)} SD from their mean): ${req.join(', ')}.`;
}

/** The class ordered by proficiency: who needs the instructor first. */
const PROFICIENCY_ORDER = { relapsed: 0, practising: 1, proficient: 2, not_started: 3 };

/** A trainee's proficiency cell: the state, since which attempt, and the CUSUM's value. */
export function proficiencyText(c) {
  if (!c) return '—';
  const learning = c.cusum?.learning?.at(-1);
  const since = c.state === 'proficient' && c.proficient_at ? ` (attempt ${c.proficient_at})` : '';
  const chart = c.state === 'proficient' ? '' : ` <span class="k" title="learning CUSUM / its limit">${fmtNum(learning)}/${fmtNum(c.cusum?.limit)}</span>`;
  return `<span class="state" data-state="${esc(c.state)}">${esc(c.state.replace('_', ' '))}</span>${since}${chart}`;
}

const fmtNum = (x) => (Number.isFinite(x) ? x.toFixed(2) : '—');

export class Classroom {
  /**
   * @param ui {token() → the instructor token, observe(id), act(id, body) → Promise<{ok, error}>,
   *            observed() → the observed session id}
   */
  constructor(ui) {
    this.ui = ui;
    this.rows = new Map(); // session id → {tr, html}
    this.history = null; // {trainee, group}
    this.groups = new Set();
    $('roster').tBodies[0].addEventListener('click', (e) => this.onRosterClick(e));
    $('compare').tBodies[0].addEventListener('click', (e) => {
      if (e.target.matches('input.ref')) { this.markReference(e.target); return; }
      const n = e.target.closest('[data-trainee]');
      if (n) this.showHistory(n.dataset.trainee, n.dataset.group);
    });
    $('unlocks').tBodies[0].addEventListener('click', (e) => {
      const b = e.target.closest('button[data-unlock]');
      if (b) this.setUnlock(b);
    });
    $('hist-close').addEventListener('click', () => { this.history = null; $('cls-history').hidden = true; });
    this.cmpPicked = false; // until the instructor picks, the comparison follows the roster's exercise
    $('cmp-exercise').addEventListener('change', () => { this.cmpPicked = true; this.refreshCompare(); });
    $('cmp-order').addEventListener('change', () => this.refreshCompare());
    $('cls-group').addEventListener('change', () => { this.exportLink(); this.refreshCompare(); this.render(this.sessions || []); });
    this.exportLink();
    this.loadExercises();
    this.timer = setInterval(() => { if (this.visible) { this.refreshHistory(); this.refreshCompare(); } }, REFRESH_MS);
  }

  get group() { return $('cls-group').value.trim(); }

  /** GET /api/attempts with `filter` (and `group`, when given); the list, or null
   * (the error shown) when the server refuses or cannot be reached. */
  async attempts(filter, group) {
    try {
      return await api.attempts({ ...filter, limit: String(LIMIT), ...(group ? { group } : {}) }, this.ui.token());
    } catch (e) {
      this.setStatus(`attempts: ${e.message}`, true);
      return null;
    }
  }

  setStatus(text, bad = false) {
    note($('cls-status'), text, bad);
  }

  /** The tab was shown or hidden. */
  show(v) {
    this.visible = v;
    $('classroom').hidden = !v;
    if (v) { this.exportLink(); this.refreshCompare(); this.refreshHistory(); }
  }

  exportLink() {
    $('cls-export').href = api.links.resultsCsv(this.group);
  }

  async loadExercises() {
    const list = await api.exercises(); // none: an empty comparison
    $('cmp-exercise').innerHTML = list.map((e) => `<option value="${esc(e.id)}">${esc(e.title)}</option>`).join('');
  }

  /** The polled session summaries (GET /api/sessions). */
  render(sessions) {
    this.sessions = sessions;
    const tb = $('roster').tBodies[0];
    const group = this.group;
    const live = sessions.filter((s) => (s.status || 'live') === 'live' && (!group || s.group === group));
    for (const s of sessions) if (s.group) this.groups.add(s.group);
    $('cls-groups').innerHTML = [...this.groups].sort().map((g) => `<option value="${esc(g)}">`).join('');
    const seen = new Set();
    let prev = null;
    for (const s of live.sort((a, b) => (a.trainee ?? a.label ?? '').localeCompare(b.trainee ?? b.label ?? ''))) {
      seen.add(s.id);
      let row = this.rows.get(s.id);
      if (!row) {
        const tr = document.createElement('tr');
        tr.dataset.id = s.id;
        row = { tr, html: '' };
        this.rows.set(s.id, row);
      }
      const html = this.rowHtml(s);
      if (html !== row.html) { // only a changed row is rebuilt (its buttons stay put)
        row.tr.innerHTML = html;
        row.html = html;
        const fill = row.tr.querySelector('.cls-fill');
        if (fill) fill.style.width = `${fill.dataset.w}%`;
      }
      row.tr.className = s.id === this.ui.observed() ? 'open' : '';
      row.tr.dataset.paused = s.paused_by || (s.paused ? 'trainee' : '');
      if (row.tr.previousElementSibling !== prev || row.tr.parentNode !== tb) (prev ? prev.after(row.tr) : tb.prepend(row.tr));
      prev = row.tr;
    }
    for (const [id, row] of this.rows) if (!seen.has(id)) { row.tr.remove(); this.rows.delete(id); }
    const sel = $('cmp-exercise');
    const onEx = live.find((s) => s.exercise?.id && [...sel.options].some((o) => o.value === s.exercise.id));
    if (!this.cmpPicked && onEx && sel.value !== onEx.exercise.id) {
      sel.value = onEx.exercise.id;
      if (this.visible) this.refreshCompare();
    }
    let empty = tb.querySelector('tr.empty');
    if (!live.length && !empty) {
      empty = document.createElement('tr');
      empty.className = 'empty';
      empty.innerHTML = '<td colspan="9">no live trainees</td>';
      tb.append(empty);
    } else if (live.length && empty) empty.remove();
  }

  rowHtml(s) {
    const name = s.trainee || s.label || '(no name)';
    const ex = s.exercise;
    const total = ex?.steps_total ?? 0;
    const step = ex ? `${Math.min(total, (ex.step ?? 0) + (ex.status === 'running' || ex.status === undefined ? 1 : 0))}/${total}` : '';
    const pct = ex ? Math.round(100 * Math.max(0, Math.min(1, ex.progress ?? 0))) : 0;
    const warn = [...(s.warnings || []).map(describeWarning), ...(s.faults || []).map(faultText)];
    if (s.recording === 'failed') warn.unshift('recording failed');
    const paused = s.awaiting_ready ? 'waiting for Ready' : s.paused_by ? `by ${s.paused_by}` : s.paused ? 'yes' : '';
    const byInstructor = s.paused && s.paused_by === 'instructor';
    return `<td class="cls-name"><button type="button" class="link" data-history="${esc(name)}" data-group="${esc(s.group ?? '')}" title="attempt history">${esc(name)}</button></td>
      <td>${esc(s.group ?? '')}</td>
      <td>${ex ? `${esc(ex.title ?? ex.id)}${ex.status && ex.status !== 'running' ? ` <span class="out-${esc(ex.status)}">· ${esc(OUTCOMES[ex.status] ?? ex.status)}</span>` : ''}`
    : `<span class="dim">${esc(s.scenario ?? '')}</span>`}</td>
      <td>${step}</td>
      <td>${ex ? `<span class="cls-bar-o" title="${pct} %"><span class="cls-fill" data-w="${pct}"></span></span>` : ''}</td>
      <td class="num">${ex && Number.isFinite(ex.score) ? Math.round(ex.score) : ''}</td>
      <td class="warn">${esc(warn.join(', '))}</td>
      <td class="${byInstructor ? 'paused-instr' : ''}">${esc(paused)}</td>
      <td class="cls-acts"><button type="button" data-act="${byInstructor ? 'resume' : 'pause'}">${byInstructor ? 'Resume' : 'Pause'}</button>
        <button type="button" data-observe="${esc(s.id)}">${s.id === this.ui.observed() ? 'Observing' : 'Observe'}</button></td>`;
  }

  async onRosterClick(e) {
    const tr = e.target.closest('tr[data-id]');
    if (!tr) return;
    const b = e.target.closest('button');
    if (!b) return;
    if (b.dataset.observe) { this.ui.observe(b.dataset.observe); return; }
    if (b.dataset.history !== undefined) { this.showHistory(b.dataset.history, b.dataset.group); return; }
    if (b.dataset.act) {
      b.disabled = true;
      const r = await this.ui.act(tr.dataset.id, { type: b.dataset.act });
      this.setStatus(r.ok ? `${b.dataset.act}: ok` : `${b.dataset.act}: ${r.error}`, !r.ok);
      b.disabled = false;
    }
  }

  showHistory(trainee, group) {
    this.history = { trainee, group: group || '' };
    $('hist-name').textContent = group ? `${trainee} (${group})` : trainee;
    $('hist-logbook').href = api.links.logbook(trainee, group);
    $('cls-history').hidden = false;
    $('history').tBodies[0].innerHTML = '<tr><td colspan="7">loading…</td></tr>';
    $('unl-name').textContent = trainee;
    $('unlocks').tBodies[0].innerHTML = '';
    this.refreshHistory();
  }

  /** The trainee's exercises as open or locked (GET /api/unlocks), each with its control. */
  async refreshUnlocks(h) {
    let u;
    try {
      u = await api.unlocks(h.trainee, h.group, this.ui.token());
    } catch (e) {
      this.setStatus(`unlocks: ${e.message}`, true);
      return;
    }
    if (this.history === h) this.showUnlocks(u);
  }

  showUnlocks(u) {
    $('unl-off').hidden = u.progression !== false;
    const titles = new Map([...$('cmp-exercise').options].map((o) => [o.value, o.textContent]));
    const name = (id) => titles.get(id) || id;
    $('unlocks').tBodies[0].innerHTML = u.exercises.map((l) => {
      const needs = l.requires.length ? l.requires.map((id) => {
        const m = l.missing.find((x) => x.exercise === id);
        return `${esc(name(id))}${m ? ` <span class="dim">(${esc(m.state.replace('_', ' '))})</span>` : ' ✓'}`;
      }).join(', ') : '—';
      const status = { open: 'open', locked: `${LOCK_ICON} locked`, unlocked: 'unlocked by instructor' }[l.status] || esc(l.status);
      const act = l.status === 'locked' ? ['1', 'Unlock'] : l.unlocked_unix ? ['0', 'Lock again'] : null;
      return `<tr data-exercise="${esc(l.exercise)}" data-status="${esc(l.status)}"><td>${esc(name(l.exercise))}</td><td>${needs}</td><td>${status}</td>
        <td>${act ? `<button type="button" data-unlock="${act[0]}" data-exercise="${esc(l.exercise)}">${act[1]}</button>` : ''}</td></tr>`;
    }).join('');
  }

  /** The instructor unlocks an exercise for the trainee of the open history, or locks it again. */
  async setUnlock(b) {
    const h = this.history;
    if (!h) return;
    b.disabled = true;
    try {
      const u = await api.unlocks(h.trainee, h.group, this.ui.token(), b.dataset.exercise, b.dataset.unlock === '1');
      this.setStatus(`${b.dataset.exercise} ${b.dataset.unlock === '1' ? 'unlocked' : 'locked again'} for ${h.trainee}`);
      if (this.history === h) this.showUnlocks(u);
    } catch (e) {
      this.setStatus(`unlock: ${e.message}`, true);
      b.disabled = false;
    }
  }

  async refreshHistory() {
    const h = this.history;
    if (!h) return;
    if (h.trainee) this.refreshUnlocks(h);
    const list = await this.attempts({ trainee: h.trainee }, h.group);
    if (!list || this.history !== h) return;
    $('history').tBodies[0].innerHTML = list.map((a) => {
      const when = a.started_unix ? new Date(a.started_unix * 1000).toLocaleString() : '';
      const replay = a.links?.replay || api.links.debrief(a.id);
      const csv = a.links?.csv;
      return `<tr data-attempt="${esc(a.id)}" data-outcome="${esc(a.outcome ?? '')}"><td>${esc(when)}</td><td>${esc(a.exercise ?? a.scenario ?? '')}</td>
        <td class="out-${esc(a.outcome ?? 'running')}">${esc(OUTCOMES[a.outcome] ?? 'running')}</td>
        <td class="num">${a.score === null || a.score === undefined ? '' : Math.round(a.score)}</td><td class="num">${f(a.sim_seconds)}</td>
        <td class="num">${strikes(a) ?? ''}</td>
        <td><a class="debrief" href="${esc(replay)}" target="_blank" rel="noopener"${a.replayable === false ? ` title="${esc(a.replay_note ?? 'not replayable')}"` : ''}>debrief</a>
          ${csv ? `<a href="${esc(csv)}" download>CSV</a>` : ''}</td></tr>`;
    }).join('') || '<tr><td colspan="7">no attempts yet</td></tr>';
  }

  /** The instructor ticks or unticks a trainee as a reference operator; the benchmark follows. */
  async markReference(box) {
    try {
      await api.markReference(box.dataset.trainee, box.dataset.group, box.checked, this.ui.token());
      this.setStatus(`${box.dataset.trainee || '(no name)'} ${box.checked ? 'is' : 'is no longer'} a reference operator`);
    } catch (e) {
      box.checked = !box.checked;
      this.setStatus(`reference operator: ${e.message}`, true);
    }
    this.refreshCompare();
  }

  async refreshCompare() {
    const ex = $('cmp-exercise').value;
    if (!ex || !this.ui.token()) return;
    const [list, progress, refs] = await Promise.all([
      this.attempts({ exercise: ex }, this.group),
      api.classProgress(ex, this.group, this.ui.token()).catch((e) => { this.setStatus(`progress: ${e.message}`, true); return null; }),
      api.referenceOperators(this.ui.token()).catch(() => []),
    ]);
    const isRef = new Set(refs.map((r) => `${r.trainee}\u0000${r.group}`));
    $('cmp-bench').innerHTML = benchmarkLine(progress?.benchmark);
    if (!list || $('cmp-exercise').value !== ex) return;
    for (const a of list) if (a.group) this.groups.add(a.group);
    // each trainee's proficiency (the server's CUSUM, docs/exercises.md), by trainee and group
    const state = new Map((progress?.trainees || []).map((c) => [`${c.trainee}\u0000${c.group}`, c]));
    const rows = compareRows(list).map((r) => ({ ...r, progress: state.get(`${r.trainee}\u0000${r.group}`) }));
    if ($('cmp-order').value === 'proficiency') {
      rows.sort((a, b) => (PROFICIENCY_ORDER[a.progress?.state] ?? 9) - (PROFICIENCY_ORDER[b.progress?.state] ?? 9) || b.best - a.best);
    }
    $('compare').tBodies[0].innerHTML = rows.map((r) => `<tr data-trainee="${esc(r.trainee)}" data-group="${esc(r.group)}" data-state="${esc(r.progress?.state ?? '')}">
        <td><button type="button" class="link" data-trainee="${esc(r.trainee)}" data-group="${esc(r.group)}">${esc(r.trainee || '(no name)')}</button></td>
        <td>${esc(r.group)}</td><td class="prof">${proficiencyText(r.progress)}</td><td class="num">${r.attempts}</td><td class="num">${r.passed}</td>
        <td class="num">${Math.round(r.best)}</td><td class="num">${r.last === null ? '—' : Math.round(r.last)}</td>
        <td class="num">${f(r.bestTime)}</td><td class="num">${r.strikes ?? '—'}</td><td class="num">${f(r.meanW, 3)}</td><td class="num">${f(r.meanJlm, 3)}</td>
        <td><input type="checkbox" class="ref" aria-label="reference operator" data-trainee="${esc(r.trainee)}" data-group="${esc(r.group)}"${isRef.has(`${r.trainee}\u0000${r.group}`) ? ' checked' : ''}${r.trainee ? '' : ' disabled'}></td></tr>`).join('')
      || '<tr><td colspan="12">no finished attempts at this exercise</td></tr>';
  }
}
