//! The 1 ms step with its default sub-steps (1) reproduces a finely sub-stepped reference (32
//! sub-steps, h = 31 µs): joint angles and line pressures of case study 1's first joints and
//! of the dual-arm grasp-and-lift agree, so the chosen integration is accurate, not only stable.

mod common;

use common::scenario_util::start;
use seaarms_core::sim::{Arm, Simulation, StepParams};

fn run_to(name: &str, substeps: usize, seconds: f64) -> Simulation {
    let (mut sc, _) = start(name);
    sc.params.step.substeps = substeps;
    let m = common::builtin("magnum");
    let mut sim = Simulation::new(m.clone(), m, sc.params.clone()).expect("sim");
    let mut t = 0.0;
    'outer: for seg in &sc.segments {
        for _ in 0..(seg.duration_s / 1e-3).round() as usize {
            if t >= seconds {
                break 'outer;
            }
            let input = sc.input_at(&sim, seg, t);
            sim.step(&input);
            t += 1e-3;
        }
    }
    sim
}

fn compare(name: &str, seconds: f64, tol_q: f64, tol_p: f64) {
    let a = run_to(name, StepParams::default().substeps, seconds);
    let b = run_to(name, 32, seconds);
    let mut dq: f64 = 0.0;
    let mut dp: f64 = 0.0;
    for i in Arm::BOTH {
        for j in 0..6 {
            dq = dq.max((a.arm(i).q[j] - b.arm(i).q[j]).abs());
            dp = dp
                .max((a.arm(i).p_in[j] - b.arm(i).p_in[j]).abs())
                .max((a.arm(i).p_out[j] - b.arm(i).p_out[j]).abs());
        }
    }
    let dz = (a.object().pose.translation.z - b.object().pose.translation.z).abs();
    println!(
        "{name} at {seconds} s: max |Δq| {dq:.2e} rad, max |ΔP| {dp:.0} Pa, |Δz_object| {dz:.2e} m"
    );
    assert!(
        dq < tol_q && dp < tol_p && dz < tol_q,
        "{name}: Δq {dq}, ΔP {dp}, Δz {dz}"
    );
}

#[test]
fn single_arm_motion_matches_fine_reference() {
    compare("case1-single-arm", 12.0, 5e-4, 1e5);
}

#[test]
fn dual_arm_closed_loop_lift_matches_fine_reference() {
    compare("case4-dual-closed-loop", 27.0, 5e-4, 5e4);
}
