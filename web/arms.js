// The two Magnum arms, drawn procedurally from what the server sends: each link is a tube
// between consecutive joint-frame origins of the state frame (so its length is the model's DH
// a/d), each joint a housing along its axis (frame z), hydraulic cylinders between an anchor on
// the link before a joint and one on the link after it (their length follows the joint), and
// the jaws opened to `jaw_opening_m`. No kinematics here: the poses are the server's.

import * as THREE from 'three';
import { poseToMatrix } from './scene.js';

export const ARM_COLOUR = 0xe8590c; // safety orange, far in hue from every grasp colour
const HOUSING_COLOUR = 0x9a4a12;
const BARREL_COLOUR = 0x4a5560;
const ROD_COLOUR = 0xe8eef4;
const JAW_COLOUR = 0x30343a;

const UNIT_CYL = new THREE.CylinderGeometry(1, 1, 1, 16); // along +y, unit radius and length
const UNIT_BOX = new THREE.BoxGeometry(1, 1, 1);

const _a = new THREE.Vector3(), _b = new THREE.Vector3(), _d = new THREE.Vector3();
const _x = new THREE.Vector3(), _z = new THREE.Vector3(), _m = new THREE.Matrix4();
const _e = new THREE.Vector3();
const _pre = new THREE.Matrix4(), _rz = new THREE.Matrix4(), _inv = new THREE.Matrix4();

/** Sets `mesh.matrix` to a cylinder of radius r from a to b. */
function tube(mesh, a, b, r) {
  _d.subVectors(b, a);
  const len = Math.max(_d.length(), 1e-4);
  _d.multiplyScalar(1 / len);
  // any unit vector perpendicular to d
  _x.set(1, 0, 0);
  if (Math.abs(_d.x) > 0.9) _x.set(0, 1, 0);
  _z.crossVectors(_x, _d).normalize();
  _x.crossVectors(_d, _z).normalize();
  mesh.matrix.makeBasis(_x.multiplyScalar(r), _d.multiplyScalar(len), _z.multiplyScalar(r));
  mesh.matrix.setPosition((a.x + b.x) / 2, (a.y + b.y) / 2, (a.z + b.z) / 2);
  mesh.matrixWorldNeedsUpdate = true;
}

/** The see-through material of a ghost arm (a posture to reach). */
export const GHOST_MATERIAL = new THREE.MeshBasicMaterial({ color: 0xbfefff, transparent: true, opacity: 0.28, depthWrite: false });
/** Glow of the selected arm's links (added to their lit colour). */
const SELECTED_EMISSIVE = 0x5a2a00;

function partOf(geom, colour, parent, material = null) {
  const m = new THREE.Mesh(geom, material || new THREE.MeshLambertMaterial({ color: colour }));
  m.matrixAutoUpdate = false;
  parent.add(m);
  return m;
}

/** Anchor in a joint's plane: radius along unit direction (dx, dy), then sideways. */
function anchor(dx, dy, radius, side) {
  return new THREE.Vector3(dx * radius - dy * side, dy * radius + dx * side, 0);
}

/** Unit 2D direction of a local point projected on the joint plane (or a default). */
function planeDir(v, fallback) {
  const l = Math.hypot(v.x, v.y);
  return l < 0.03 ? fallback : [v.x / l, v.y / l];
}

/** Farthest a cylinder's rod end sits from its joint (m), along the driven link. */
const ROD_REACH_M = 0.3;
/** Share of the driven link's length (in the joint plane) the rod end may use at most. */
const ROD_REACH_SHARE = 0.6;

