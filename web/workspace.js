// Workspace heat map: asks the server for the map and draws it; no kinematics here.

import { $ } from './page.js';
import { workspaceMap } from './api.js';

/** Colour for t in [0, 1] on a dark-blue → cyan → yellow ramp. */
export function ramp(t) {
  const c = Math.max(0, Math.min(1, t));
  const stops = [[12, 30, 80], [0, 170, 200], [250, 230, 60]];
  const seg = c < 0.5 ? 0 : 1;
  const u = c < 0.5 ? c * 2 : (c - 0.5) * 2;
  const a = stops[seg], b = stops[seg + 1];
  return a.map((v, i) => Math.round(v + (b[i] - v) * u));
}

export async function fetchMap({ robot, measure, orientation, n }) {
  const doc = await workspaceMap({ robot, orientation, nx: n, nz: n });
  return { doc, grid: doc[measure] };
}

export function draw(canvas, doc, grid, measure) {
  const ctx = canvas.getContext('2d');
  const nz = grid.length, nx = grid[0].length;
  let max = 0;
  for (const row of grid) for (const v of row) if (v != null && v > max) max = v;
  const cw = canvas.width / nx, ch = canvas.height / nz;
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  for (let iz = 0; iz < nz; iz++) {
    for (let ix = 0; ix < nx; ix++) {
      const v = grid[iz][ix];
      const [r, g, b] = v == null ? [60, 66, 72] : ramp(max > 0 ? v / max : 0);
      ctx.fillStyle = `rgb(${r},${g},${b})`;
      // z grows upwards on screen.
      ctx.fillRect(ix * cw, canvas.height - (iz + 1) * ch, Math.ceil(cw), Math.ceil(ch));
    }
  }
  const x = doc.x, z = doc.z;
  $('legend').textContent = `${measure}: 0 … ${max.toFixed(3)} (bright = high); X ${x[0].toFixed(2)}…${x[x.length - 1].toFixed(2)} m left→right, Z ${z[0].toFixed(2)}…${z[z.length - 1].toFixed(2)} m bottom→top; ` +
    `best ${measure} at X ${doc.summary[`max_${measure}`]?.x?.toFixed?.(2) ?? '–'} m, Z ${doc.summary[`max_${measure}`]?.z?.toFixed?.(2) ?? '–'} m`;
  return max;
}

async function compute() {
  const opts = { robot: $('robot').value, measure: $('measure').value, orientation: $('orientation').value, n: Number($('grid').value) };
  $('status').textContent = 'computing…';
  try {
    const t0 = performance.now();
    const { doc, grid } = await fetchMap(opts);
    const max = draw($('map'), doc, grid, opts.measure);
    window.__workspace = { doc, measure: opts.measure, max };
    $('status').textContent = `${doc.summary.reachable} of ${doc.summary.cells} cells reachable, ${(performance.now() - t0).toFixed(0)} ms`;
  } catch (e) {
    $('status').textContent = `error: ${e.message}`;
  }
}

$('go').addEventListener('click', compute);
for (const id of ['robot', 'measure', 'orientation', 'grid']) $(id).addEventListener('change', compute);
compute();
