//! Optional water effects (issue criterion 1): with buoyancy each uniform link weighs
//! (1 − ρ_water/ρ_link) of its air weight, so RNEA gravity torques scale by exactly that
//! factor; quadratic joint drag slows a joint driven at full command; both keep the step finite.

mod common;

use nalgebra::Vector3;
use seaarms_core::dynamics::{DynData, Inertials, MAGNUM_LINK_DENSITY_KGM3, rnea};
use seaarms_core::kinematics::{KinData, forward_kinematics};
use seaarms_core::sim::{Arm, Input, SimParams, Simulation};

#[test]
fn buoyancy_scales_gravity_torques() {
    let m = common::builtin("magnum");
    let inr = Inertials::magnum(&m).expect("inertials");
    let mut kin = KinData::new(&m);
    let mut d = DynData::new(&m);
    let q = [0.1, 0.4, -0.9, 0.3, -0.2, 0.5];
    forward_kinematics(&m, &mut kin, &q);
    let g = Vector3::new(0.0, 0.0, -9.81);
    let (mut air, mut water) = ([0.0; 6], [0.0; 6]);
    rnea(
        &m, &inr, &kin, &[0.0; 6], &[0.0; 6], &g, 0.0, &mut air, &mut d,
    );
    rnea(
        &m, &inr, &kin, &[0.0; 6], &[0.0; 6], &g, 1025.0, &mut water, &mut d,
    );
    let k = 1.0 - 1025.0 / MAGNUM_LINK_DENSITY_KGM3;
    for j in 0..6 {
        assert!(
            (water[j] - k * air[j]).abs() < 1e-9 * (1.0 + air[j].abs()),
            "joint {j}"
        );
    }
}

#[test]
fn drag_slows_the_arm_and_water_run_is_finite() {
    let run = |buoyancy: bool, drag: f64| {
        let m = common::builtin("magnum");
        let mut p = SimParams::case_study(&m, &m).expect("params");
        p.step.buoyancy = buoyancy;
        p.step.joint_drag = drag;
        let mut s = Simulation::new(m.clone(), m, p).expect("sim");
        let mut inp = Input::default();
        inp.arms[Arm::Left.index()].valves[5] = 1.0;
        let q0 = s.arm(Arm::Left).q[5];
        for _ in 0..1000 {
            s.step(&inp);
        }
        assert_eq!(s.numerical_faults(), 0);
        s.arm(Arm::Left).q[5] - q0
    };
    let free = run(false, 0.0);
    let dragged = run(true, 20.0);
    assert!(dragged < 0.9 * free, "drag: {dragged} rad vs {free} rad");
}