export class Arm {
  /**
   * @param spec hello.arms[i]: {model, base}
   * @param ghost true: drawn see-through (a posture to reach), not lit
   */
  constructor(spec, parent, name, ghost = false) {
    this.name = name;
    this.ghost = ghost;
    this.group = new THREE.Group();
    parent.add(this.group);
    const part = (geom, colour, group) => partOf(geom, colour, group, ghost ? GHOST_MATERIAL : null);
    this.n = spec.model.joints.length;
    this.q = new Array(this.n).fill(0);
    this.pedestal = part(UNIT_CYL, 0x3b4652, this.group);
    this.basePos = new THREE.Vector3(...spec.base.position);
    this.links = [];
    this.housings = [];
    this.barrels = [];
    this.rods = [];
    this.anchors = null; // per joint [A in the pre-motion frame, B in the joint frame], lazily
    for (let i = 0; i < this.n; i++) {
      this.links.push(part(UNIT_CYL, ARM_COLOUR, this.group));
      this.housings.push(part(UNIT_CYL, i === this.n - 1 ? JAW_COLOUR : HOUSING_COLOUR, this.group));
      if (i < this.n - 1) { // joints 1-5 are cylinder driven; the last (rotate) is a rotary motor
        this.barrels.push(part(UNIT_CYL, BARREL_COLOUR, this.group));
        this.rods.push(part(UNIT_CYL, ROD_COLOUR, this.group));
      }
    }
    this.rotMark = part(UNIT_BOX, 0xffffff, this.group);
    // the selection mark: a ring round the pedestal (placed in update)
    this.ring = ghost ? null : partOf(new THREE.TorusGeometry(0.16, 0.018, 8, 32), 0, this.group,
      new THREE.MeshBasicMaterial({ color: 0xffd700 }));
    if (this.ring) this.ring.visible = false;
    this.wrist = part(UNIT_BOX, JAW_COLOUR, this.group);
    this.fingers = [part(UNIT_BOX, JAW_COLOUR, this.group), part(UNIT_BOX, JAW_COLOUR, this.group)];
    this.frames = [];
    for (let i = 0; i < this.n; i++) this.frames.push(new THREE.Matrix4());
    this.tool = new THREE.Matrix4();
    this.origins = Array.from({ length: this.n + 1 }, () => new THREE.Vector3());
  }

  /** Marks the arm the sticks drive: its links glow and a ring circles its pedestal. */
  setSelected(on) {
    if (this.ghost) return;
    this.selected = on;
    for (const l of this.links) l.material.emissive.setHex(on ? SELECTED_EMISSIVE : 0);
    this.ring.visible = on;
  }

  computeAnchors() {
    const o = this.origins;
    this.anchors = [];
    for (let k = 0; k < this.n - 1; k++) {
      _pre.copy(this.frames[k]).multiply(_rz.makeRotationZ(-this.q[k]));
      _inv.copy(_pre).invert();
      const back = planeDir(_a.copy(k > 0 ? o[k - 1] : this.basePos.clone().setZ(o[0].z - 0.3)).applyMatrix4(_inv), [-1, 0]);
      _inv.copy(this.frames[k]).invert();
      // the rod end on the driven link: toward the first later origin off the joint axis (a
      // wrist joint's own link may have zero length; o[n] is the tool point), within the
      // link, so a short link (the pitch link, the yaw joint's) keeps its rod on the arm
      let j = k + 1;
      while (j < this.n && Math.hypot(..._b.copy(o[j]).applyMatrix4(_inv).toArray().slice(0, 2)) < 0.03) j++;
      _b.copy(o[j]).applyMatrix4(_inv);
      const fwd = planeDir(_b, [1, 0]);
      const reach = Math.min(ROD_REACH_M, ROD_REACH_SHARE * Math.hypot(_b.x, _b.y));
      const side = 0.075;
      this.anchors.push([anchor(back[0], back[1], 0.13, side), anchor(fwd[0], fwd[1], Math.max(reach, 0.05), -side)]);
    }
  }

