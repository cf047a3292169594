// The debrief's second attempt (issue 30 item 5): choose one of the trainee's other finished
// attempts at the same exercise, or the reference operators' best (GET
// /api/sessions/{id}/ghosts) — it is drawn as the ghost on the replay's clock (web/ghost.js)
// and a table sets the two side by side: the score, the time and each scoring term of the
// exercise, for A (this attempt) and B (the chosen one), the difference B − A and which is
// better (a term is better low when its `good` value is below its `bad` one, as the score
// counts it; docs/exercises.md). Labels are the completion card's (web/assessment.js).

import { metricLabel } from './assessment.js';
import { esc, num } from './page.js';
import { sessionGhosts, attemptTrack } from './api.js';
import { Ghost, choiceLabel } from './ghost.js';

/** The rows compared: [key, label, value of an assessment, lower is better]. */
function rows(a, b) {
  const out = [['score', 'score', (x) => x?.score, false], ['time_s', metricLabel('time_s'), (x) => x?.time_s, true]];
  const seen = new Set(['time_s']);
  for (const t of [...(a?.terms || []), ...(b?.terms || [])]) {
    if (seen.has(t.metric)) continue;
    seen.add(t.metric);
    const value = (x) => (x?.terms || []).find((u) => u.metric === t.metric)?.value;
    out.push([t.metric, metricLabel(t.metric), value, t.good < t.bad]);
  }
  return out;
}

/**
 * The side-by-side table of two assessments.
 * @param a this attempt's assessment, b the other's (GET /api/attempts/{id} `assessment`)
 * @param names {a, b}: the columns' headings
 */
export function compareHtml(a, b, names = { a: 'A (this)', b: 'B' }) {
  const body = rows(a, b).map(([key, label, value, lowerBetter]) => {
    const va = value(a), vb = value(b);
    const both = Number.isFinite(va) && Number.isFinite(vb);
    const d = both ? vb - va : null;
    const better = !both || d === 0 ? '=' : (d < 0) === lowerBetter ? 'B' : 'A';
    return `<tr data-metric="${esc(key)}" data-a="${Number.isFinite(va) ? va : ''}" data-b="${Number.isFinite(vb) ? vb : ''}" data-diff="${both ? d : ''}" data-better="${both ? better : ''}">
      <td>${esc(label)}</td><td>${Number.isFinite(va) ? num(va) : '—'}</td><td>${Number.isFinite(vb) ? num(vb) : '—'}</td>
      <td>${both ? `${d > 0 ? '+' : ''}${num(d)}` : '—'}</td><td>${both ? better : ''}</td></tr>`;
  });
  return `<table class="card-compare"><tr><th>measure</th><th>${esc(names.a)}</th><th>${esc(names.b)}</th><th>B − A</th><th>better</th></tr>${body.join('')}</table>`;
}

/**
 * Mounts the chooser and the table in the debrief for attempt `attempt` (GET /api/attempts/{id}).
 * @param view the debrief's View
 * @param select the <select> to fill, table the element for the table
 * @param token the page's `?token=` ('' when the cookies open it)
 */
export async function mountCompare({ view, select, table, attempt, token }) {
  const ghost = new Ghost(view);
  const state = { ghost, choices: null, chosen: null };
  if (!attempt.exercise) return state;
  const g = await sessionGhosts(attempt.session, attempt.exercise, token);
  state.choices = g;
  if (!g) { select.disabled = true; return state; }
  const options = [['none', 'none']];
  if (g.reference) options.push([g.reference.attempt, choiceLabel('reference', g.reference)]);
  for (const c of g.attempts) {
    if (c.attempt === attempt.id) continue;
    const when = new Date(c.started_unix * 1000).toLocaleString();
    options.push([c.attempt, `${c.attempt === g.best?.attempt ? 'my best — ' : ''}${when}, score ${Math.round(c.score)}`]);
  }
  select.replaceChildren(...options.map(([v, l]) => new Option(l, v)));
  select.disabled = options.length < 2;
  const candidates = [g.reference, ...g.attempts].filter(Boolean);
  select.addEventListener('change', async () => {
    const id = select.value;
    const c = candidates.find((x) => x.attempt === id) || null;
    state.chosen = c;
    select.blur();
    if (!c) { ghost.clear(); table.innerHTML = ''; return; }
    const b = c === g.reference ? 'B (reference)' : 'B (other)';
    table.innerHTML = compareHtml(attempt.assessment, c.assessment, { a: 'A (this)', b });
    const track = await attemptTrack(c.attempt, attempt.session, token);
    if (select.value !== id) return;
    if (track) ghost.show(track); else ghost.clear();
  });
  return state;
}
