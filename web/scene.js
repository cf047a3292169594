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
    this.scene.add(new THREE.HemisphereLight(0xdfefff, 0x40352a, 1.6));
    const sun = new THREE.DirectionalLight(0xffffff, 1.6);
    sun.position.set(2, -3, 5);
    this.scene.add(sun);
    const fill = new THREE.DirectionalLight(0xffffff, 0.6);
    fill.position.set(-3, 2, 2);
    this.scene.add(fill);
    this.root = new THREE.Group();
    this.scene.add(this.root);
    this.seabed = null;
    this.object = null;
    this.objectMaterial = new THREE.MeshLambertMaterial({ color: GRASP_COLOURS.free });
    this.grasp = 'free';
    // The water current: an arrow above the work area, pointing where the water flows,
    // CURRENT_ARROW_M_PER_M_S long per m/s (hidden in still water and in air).
    this.current = new THREE.ArrowHelper(new THREE.Vector3(1, 0, 0), new THREE.Vector3(), 1, CURRENT_COLOUR, 0.12, 0.07);
    this.current.visible = false;
    this.currentKey = '';
    this.root.add(this.current);
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
      new THREE.LineBasicMaterial({ color: 0x222222 }));
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
        this.current.setLength(CURRENT_ARROW_M_PER_M_S * cur.speed_m_s, 0.12, 0.07);
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
