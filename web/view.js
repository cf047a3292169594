// The 3D view shared by the trainee page and the instructor dashboard: world, both arms,
// ellipsoids, four viewports, the draw loop (latest state wins: each animation frame draws the
// newest state once), the optional polytope fetcher, and read-only debug hooks for tests.

import { World, GRASP_COLOURS, CURRENT_COLOUR, CURRENT_ARROW_M_PER_M_S } from './scene.js';
import { Arm, ARM_COLOUR } from './arms.js';
import { Ellipsoids, ELLIPSOID_COLOURS } from './ellipsoids.js';
import { Viewports } from './viewports.js';
import { Water } from './water.js';
import * as THREE from 'three';
import { Markers } from './markers.js';
import { waterText } from './status.js';
import { analysis } from './api.js';

const SIDES = ['left', 'right'];
const POLYTOPE_PERIOD_MS = 1000;

export class View {
  constructor({ canvas, viewportsEl, legendEl }) {
    this.world = new World(canvas);
    this.water = new Water(this.world);
    this.viewports = new Viewports(this.world, viewportsEl, this.water);
    this.ellipsoids = new Ellipsoids(this.world.root);
    this.markers = new Markers(this.world, () => { this.viewports.dirty = true; });
    this.selectedArm = null;
    this.arms = null;
    this.hello = null;
    this.pending = null; // newest undrawn state
    this.drawn = null; // last drawn state
    this.statesDrawn = 0;
    this.firstStateFrameAt = null; // ms after navigation: first frame with the arms drawn
    this.legendEl = legendEl;
    this.polytopes = false;
    this.lastFrameAt = -Infinity;
    const want = Number(new URLSearchParams(location.search).get('maxfps'));
    this.maxFps = want > 0 ? want : (this.world.software ? 15 : 120);
    this.polyBusy = false;
    /** What else draws from the hello and each drawn state ({setHello(hello), update(state)}:
     * the ghost, web/ghost.js). */
    this.overlays = new Set();
    this.legend();
    const loop = () => {
      this.frame();
      this.raf = requestAnimationFrame(loop);
    };
    this.raf = requestAnimationFrame(loop);
  }

  legend() {
    if (!this.legendEl) return;
    // Swatch colours are set through the CSSOM below: the page's CSP refuses style="" attributes.
    // Each entry (swatch and words) stays on one line where the legend wraps.
    const sw = (c, text) => `<span class="li"><span class="sw" data-colour="#${c.toString(16).padStart(6, '0')}"></span>${text}</span>`;
    // the water current's arrow (scene.js), named while there is one to see
    const cur = this.current?.speed_m_s > 0
      ? `<br><span class="legend-current">water current ${sw(CURRENT_COLOUR, `arrow: ${waterText(this.current)}`)}` +
        ` <span class="li">(${CURRENT_ARROW_M_PER_M_S} m per m/s)</span></span>` : '';
    // the ellipsoids' colours are named only while they are drawn (the legend covers a view)
    const ell = this.ellipsoids.showEllipsoids
      ? `ellipsoids ${sw(ELLIPSOID_COLOURS.left, 'left')} ${sw(ELLIPSOID_COLOURS.right, 'right')} ${sw(ELLIPSOID_COLOURS.dual, 'dual')}` +
        ` <span class="li">— 1 m/s drawn as ${this.ellipsoids.scale} m</span><br>` : '';
    this.legendEl.innerHTML =
      `${ell}object ${sw(GRASP_COLOURS.free, 'free')}` +
      ` ${sw(GRASP_COLOURS.one_on_surface, 'one holding, on surface')} ${sw(GRASP_COLOURS.one_lifted, 'one lifted')}` +
      ` ${sw(GRASP_COLOURS.one_holding_other_contact, 'one holds, other touches')} ${sw(GRASP_COLOURS.both_holding, 'both holding')}${cur}`;
    for (const el of this.legendEl.querySelectorAll('.sw')) el.style.background = el.dataset.colour;
  }

  setHello(hello) {
    this.hello = hello;
    if (this.arms) for (const a of this.arms) a.dispose();
    this.world.setup(hello);
    this.arms = hello.arms.map((spec, i) => new Arm(spec, this.world.root, SIDES[i]));
    this.markers.setup(hello);
    if (this.selectedArm) this.setSelectedArm(this.selectedArm);
    this.viewports.setCentre(World.workCentre(hello));
    this.viewports.setHello(hello);
    this.water.setup(hello);
    this.workSitePending = false;
    this.pending = null;
    for (const s of SIDES) this.ellipsoids.setPolytope(s, null);
    for (const o of this.overlays) o.setHello(hello);
  }

