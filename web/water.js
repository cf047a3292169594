// Murky water in the pilot views (issue 28): distance fog for a visibility in metres, the
// vehicle's lights (spot lights with a limited cone and inverse-square falloff), backscatter
// (a light Points cloud of suspended particles drifting with the current) and silt clouds
// where anything touches the seabed — derived from what the state frame carries (the box's
// pose and size, every drawn arm point) against hello.seabed_z_m, drifting with
// `frame.current` and settling. A picture only: no physics here, every pose is the server's.
// The engineering views (top/front/side/perspective) draw without any of it.

import * as THREE from 'three';
import { poseToMatrix } from './scene.js';
import { vehicleFrame } from './cameras.js';

/** Default visibility (m): the toolbar's starting value (murky coastal water; clear ocean
 * water gives tens of metres). */
export const DEFAULT_VISIBILITY_M = 6;
/** Colour of the water: the fog and the views' background. */
export const WATER_COLOUR = 0x0d3338;
/** Contrast left at the visibility distance (the usual 2 % threshold of the meteorological
 * visibility, Koschmieder): three's FogExp2 fades as 1 − exp(−(d·r)²), so
 * d = sqrt(−ln 0.02) / visibility. */
const CONTRAST_AT_VISIBILITY = 0.02;
/** A corner of the box this close to the seabed (m) touches it. */
export const SILT_CONTACT_M = 0.01;
/** Speed along the seabed (m/s) above which a touching point keeps stirring silt up. */
const STIR_SPEED_M_S = 0.02;
const SILT_MAX = 1500;
const SILT_LIFE_S = 12;
const SILT_BURST = 90;
const SILT_COLOUR = new THREE.Color(0xb3a27a);
/** Silt settles at about a centimetre per second (fine silt, Stokes); it rises first from the
 * strike's kick and drifts with the water (relaxing to the current in ~1.5 s). */
const SETTLE_M_S = 0.01;
const DRIFT_TAU_S = 1.5;
const BACKSCATTER_COUNT = 600;

/** Fog density of THREE.FogExp2 for a visibility in metres. */
export function fogDensity(visibility_m) {
  return Math.sqrt(-Math.log(CONTRAST_AT_VISIBILITY)) / Math.max(0.2, visibility_m);
}

/** The water's velocity (m/s, world) from a frame's `current` ({speed_m_s, heading_deg}). */
function currentVelocity(cur, out) {
  if (!cur || !(cur.speed_m_s > 0)) return out.set(0, 0, 0);
  const a = (cur.heading_deg * Math.PI) / 180;
  return out.set(Math.cos(a) * cur.speed_m_s, Math.sin(a) * cur.speed_m_s, 0);
}

const _m = new THREE.Matrix4(), _v = new THREE.Vector3();

/**
 * Points of a state frame that touch the seabed: [{key, at: [x, y, z], moving}] — the box's
 * corners (pose and `size_m`) within SILT_CONTACT_M of `seabed_z_m`, and each arm's contact
 * with the seabed as the server reports it (`arms.*.touch`). `prev` (the previous frame's
 * points by key) gives the arm points' speed; the box's comes from the frame's
 * `object.velocity`.
 */
export function seabedContacts(state, hello, prev = new Map()) {
  const z0 = hello.seabed_z_m;
  const out = [];
  const points = new Map();
  const s = hello.object.size_m;
  poseToMatrix(state.object.pose, _m);
  const ov = state.object.velocity || [0, 0, 0];
  const boxMoving = Math.hypot(ov[0], ov[1]) > STIR_SPEED_M_S;
  let k = 0;
  for (const sx of [-1, 1]) for (const sy of [-1, 1]) for (const sz of [-1, 1]) {
    const p = _v.set(sx * s[0] / 2, sy * s[1] / 2, sz * s[2] / 2).applyMatrix4(_m);
    const key = `box${k++}`;
    points.set(key, p.toArray());
    if (p.z - z0 < SILT_CONTACT_M) out.push({ key, at: p.toArray(), moving: boxMoving });
  }
  // an arm on the seabed: the server's contact (`arms.*.touch`, the strongest of the arm's
  // contact points; sim/contact.rs)
  for (const side of ['left', 'right']) {
    const t = state.arms[side].touch;
    if (!t || t.partner !== 'seabed') continue;
    const key = side;
    points.set(key, t.point_m);
    const q = prev.get(key);
    const moving = !!q && Math.hypot(t.point_m[0] - q[0], t.point_m[1] - q[1]) > 0.002; // a frame apart
    out.push({ key, at: t.point_m.slice(), moving });
  }
  out.points = points;
  return out;
}

