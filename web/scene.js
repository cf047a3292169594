// The 3D scene: renderer, lights, seabed, the object and its grasp colour. World frame is the
// server's: z up (robotics). `THREE.Object3D.DEFAULT_UP` is set to +z before any camera is made.
// Draws only: every pose and size comes from the server's hello and state frames.

import * as THREE from 'three';

THREE.Object3D.DEFAULT_UP.set(0, 0, 1);

/** Object colour per grasp state (Lim §4.1, Fig. 4-4). */
export const GRASP_COLOURS = {
  free: 0xb4b4b4, // neutral grey
  one_on_surface: 0x000000, // black: one jaw holds it, still on the surface
  one_lifted: 0x7fd4ff, // light blue: one jaw holds it off the surface
  one_holding_other_contact: 0xff2020, // red: one holds, the other touches
  both_holding: 0xffd700, // yellow: both jaws hold it
};

export const BACKGROUND = 0x0d2438;
/** The box's edges: light, so the black grasp state (one holding, on surface) keeps its
 * outline on the dark background (issue 28). */
const BOX_EDGE_COLOUR = 0xd8d8d8;
/** The water current's arrow: its colour, and its length per m/s of current speed. */
export const CURRENT_COLOUR = 0x5fd0ff;
export const CURRENT_ARROW_M_PER_M_S = 0.5;
const SOFTWARE_PIXEL_RATIO = 0.6;

/** Sets a Matrix4 from a server pose {position:[3], rotation: 3×3 rows}. */
export function poseToMatrix(pose, m = new THREE.Matrix4()) {
  const r = pose.rotation, p = pose.position;
  m.set(r[0][0], r[0][1], r[0][2], p[0],
        r[1][0], r[1][1], r[1][2], p[1],
        r[2][0], r[2][1], r[2][2], p[2],
        0, 0, 0, 1);
  return m;
}

/** True when WebGL runs on a CPU rasterizer (probed on a throw-away canvas). */
function softwareRenderer() {
  try {
    const gl = document.createElement('canvas').getContext('webgl2');
    if (!gl) return true;
    const ext = gl.getExtension('WEBGL_debug_renderer_info');
    const name = ext ? String(gl.getParameter(ext.UNMASKED_RENDERER_WEBGL)) : '';
    gl.getExtension('WEBGL_lose_context')?.loseContext();
    return /swiftshader|llvmpipe|softpipe|software/i.test(name);
  } catch {
    return false;
  }
}

/** The water current's arrow: a solid shaft and head (a line one pixel wide is lost over the
 * box in the top view), tail at its position, pointing along `setDirection`, `setLength` long. */
class CurrentArrow extends THREE.Group {
  constructor() {
    super();
    const material = new THREE.MeshBasicMaterial({ color: CURRENT_COLOUR });
    // unit cylinder and cone along +y from the origin, scaled in `setLength`
    this.shaft = new THREE.Mesh(new THREE.CylinderGeometry(1, 1, 1, 12).translate(0, 0.5, 0), material);
    this.head = new THREE.Mesh(new THREE.ConeGeometry(1, 1, 16).translate(0, 0.5, 0), material);
    this.add(this.shaft, this.head);
  }

  /** World points of the tail and the tip, for tests. */
  ends() {
    this.updateWorldMatrix(true, false);
    return [this.localToWorld(new THREE.Vector3()).toArray(), this.localToWorld(new THREE.Vector3(0, this.length_m ?? 0, 0)).toArray()];
  }

  /** `dir`: a unit vector (world frame). */
  setDirection(dir) { this.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), dir); }

  setLength(length_m) {
    this.length_m = length_m;
    const head = Math.min(CURRENT_HEAD_M, 0.5 * length_m);
    this.shaft.scale.set(CURRENT_SHAFT_RADIUS_M, length_m - head, CURRENT_SHAFT_RADIUS_M);
    this.head.scale.set(2.5 * CURRENT_SHAFT_RADIUS_M, head, 2.5 * CURRENT_SHAFT_RADIUS_M);
    this.head.position.set(0, length_m - head, 0);
  }
}
const CURRENT_SHAFT_RADIUS_M = 0.015;
const CURRENT_HEAD_M = 0.12;

