// Translational manipulability ellipsoids (radii in m/s along the server's unit axes, world
// frame) at each end-effector, the dual-arm ellipsoid (Lim eq. 3.68) at the object while both
// jaws hold it, and optionally the velocity polytopes (POST /api/analysis with polytope: true,
// fetched at a low rate). Drawn at `scale` metres per m/s (legend in the page).

import * as THREE from 'three';
import { poseToMatrix } from './scene.js';

const SPHERE = new THREE.SphereGeometry(1, 32, 16);
const MIN_RADIUS = 1e-3;
const _m = new THREE.Matrix4(), _p = new THREE.Matrix4();
const _x = new THREE.Vector3(), _y = new THREE.Vector3(), _z = new THREE.Vector3();

/** Okabe–Ito bluish green (left), reddish purple (right), light grey (dual): colour-blind
 * safe and shared with no marker, zone or grasp colour (palette: web/markers.js, docs/views.md). */
export const ELLIPSOID_COLOURS = { left: 0x009e73, right: 0xcc79a7, dual: 0xf6f5f4 };

function ellipsoidMesh(colour, parent) {
  const mat = new THREE.MeshLambertMaterial({ color: colour, transparent: true, opacity: 0.35, depthWrite: false });
  const m = new THREE.Mesh(SPHERE, mat);
  m.matrixAutoUpdate = false;
  m.renderOrder = 2;
  m.visible = false; // until the first state frame places it
  const wire = new THREE.LineSegments(new THREE.EdgesGeometry(new THREE.SphereGeometry(1, 12, 6), 1),
    new THREE.LineBasicMaterial({ color: colour, transparent: true, opacity: 0.5 }));
  m.add(wire);
  parent.add(m);
  return m;
}

/** matrix = translate(pos) · [a₀r₀s a₁r₁s a₂r₂s] */
function place(mesh, position, ell, scale) {
  const a = ell.axes, r = ell.radii;
  _x.fromArray(a[0]).multiplyScalar(Math.max(r[0] * scale, MIN_RADIUS));
  _y.fromArray(a[1]).multiplyScalar(Math.max(r[1] * scale, MIN_RADIUS));
  _z.fromArray(a[2]).multiplyScalar(Math.max(r[2] * scale, MIN_RADIUS));
  mesh.matrix.makeBasis(_x, _y, _z).setPosition(position[0], position[1], position[2]);
  mesh.matrixWorldNeedsUpdate = true;
}

export class Ellipsoids {
  constructor(parent) {
    this.group = new THREE.Group();
    parent.add(this.group);
    this.scale = 0.25; // m per m/s
    this.left = ellipsoidMesh(ELLIPSOID_COLOURS.left, this.group);
    this.right = ellipsoidMesh(ELLIPSOID_COLOURS.right, this.group);
    this.dual = ellipsoidMesh(ELLIPSOID_COLOURS.dual, this.group);
    this.polys = { left: null, right: null };
    this.polyGroup = new THREE.Group();
    parent.add(this.polyGroup);
    this.polyMat = {
      left: new THREE.MeshLambertMaterial({ color: ELLIPSOID_COLOURS.left, transparent: true, opacity: 0.3, depthWrite: false, side: THREE.DoubleSide }),
      right: new THREE.MeshLambertMaterial({ color: ELLIPSOID_COLOURS.right, transparent: true, opacity: 0.3, depthWrite: false, side: THREE.DoubleSide }),
    };
    this.showEllipsoids = true;
  }

  setVisible(v) { this.showEllipsoids = v; this.group.visible = v; }
  setPolytopesVisible(v) { this.polyGroup.visible = v; }

  update(state) {
    const l = state.arms.left, r = state.arms.right;
    place(this.left, l.pose.position, l.ellipsoid, this.scale);
    place(this.right, r.pose.position, r.ellipsoid, this.scale);
    this.left.visible = this.right.visible = true;
    if (state.dual) {
      this.dual.visible = true;
      place(this.dual, state.object.pose.position, state.dual.ellipsoid, this.scale);
    } else {
      this.dual.visible = false;
    }
    for (const side of ['left', 'right']) {
      const p = this.polys[side];
      if (p) {
        const pos = state.arms[side].pose.position;
        p.matrix.copy(p.userData.rot).premultiply(_m.makeScale(this.scale, this.scale, this.scale))
          .premultiply(_p.makeTranslation(pos[0], pos[1], pos[2]));
        p.matrixWorldNeedsUpdate = true;
      }
    }
  }

  /** Replaces one arm's polytope (vertices in the arm's base frame, m/s). */
  setPolytope(side, polytope, baseRotation) {
    const old = this.polys[side];
    if (old) { this.polyGroup.remove(old); old.geometry.dispose(); old.children.forEach((c) => c.geometry.dispose()); }
    this.polys[side] = null;
    if (!polytope || polytope.vertices.length < 4) return;
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.Float32BufferAttribute(polytope.vertices.flat(), 3));
    g.setIndex(polytope.facets.flat());
    g.computeVertexNormals();
    const mesh = new THREE.Mesh(g, this.polyMat[side]);
    mesh.add(new THREE.LineSegments(new THREE.EdgesGeometry(g, 10),
      new THREE.LineBasicMaterial({ color: this.polyMat[side].color })));
    mesh.matrixAutoUpdate = false;
    const rot = poseToMatrix({ position: [0, 0, 0], rotation: baseRotation });
    mesh.userData.rot = rot;
    mesh.renderOrder = 1;
    this.polyGroup.add(mesh);
    this.polys[side] = mesh;
  }

  /** Drawn radii (m) of an ellipsoid mesh, for tests. */
  drawnRadii(which) {
    const e = this[which].matrix.elements;
    return [0, 1, 2].map((c) => Math.hypot(e[4 * c], e[4 * c + 1], e[4 * c + 2]));
  }
}