  setState(state) { this.pending = state; }

  /** What an exercise works on, world (m): the box's handles, the panel's items, the targets
   * and the zones (from the hello's scene and the newest frame's box pose); empty without a
   * scene. */
  workSiteBox() {
    const box = new THREE.Box3();
    const sc = this.hello?.scene;
    if (!sc) return box;
    const st = this.drawn;
    for (const h of this.markers.handles) box.expandByPoint(h.group.getWorldPosition(new THREE.Vector3()));
    if (sc.panel) {
      for (const p of [sc.panel.valve_grip_m, sc.panel.receptacle_m, sc.panel.holster_m]) box.expandByPoint(new THREE.Vector3(...p));
    }
    for (const t of sc.targets || []) box.expandByPoint(new THREE.Vector3(...t.position_m));
    for (const z of sc.zones || []) {
      for (const s of [-1, 1]) box.expandByPoint(new THREE.Vector3(z.center_m[0] + s * z.half_size_m[0], z.center_m[1] + s * z.half_size_m[1], this.hello.seabed_z_m));
    }
    if (st && (sc.zones || []).length) box.expandByPoint(new THREE.Vector3(...st.object.pose.position));
    return box;
  }

  /** The work-site preset once the next state frame is drawn (the handles ride on the box). */
  frameWorkSiteSoon() { this.workSitePending = true; }

  /** The "work site" camera preset (key K, toolbar button). */
  frameWorkSite() {
    this.world.object?.updateMatrixWorld(true);
    this.viewports.frameWorkSite(this.workSiteBox());
  }

  /** Highlights the arm the sticks drive ('left' or 'right'; null: none, e.g. an observer). */
  setSelectedArm(side) {
    this.selectedArm = side;
    if (this.arms) this.arms.forEach((a, i) => a.setSelected(SIDES[i] === side));
    this.viewports.dirty = true;
  }

  setEllipsoidScale(s) {
    this.ellipsoids.scale = s;
    this.legend();
    if (this.drawn) { this.ellipsoids.update(this.drawn); this.viewports.dirty = true; }
  }

  setEllipsoidsVisible(v) { this.ellipsoids.setVisible(v); this.legend(); this.viewports.dirty = true; }

  setPolytopesVisible(v) {
    this.polytopes = v;
    this.ellipsoids.setPolytopesVisible(v);
    clearInterval(this.polyTimer);
    if (v) {
      this.fetchPolytopes();
      this.polyTimer = setInterval(() => this.fetchPolytopes(), POLYTOPE_PERIOD_MS);
    }
    this.viewports.dirty = true;
  }

  /** Velocity polytopes at the current q from POST /api/analysis (server-computed). */
  async fetchPolytopes() {
    if (this.polyBusy || !this.hello || !this.drawn) return;
    this.polyBusy = true;
    try {
      await Promise.all(SIDES.map(async (side, i) => {
        const spec = this.hello.arms[i];
        const a = await analysis({ robot: spec.model, q: this.drawn.arms[side].q, polytope: true });
        if (!a) return;
        if (this.polytopes) this.ellipsoids.setPolytope(side, a.polytope, spec.base.rotation);
      }));
      if (this.drawn) this.ellipsoids.update(this.drawn);
      this.viewports.dirty = true;
    } catch { /* next period retries */ } finally {
      this.polyBusy = false;
    }
  }

  frame() {
    // A CPU rasterizer draws at most 15 fps (the newest state each time), leaving CPU to the
    // page's input timer; ?maxfps=N overrides.
    const now = performance.now();
    if (now - this.lastFrameAt < 1000 / this.maxFps - 4) return;
    const dt_s = Number.isFinite(this.lastFrameAt) ? (now - this.lastFrameAt) / 1000 : 0;
    this.lastFrameAt = now;
    this.viewports.step(dt_s);
    // the water's particles move by themselves: the pilot views redraw every frame
    if (this.viewports.set === 'pilot' && this.water.step(dt_s)) this.viewports.dirty = true;
    const s = this.pending;
    if (s && this.arms) {
      this.pending = null;
      this.arms[0].update(s.arms.left);
      this.arms[1].update(s.arms.right);
      this.world.update(s);
      if (waterText(s.current) !== waterText(this.current)) { this.current = s.current; this.legend(); }
      this.ellipsoids.update(s);
      this.markers.update(s);
      for (const o of this.overlays) o.update(s);
      this.water.update(s);
      this.viewports.state = s;
      this.drawn = s;
      if (this.workSitePending) { this.workSitePending = false; this.frameWorkSite(); }
      this.statesDrawn++;
      this.viewports.dirty = true;
    }
    if (this.viewports.render() && this.drawn && this.firstStateFrameAt === null) {
      this.firstStateFrameAt = performance.now();
    }
  }

