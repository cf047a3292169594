// Two view sets drawn with one renderer into scissored rectangles of one canvas, four at a
// time (any one can be shown large). Each viewport is an overlay <div> that takes the pointer.
// - "engineering" (Lim Fig. 4-1): top, front, side (orthographic) and a free perspective view
//   with OrbitControls — daylight, no water: the training wheels.
// - "pilot" (issue 28): the cameras an ROV operator works through (web/cameras.js: the pan-tilt
//   main camera, a camera on each wrist, a fixed overview), drawn in murky water (web/water.js).
// The active view (the last one pointed at, or the large one) is the one the sticks follow in
// Cartesian mode (web/input.js); the wheel zooms toward the cursor.

import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { PILOT_CAMERAS, PanTilt, placePilotCamera, vehicleFrame } from './cameras.js';
import { BACKGROUND } from './scene.js';
import { WATER_COLOUR } from './water.js';

const ORTHO_HALF_HEIGHT_M = 1.3;
/** Each set's views in grid order and the one shown large by default. */
export const VIEW_SETS = {
  engineering: { views: ['top', 'front', 'side', 'persp'], main: 'persp' },
  pilot: { views: PILOT_CAMERAS.map((c) => c.name), main: 'pilot' },
};

export class Viewports {
  constructor(world, container, water) {
    this.world = world;
    this.water = water;
    this.container = container;
    this.centre = new THREE.Vector3(0.8, 0.5, 0.3);
    this.single = null; // name of the large view, or null for four
    this.set = 'engineering';
    this.allowedSets = Object.keys(VIEW_SETS);
    this.active = 'persp';
    this.dirty = true;
    this.frames = 0;
    this.firstFrameAt = null;
    this.vehicle = null; // vehicle frame (web/cameras.js), from the hello
    this.state = null; // newest drawn state frame (the wrist cameras ride on it)
    const mk = (name, title, camera, set) => {
      const el = document.createElement('div');
      el.className = 'vp';
      el.dataset.view = name;
      el.dataset.set = set;
      el.innerHTML = `<span class="vp-title">${title}</span><button class="vp-max" title="one large view">⤢</button>`;
      container.appendChild(el);
      const max = el.querySelector('.vp-max');
      max.addEventListener('pointerdown', (e) => e.stopPropagation()); // not an orbit drag
      max.addEventListener('click', () => this.toggleSingle(name));
      el.addEventListener('dblclick', () => this.toggleSingle(name));
      el.addEventListener('pointerdown', () => this.setActive(name), true);
      return { name, title, el, camera, set, zoom: 1, pan: new THREE.Vector2(), base: new THREE.Vector3() };
    };
    const ortho = () => new THREE.OrthographicCamera(-1, 1, 1, -1, 0.01, 100);
    this.views = [
      mk('top', 'Top (+x up)', ortho(), 'engineering'),
      mk('front', 'Front (from the vehicle, +x ahead)', ortho(), 'engineering'),
      mk('side', 'Side (from the right)', ortho(), 'engineering'),
      mk('persp', 'Perspective (drag: orbit, wheel: zoom)', new THREE.PerspectiveCamera(45, 1, 0.02, 100), 'engineering'),
      ...PILOT_CAMERAS.map((c) => Object.assign(mk(c.name, c.title, new THREE.PerspectiveCamera(c.fov_deg, 1, 0.02, 60), 'pilot'), { spec: c })),
    ];
    const persp = this.view('persp');
    this.controls = new OrbitControls(persp.camera, persp.el);
    this.controls.enableDamping = false;
    this.controls.zoomToCursor = true; // the wheel zooms toward the point under the cursor
    this.controls.addEventListener('change', () => { this.dirty = true; });
    for (const v of this.views.filter((x) => x.camera.isOrthographicCamera)) {
      v.el.addEventListener('wheel', (e) => { e.preventDefault(); this.zoomOrtho(v, e); }, { passive: false });
    }
    const pilot = this.view('pilot');
    this.panTilt = new PanTilt(pilot.spec);
    this.bindPanTilt(pilot);
    for (const v of this.views.filter((x) => x.spec && !x.spec.panTilt)) {
      v.el.addEventListener('wheel', (e) => { // a fixed camera's zoom (its lens), to the cursor's side
        e.preventDefault();
        v.zoom = Math.min(5, Math.max(1, v.zoom * (e.deltaY > 0 ? 0.9 : 1.1)));
        this.dirty = true;
      }, { passive: false });
    }
    new ResizeObserver(() => { this.dirty = true; }).observe(container);
    this.placeCameras();
    this.showSet('engineering');
  }

  view(name) { return this.views.find((v) => v.name === name); }

