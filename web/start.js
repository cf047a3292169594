// The start screen: the trainee's name (required) and class/group (optional), both
// remembered in this browser, the exercises with their goals (GET /api/exercises,
// docs/exercises.md) and free play. Resolves with the body of POST /api/sessions:
// {exercise, trainee, group?} or {scenario: 'training', trainee, group?}.

import { esc } from './page.js';
import { exercises } from './api.js';

const NAME_KEY = 'seaarms.trainee';
const GROUP_KEY = 'seaarms.group';
/** Longest display name and group sent (the server accepts up to 64 characters). */
const MAX_NAME_CHARS = 40;

/** What each proficiency state says to the trainee. */
const STATE_TEXT = {
  practising: 'practising', proficient: 'proficient', relapsed: 'proficient before: practise again',
};

/** A learning curve: each finished attempt's score (0–100) left to right, passes filled,
 * failures hollow, the points that made the trainee proficient ringed. SVG, no inline style
 * (the page's CSP). */
export function curveSvg(c, width = 220, height = 40) {
  const n = c.attempts.length;
  const x = (i) => (n === 1 ? width / 2 : 6 + ((width - 12) * i) / (n - 1));
  const y = (s) => height - 4 - ((height - 8) * Math.max(0, Math.min(100, s))) / 100;
  const line = c.attempts.map((a, i) => `${i ? 'L' : 'M'}${x(i).toFixed(1)},${y(a.score).toFixed(1)}`).join(' ');
  const dots = c.attempts.map((a, i) => `<circle class="${a.passed ? 'pass' : 'fail'}" cx="${x(i).toFixed(1)}" cy="${y(a.score).toFixed(1)}" r="2.5"/>`).join('');
  const rings = (c.cusum?.proficient_at || []).map((k) => `<circle class="at" cx="${x(k - 1).toFixed(1)}" cy="${y(c.attempts[k - 1].score).toFixed(1)}" r="5"/>`).join('');
  return `<svg class="curve" viewBox="0 0 ${width} ${height}" width="${width}" height="${height}" role="img"
    aria-label="scores of ${n} attempts"><path d="${line}"/>${dots}${rings}</svg>`;
}

/** Fills each exercise's curve and state from GET /api/sessions/{id}/progress. */
function showCurves(el, p) {
  for (const c of p.exercises || []) {
    const slot = el.querySelector(`[data-progress="${CSS.escape(c.exercise)}"]`);
    if (!slot || !c.attempts.length) continue;
    const last = c.attempts[c.attempts.length - 1];
    const since = c.state === 'proficient' && c.proficient_at ? ` since attempt ${c.proficient_at}` : '';
    slot.innerHTML = `${curveSvg(c)}<span class="ex-state" data-state="${esc(c.state)}">${esc(STATE_TEXT[c.state] || c.state)}${since}</span>
      <span class="ex-last">${c.attempts.length} attempt${c.attempts.length === 1 ? '' : 's'}, last ${Math.round(last.score)}</span>`;
    slot.hidden = false;
  }
}

export class StartScreen {
  constructor(el) {
    this.el = el;
    this.exercises = [];
    this.note = null; // e.g. why the previous session ended, shown on the card once
  }

  /** The exercise after `id` in the server's list (wrapping), for "next exercise". */
  next(id) {
    const i = this.exercises.findIndex((e) => e.id === id);
    const n = this.exercises.length ? this.exercises[(i + 1) % this.exercises.length] : null;
    return n && n.id !== id ? n : null;
  }

  /** Shows the screen; resolves with the trainee's choice. `selected`: exercise id to preselect;
   * `progress`: loads the trainee's learning curves (GET /api/sessions/{id}/progress), each
   * drawn under its exercise; `back`: offer "Back to my session" (resolves null). */
  async choose(selected, progress = null, back = false) {
    this.exercises = await exercises();
    const name = localStorage.getItem(NAME_KEY) || '';
    const group = localStorage.getItem(GROUP_KEY) || '';
    const el = this.el;
    el.innerHTML = `<form class="start-card" novalidate>
      <h2>seaarms training</h2>
      ${this.note ? `<p class="start-note">${esc(this.note)}</p>` : ''}
      <div class="start-who">
        <label class="start-name">Your name <input id="start-name" name="trainee" maxlength="${MAX_NAME_CHARS}" required
          autocomplete="nickname" spellcheck="false" value="${esc(name)}" placeholder="shown to your instructor"></label>
        <label class="start-name">Class / group <input id="start-group" name="group" maxlength="${MAX_NAME_CHARS}"
          autocomplete="off" spellcheck="false" value="${esc(group)}" placeholder="optional"></label>
      </div>
      <p class="start-need" id="start-need" hidden>Type your name first: your instructor finds you by it.</p>
      <h3>Choose an exercise</h3>
      <ul class="ex-list">${this.exercises.map((e) => `
        <li><label class="ex" data-id="${esc(e.id)}"><input type="radio" name="exercise" value="${esc(e.id)}"${e.id === selected ? ' checked' : ''}>
          <span class="ex-title">${esc(e.title)}</span>
          <span class="ex-meta">${e.steps.length} steps · ${Math.round(e.time_limit_s)} s limit · ${esc(e.control.mode)}${e.control.method === 'closed' ? ', closed loop' : ''}</span>
          <span class="ex-goal">${esc(e.goal)}</span>
          <span class="ex-skills">${e.skills.map((s) => `<span>${esc(s)}</span>`).join('')}</span>
          <span class="ex-progress" data-progress="${esc(e.id)}" hidden></span></label></li>`).join('')}
      </ul>
      ${this.exercises.length ? '' : '<p class="ex-none">No exercises on this server: free play only.</p>'}
      <div class="start-actions">
        <button type="submit" id="start-exercise" ${this.exercises.length ? '' : 'disabled'}>Start exercise</button>
        <button type="button" id="start-free">Free play</button>
        ${back ? '<button type="button" id="start-back">Back to my session</button>' : ''}
      </div>
    </form>`;
    el.hidden = false;
    this.note = null;
    if (progress) progress().then((p) => { if (p && el.contains(form)) showCurves(el, p); });
    const form = el.querySelector('form');
    const start = el.querySelector('#start-exercise');
    const picked = () => form.querySelector('input[name=exercise]:checked')?.value;
    start.disabled = !picked();
    form.addEventListener('change', () => { start.disabled = !picked(); });
    return new Promise((resolve) => {
      const nameField = el.querySelector('#start-name');
      const done = (choice) => {
        const trainee = nameField.value.trim().slice(0, MAX_NAME_CHARS);
        const grp = el.querySelector('#start-group').value.trim().slice(0, MAX_NAME_CHARS);
        if (!trainee) { // the name is required (a blank of spaces passes `required`)
          el.querySelector('#start-need').hidden = false;
          nameField.value = '';
          nameField.focus();
          return;
        }
        localStorage.setItem(NAME_KEY, trainee);
        localStorage.setItem(GROUP_KEY, grp);
        el.hidden = true;
        el.replaceChildren();
        resolve(grp ? { ...choice, trainee, group: grp } : { ...choice, trainee });
      };
      form.addEventListener('submit', (e) => {
        e.preventDefault();
        if (picked()) done({ exercise: picked() });
      });
      el.querySelector('#start-free').addEventListener('click', () => done({ scenario: 'training' }));
      el.querySelector('#start-back')?.addEventListener('click', () => { el.hidden = true; el.replaceChildren(); resolve(null); });
    });
  }
}