export class World {
  constructor(canvas) {
    this.canvas = canvas;
    this.software = softwareRenderer();
    // multisampling in a software rasterizer (SwiftShader, llvmpipe) costs more than it shows
    this.renderer = new THREE.WebGLRenderer({ canvas, antialias: !this.software, powerPreference: 'high-performance' });
    // ?pr=N overrides the pixel ratio (a CPU rasterizer draws at reduced resolution by default)
    const pr = Number(new URLSearchParams(location.search).get('pr'));
    this.renderer.setPixelRatio(pr > 0 ? pr : this.software ? SOFTWARE_PIXEL_RATIO : Math.min(window.devicePixelRatio || 1, 1.5));
    this.renderer.setClearColor(BACKGROUND, 1);
    this.renderer.setScissorTest(true);
    this.scene = new THREE.Scene();
    const hemi = new THREE.HemisphereLight(0xdfefff, 0x40352a, 1.6);
    this.scene.add(hemi);
    const sun = new THREE.DirectionalLight(0xffffff, 1.6);
    sun.position.set(2, -3, 5);
    this.scene.add(sun);
    const fill = new THREE.DirectionalLight(0xffffff, 0.6);
    fill.position.set(-3, 2, 2);
    this.scene.add(fill);
    // the engineering views' daylight; the pilot views (web/water.js) keep a faint glow from
    // the surface and rely on the vehicle's lamps
    this.daylight = { hemi, sun, fill, hemiIntensity: hemi.intensity };
    this.root = new THREE.Group();
    this.scene.add(this.root);
    this.seabed = null;
    this.object = null;
    this.objectMaterial = new THREE.MeshLambertMaterial({ color: GRASP_COLOURS.free });
    this.grasp = 'free';
    // The water current: an arrow above the work area, pointing where the water flows,
    // CURRENT_ARROW_M_PER_M_S long per m/s (hidden in still water and in air).
    this.current = new CurrentArrow();
    this.current.visible = false;
    this.currentKey = '';
    this.root.add(this.current);
  }

  /** Daylight on (engineering views) or down to a faint glow from above (pilot views). */
  setDaylight(on) {
    const d = this.daylight;
    d.hemi.intensity = on ? d.hemiIntensity : 0.08;
    d.sun.visible = d.fill.visible = on;
  }

  /** (Re)builds the static parts from a hello message. */
  setup(hello) {
    if (this.seabed) { this.root.remove(this.seabed); this.seabed.geometry.dispose(); }
    if (this.object) { this.root.remove(this.object); this.object.geometry.dispose(); }
    const z = hello.seabed_z_m;
    const bed = new THREE.PlaneGeometry(8, 8, 1, 1);
    this.seabed = new THREE.Mesh(bed, new THREE.MeshLambertMaterial({ color: 0x6b5a3e }));
    this.seabed.position.set(0.8, 0.5, z);
    this.root.add(this.seabed);
    const grid = new THREE.GridHelper(8, 32, 0x8a7a58, 0x7a6a4c);
    grid.rotation.x = Math.PI / 2; // GridHelper lies in XZ; rotate into the seabed plane
    grid.position.set(0, 0, 0.001);
    this.seabed.add(grid);
    const s = hello.object.size_m;
    this.object = new THREE.Mesh(new THREE.BoxGeometry(s[0], s[1], s[2]), this.objectMaterial);
    this.object.matrixAutoUpdate = false;
    this.root.add(this.object);
    const edges = new THREE.LineSegments(new THREE.EdgesGeometry(this.object.geometry),
      new THREE.LineBasicMaterial({ color: BOX_EDGE_COLOUR }));
    this.object.add(edges);
    const c = World.workCentre(hello);
    this.current.position.set(c.x, c.y, c.z + 0.6);
  }

  /** Object pose and grasp colour from a state frame; the current's arrow. */
  update(state) {
    if (!this.object) return;
    const cur = state.current;
    const key = cur ? `${cur.speed_m_s}/${cur.heading_deg}` : '';
    if (key !== this.currentKey) {
      this.currentKey = key;
      this.current.visible = !!cur && cur.speed_m_s > 0;
      if (this.current.visible) {
        const a = (cur.heading_deg * Math.PI) / 180;
        this.current.setDirection(new THREE.Vector3(Math.cos(a), Math.sin(a), 0));
        this.current.setLength(CURRENT_ARROW_M_PER_M_S * cur.speed_m_s);
      }
    }
    poseToMatrix(state.object.pose, this.object.matrix);
    this.object.matrixWorldNeedsUpdate = true;
    if (state.grasp !== this.grasp) {
      this.grasp = state.grasp;
      const c = GRASP_COLOURS[state.grasp];
      this.objectMaterial.color.setHex(c === undefined ? GRASP_COLOURS.free : c);
    }
  }

  /** Centre of the work area (for cameras), from the arm bases in the hello. */
  static workCentre(hello) {
    const c = new THREE.Vector3();
    for (const a of hello.arms) {
      const r = a.base.rotation;
      // the arms reach along +x of their bases (Lim Fig. 3-5: workspace X 0.9-1.4 m)
      c.add(new THREE.Vector3(...a.base.position))
        .add(new THREE.Vector3(r[0][0], r[1][0], r[2][0]).multiplyScalar(0.8));
    }
    c.multiplyScalar(1 / hello.arms.length);
    c.z = Math.max(c.z, hello.seabed_z_m) + 0.3;
    return c;
  }
}
