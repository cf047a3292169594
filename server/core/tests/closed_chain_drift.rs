//! With both jaws closed the chain arms–object is closed (Lim §3.4, eqs 3.38–3.47): the
//! constraint-stabilized simulation keeps each jaw on its grasp point to < 1 mm over 60 s of
//! holding, in the air and on the seabed, and the contact wrenches carry the object's weight.

mod common;

use common::scenario_util::{run_while, start};
use seaarms_core::grasp::GraspState;
use seaarms_core::sim::{Arm, ControlMethod, Input};

fn hold_for_60_s(method: ControlMethod, lifted: bool) {
    let (sc, mut sim) = start("case4-dual-closed-loop");
    // Run until both hold (and, if asked, through the closed-loop lift of stage C).
    run_while(&sc, &mut sim, |k, s| {
        let seg = &sc.segments[k];
        if lifted {
            seg.stage != "D"
        } else {
            !(s.arm(Arm::Left).holding && s.arm(Arm::Right).holding)
        }
    });
    assert_eq!(sim.grasp_state(), GraspState::BothHolding);
    let p0 = sim.object().pose.translation.vector;
    let input = Input {
        method,
        ..Input::default()
    };
    let mut worst: f64 = 0.0;
    for _ in 0..60_000 {
        sim.step(&input);
        worst = worst
            .max(sim.grasp_error(Arm::Left).0)
            .max(sim.grasp_error(Arm::Right).0);
        // The runner's per-step monitor is the same position error.
        for a in Arm::BOTH {
            assert!((sim.grasp_position_error(a) - sim.grasp_error(a).0).abs() < 1e-15);
        }
    }
    let moved = (sim.object().pose.translation.vector - p0).norm();
    let cw = [
        sim.arm(Arm::Left).contact_wrench,
        sim.arm(Arm::Right).contact_wrench,
    ];
    let lift = cw[0][2] + cw[1][2];
    println!(
        "{method:?} lifted={lifted}: worst grasp error {worst:.2e} m, object moved {moved:.2e} m, jaws carry {lift:.1} N"
    );
    assert!(worst < 1e-3, "grasp drift {worst} m");
    assert!(sim.numerical_faults() == 0);
    if lifted {
        assert!(moved < 1e-3, "object moved {moved} m while held");
        assert!(
            (lift - 50.0 * 9.81).abs() < 5.0,
            "jaws carry {lift} N, object weighs 490.5 N"
        );
        assert_eq!(sim.grasp_state(), GraspState::BothHolding);
    }
}

#[test]
fn both_jaws_hold_lifted_object_open_loop_without_drift() {
    hold_for_60_s(ControlMethod::Open, true);
}

#[test]
fn both_jaws_hold_lifted_object_closed_loop_without_drift() {
    hold_for_60_s(ControlMethod::Closed, true);
}

#[test]
fn both_jaws_hold_object_on_seabed_without_drift() {
    hold_for_60_s(ControlMethod::Open, false);
}