  /** The pan-tilt camera follows a mouse drag (the picture moves with the pointer) and the
   * wheel (zoom); the unit slews at its rates (web/cameras.js PAN_TILT). */
  bindPanTilt(v) {
    let drag = null;
    v.el.addEventListener('pointerdown', (e) => {
      if (e.target.closest('.vp-max')) return;
      drag = { x: e.clientX, y: e.clientY, id: e.pointerId };
      v.el.setPointerCapture(e.pointerId);
    });
    v.el.addEventListener('pointermove', (e) => {
      if (!drag || e.pointerId !== drag.id) return;
      const h = v.el.getBoundingClientRect().height || 1;
      const degPerPx = v.spec.fov_deg / this.panTilt.zoom / h;
      this.panTilt.nudge((e.clientX - drag.x) * degPerPx, (e.clientY - drag.y) * degPerPx);
      drag.x = e.clientX; drag.y = e.clientY;
    });
    const end = () => { drag = null; };
    v.el.addEventListener('pointerup', end);
    v.el.addEventListener('pointercancel', end);
    v.el.addEventListener('wheel', (e) => {
      e.preventDefault();
      this.panTilt.nudge(0, 0, e.deltaY > 0 ? 1 / 1.15 : 1.15);
    }, { passive: false });
  }

  /** Orthographic wheel zoom that keeps the world point under the cursor where it is. */
  zoomOrtho(v, e) {
    const b = v.el.getBoundingClientRect();
    const nx = ((e.clientX - b.left) / b.width) * 2 - 1, ny = 1 - ((e.clientY - b.top) / b.height) * 2;
    const hh = ORTHO_HALF_HEIGHT_M / v.zoom;
    v.zoom = Math.min(8, Math.max(0.25, v.zoom * (e.deltaY > 0 ? 0.9 : 1.1)));
    const dh = hh - ORTHO_HALF_HEIGHT_M / v.zoom;
    v.pan.x += nx * (b.width / b.height) * dh;
    v.pan.y += ny * dh;
    this.dirty = true;
  }

  /** The views a session may use (an exercise with `"views": "pilot"` allows only those). */
  setAllowedSets(sets) {
    this.allowedSets = sets;
    if (!sets.includes(this.set)) this.showSet(sets[0]);
  }

  /** Shows a view set ('engineering' or 'pilot'); a large view becomes that set's main one. */
  showSet(set) {
    if (!this.allowedSets.includes(set)) return;
    this.set = set;
    for (const v of this.views) v.el.hidden = v.set !== set;
    if (this.single) this.toggleSingle(VIEW_SETS[set].main, true);
    this.setActive(this.single || VIEW_SETS[set].main);
    this.dirty = true;
  }

  /** The view the sticks follow (Cartesian mode, camera frame). */
  setActive(name) {
    this.active = name;
    for (const v of this.views) v.el.classList.toggle('active', v.name === name);
  }

  /** The active view's camera (its matrixWorld: camera x right, y up, z toward the viewer). */
  activeCamera() { return this.view(this.active).camera; }

  /** Aims every camera at the work area centre. */
  setCentre(c) {
    this.centre.copy(c);
    this.placeCameras();
  }

  setHello(hello) {
    this.vehicle = vehicleFrame(hello);
    this.state = null;
  }

  placeCameras() {
    const c = this.centre;
    const [top, front, side, persp] = this.views.map((v) => v.camera);
    top.position.set(c.x, c.y, c.z + 10); top.up.set(1, 0, 0); top.lookAt(c);
    front.position.set(c.x - 10, c.y, c.z); front.up.set(0, 0, 1); front.lookAt(c);
    side.position.set(c.x, c.y - 10, c.z); side.up.set(0, 0, 1); side.lookAt(c);
    for (const v of this.views.slice(0, 3)) { v.base.copy(v.camera.position); v.pan.set(0, 0); v.camera.updateMatrixWorld(); }
    persp.position.set(c.x + 2.2, c.y - 2.6, c.z + 1.6);
    persp.up.set(0, 0, 1);
    this.controls.target.copy(c);
    this.controls.update();
    this.dirty = true;
  }