  /** Read-only hooks for the browser tests; `conn()` is the page's current connection
   * (web/connection.js) or null. */
  debugHooks(conn, extra = {}) {
    const v = this;
    const hooks = {
      get connection() { return conn()?.debugInfo() ?? null; },
      get lastReceived() { return conn()?.latest; },
      statusText() { return document.getElementById('status').innerText; },
      get hello() { return v.hello; },
      get lastState() { return v.drawn; },
      get statesDrawn() { return v.statesDrawn; },
      get framesRendered() { return v.viewports.frames; },
      get renderMs() { return v.viewports.renderMs; },
      get firstFrameAt() { return v.viewports.firstFrameAt; },
      get firstStateFrameAt() { return v.firstStateFrameAt; },
      drawnJointAngles() { return v.arms ? v.arms.map((a) => a.q.slice()) : null; },
      drawnJawCentres() { return v.arms ? v.arms.map((a) => a.drawnJawCentre()) : null; },
      drawnJawGaps() { return v.arms ? v.arms.map((a) => a.drawnJawGap()) : null; },
      drawnRods() { return v.arms ? v.arms.map((a) => a.drawnRods()) : null; },
      drawnObjectColour() { return v.world.objectMaterial.color.getHex(); },
      /** The water current's arrow: shown, and its tail and tip (world, m). */
      drawnCurrent() { const a = v.world.current; return { visible: a.visible, ends: a.ends() }; },
      drawnObjectPosition() { return v.world.object ? [...v.world.object.matrix.elements.slice(12, 15)] : null; },
      drawnEllipsoidRadii(which) { return v.ellipsoids.drawnRadii(which); },
      project(view, p) { return v.viewports.project(view, p); },
      /** The shown view set's viewports (web/viewports.js VIEW_SETS), each shown or not. */
      viewports() {
        const vp = v.viewports;
        return vp.views.filter((x) => x.set === vp.set).map((x) => ({ name: x.name, set: x.set, rect: x.el.getBoundingClientRect().toJSON(),
          visible: !vp.single || vp.single === x.name }));
      },
      /** View sets: the shown one, those allowed, the active view (the sticks follow it). */
      viewSet() { const vp = v.viewports; return { set: vp.set, allowed: vp.allowedSets.slice(), active: vp.active, single: vp.single }; },
      /** A view camera's world matrix (column-major 16) and projection, for tests. */
      cameraOf(name) {
        const x = v.viewports.view(name);
        const b = x.el.getBoundingClientRect();
        v.viewports.prepare(x, b.width / Math.max(1, b.height));
        return { world: x.camera.matrixWorld.toArray(), projection: x.camera.projectionMatrix.toArray(), rect: b.toJSON() };
      },
      /** Pan-tilt unit: angles (deg) and zoom now and their targets. */
      panTilt() { const p = v.viewports.panTilt; return { pan: p.pan, tilt: p.tilt, zoom: p.zoom, target: { ...p.target } }; },
      /** The water: visibility (m), silt particles emitted so far and alive now. */
      water() { return { colour: v.water.fog.color.getHex(), visibility_m: v.water.visibility_m, siltEmitted: v.water.siltEmitted, siltAlive: v.water.siltAlive() }; },
      /** The work site's box (world, m): what the "work site" preset frames. */
      workSite() { const b = v.workSiteBox(); return b.isEmpty() ? null : { min: b.min.toArray(), max: b.max.toArray() }; },
      ellipsoidsShown() { return v.ellipsoids.showEllipsoids; },
      colours: { arm: ARM_COLOUR, grasp: GRASP_COLOURS },
      /** What the exercise scene draws: handles (world centres and capture cue), counts. */
      drawnScene() {
        const m = v.markers;
        return {
          handles: m.handles.map((h, i) => ({ at: h.group.getWorldPosition(new h.group.position.constructor()).toArray(), capture: m.capture[i] })),
          objects: m.group.children.length, ghosts: m.ghosts.length,
        };
      },
      selectedArmDrawn() { return v.arms ? SIDES.filter((s, i) => v.arms[i].selected) : null; },
    };
    // keep the extra getters live (a spread would read them once)
    return Object.freeze(Object.defineProperties(hooks, Object.getOwnPropertyDescriptors(extra)));
  }
}