  /** Places every part from one arm of a state frame. */
  update(af) {
    const n = this.n, o = this.origins;
    for (let i = 0; i < n; i++) {
      this.q[i] = af.q[i];
      poseToMatrix(af.joint_frames[i], this.frames[i]);
      o[i].setFromMatrixPosition(this.frames[i]);
    }
    poseToMatrix(af.pose, this.tool);
    o[n].setFromMatrixPosition(this.tool);
    if (!this.anchors) this.computeAnchors();

    // pedestal from the seabed side up to the first joint
    _a.copy(o[0]); _a.z -= 0.35;
    tube(this.pedestal, _a, _b.copy(o[0]).setZ(o[0].z - 0.05), 0.09);
    if (this.ring) {
      this.ring.matrix.makeTranslation(o[0].x, o[0].y, o[0].z - 0.2);
      this.ring.matrixWorldNeedsUpdate = true;
    }
    const radii = [0.06, 0.045, 0.04, 0.035, 0.032, 0.03];
    for (let i = 0; i < n; i++) {
      const end = i < n - 1 ? o[i + 1] : _d.set(0, 0, -0.05).applyMatrix4(this.tool);
      tube(this.links[i], o[i], i < n - 1 ? end : _b.copy(end), radii[Math.min(i, 5)]);
      // housing along the joint axis (frame z)
      const h = this.housings[i];
      const len = i === n - 1 ? 0.08 : 0.13, r = i === n - 1 ? 0.04 : 0.055;
      h.matrix.copy(this.frames[i]).multiply(_m.makeRotationX(Math.PI / 2))
        .multiply(_rz.makeScale(r, len, r));
      h.matrixWorldNeedsUpdate = true;
    }
    // hydraulic cylinders (joints 1-5)
    for (let k = 0; k < n - 1; k++) {
      const [A, B] = this.anchors[k];
      _pre.copy(this.frames[k]).multiply(_rz.makeRotationZ(-this.q[k]));
      _a.copy(A).applyMatrix4(_pre);
      _b.copy(B).applyMatrix4(this.frames[k]);
      const full = _a.distanceTo(_b);
      tube(this.rods[k], _a, _b, 0.011);
      _e.subVectors(_b, _a).multiplyScalar(Math.min(0.14 / Math.max(full, 1e-3), 0.8)).add(_a);
      tube(this.barrels[k], _a, _e, 0.024);
    }
    // rotary marker on the rotate joint: turns with q6
    this.rotMark.matrix.copy(this.frames[n - 1])
      .multiply(_m.makeTranslation(0.03, 0, 0.0))
      .multiply(_rz.makeScale(0.03, 0.012, 0.085));
    this.rotMark.matrixWorldNeedsUpdate = true;
    // wrist plate and jaws in the tool frame (z along the jaw, y across the opening)
    this.wrist.matrix.copy(this.tool).multiply(_m.makeTranslation(0, 0, -0.055))
      .multiply(_rz.makeScale(0.09, 0.09, 0.02)); // the collision shape (robots/magnum.json)
    this.wrist.matrixWorldNeedsUpdate = true;
    const half = Math.max(af.jaw_opening_m, 0) / 2 + 0.008;
    for (let s = 0; s < 2; s++) {
      const f = this.fingers[s];
      f.matrix.copy(this.tool).multiply(_m.makeTranslation(0, s ? half : -half, 0))
        .multiply(_rz.makeScale(0.035, 0.016, 0.04)); // the collision shape's size (robots/magnum.json)
      f.matrixWorldNeedsUpdate = true;
    }
  }

  /** Drawn jaw centre (world), read back from the finger meshes: for tests. */
  drawnJawCentre() {
    const a = new THREE.Vector3().setFromMatrixPosition(this.fingers[0].matrix);
    const b = new THREE.Vector3().setFromMatrixPosition(this.fingers[1].matrix);
    return a.add(b).multiplyScalar(0.5).toArray();
  }

  /** Drawn link polyline (joint origins, then the tool point) and each cylinder's rod end
   * (world, m), the ends read back from the rod meshes: for tests. */
  drawnRods() {
    const rodEnds = this.rods.map((r) => { const e = r.matrix.elements; return [0, 1, 2].map((i) => e[12 + i] + 0.5 * e[4 + i]); });
    return { links: this.origins.map((o) => o.toArray()), rodEnds };
  }

  /** Drawn finger separation (m): for tests. */
  drawnJawGap() {
    const a = new THREE.Vector3().setFromMatrixPosition(this.fingers[0].matrix);
    const b = new THREE.Vector3().setFromMatrixPosition(this.fingers[1].matrix);
    return a.distanceTo(b) - 0.016;
  }

  dispose() {
    this.group.traverse((o) => { if (o.material && o.material !== GHOST_MATERIAL) o.material.dispose(); });
    this.ring?.geometry.dispose();
    this.group.parent?.remove(this.group);
  }
}