  /**
   * The "work site" preset: every engineering view framed on `box` (a THREE.Box3 of what the
   * exercise works on: handles, panel, targets, zones), the perspective view from the
   * vehicle's side and above; the pan-tilt camera turned to its centre.
   */
  frameWorkSite(box) {
    if (box.isEmpty()) return;
    const c = box.getCenter(new THREE.Vector3());
    const r = Math.max(0.15, box.getSize(new THREE.Vector3()).length() / 2);
    this.setCentre(c);
    for (const v of this.views.slice(0, 3)) v.zoom = Math.min(8, Math.max(0.25, ORTHO_HALF_HEIGHT_M / (1.3 * r)));
    const persp = this.view('persp').camera;
    const dist = (1.4 * r) / Math.sin((persp.fov * Math.PI) / 360);
    persp.position.copy(c).add(new THREE.Vector3(-0.55, -0.45, 0.7).normalize().multiplyScalar(dist));
    this.controls.target.copy(c);
    this.controls.update();
    if (this.vehicle) {
      const spec = this.view('pilot').spec;
      const p = new THREE.Vector3(...spec.position_m).applyMatrix4(this.vehicle);
      const d = c.clone().sub(p).transformDirection(this.vehicle.clone().invert());
      this.panTilt.target.pan = (Math.atan2(d.y, d.x) * 180) / Math.PI;
      this.panTilt.target.tilt = (Math.asin(Math.max(-1, Math.min(1, d.z))) * 180) / Math.PI;
      this.panTilt.clampTarget();
    }
    this.dirty = true;
  }

  toggleSingle(name, keep = false) {
    this.single = this.single === name && !keep ? null : name;
    this.container.classList.toggle('single', this.single !== null);
    for (const v of this.views) v.el.classList.toggle('big', v.name === this.single);
    if (this.single) this.setActive(this.single);
    this.dirty = true;
  }

  /** Cycles four views → the set's main view large → four. */
  cycleLayout() { this.toggleSingle(this.single ? this.single : VIEW_SETS[this.set].main); }

  /** Advances what moves by itself (the pan-tilt unit); true when it moved. */
  step(dt_s) {
    const moved = this.panTilt.step(dt_s);
    if (moved) this.dirty = true;
    return moved;
  }

  /** Places one view's camera for a viewport of `aspect`; false when it cannot be drawn. */
  prepare(v, aspect) {
    const cam = v.camera;
    if (cam.isOrthographicCamera) {
      const hh = ORTHO_HALF_HEIGHT_M / v.zoom;
      cam.left = -hh * aspect; cam.right = hh * aspect; cam.top = hh; cam.bottom = -hh;
      // the zoom-to-cursor offset along the camera's own right and up axes
      const e = cam.matrixWorld.elements;
      cam.position.copy(v.base).add(new THREE.Vector3(e[0], e[1], e[2]).multiplyScalar(v.pan.x))
        .add(new THREE.Vector3(e[4], e[5], e[6]).multiplyScalar(v.pan.y));
      cam.updateMatrixWorld();
    } else {
      cam.aspect = aspect;
    }
    if (v.spec) {
      if (!this.vehicle || !placePilotCamera(cam, v.spec, this.vehicle, this.state, this.panTilt)) return false;
      if (!v.spec.panTilt) cam.zoom = v.zoom;
    }
    cam.updateProjectionMatrix();
    return true;
  }

  /** Renders every visible viewport; returns true if something was drawn. */
  render(force = false) {
    if (!this.dirty && !force) return false;
    this.dirty = false;
    const t0 = performance.now();
    const r = this.world.renderer;
    const canvas = r.domElement;
    const cw = canvas.clientWidth, ch = canvas.clientHeight;
    if (cw === 0 || ch === 0) return false;
    const size = r.getSize(new THREE.Vector2());
    if (size.x !== cw || size.y !== ch) r.setSize(cw, ch, false);
    const cr = canvas.getBoundingClientRect();
    r.setClearColor(BACKGROUND, 1);
    r.setScissorTest(false);
    r.clear();
    r.setScissorTest(true);
    for (const v of this.views) {
      if (v.set !== this.set || (this.single && v.name !== this.single)) continue;
      const b = v.el.getBoundingClientRect();
      const x = b.left - cr.left, y = cr.bottom - b.bottom, w = b.width, h = b.height;
      if (w < 2 || h < 2) continue;
      r.setViewport(x, y, w, h);
      r.setScissor(x, y, w, h);
      if (!this.prepare(v, w / h)) continue;
      const pilot = v.set === 'pilot';
      this.water.show(pilot);
      r.setClearColor(pilot ? WATER_COLOUR : BACKGROUND, 1);
      r.render(this.world.scene, v.camera);
    }
    this.water.show(false);
    this.frames++;
    const t1 = performance.now();
    this.renderMs = this.renderMs === undefined ? t1 - t0 : 0.9 * this.renderMs + 0.1 * (t1 - t0);
    if (this.firstFrameAt === null) this.firstFrameAt = t1;
    return true;
  }

  /** Screen position (CSS px, page) of a world point in a view, for tests. */
  project(name, p) {
    const v = this.view(name);
    const b = v.el.getBoundingClientRect();
    this.prepare(v, b.width / Math.max(1, b.height));
    const q = new THREE.Vector3(...p).project(v.camera);
    return { x: b.left + (q.x + 1) / 2 * b.width, y: b.top + (1 - q.y) / 2 * b.height };
  }
}
