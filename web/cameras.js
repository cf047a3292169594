// The pilot cameras as DATA (issue 28): what an ROV operator works through — the vehicle's
// pan-tilt main camera between and above the arm bases, a camera on each wrist, and a fixed
// overview camera. Every camera's field of view, position and orientation is in PILOT_CAMERAS
// below; `placePilotCamera` only turns that data and the server's frames into a camera pose.
//
// Frames:
// - "vehicle": origin midway between the two arm bases (hello.arms[*].base.position), axes
//   those of the left arm's base (the built-in setup's bases are not rotated: x ahead, y to
//   port/left, z up). Positions and look-at points are metres in this frame.
// - "jaw:<side>": that arm's tool frame from each state frame (`arms.<side>.pose`: z along the
//   jaw, y across the opening), so the wrist camera moves with the jaw.

import * as THREE from 'three';
import { poseToMatrix } from './scene.js';

/**
 * Pan-tilt unit of the main camera. Limits and rates are representative of the electric
 * pan-and-tilt units on work-class ROVs (maker datasheets commonly give pan ranges of about
 * ±170° to continuous, tilt of about ±90°, and speeds of a few to about 20 °/s): we take
 * pan ±170° at 20 °/s and tilt −85°…+30° (down is negative; −85° rather than −90° keeps the
 * picture's up defined) at 15 °/s — our reading, not one
 * unit's datasheet. The zoom is a 1×–5× optical zoom (a typical subsea zoom camera has
 * 10×–36×; 5× is enough at arm's length) that runs its whole range in 3 s.
 */
export const PAN_TILT = {
  pan_deg: [-170, 170], pan_rate_deg_s: 20,
  tilt_deg: [-85, 30], tilt_rate_deg_s: 15,
  zoom: [1, 5], zoom_rate_per_s: 4 / 3,
};

/** Each pilot camera: `name` (the viewport's), `title`, `mount` (frame, above), `fov_deg`
 * (vertical, at zoom 1), `position_m` and either `look_at_m` or (the pan-tilt camera) `pan_deg`
 * and `tilt_deg` at rest; `up` (the mount frame's axis that is up on screen). */
export const PILOT_CAMERAS = [
  // Main camera on its pan-tilt unit: 0.45 m above the bases' midpoint and 0.15 m behind them
  // (between the arms' shoulders, as on a work-class ROV's front frame), looking ahead and
  // 18° down at the work site in front of the vehicle.
  { name: 'pilot', title: 'Pilot camera (pan-tilt: drag / L3 + right stick / arrows; wheel: zoom)', mount: 'vehicle',
    position_m: [-0.15, 0, 0.45], pan_deg: 0, tilt_deg: -18, fov_deg: 55, up: [0, 0, 1], panTilt: true },
  // Wrist cameras: 12 cm off the jaw's axis on the wrist plate (tool x), 6 cm behind the jaw
  // centre, looking past the jaw tips (30 cm ahead along tool z); wide angle as such cameras are.
  { name: 'wrist-left', title: 'Left wrist camera', mount: 'jaw:left',
    position_m: [0.12, 0, -0.06], look_at_m: [0, 0, 0.3], fov_deg: 75, up: [1, 0, 0] },
  { name: 'wrist-right', title: 'Right wrist camera', mount: 'jaw:right',
    position_m: [0.12, 0, -0.06], look_at_m: [0, 0, 0.3], fov_deg: 75, up: [1, 0, 0] },
  // A fixed overview camera high on the vehicle's starboard corner, over the whole work site.
  { name: 'overview', title: 'Overview camera (fixed)', mount: 'vehicle',
    position_m: [-0.1, -0.75, 0.85], look_at_m: [1.2, 0, -0.25], fov_deg: 60, up: [0, 0, 1] },
];

const _m = new THREE.Matrix4(), _p = new THREE.Vector3(), _t = new THREE.Vector3(), _u = new THREE.Vector3();

/** The vehicle frame (above) from a hello: a Matrix4 vehicle → world. */
export function vehicleFrame(hello) {
  const m = poseToMatrix({ position: [0, 0, 0], rotation: hello.arms[0].base.rotation });
  const c = new THREE.Vector3();
  for (const a of hello.arms) c.add(new THREE.Vector3(...a.base.position));
  c.multiplyScalar(1 / hello.arms.length);
  return m.setPosition(c);
}

