// What an exercise shows in 3D besides the arms and the box, from the hello's `scene`
// (docs/exercises.md): the box's handles (the only places a jaw can grasp) with their capture
// spheres, lit when a jaw is within grasp range (the frame's `arms.*.capture`); floating
// targets; zones on the seabed; obstacles; and ghost arms at the joint angles to reach (their
// joint frames from POST /api/analysis: the server's kinematics, as for the live arms).

import * as THREE from 'three';
import { poseToMatrix } from './scene.js';
import { Arm } from './arms.js';
import { analysis } from './api.js';

const HANDLE_COLOUR = 0x19c3d6; // cyan: far in hue from the arms' orange and the grasp colours
const CAPTURE_COLOUR = 0x3cff6e; // green: a closing jaw would grasp
const TARGET_COLOUR = 0xff4fd8;
const ZONE_COLOUR = 0x3cff6e;
const OBSTACLE_COLOUR = 0xd03030;
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
  }

  /** (Re)builds from a hello (after `World.setup`, which made the box these attach to). */
  setup(hello) {
    this.clear();
    const id = ++this.setupId;
    const sc = hello.scene;
    if (!sc) return;
    const box = this.world.object;
    const top = hello.object.size_m[2] / 2;
    (sc.handles_m || []).forEach((h) => {
      const g = new THREE.Group();
      g.position.set(h[0], h[1], h[2]);
      const mat = new THREE.MeshLambertMaterial({ color: HANDLE_COLOUR });
      const bar = new THREE.Mesh(new THREE.CylinderGeometry(HANDLE_RADIUS_M, HANDLE_RADIUS_M, HANDLE_LENGTH_M, 12), mat);
      bar.rotation.z = Math.PI / 2; // cylinder axis y → x
      g.add(bar);
      const rise = h[2] - top; // posts from the top face up to the bar
      for (const sx of [-1, 1]) {
        const post = new THREE.Mesh(new THREE.CylinderGeometry(0.008, 0.008, rise, 8), mat);
        post.rotation.x = Math.PI / 2;
        post.position.set(sx * HANDLE_LENGTH_M / 2, 0, -rise / 2);
        g.add(post);
      }
      const material = translucent(HANDLE_COLOUR, 0.12);
      const sphere = new THREE.Mesh(new THREE.SphereGeometry(sc.capture_radius_m, 20, 14), material);
      g.add(sphere);
      box.add(g);
      this.handles.push({ group: g, sphere, material });
    });
    for (const t of sc.targets || []) {
      const m = new THREE.Mesh(new THREE.SphereGeometry(t.radius_m, 20, 14), translucent(TARGET_COLOUR, 0.45));
      m.position.set(...t.position_m);
      m.add(new THREE.Mesh(new THREE.SphereGeometry(Math.min(0.006, t.radius_m / 3), 8, 6), new THREE.MeshBasicMaterial({ color: TARGET_COLOUR })));
      this.group.add(m);
    }
    for (const z of sc.zones || []) {
      const geom = new THREE.PlaneGeometry(2 * z.half_size_m[0], 2 * z.half_size_m[1]);
      const m = new THREE.Mesh(geom, translucent(ZONE_COLOUR, 0.3));
      m.position.set(z.center_m[0], z.center_m[1], hello.seabed_z_m + 0.004);
      m.add(new THREE.LineSegments(new THREE.EdgesGeometry(geom), new THREE.LineBasicMaterial({ color: ZONE_COLOUR })));
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

  /** Capture cue from a state frame: a handle's sphere lights when a jaw can grasp it. */
  update(state) {
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
