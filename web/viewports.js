// Four viewports like Lim Fig. 4-1 (top, front, side: orthographic; a free perspective view
// with OrbitControls), drawn with one renderer into scissored rectangles of one canvas.
// Each viewport is an overlay <div> that takes the pointer; any one can be shown large.

import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const ORTHO_HALF_HEIGHT_M = 1.3;

export class Viewports {
  constructor(world, container) {
    this.world = world;
    this.container = container;
    this.centre = new THREE.Vector3(0.8, 0.5, 0.3);
    this.single = null; // name of the large view, or null for four
    this.dirty = true;
    this.frames = 0;
    this.firstFrameAt = null;
    const mk = (name, title, camera) => {
      const el = document.createElement('div');
      el.className = 'vp';
      el.dataset.view = name;
      el.innerHTML = `<span class="vp-title">${title}</span><button class="vp-max" title="one large view">⤢</button>`;
      container.appendChild(el);
      const max = el.querySelector('.vp-max');
      max.addEventListener('pointerdown', (e) => e.stopPropagation()); // not an orbit drag
      max.addEventListener('click', () => this.toggleSingle(name));
      el.addEventListener('dblclick', () => this.toggleSingle(name));
      return { name, title, el, camera };
    };
    const ortho = () => new THREE.OrthographicCamera(-1, 1, 1, -1, 0.01, 100);
    this.views = [
      mk('top', 'Top (+x up)', ortho()),
      mk('front', 'Front (from the vehicle, +x ahead)', ortho()),
      mk('side', 'Side (from the right)', ortho()),
      mk('persp', 'Perspective (drag: orbit, wheel: zoom)', new THREE.PerspectiveCamera(45, 1, 0.02, 100)),
    ];
    for (const v of this.views) v.zoom = 1;
    const persp = this.views[3];
    this.controls = new OrbitControls(persp.camera, persp.el);
    this.controls.enableDamping = false;
    this.controls.addEventListener('change', () => { this.dirty = true; });
    for (const v of this.views.slice(0, 3)) {
      v.el.addEventListener('wheel', (e) => {
        e.preventDefault();
        v.zoom = Math.min(8, Math.max(0.25, v.zoom * (e.deltaY > 0 ? 0.9 : 1.1)));
        this.dirty = true;
      }, { passive: false });
    }
    new ResizeObserver(() => { this.dirty = true; }).observe(container);
    this.placeCameras();
  }

  /** Aims every camera at the work area centre. */
  setCentre(c) {
    this.centre.copy(c);
    this.placeCameras();
  }

  placeCameras() {
    const c = this.centre;
    const [top, front, side, persp] = this.views.map((v) => v.camera);
    top.position.set(c.x, c.y, c.z + 10); top.up.set(1, 0, 0); top.lookAt(c);
    front.position.set(c.x - 10, c.y, c.z); front.up.set(0, 0, 1); front.lookAt(c);
    side.position.set(c.x, c.y - 10, c.z); side.up.set(0, 0, 1); side.lookAt(c);
    persp.position.set(c.x + 2.2, c.y - 2.6, c.z + 1.6);
    persp.up.set(0, 0, 1);
    this.controls.target.copy(c);
    this.controls.update();
    this.dirty = true;
  }

  toggleSingle(name) {
    this.single = this.single === name ? null : name;
    this.container.classList.toggle('single', this.single !== null);
    for (const v of this.views) v.el.classList.toggle('big', v.name === this.single);
    this.dirty = true;
  }

  /** Cycles four views → perspective large → four. */
  cycleLayout() { this.toggleSingle(this.single ? this.single : 'persp'); }

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
    r.setScissorTest(false);
    r.clear();
    r.setScissorTest(true);
    for (const v of this.views) {
      if (this.single && v.name !== this.single) continue;
      const b = v.el.getBoundingClientRect();
      const x = b.left - cr.left, y = cr.bottom - b.bottom, w = b.width, h = b.height;
      if (w < 2 || h < 2) continue;
      r.setViewport(x, y, w, h);
      r.setScissor(x, y, w, h);
      const cam = v.camera;
      const aspect = w / h;
      if (cam.isOrthographicCamera) {
        const hh = ORTHO_HALF_HEIGHT_M / v.zoom;
        cam.left = -hh * aspect; cam.right = hh * aspect; cam.top = hh; cam.bottom = -hh;
      } else {
        cam.aspect = aspect;
      }
      cam.updateProjectionMatrix();
      r.render(this.world.scene, cam);
    }
    this.frames++;
    const t1 = performance.now();
    this.renderMs = this.renderMs === undefined ? t1 - t0 : 0.9 * this.renderMs + 0.1 * (t1 - t0);
    if (this.firstFrameAt === null) this.firstFrameAt = t1;
    return true;
  }

  /** Screen position (CSS px, page) of a world point in a view, for tests. */
  project(name, p) {
    const v = this.views.find((x) => x.name === name);
    const b = v.el.getBoundingClientRect();
    const q = new THREE.Vector3(...p).project(v.camera);
    return { x: b.left + (q.x + 1) / 2 * b.width, y: b.top + (1 - q.y) / 2 * b.height };
  }
}