export class Water {
  /** Adds the water's parts to `world` (web/scene.js); all hidden until `show(true)`. */
  constructor(world) {
    this.world = world;
    this.visibility_m = DEFAULT_VISIBILITY_M;
    this.fog = new THREE.FogExp2(WATER_COLOUR, fogDensity(this.visibility_m));
    this.group = new THREE.Group();
    this.group.visible = false;
    world.root.add(this.group);
    // the vehicle's two lamps beside the main camera, and a small lamp on each wrist camera
    // (angle: half the cone; decay 2: inverse-square falloff; intensity in candela)
    const spot = (intensity, angle) => {
      const l = new THREE.SpotLight(0xfff4e0, intensity, 0, angle, 0.35, 2);
      this.group.add(l, l.target);
      return l;
    };
    this.lamps = [spot(14, 0.5), spot(14, 0.5)];
    this.wristLamps = { left: spot(1.2, 0.6), right: spot(1.2, 0.6) };
    this.current = new THREE.Vector3();
    // backscatter: suspended particles in the water in front of the vehicle
    this.scatter = this.points(BACKSCATTER_COUNT, 0xcfe3dc, 0.007, 0.5);
    this.scatterVel = new Float32Array(BACKSCATTER_COUNT * 3);
    // silt: a pool of particles, each alive for SILT_LIFE_S after a strike
    this.silt = this.points(SILT_MAX, 0xffffff, 0.05, 1, true);
    this.siltVel = new Float32Array(SILT_MAX * 3);
    this.siltAge = new Float32Array(SILT_MAX).fill(Infinity);
    this.siltNext = 0;
    this.siltEmitted = 0; // particles ever emitted, for tests
    this.prevPoints = null;
    this.touching = new Set();
    this.hello = null;
    this.rand = mulberry32(28);
  }

