// The toolbar's view controls shared by the trainee page and the debrief page: ellipsoids,
// polytopes, ellipsoid scale, plots on/off and the four views / one large view switch. The
// pages carry the same elements (ids chk-ell, chk-plots, btn-layout; chk-poly and sel-ell-scale
// where the page has them).

import { $ } from './page.js';
import { View } from './view.js';
import { StatusBar } from './status.js';
import { Plots } from './plots.js';

/** The parts of a page with the 3D views, the status bar and the plots (elements #canvas,
 * #viewports, #legend, #status, #plots), the toolbar's view controls bound to them:
 * {view, status, plots, controls} (controls: bindViewControls's). */
export function mountViews() {
  const view = new View({ canvas: $('canvas'), viewportsEl: $('viewports'), legendEl: $('legend') });
  const status = new StatusBar($('status'));
  const plots = new Plots($('plots'));
  return { view, status, plots, controls: bindViewControls(view, plots) };
}

/** The instructor's visibility (a state frame's `visibility_m`, m, or null): applied to the
 * water, shown in the visibility menu and locked there while set. */
export function followVisibility(view, visibility_m) {
  const sel = $('sel-visibility');
  const set = typeof visibility_m === 'number' && visibility_m > 0;
  if (set && view.water.visibility_m !== visibility_m) {
    view.water.setVisibility(visibility_m);
    view.viewports.dirty = true;
  }
  if (!sel) return;
  if (set) {
    const v = String(visibility_m);
    if (![...sel.options].some((o) => o.value === v)) sel.add(new Option(`${visibility_m} m`, v));
    sel.value = v;
  }
  if (sel.disabled !== set) {
    sel.disabled = set;
    sel.title = set ? 'Water visibility, set by the instructor' : 'Water visibility in the pilot cameras';
  }
}

/** Binds the controls to `view` (web/view.js) and `plots` (web/plots.js, its panel #plots);
 * returns {layout()} (the keyboard's V). */
export function bindViewControls(view, plots) {
  const layout = () => {
    view.viewports.cycleLayout();
    $('btn-layout').textContent = view.viewports.single ? '4 views' : '1 view';
  };
  $('btn-layout').addEventListener('click', layout);
  $('chk-ell').addEventListener('change', (e) => view.setEllipsoidsVisible(e.target.checked));
  $('sel-views')?.addEventListener('change', (e) => view.viewports.showSet(e.target.value));
  $('sel-visibility')?.addEventListener('change', (e) => { view.water.setVisibility(+e.target.value); view.viewports.dirty = true; });
  $('btn-worksite')?.addEventListener('click', () => view.frameWorkSite());
  $('chk-poly')?.addEventListener('change', (e) => view.setPolytopesVisible(e.target.checked));
  $('sel-ell-scale')?.addEventListener('change', (e) => view.setEllipsoidScale(+e.target.value));
  $('chk-plots').addEventListener('change', (e) => {
    $('plots').hidden = !e.target.checked;
    plots.visible = e.target.checked;
    view.viewports.dirty = true;
  });
  return { layout };
}
