// What an exercise shows in 3D besides the arms and the box, from the hello's `scene`
// (docs/exercises.md): the box's handles (the only places a jaw can grasp) with their capture
// spheres, lit when a jaw is within grasp range (the frame's `arms.*.capture`); floating
// targets; zones on the seabed; obstacles; and ghost arms at the joint angles to reach (their
// joint frames from POST /api/analysis: the server's kinematics, as for the live arms).

import * as THREE from 'three';
import { poseToMatrix } from './scene.js';
import { Arm } from './arms.js';
import { analysis } from './api.js';

// Palette (issue 28; docs/views.md): colour-blind safe, after Okabe & Ito's eight colours, each
// readable on the dark water and none shared with an ellipsoid (web/ellipsoids.js: left
// bluish green #009E73, right reddish purple #CC79A7, dual light grey) or a grasp state
// (web/scene.js, Lim Fig. 4-4): handles sky blue, capture cue white, reach markers yellow
// (the current one opaque with its letter and distance, the others faint), zones blue-outlined
// sky blue, obstacles vermillion.
const HANDLE_COLOUR = 0x56b4e9; // Okabe–Ito sky blue
const CAPTURE_COLOUR = 0xffffff; // white: a closing jaw would grasp
const TARGET_COLOUR = 0xf0e442; // Okabe–Ito yellow
const ZONE_COLOUR = 0x56b4e9; // Okabe–Ito sky blue (fill) …
const ZONE_EDGE_COLOUR = 0xf0f0f0; // … with a light outline
const OBSTACLE_COLOUR = 0xd55e00; // Okabe–Ito vermillion
/** Reach markers are drawn at least this radius (m: 5 cm across), whatever the tolerance. */
const MIN_MARKER_RADIUS_M = 0.025;
/** Handle bar drawn along the box's x (m); its thickness is the model's 4 cm bar. */
const HANDLE_LENGTH_M = 0.12;
const HANDLE_RADIUS_M = 0.02;
const SIDES = ['left', 'right'];

function translucent(colour, opacity) {
  return new THREE.MeshBasicMaterial({ color: colour, transparent: true, opacity, depthWrite: false });
}

/** A server pose {position, rotation rows} from a Matrix4. */
function matrixToPose(m) {
  const e = m.elements; // column-major
  return { position: [e[12], e[13], e[14]], rotation: [[e[0], e[4], e[8]], [e[1], e[5], e[9]], [e[2], e[6], e[10]]] };
}

/** A text label that always faces the camera (a sprite with a canvas texture). */
class Label {
  constructor(text) {
    this.canvas = document.createElement('canvas');
    this.canvas.width = 256; this.canvas.height = 64;
    this.texture = new THREE.CanvasTexture(this.canvas);
    this.sprite = new THREE.Sprite(new THREE.SpriteMaterial({ map: this.texture, depthTest: false, transparent: true }));
    this.sprite.renderOrder = 5;
    this.sprite.scale.set(0.2, 0.05, 1);
    this.text = null;
    this.set(text, false);
  }

  set(text, current) {
    const key = `${text}|${current}`;
    if (key === this.text) return;
    this.text = key;
    const g = this.canvas.getContext('2d');
    g.clearRect(0, 0, 256, 64);
    g.font = 'bold 44px system-ui, sans-serif';
    g.textAlign = 'center';
    g.textBaseline = 'middle';
    g.lineWidth = 8;
    g.strokeStyle = '#000000';
    g.strokeText(text, 128, 32);
    g.fillStyle = current ? '#f0e442' : '#c8c08a';
    g.fillText(text, 128, 32);
    this.texture.needsUpdate = true;
  }
}

export class Markers {
  /** @param redraw() asks the views to draw again (a ghost arrives after its fetch) */
  constructor(world, redraw) {
    this.world = world;
    this.redraw = redraw;
    this.group = new THREE.Group();
    world.root.add(this.group);
    this.handles = []; // {sphere, material}
    this.ghosts = [];
    this.capture = [null, null]; // per handle: the arm within grasp range, for tests
    this.setupId = 0;
  }

  clear() {
    for (const h of this.handles) h.group.parent?.remove(h.group);
    const dispose = (o) => o.traverse((c) => { c.geometry?.dispose(); c.material?.dispose(); });
    for (const h of this.handles) dispose(h.group);
    for (const c of [...this.group.children]) { dispose(c); this.group.remove(c); }
    for (const g of this.ghosts) g.dispose();
    this.handles = [];
    this.ghosts = [];
    this.panel = null;
    this.targets = [];
    this.current = null;
  }