  points(n, colour, size, opacity, perVertexAlpha = false) {
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(new Float32Array(n * 3), 3));
    const mat = new THREE.PointsMaterial({ color: colour, size, transparent: true, opacity, depthWrite: false, sizeAttenuation: true });
    if (perVertexAlpha) {
      g.setAttribute('color', new THREE.BufferAttribute(new Float32Array(n * 4), 4));
      mat.vertexColors = true;
    }
    const p = new THREE.Points(g, mat);
    p.frustumCulled = false;
    this.group.add(p);
    return p;
  }

  setVisibility(m) {
    this.visibility_m = m;
    this.fog.density = fogDensity(m);
  }

  /** The static parts from a hello: lamps on the vehicle, the backscatter's box. */
  setup(hello) {
    this.hello = hello;
    const veh = vehicleFrame(hello);
    this.lamps.forEach((l, i) => {
      l.position.set(-0.05, i ? -0.45 : 0.45, 0.35).applyMatrix4(veh);
      l.target.position.set(1.4, 0, -0.2).applyMatrix4(veh);
      l.target.updateMatrixWorld();
    });
    // backscatter box (vehicle frame): 0.1–2.3 m ahead, ±1 m across, seabed to 0.9 m up
    const pos = this.scatter.geometry.attributes.position.array;
    const zLow = hello.seabed_z_m - veh.elements[14];
    this.scatterBox = { veh, min: [0.1, -1, zLow], max: [2.3, 1, 0.9] };
    for (let i = 0; i < BACKSCATTER_COUNT; i++) {
      for (let c = 0; c < 3; c++) pos[3 * i + c] = this.scatterBox.min[c] + this.rand() * (this.scatterBox.max[c] - this.scatterBox.min[c]);
      for (let c = 0; c < 3; c++) this.scatterVel[3 * i + c] = (this.rand() - 0.5) * 0.01;
    }
    this.scatter.matrixAutoUpdate = false;
    this.scatter.matrix.copy(veh);
    this.scatter.geometry.attributes.position.needsUpdate = true;
    this.siltAge.fill(Infinity);
    this.prevPoints = null;
    this.touching.clear();
  }

  /** A state frame: wrist lamps follow the jaws; new seabed touches raise silt. */
  update(state) {
    if (!this.hello) return;
    currentVelocity(state.current, this.current);
    for (const side of ['left', 'right']) {
      poseToMatrix(state.arms[side].pose, _m);
      const l = this.wristLamps[side];
      l.position.set(-0.08, 0, -0.1).applyMatrix4(_m);
      l.target.position.set(0, 0, 0.5).applyMatrix4(_m);
      l.target.updateMatrixWorld();
    }
    const contacts = seabedContacts(state, this.hello, this.prevPoints || undefined);
    const now = new Set();
    for (const c of contacts) {
      now.add(c.key);
      // the first frame only learns what already rests on the seabed (the box at the start)
      if (this.prevPoints && !this.touching.has(c.key)) this.emit(c.at, SILT_BURST, 0.12);
      else if (c.moving) this.emit(c.at, 6, 0.06);
    }
    this.touching = now;
    this.prevPoints = contacts.points;
  }

  /** `n` silt particles kicked up at `at` (world), outward and up at about `kick` m/s. */
  emit(at, n, kick) {
    const pos = this.silt.geometry.attributes.position.array;
    for (let k = 0; k < n; k++) {
      const i = this.siltNext;
      this.siltNext = (this.siltNext + 1) % SILT_MAX;
      const a = this.rand() * 2 * Math.PI, r = 0.02 * this.rand();
      pos[3 * i] = at[0] + r * Math.cos(a);
      pos[3 * i + 1] = at[1] + r * Math.sin(a);
      pos[3 * i + 2] = this.hello.seabed_z_m + 0.01;
      const s = kick * (0.4 + this.rand());
      this.siltVel[3 * i] = s * Math.cos(a);
      this.siltVel[3 * i + 1] = s * Math.sin(a);
      this.siltVel[3 * i + 2] = kick * (0.5 + this.rand());
      this.siltAge[i] = 0;
    }
    this.siltEmitted += n;
  }

  /** Animates the particles by `dt_s`; returns true while anything moves (a redraw). */
  step(dt_s) {
    if (!this.hello) return false;
    const dt = Math.min(dt_s, 0.1);
    const cur = this.current;
    // backscatter drifts with the current (vehicle frame ≈ world axes here) and wraps round
    const sp = this.scatter.geometry.attributes.position.array, b = this.scatterBox;
    const cv = [cur.x, cur.y, cur.z];
    for (let i = 0; i < BACKSCATTER_COUNT; i++) {
      for (let c = 0; c < 3; c++) {
        let v = sp[3 * i + c] + (cv[c] + this.scatterVel[3 * i + c]) * dt;
        const lo = b.min[c], hi = b.max[c];
        if (v < lo) v += hi - lo; else if (v > hi) v -= hi - lo;
        sp[3 * i + c] = v;
      }
    }
    this.scatter.geometry.attributes.position.needsUpdate = true;
    // silt: rises from the kick, relaxes to the current sideways and to settling downwards
    const p = this.silt.geometry.attributes.position.array;
    const col = this.silt.geometry.attributes.color.array;
    const floor = this.hello.seabed_z_m + 0.004;
    const relax = Math.min(1, dt / DRIFT_TAU_S);
    for (let i = 0; i < SILT_MAX; i++) {
      const age = (this.siltAge[i] += dt);
      const alpha = age < SILT_LIFE_S ? 0.85 * (1 - age / SILT_LIFE_S) : 0;
      col[4 * i] = SILT_COLOUR.r; col[4 * i + 1] = SILT_COLOUR.g; col[4 * i + 2] = SILT_COLOUR.b; col[4 * i + 3] = alpha;
      if (!(alpha > 0)) continue;
      const v = this.siltVel;
      v[3 * i] += (cur.x - v[3 * i]) * relax;
      v[3 * i + 1] += (cur.y - v[3 * i + 1]) * relax;
      v[3 * i + 2] += (-SETTLE_M_S - v[3 * i + 2]) * relax;
      p[3 * i] += v[3 * i] * dt;
      p[3 * i + 1] += v[3 * i + 1] * dt;
      p[3 * i + 2] = Math.max(floor, p[3 * i + 2] + v[3 * i + 2] * dt);
    }
    this.silt.geometry.attributes.position.needsUpdate = true;
    this.silt.geometry.attributes.color.needsUpdate = true;
    return true;
  }

  /** Silt particles now in the water (for tests and the status). */
  siltAlive() { let n = 0; for (const a of this.siltAge) if (a < SILT_LIFE_S) n++; return n; }

  /** Before drawing a view: the water on (a pilot view) or off (an engineering view). */
  show(on) {
    this.group.visible = on;
    this.world.scene.fog = on ? this.fog : null;
    this.world.setDaylight(!on);
  }
}

/** A small seeded generator (the picture is the same on every run). */
function mulberry32(a) {
  return () => {
    a |= 0; a = (a + 0x6d2b79f5) | 0;
    let t = Math.imul(a ^ (a >>> 15), 1 | a);
    t = (t + Math.imul(t ^ (t >>> 7), 61 | t)) ^ t;
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}
