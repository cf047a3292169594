// Static preview for a server without the session API (POST /api/sessions → 404): the two
// arms at a fixed posture, drawn from the server's own model (GET /api/robots/magnum) and
// analysis (POST /api/analysis: joint frames, pose, ellipsoid, measures). No simulation.

const Q0 = [0, 0.6, -1.2, 0.4, 0, 0];
const BASES = [
  { position: [0, 0.5, 0], rotation: [[1, 0, 0], [0, 1, 0], [0, 0, 1]] },
  { position: [0, -0.5, 0], rotation: [[1, 0, 0], [0, 1, 0], [0, 0, 1]] },
];

function shift(pose, base) {
  const p = base.position;
  return { position: pose.position.map((v, i) => v + p[i]), rotation: pose.rotation };
}

export async function previewFrames() {
  const model = await (await fetch('/api/robots/magnum')).json();
  const arms = await Promise.all(BASES.map(async (base) => {
    const r = await fetch('/api/analysis', {
      method: 'POST', headers: { 'content-type': 'application/json' },
      body: JSON.stringify({ robot: 'magnum', q: Q0 }),
    });
    const a = await r.json();
    const t = a.measures.translational;
    return {
      q: Q0, qd: [0, 0, 0, 0, 0, 0], p_in: [0, 0, 0, 0, 0, 0], p_out: [0, 0, 0, 0, 0, 0],
      jaw_opening_m: 0.1, holding: false, contact: false,
      pose: shift(a.pose, base), joint_frames: a.joint_frames.map((f) => shift(f, base)),
      ellipsoid: { radii: t.ellipsoid.radii, axes: t.ellipsoid.axes },
      measures: { yoshikawa: t.yoshikawa, isotropy: t.isotropy, hong: t.hong, condition_number: t.condition_number, jlm: a.jlm },
      contact_force_n: [0, 0, 0], contact_torque_nm: [0, 0, 0], relief_open: [false, false, false, false, false, false],
    };
  }));
  const hello = {
    type: 'hello', session: 'preview', role: 'preview',
    arms: BASES.map((base) => ({ model, base })),
    object: { size_m: [0.3, 0.2, 0.2], mass_kg: 10 }, seabed_z_m: -0.3,
    settings: { control_mode: 'joint', control_method: 'open', arm_speed: 1 }, scenario: 'preview', frame_hz: 0,
  };
  const state = {
    type: 'state', t: 0, seq: 0, input_seq: 0, paused: true, settings: hello.settings,
    arms: { left: arms[0], right: arms[1] }, dual: null,
    object: { pose: { position: [1.1, 0, -0.2], rotation: [[1, 0, 0], [0, 1, 0], [0, 0, 1]] }, velocity: [0, 0, 0] },
    grasp: 'free', internal_force_n: [0, 0, 0], internal_torque_nm: [0, 0, 0], relief_events: 0, warnings: [], faults: [],
  };
  return { hello, state };
}
