// The start screen: the trainee's name (required) and class/group (optional), both
// remembered in this browser, the exercises with their goals (GET /api/exercises,
// docs/exercises.md) and free play. Resolves with the body of POST /api/sessions:
// {exercise, trainee, group?} or {scenario: 'training', trainee, group?}.
//
// Progression (docs/exercises.md "Progression"): an exercise whose `requires` the trainee has
// not met is shown with a lock and the reason, and cannot be chosen. With a session, the
// trainee's own locks come with their progress (GET /api/sessions/{id}/progress `locks`); a
// new browser has no session yet, so every exercise with requirements is shown locked until
// the trainee has started one (the server keeps no public lookup of a trainee by name).

import { esc, LOCK_ICON } from './page.js';
import { catalogue } from './api.js';

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

/** How a required exercise's state reads in a lock's reason. */
const NEED_STATE = { not_started: 'not started yet', practising: 'practising', proficient: 'proficient', relapsed: 'relapsed' };

/** The locks a new browser assumes (no record known): each exercise with requirements is
 * locked while the server's progression is on. */
export function catalogueLocks(list, progression) {
  return new Map(list.map((e) => [e.id, {
    exercise: e.id,
    status: progression && e.requires?.length ? 'locked' : 'open',
    missing: (progression && e.requires) ? e.requires.map((id) => ({ exercise: id, state: null })) : [],
  }]));
}

/** Why an exercise is locked (or that the instructor opened it), in words. */
export function lockText(lock, titles) {
  if (lock?.status === 'unlocked') return 'unlocked by your instructor';
  if (lock?.status !== 'locked') return '';
  const needs = lock.missing.map((m) => `${titles.get(m.exercise) || m.exercise}${m.state ? ` (you: ${NEED_STATE[m.state] || m.state})` : ''}`);
  return `needs: proficiency in ${needs.join(' and ')}`;
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
    this.locks = new Map(); // exercise id → {status: open | locked | unlocked, missing}
    this.note = null; // e.g. why the previous session ended, shown on the card once
  }

  /** Takes the trainee's locks from their progress (GET /api/sessions/{id}/progress). */
  setLocks(p) {
    if (p?.locks) this.locks = new Map(p.locks.map((l) => [l.exercise, l]));
  }

  /** The first exercise after `id` in the server's list (wrapping) that is open to the
   * trainee, for "next exercise"; null when none is. */
  next(id) {
    const n = this.exercises.length;
    const i = this.exercises.findIndex((e) => e.id === id);
    for (let k = 1; k < n; k++) {
      const e = this.exercises[(i + k + n) % n];
      if (e.id !== id && this.locks.get(e.id)?.status !== 'locked') return e;
    }
    return null;
  }

  /** Shows each exercise's lock on the screen `el`: a locked one cannot be chosen. */
  showLocks(el) {
    const titles = new Map(this.exercises.map((e) => [e.id, e.title]));
    let locked = 0;
    for (const label of el.querySelectorAll('label.ex')) {
      const lock = this.locks.get(label.dataset.id);
      const input = label.querySelector('input');
      const isLocked = lock?.status === 'locked';
      locked += isLocked ? 1 : 0;
      label.classList.toggle('locked', isLocked);
      label.dataset.lock = lock?.status || 'open';
      input.disabled = isLocked;
      if (isLocked) input.checked = false;
      const why = label.querySelector('.ex-lock');
      const text = lockText(lock, titles);
      why.innerHTML = text ? `${isLocked ? LOCK_ICON : ''} ${esc(text)}` : '';
      why.hidden = !text;
    }
    const hint = el.querySelector('#start-locked');
    if (hint) hint.hidden = !locked;
    el.querySelector('form')?.dispatchEvent(new Event('change'));
  }

  /** Shows the screen; resolves with the trainee's choice. `selected`: exercise id to preselect;
   * `progress`: loads the trainee's learning curves (GET /api/sessions/{id}/progress), each
   * drawn under its exercise; `back`: offer "Back to my session" (resolves null). */
  async choose(selected, progress = null, back = false) {
    const cat = await catalogue();
    this.exercises = cat.exercises || [];
    this.locks = catalogueLocks(this.exercises, cat.progression !== false);
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
          <span class="ex-lock" hidden></span>
          <span class="ex-meta">${e.steps.length} steps · ${Math.round(e.time_limit_s)} s limit · ${esc(e.control.mode)}${e.control.method === 'closed' ? ', closed loop' : ''}</span>
          <span class="ex-goal">${esc(e.goal)}</span>
          <span class="ex-skills">${e.skills.map((s) => `<span>${esc(s)}</span>`).join('')}</span>
          <span class="ex-progress" data-progress="${esc(e.id)}" hidden></span></label></li>`).join('')}
      </ul>
      <p class="start-locked" id="start-locked" hidden>${LOCK_ICON} An exercise opens once you are proficient in the ones it needs${progress ? '' : ' (returning? start an open exercise: your record then opens the rest)'}; your instructor can also unlock one for you.</p>
      ${this.exercises.length ? '' : '<p class="ex-none">No exercises on this server: free play only.</p>'}
      <div class="start-actions">
        <button type="submit" id="start-exercise" ${this.exercises.length ? '' : 'disabled'}>Start exercise</button>
        <button type="button" id="start-free">Free play</button>
        ${back ? '<button type="button" id="start-back">Back to my session</button>' : ''}
      </div>
    </form>`;
    el.hidden = false;
    this.note = null;
    const form = el.querySelector('form');
    this.showLocks(el);
    if (progress) {
      progress().then((p) => {
        if (!p || !el.contains(form)) return;
        showCurves(el, p);
        this.setLocks(p);
        this.showLocks(el);
      });
    }
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