/** The pan-tilt unit's state: angles slew toward their targets at the unit's rates. */
export class PanTilt {
  constructor(spec) {
    this.rest = { pan: spec.pan_deg, tilt: spec.tilt_deg, zoom: 1 };
    this.pan = this.rest.pan; this.tilt = this.rest.tilt; this.zoom = 1;
    this.target = { ...this.rest };
    this.rates = { pan: 0, tilt: 0, zoom: 0 }; // held commands, fractions of the full rates
  }

  /** Held rate commands in [−1, 1] of the unit's rates (sticks, keys); pan + turns left. */
  command(pan, tilt, zoom) { this.rates = { pan, tilt, zoom }; }

  /** Moves the targets by an amount (mouse drag, wheel); the unit follows at its rates. */
  nudge(dPanDeg, dTiltDeg, zoomFactor = 1) {
    this.target.pan += dPanDeg;
    this.target.tilt += dTiltDeg;
    this.target.zoom *= zoomFactor;
    this.clampTarget();
  }

  clampTarget() {
    const t = this.target, L = PAN_TILT;
    t.pan = Math.min(L.pan_deg[1], Math.max(L.pan_deg[0], t.pan));
    t.tilt = Math.min(L.tilt_deg[1], Math.max(L.tilt_deg[0], t.tilt));
    t.zoom = Math.min(L.zoom[1], Math.max(L.zoom[0], t.zoom));
  }

  /** Advances by `dt_s`; returns true when anything moved. */
  step(dt_s) {
    const L = PAN_TILT, r = this.rates, t = this.target;
    if (r.pan || r.tilt || r.zoom) {
      // a held command drives the unit at that share of its rate (the target runs just ahead)
      t.pan = this.pan + r.pan * L.pan_rate_deg_s * dt_s;
      t.tilt = this.tilt + r.tilt * L.tilt_rate_deg_s * dt_s;
      t.zoom = this.zoom + r.zoom * L.zoom_rate_per_s * dt_s;
      this.clampTarget();
    }
    const toward = (v, goal, maxStep) => v + Math.max(-maxStep, Math.min(maxStep, goal - v));
    const before = [this.pan, this.tilt, this.zoom];
    this.pan = toward(this.pan, t.pan, L.pan_rate_deg_s * dt_s);
    this.tilt = toward(this.tilt, t.tilt, L.tilt_rate_deg_s * dt_s);
    this.zoom = toward(this.zoom, t.zoom, L.zoom_rate_per_s * dt_s);
    return before[0] !== this.pan || before[1] !== this.tilt || before[2] !== this.zoom;
  }
}

/**
 * Places `camera` (a PerspectiveCamera) for `spec` (a PILOT_CAMERAS entry): `vehicle` is
 * vehicleFrame(hello), `state` the newest drawn state frame (wrist cameras wait for one),
 * `pt` the PanTilt of a pan-tilt camera. Returns false when it cannot be placed yet.
 */
export function placePilotCamera(camera, spec, vehicle, state, pt) {
  let frame;
  if (spec.mount === 'vehicle') frame = vehicle;
  else {
    const side = spec.mount.split(':')[1];
    if (!state) return false;
    frame = poseToMatrix(state.arms[side].pose, _m);
  }
  _p.fromArray(spec.position_m).applyMatrix4(frame);
  if (spec.panTilt) {
    const pan = (pt.pan * Math.PI) / 180, tilt = (pt.tilt * Math.PI) / 180;
    // pan about the vehicle's z from its x, then tilt up from the horizontal
    _t.set(Math.cos(tilt) * Math.cos(pan), Math.cos(tilt) * Math.sin(pan), Math.sin(tilt))
      .add(_u.fromArray(spec.position_m)).applyMatrix4(frame);
    camera.zoom = pt.zoom;
  } else {
    _t.fromArray(spec.look_at_m).applyMatrix4(frame);
  }
  // the up axis in world: the mount's rotation applied to `up`
  _u.fromArray(spec.up).transformDirection(frame);
  camera.position.copy(_p);
  camera.up.copy(_u);
  camera.lookAt(_t);
  camera.fov = spec.fov_deg;
  camera.updateMatrixWorld();
  return true;
}
