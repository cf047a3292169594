// Sticks that follow the view (issue 28): the rotation that takes the Cartesian sticks'
// axes into the world frame (web/input.js toWorld) for the frame the trainee chose, and in
// joint mode which way each joint's + turns the jaw on the active view. Geometry of the
// server's frames and the page's cameras only.

import * as THREE from 'three';
import { poseToMatrix } from './scene.js';

/**
 * Rows of R (world ← stick) for the stick frame `name`:
 * - 'camera': columns [screen right, screen up, into the screen] of `camera` (its matrixWorld:
 *   x right, y up, z toward the viewer);
 * - 'vehicle': the vehicle's axes (the left base's rotation: x ahead, y left, z up; the
 *   built-in bases are not rotated, so this is the world's);
 * - 'base': the selected arm's base rotation.
 */
export function frameRows(name, camera, hello, side) {
  if (name === 'camera' && camera) {
    camera.updateMatrixWorld();
    const e = camera.matrixWorld.elements;
    const x = new THREE.Vector3(e[0], e[1], e[2]).normalize();
    const y = new THREE.Vector3(e[4], e[5], e[6]).normalize();
    const f = new THREE.Vector3(-e[8], -e[9], -e[10]).normalize();
    return [[x.x, y.x, f.x], [x.y, y.y, f.y], [x.z, y.z, f.z]];
  }
  if (!hello) return null;
  const i = name === 'base' && side === 'right' ? 1 : 0;
  return hello.arms[i].base.rotation.map((r) => r.slice());
}

const _o = new THREE.Vector3(), _z = new THREE.Vector3(), _j = new THREE.Vector3(), _v = new THREE.Vector3();
const _m = new THREE.Matrix4();

/**
 * For each joint of one arm's frame (`joint_frames`: joint i turns about its frame's z at its
 * origin), the way its + turns the jaw on `camera`'s picture: the jaw centre's velocity
 * z × (jaw − origin) in screen terms (→ right, ← left, ↑ up, ↓ down, away, toward you), or for
 * a joint whose axis runs through the jaw (the rotate joint), ↻ / ↺ as seen.
 */
export function jointTurnWords(arm, camera) {
  camera.updateMatrixWorld();
  const e = camera.matrixWorld.elements;
  const right = new THREE.Vector3(e[0], e[1], e[2]), up = new THREE.Vector3(e[4], e[5], e[6]);
  const back = new THREE.Vector3(e[8], e[9], e[10]);
  _j.fromArray(arm.pose.position);
  return arm.joint_frames.map((f) => {
    poseToMatrix(f, _m);
    _o.setFromMatrixPosition(_m);
    _z.setFromMatrixColumn(_m, 2).normalize();
    _v.subVectors(_j, _o).cross(_z).negate(); // z × r
    if (_v.length() < 0.02) return _z.dot(back) > 0 ? '↺ jaw anticlockwise' : '↻ jaw clockwise';
    const s = [_v.dot(right), _v.dot(up), -_v.dot(back)];
    const k = s.map(Math.abs).indexOf(Math.max(...s.map(Math.abs)));
    return (s[k] > 0 ? ['jaw → right', 'jaw ↑ up', 'jaw away'] : ['jaw ← left', 'jaw ↓ down', 'jaw toward you'])[k];
  });
}