  /** The current reach marker: opaque, its letter and the step's jaw distance shown. */
  updateTargets(state) {
    if (!this.targets.length) return;
    const ex = state.exercise;
    const step = ex && !ex.done ? this.steps?.[ex.step] : null;
    const want = step?.done_when?.kind === 'tool_at' ? step.done_when : null;
    this.current = null;
    for (const t of this.targets) {
      const on = !!want && want.target === t.id;
      t.material.opacity = on ? 0.75 : 0.22;
      let text = t.id;
      if (on) {
        const p = state.arms[want.arm]?.pose.position;
        const d = p ? Math.hypot(p[0] - t.at[0], p[1] - t.at[1], p[2] - t.at[2]) : NaN;
        text = `${t.id}  ${(100 * d).toFixed(1)} cm`;
        this.current = { id: t.id, distance_m: d };
      }
      t.label.set(text, on);
    }
  }

  /** (Re)builds from a hello (after `World.setup`, which made the box these attach to). */
  setup(hello) {
    this.clear();
    const id = ++this.setupId;
    this.steps = hello.exercise?.steps || null;
    const sc = hello.scene;
    if (!sc) return;
    const box = this.world.object;
    const top = hello.object.size_m[2] / 2;
    (sc.handles_m || []).forEach((h, i) => {
      const g = new THREE.Group();
      g.position.set(h[0], h[1], h[2]);
      const mat = new THREE.MeshLambertMaterial({ color: HANDLE_COLOUR });
      // The bar along its axis (box frame; the side handles along x, the lifting point as sent).
      const axis = new THREE.Vector3(...(sc.handle_axes?.[i] || [1, 0, 0])).normalize();
      const bar = new THREE.Mesh(new THREE.CylinderGeometry(HANDLE_RADIUS_M, HANDLE_RADIUS_M, HANDLE_LENGTH_M, 12), mat);
      bar.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), axis); // cylinder axis y → bar
      g.add(bar);
      const rise = h[2] - top; // posts from the top face up to the bar
      const centre = sc.handle_posts?.[i] === 'centre';
      // A grab handle stands on two thin end posts; the lifting point (a T-handle) on one
      // post under its centre, as thick as the collision shape (0.015 m).
      for (const s of centre ? [0] : [-1, 1]) {
        const r = centre ? 0.015 : 0.008;
        const post = new THREE.Mesh(new THREE.CylinderGeometry(r, r, rise, 8), mat);
        post.rotation.x = Math.PI / 2;
        post.position.copy(axis.clone().multiplyScalar(s * HANDLE_LENGTH_M / 2));
        post.position.z = -rise / 2;
        g.add(post);
      }
      const material = translucent(HANDLE_COLOUR, 0.12);
      const sphere = new THREE.Mesh(new THREE.SphereGeometry(sc.capture_radius_m, 20, 14), material);
      g.add(sphere);
      box.add(g);
      this.handles.push({ group: g, sphere, material });
    });
    this.targets = [];
    for (const t of sc.targets || []) {
      const material = translucent(TARGET_COLOUR, 0.3);
      const m = new THREE.Mesh(new THREE.SphereGeometry(Math.max(MIN_MARKER_RADIUS_M, t.radius_m), 20, 14), material);
      m.position.set(...t.position_m);
      m.add(new THREE.Mesh(new THREE.SphereGeometry(0.008, 8, 6), new THREE.MeshBasicMaterial({ color: TARGET_COLOUR })));
      const label = new Label(t.id);
      label.sprite.position.set(0, 0, Math.max(MIN_MARKER_RADIUS_M, t.radius_m) + 0.05);
      m.add(label.sprite);
      this.group.add(m);
      this.targets.push({ id: t.id, at: t.position_m, mesh: m, material, label });
    }
    this.current = null;
    for (const z of sc.zones || []) {
      const geom = new THREE.PlaneGeometry(2 * z.half_size_m[0], 2 * z.half_size_m[1]);
      const m = new THREE.Mesh(geom, translucent(ZONE_COLOUR, 0.3));
      m.position.set(z.center_m[0], z.center_m[1], hello.seabed_z_m + 0.004);
      m.add(new THREE.LineSegments(new THREE.EdgesGeometry(geom), new THREE.LineBasicMaterial({ color: ZONE_EDGE_COLOUR })));
      this.group.add(m);
    }
    for (const o of sc.obstacles || []) {
      const geom = new THREE.BoxGeometry(...o.half_size_m.map((h) => 2 * h));
      const m = new THREE.Mesh(geom, translucent(OBSTACLE_COLOUR, 0.4));
      m.position.set(...o.center_m);
      m.add(new THREE.LineSegments(new THREE.EdgesGeometry(geom), new THREE.LineBasicMaterial({ color: OBSTACLE_COLOUR })));
      this.group.add(m);
    }
    for (const g of sc.ghosts || []) this.addGhost(hello, g, id);
    if (sc.panel) this.addPanel(sc.panel, sc.capture_radius_m);
  }

  /** The intervention panel: plate, quarter-turn T-bar valve, receptacle and holster rings,
   * and the hot stab (moved by each frame's `panel`). World frame; the items' axes are +x. */
  addPanel(p, captureRadius) {
    const plate = new THREE.Mesh(new THREE.BoxGeometry(...p.size_m), new THREE.MeshLambertMaterial({ color: 0xe8c547 }));
    plate.matrixAutoUpdate = false;
    plate.matrix.copy(poseToMatrix(p.pose));
    plate.matrix.multiply(new THREE.Matrix4().makeTranslation(p.size_m[0] / 2, 0, 0)); // face at the frame origin
    this.group.add(plate);
    const face = p.pose.position[0];
    const steel = new THREE.MeshLambertMaterial({ color: 0xb0b8c0 });
    // Valve: a stem from the face to the grip point and the T-bar, turned by the valve angle.
    const valve = new THREE.Group();
    valve.position.set(...p.valve_grip_m);
    const stemLength = face - p.valve_grip_m[0];
    const stem = new THREE.Mesh(new THREE.CylinderGeometry(0.012, 0.012, stemLength, 10), steel);
    stem.rotation.z = Math.PI / 2;
    stem.position.x = stemLength / 2;
    valve.add(stem);
    const bar = new THREE.Group();
    bar.add(new THREE.Mesh(new THREE.CylinderGeometry(0.015, 0.015, 0.16, 10), new THREE.MeshLambertMaterial({ color: HANDLE_COLOUR })));
    valve.add(bar);
    const valveCue = translucent(HANDLE_COLOUR, 0.12);
    valve.add(new THREE.Mesh(new THREE.SphereGeometry(captureRadius, 20, 14), valveCue));
    this.group.add(valve);
    for (const mouth of [p.receptacle_m, p.holster_m]) {
      const ring = new THREE.Mesh(new THREE.TorusGeometry(0.03, 0.006, 8, 24), steel);
      ring.rotation.y = Math.PI / 2;
      ring.position.set(mouth[0] - 0.002, mouth[1], mouth[2]);
      this.group.add(ring);
    }
    // Hot stab: a cylinder along its pose's x axis with a cue sphere at its handle end.
    const stab = new THREE.Group();
    stab.matrixAutoUpdate = false;
    const body = new THREE.Mesh(new THREE.CylinderGeometry(0.02, 0.02, 0.14, 12), new THREE.MeshLambertMaterial({ color: 0xff8c1a }));
    body.rotation.z = Math.PI / 2;
    stab.add(body);
    const stabCue = translucent(HANDLE_COLOUR, 0.12);
    stab.add(new THREE.Mesh(new THREE.SphereGeometry(captureRadius, 20, 14), stabCue));
    this.group.add(stab);
    this.panel = { bar, stab, cues: { valve: valveCue, stab: stabCue } };
  }

  /** A see-through arm at the ghost's joint angles (frames from POST /api/analysis). */
  async addGhost(hello, ghost, id) {
    const i = SIDES.indexOf(ghost.arm);
    if (i < 0) return;
    const spec = hello.arms[i];
    const q = ghost.q_deg.map((d) => d * Math.PI / 180);
    const a = await analysis({ robot: spec.model, q });
    if (!a) return;
    if (id !== this.setupId) return; // a newer hello arrived meanwhile
    const base = poseToMatrix(spec.base);
    const world = (p) => matrixToPose(base.clone().multiply(poseToMatrix(p)));
    const arm = new Arm(spec, this.group, `ghost-${ghost.arm}`, true);
    arm.update({ q, joint_frames: a.joint_frames.map(world), pose: world(a.pose), jaw_opening_m: 0.05 });
    this.ghosts.push(arm);
    this.redraw();
  }

  /** Capture cue from a state frame: a handle's sphere lights when a jaw can grasp it. The
   * current reach marker (the step's `tool_at` target) is highlighted with its distance to
   * the step's jaw. */
  update(state) {
    this.updateTargets(state);
    if (this.panel && state.panel) {
      this.panel.bar.rotation.x = state.panel.valve_angle_deg * Math.PI / 180;
      this.panel.stab.matrix.copy(poseToMatrix(state.panel.stab_pose));
      for (const [item, m] of Object.entries(this.panel.cues)) {
        const lit = SIDES.some((s) => state.arms[s].capture === item);
        m.color.setHex(lit ? CAPTURE_COLOUR : HANDLE_COLOUR);
        m.opacity = lit ? 0.45 : 0.12;
      }
    }
    this.handles.forEach((h, i) => {
      const by = SIDES.find((s) => state.arms[s].capture === `handle-${i}`) || null;
      if (by === this.capture[i]) return;
      this.capture[i] = by;
      h.material.color.setHex(by ? CAPTURE_COLOUR : HANDLE_COLOUR);
      h.material.opacity = by ? 0.45 : 0.12;
    });
  }
}
