//! Panel test helpers: the jaw pointing into the panel, closed-form IK start postures, a
//! Cartesian P controller through the joint servo, and taking the hot stab out of its holster.

use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3, Vector6};
use seaarms_core::control::rotation_error;
use seaarms_core::ik::magnum_ik;
use seaarms_core::panel::{PanelParams, StabPhase};
use seaarms_core::sim::{Arm, Graspable, Input, SimParams, Simulation};

/// Tool orientation with the jaw (tool z) pointing along +x, into the panel.
pub(crate) fn jaw_into_panel() -> UnitQuaternion<f64> {
    let r = Matrix3::new(0.0, 0.0, 1.0, 0.0, -1.0, 0.0, 1.0, 0.0, 0.0);
    UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r))
}

pub(crate) fn tool_at(p: Vector3<f64>) -> Isometry3<f64> {
    Isometry3::from_parts(Translation3::from(p), jaw_into_panel())
}

/// Closed-form IK of `arm` for the world tool pose `target` (first solution within limits).
pub(crate) fn ik(params: &SimParams, arm: Arm, target: &Isometry3<f64>) -> Option<[f64; 6]> {
    let m = super::builtin("magnum");
    let local = params.arms[arm.index()].base.inverse() * target;
    magnum_ik(&m, &local).ok()?.into_iter().next()
}

/// The case-study set-up with the standard panel, `arm` starting with its tool at `target`.
pub(crate) fn sim_at(arm: Arm, target: &Isometry3<f64>) -> Simulation {
    let m = super::builtin("magnum");
    let mut p = SimParams::case_study(&m, &m)
        .expect("params")
        .with_panel(PanelParams::standard());
    p.arms[arm.index()].initial_q = ik(&p, arm, target).expect("reachable");
    Simulation::new(m.clone(), m, p).expect("sim")
}

pub(crate) fn jaw(arm: Arm, cmd: f64) -> Input {
    let mut i = Input::default();
    i.arms[arm.index()].jaw = cmd;
    i
}

/// A Cartesian P controller through the joint servo: joint-velocity reference J⁻¹·(k·pose
/// error), the tool speed capped at 0.05 m/s and 0.2 rad/s.
pub(crate) fn toward(sim: &Simulation, arm: Arm, target: &Isometry3<f64>, jaw_cmd: f64) -> Input {
    let t = sim.end_effector(arm);
    let mut dp = (target.translation.vector - t.translation.vector) * 3.0;
    if dp.norm() > 0.05 {
        dp *= 0.05 / dp.norm();
    }
    let mut dr = rotation_error(&target.rotation, &t.rotation) * 3.0;
    if dr.norm() > 0.2 {
        dr *= 0.2 / dr.norm();
    }
    let v = Vector6::new(dp.x, dp.y, dp.z, dr.x, dr.y, dr.z);
    let qd = sim
        .jacobian_world(arm)
        .try_inverse()
        .map(|ji| ji * v)
        .unwrap_or_else(Vector6::zeros);
    let mut i = jaw(arm, jaw_cmd);
    i.arms[arm.index()].joint_velocity_ref = Some(qd.into());
    i
}

pub(crate) fn run_toward(sim: &mut Simulation, arm: Arm, target: &Isometry3<f64>, steps: usize) {
    for _ in 0..steps {
        let i = toward(sim, arm, target, -0.2);
        sim.step(&i);
    }
}

/// Grasps the stab in its holster with `arm` and pulls it clear; returns the simulation.
pub(crate) fn stab_in_hand(arm: Arm) -> (Simulation, PanelParams) {
    let panel = PanelParams::standard();
    let mut sim = sim_at(arm, &tool_at(panel.holstered_stab().translation.vector));
    assert_eq!(sim.in_capture_range(arm), Some(Graspable::Stab));
    for _ in 0..800 {
        sim.step(&jaw(arm, -1.0));
    }
    assert_eq!(sim.panel().expect("panel").stab_phase, StabPhase::Held(arm));
    let out = panel.holstered_stab().translation.vector - panel.normal() * 0.045;
    run_toward(&mut sim, arm, &tool_at(out), 2500);
    let s = sim.panel().expect("panel");
    assert_eq!(s.stab_phase, StabPhase::Held(arm));
    assert!((s.stab_handle_m() - out).norm() < 0.005, "pulled clear");
    (sim, panel)
}

/// The tool pose that puts the stab's tip `depth` past the receptacle mouth, offset
/// laterally by `offset` (world), rotated by `tilt` (rad) about z.
pub(crate) fn insert_pose(
    panel: &PanelParams,
    depth: f64,
    offset: Vector3<f64>,
    tilt: f64,
) -> Isometry3<f64> {
    let n = panel.normal();
    let seated = panel.seated_stab().translation.vector;
    let grip = seated - n * (panel.stab.insertion_depth_m - depth) + offset;
    let rot = UnitQuaternion::from_scaled_axis(Vector3::z() * tilt) * jaw_into_panel();
    Isometry3::from_parts(Translation3::from(grip), rot)
}
