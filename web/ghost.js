// The ghost (issue 30 item 5): an earlier attempt drawn see-through over the one on screen —
// both arms with the ghost material of web/arms.js (no ellipsoids, no lighting, depth-write
// off, so it never hides the work) and the box as a see-through block — time-aligned to the
// clock of the attempt on screen: the state frame's `t`, the simulated seconds since the
// attempt's start (an exercise's clock starts at "Ready": no step passes before it), which in
// the debrief is the replay's time. Poses come from the server's track
// (GET /api/attempts/{id}/track, 10 Hz, docs/api.md), interpolated linearly between samples
// (positions and rotation entries: at 10 Hz the blend of two rotations is indistinguishable
// from the rotation between them); after the track's end the last pose holds.

import * as THREE from 'three';
import { Arm, GHOST_MATERIAL } from './arms.js';
import { poseToMatrix } from './scene.js';

const SIDES = ['left', 'right'];

/** A pose as the frames carry it, to interpolate into. */
const newPose = () => ({ position: [0, 0, 0], rotation: [[1, 0, 0], [0, 1, 0], [0, 0, 1]] });

/** Sets `dst` to the pose between the track's 12-number poses `a` and `b` at fraction `f`. */
function lerpPose(dst, a, b, f) {
  for (let i = 0; i < 3; i++) {
    dst.position[i] = a[i] + f * (b[i] - a[i]);
    for (let j = 0; j < 3; j++) dst.rotation[i][j] = a[3 + 3 * i + j] + f * (b[3 + 3 * i + j] - a[3 + 3 * i + j]);
  }
}

export class Ghost {
  /** @param view the page's View (web/view.js): the ghost draws after each of its states */
  constructor(view) {
    this.view = view;
    this.hello = view.hello; // set again by every hello (View.setHello)
    this.track = null;
    this.arms = null;
    this.box = null;
    this.i = 0; // the sample at or before the last time drawn
    this.t = null; // the last time drawn (s)
    // the frames the arms are drawn from (Arm.update reads q, joint_frames, pose, jaw_opening_m)
    this.frames = SIDES.map(() => ({ q: [0, 0, 0, 0, 0, 0], jaw_opening_m: 0, joint_frames: [], pose: newPose() }));
    this.boxPose = newPose();
    view.overlays.add(this);
  }

  /** The attempt drawn, or null. */
  get attempt() { return this.track?.attempt ?? null; }

  setHello(hello) {
    this.hello = hello;
    this.build();
  }

  /** Draws `track` (GET /api/attempts/{id}/track's answer) from now on; null: no ghost. */
  show(track) {
    this.track = track?.samples?.length ? track : null;
    this.i = 0;
    this.build();
    if (this.arms) this.poseAt(this.view.drawn?.t ?? 0);
    this.view.viewports.dirty = true;
  }

  clear() { this.show(null); }

  build() {
    for (const a of this.arms || []) a.dispose();
    if (this.box) { this.box.parent?.remove(this.box); this.box.geometry.dispose(); }
    this.arms = null;
    this.box = null;
    this.t = null;
    if (!this.hello || !this.track) return;
    const root = this.view.world.root;
    this.arms = this.hello.arms.map((spec, k) => new Arm(spec, root, `ghost-track-${SIDES[k]}`, true));
    const n = this.arms[0].n;
    for (const f of this.frames) f.joint_frames = Array.from({ length: n }, newPose);
    const size = this.hello.object?.size_m;
    if (size) {
      this.box = new THREE.Mesh(new THREE.BoxGeometry(size[0], size[1], size[2]), GHOST_MATERIAL);
      this.box.name = 'ghost-track-box';
      this.box.matrixAutoUpdate = false;
      root.add(this.box);
    }
  }

  /** After each drawn state: the ghost at the state's time. */
  update(s) {
    if (this.arms) this.poseAt(s.t);
  }

  /** Places the ghost at time `t` (s since the attempt's start). */
  poseAt(t) {
    const S = this.track.samples;
    let i = Math.min(this.i, S.length - 1);
    while (i > 0 && S[i].t > t) i--;
    while (i < S.length - 1 && S[i + 1].t <= t) i++;
    this.i = i;
    const a = S[i], b = S[Math.min(i + 1, S.length - 1)];
    const f = b.t > a.t ? Math.min(1, Math.max(0, (t - a.t) / (b.t - a.t))) : 0;
    for (let k = 0; k < 2; k++) {
      const A = a.arms[k], B = b.arms[k], fr = this.frames[k];
      for (let j = 0; j < A.q.length; j++) fr.q[j] = A.q[j] + f * (B.q[j] - A.q[j]);
      fr.jaw_opening_m = A.jaw_opening_m + f * (B.jaw_opening_m - A.jaw_opening_m);
      for (let j = 0; j < fr.joint_frames.length; j++) lerpPose(fr.joint_frames[j], A.joint_frames[j], B.joint_frames[j], f);
      lerpPose(fr.pose, A.pose, B.pose, f);
      this.arms[k].update(fr);
    }
    if (this.box) {
      lerpPose(this.boxPose, a.object, b.object, f);
      poseToMatrix(this.boxPose, this.box.matrix);
      this.box.matrixWorldNeedsUpdate = true;
    }
    this.t = t;
  }

  /** For the tests: the attempt drawn, the time, the meshes in the scene, each arm's drawn
   * joint angles and tool point (world, m). */
  debug() {
    let meshes = 0;
    this.view.world.root.traverse((o) => { if (o.isMesh && o.material === GHOST_MATERIAL && /^ghost-track/.test(this.ownerName(o))) meshes++; });
    return {
      attempt: this.attempt, t: this.t, meshes,
      q: this.arms ? this.arms.map((a) => a.q.slice()) : null,
      tool: this.arms ? this.arms.map((a) => a.origins[a.n].toArray()) : null,
    };
  }

  /** The name of the ghost group a mesh belongs to (its arm's or the box's). */
  ownerName(o) {
    if (o.name === 'ghost-track-box') return o.name;
    const owner = (this.arms || []).find((a) => a.group === o.parent);
    return owner ? owner.name : '';
  }
}

/** The choices' labels: "my best (score 84)", "reference (score 91)". */
export function choiceLabel(kind, c) {
  const what = kind === 'best' ? 'my best' : kind === 'reference' ? 'reference' : kind;
  return c ? `${what} (score ${Math.round(c.score)})` : `${what} (none yet)`;
}
