// The printable logbook page (/logbook?trainee=&group=): a trainee's exercises — dates,
// attempts, passes, best and last scores, proficiency and the date it was reached, the
// instructor's sign-off — from GET /api/logbook, opened with the instructor's sign-in cookie
// (no token in the URL). Each exercise has a sign-off (or revoke) button; "Print" prints the
// page with the print stylesheet (no toolbar, black on white). Wire: docs/api.md "Logbook".

import * as api from './api.js';

const $ = (id) => document.getElementById(id);
const esc = (s) => String(s ?? '').replace(/[&<>"']/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;', "'": '&#39;' })[c]);

/** A Unix time as an ISO 8601 UTC date and minute ("2023-11-14 22:13"), or ''. */
export function utc(unix) {
  if (unix === null || unix === undefined) return '';
  return new Date(unix * 1000).toISOString().slice(0, 16).replace('T', ' ');
}

const STATES = { not_started: 'not started', practising: 'practising', proficient: 'proficient', relapsed: 'relapsed' };
const score = (x) => (x === null || x === undefined ? '' : String(Math.round(x)));

/** One exercise's row. */
export function rowHtml(e) {
  const prof = e.proficient_at
    ? `${STATES[e.state] ?? e.state} <small>since attempt ${e.proficient_at}, ${esc(utc(e.proficient_unix))}${e.by === 'benchmark' ? ' (benchmark)' : ''}</small>`
    : esc(STATES[e.state] ?? e.state);
  const s = e.signoff;
  const signed = s
    ? `${esc(utc(s.signed_unix))} by <span class="lb-assessor">${esc(s.assessor)}</span>${s.note ? `<br><small>${esc(s.note)}</small>` : ''}`
    : '';
  const act = s
    ? `<button type="button" data-revoke="${esc(e.exercise)}">Revoke</button>`
    : `<button type="button" data-sign="${esc(e.exercise)}">Sign off</button>`;
  return `<tr data-exercise="${esc(e.exercise)}" class="lb-${esc(e.state)}"><td>${esc(e.title)}</td>
    <td>${esc(utc(e.first_unix))}</td><td>${esc(utc(e.last_unix))}</td>
    <td class="num">${e.finished} / ${e.attempts}</td><td class="num">${e.passes}</td>
    <td class="num">${score(e.best_score)}</td><td class="num">${score(e.last_score)}</td>
    <td>${prof}</td><td class="lb-signoff">${signed}</td><td class="lb-act">${act}</td></tr>`;
}

class Logbook {
  constructor() {
    const q = new URLSearchParams(location.search);
    this.trainee = q.get('trainee') || '';
    this.group = q.get('group') || '';
    $('lb-name').textContent = this.group ? `${this.trainee} (${this.group})` : this.trainee;
    $('lb-csv').href = api.links.logbookCsv(this.trainee, this.group);
    $('lb-assessor').value = localStorage.getItem('seaarms.assessor') || '';
    $('lb-print').addEventListener('click', () => window.print());
    $('lb-table').addEventListener('click', (ev) => this.click(ev));
  }

  status(text, bad = false) {
    $('lb-status').textContent = text;
    $('lb-status').classList.toggle('bad', bad);
  }

  async load() {
    try {
      const book = await api.logbook(this.trainee, this.group);
      this.book = book;
      $('lb-meta').textContent = `Group: ${book.group || '(none)'} · generated ${utc(book.generated_unix)} UTC`;
      $('lb-table').tBodies[0].innerHTML = book.exercises.map(rowHtml).join('');
      window.__seaarmsLogbook = book;
    } catch (e) {
      this.status(`${e.message}${/token/.test(e.message) ? ' — sign in on the instructor page first' : ''}`, true);
    }
  }

  async click(ev) {
    const b = ev.target.closest('button');
    if (!b) return;
    b.disabled = true;
    try {
      if (b.dataset.sign) {
        const assessor = $('lb-assessor').value.trim();
        if (!assessor) { this.status('type the assessor\'s name first', true); $('lb-assessor').focus(); return; }
        localStorage.setItem('seaarms.assessor', assessor);
        await api.signOff({ trainee: this.trainee, group: this.group, exercise: b.dataset.sign, assessor, note: $('lb-note').value }, undefined);
        this.status(`signed off: ${b.dataset.sign}`);
      } else if (b.dataset.revoke) {
        await api.revokeSignoff(this.trainee, this.group, b.dataset.revoke, undefined);
        this.status(`sign-off revoked: ${b.dataset.revoke}`);
      }
      await this.load();
    } catch (e) {
      this.status(e.message, true);
    } finally {
      b.disabled = false;
    }
  }
}

if (typeof document !== 'undefined') new Logbook().load();
