//! Jaw function per Lim Table 1-1 (7.5 cm opening at 10.2 cm/s, 150 kgf clamp force) and the
//! arm speed setting (Lim §4.1) scaling every input.

mod common;

use seaarms_core::sim::{Arm, Input, SimParams, Simulation};

fn sim() -> Simulation {
    let m = common::builtin("magnum");
    let p = SimParams::case_study(&m, &m).expect("params");
    Simulation::new(m.clone(), m, p).expect("sim")
}

#[test]
fn jaw_closes_fully_in_0_735_s() {
    let mut s = sim();
    assert!((s.arm(Arm::Left).jaw_opening_m - 0.075).abs() < 1e-12);
    let mut close = Input::default();
    close.arms[Arm::Left.index()].jaw = -1.0;
    for _ in 0..700 {
        s.step(&close);
    }
    let left = s.arm(Arm::Left).jaw_opening_m;
    assert!(
        (left - (0.075 - 0.102 * 0.7)).abs() < 1e-9,
        "after 0.7 s: {left} m"
    );
    for _ in 0..100 {
        s.step(&close);
    }
    assert_eq!(s.arm(Arm::Left).jaw_opening_m, 0.0);
    assert_eq!(
        s.arm(Arm::Left).clamp_force_n,
        0.0,
        "no clamp force on nothing"
    );
    assert!(
        (s.params().arms[Arm::Left.index()]
            .hydraulics
            .jaw
            .clamp_force_n
            - 1471.0)
            .abs()
            < 1.0
    );
}

#[test]
fn speed_setting_scales_joint_motion() {
    let run = |scale: f64| {
        let mut s = sim();
        let mut inp = Input {
            speed_scale: scale,
            ..Input::default()
        };
        inp.arms[Arm::Left.index()].valves[4] = 1.0;
        let q0 = s.arm(Arm::Left).q[4];
        for _ in 0..300 {
            s.step(&inp);
        }
        s.arm(Arm::Left).q[4] - q0
    };
    let (full, half) = (run(1.0), run(0.5));
    assert!(
        (half / full - 0.5).abs() < 0.05,
        "half speed moved {half} vs {full}"
    );
}
