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

  /** Shows the screen; resolves with the trainee's choice. `selected`: exercise id to preselect. */
  async choose(selected) {
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
          <span class="ex-skills">${e.skills.map((s) => `<span>${esc(s)}</span>`).join('')}</span></label></li>`).join('')}
      </ul>
      ${this.exercises.length ? '' : '<p class="ex-none">No exercises on this server: free play only.</p>'}
      <div class="start-actions">
        <button type="submit" id="start-exercise" ${this.exercises.length ? '' : 'disabled'}>Start exercise</button>
        <button type="button" id="start-free">Free play</button>
      </div>
    </form>`;
    el.hidden = false;
    this.note = null;
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
    });
  }
}
