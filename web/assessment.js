// The assessment card of an exercise attempt (docs/exercises.md "The assessment"): verdict,
// score, time and steps, why it did not pass, each scoring term and each pass limit against
// the attempt's value. Shared by the trainee's completion card (web/task.js) and the debrief
// page (web/replay.js). Every number is the server's.

import { esc, num } from './page.js';

/** "metric_name_unit" → "metric name (unit)". */
export function metricLabel(m) {
  const units = { _s: 's', _n: 'N', _m: 'm', _m_s3: 'm/s³', _deg: '°', _nm: 'N·m' };
  for (const [suffix, unit] of Object.entries(units).sort((a, b) => b[0].length - a[0].length)) {
    if (m.endsWith(suffix)) return `${m.slice(0, -suffix.length).replaceAll('_', ' ')} (${unit})`;
  }
  return m.replaceAll('_', ' ');
}

/**
 * The card's HTML.
 * @param a the assessment JSON (GET /api/sessions/{id}/assessment, or an attempt's
 *          `assessment`), or null when it could not be read
 * @param title the exercise's title
 * @param frame the last state frame's `exercise` (score, passed, elapsed_s, step, steps),
 *          used when `a` is null
 * @param verdict overrides the pass/fail headline (e.g. "Abandoned"), optional
 */
export function assessmentHtml(a, { title, frame = null, verdict = null }) {
  const score = a ? a.score : frame?.score ?? 0;
  const passed = a ? a.passed : !!frame?.passed;
  const terms = a?.terms || [];
  const limits = a?.limits || [];
  const time = a ? `${num(a.time_s)} s` : frame ? `${frame.elapsed_s.toFixed(1)} s` : '';
  const steps = a ? `${a.step_times_s.length} of ${a.steps_total}` : frame ? `${frame.step} of ${frame.steps}` : '';
  const why = a?.failed_because || [];
  return `<div class="card-head ${passed ? 'pass' : 'fail'}">
      <span class="card-verdict">${esc(verdict || (passed ? 'Passed' : 'Not passed'))}</span>
      <span class="card-score" data-score="${Math.round(score)}">${Math.round(score)}<small>/100</small></span></div>
    <p class="card-title">${esc(title)}${time ? ` — ${time}` : ''}${steps ? `, ${steps} steps` : ''}</p>
    ${passMarksHtml(a?.pass_marks)}
    ${why.length ? `<ul class="card-why">${why.map((w) => `<li>${esc(w)}</li>`).join('')}</ul>` : ''}
    ${terms.length ? `<table class="card-terms"><tr><th>metric</th><th>yours</th><th>good</th><th>poor</th><th>points</th></tr>
      ${terms.map((t) => `<tr><td>${esc(metricLabel(t.metric))}</td><td>${num(t.value)}</td><td>${num(t.good)}</td><td>${num(t.bad)}</td>
        <td>${(t.score * t.weight).toFixed(1)} / ${num(t.weight)}</td></tr>`).join('')}</table>` : ''}
    ${limits.length ? `<table class="card-limits"><tr><th>pass limit</th><th>yours</th><th>allowed</th><th></th></tr>
      ${limits.map((l) => `<tr class="${l.met ? 'ok' : 'bad'}"><td>${esc(metricLabel(l.metric))}</td><td>${num(l.value)}</td>
        <td>${l.max !== null && l.max !== undefined ? `≤ ${num(l.max)}` : ''}${l.min !== null && l.min !== undefined ? ` ≥ ${num(l.min)}` : ''}</td>
        <td>${l.met ? '✓' : '✗'}</td></tr>`).join('')}</table>` : ''}`;
}

/** What the attempt is judged by: the reference operators' lines it started with, or the
 * exercise's pass mark (and why, when the exercise asks for the benchmark but it does not apply
 * yet). `pm`: the assessment's `pass_marks`. */
function passMarksHtml(pm) {
  if (!pm) return '';
  if (pm.kind === 'benchmark' && pm.benchmark) {
    const b = pm.benchmark;
    const lines = b.lines.map((l) => `${esc(metricLabel(l.metric))} ${l.higher_is_better ? '≥' : '≤'} ${num(l.line)}`).join(', ');
    return `<p class="card-marks" data-marks="benchmark">Pass marks from the reference operators (${b.reference_attempts} attempts, ${num(b.k)} SD from their mean): ${lines}.</p>`;
  }
  return `<p class="card-marks" data-marks="fixed"${pm.note ? ` title="${esc(pm.note)}"` : ''}>Pass mark: score ≥ ${num(pm.min_score)}${pm.note ? ' (until the reference operators\' benchmark applies)' : ''}.</p>`;
}

/**
 * The attempt against the reference operators' benchmark (docs/exercises.md "Benchmarks"):
 * each measure's reference band (mean ± SD, n) and pass line, the attempt's value and, for the
 * measures the benchmark requires, whether it meets the line; or, while too few reference
 * attempts exist, a line saying the exercise file's pass marks apply.
 * @param a the assessment JSON (its metrics and `score`)
 * @param bench an exercise's `benchmark` (GET /api/sessions/{id}/progress), or null
 */
export function benchmarkHtml(a, bench) {
  if (!a || !bench) return '';
  if (!bench.applies) {
    return `<p class="card-bench-none" data-bench="none">No reference benchmark yet (${bench.reference_attempts} of the ${bench.min_reference_attempts} reference operators' attempts it needs): the exercise's own pass marks apply.</p>`;
  }
  const value = (m) => (m === 'score' ? a.score : a[m]);
  const rows = bench.measures.filter((m) => m.benchmark && Number.isFinite(value(m.metric))).map((m) => {
    const v = value(m.metric);
    const b = m.benchmark;
    const met = m.higher_is_better ? v >= m.line : v <= m.line;
    const mark = m.required ? (met ? '✓' : '✗') : (met ? '·' : '');
    return `<tr class="${m.required ? (met ? 'ok' : 'bad') : ''}" data-bench-metric="${esc(m.metric)}" data-met="${met}">
      <td>${esc(metricLabel(m.metric))}${m.required ? ' *' : ''}</td><td>${num(v)}</td>
      <td>${num(b.mean)} ± ${num(b.sd)}</td><td>${m.higher_is_better ? '≥' : '≤'} ${num(m.line)}</td><td>${mark}</td></tr>`;
  });
  return `<table class="card-bench" data-bench="applies"><caption>Against the reference operators (${bench.reference_attempts} attempts; line ${num(bench.k)} SD from their mean; * required)</caption>
    <tr><th>measure</th><th>yours</th><th>reference</th><th>line</th><th></th></tr>${rows.join('')}</table>`;
}
