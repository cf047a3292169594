//! Helpers to advance a simulation through a scripted scenario.
#![allow(dead_code)]

use seaarms_core::grasp::GraspState;
use seaarms_core::sim::scenario::{Scenario, scenario};
use seaarms_core::sim::{Arm, Environment, Input, Simulation};

/// Builds `name` and a simulation at its reset state.
pub(crate) fn start(name: &str) -> (Scenario, Simulation) {
    let m = super::builtin("magnum");
    let sc = scenario(name, &m, &m).expect("scenario");
    let sim = Simulation::new(m.clone(), m, sc.params.clone()).expect("sim");
    (sc, sim)
}

/// Runs the scenario's segments while `keep_going(segment index, sim)` holds; returns the
/// index of the first segment not run (or the number of segments).
pub(crate) fn run_while(
    sc: &Scenario,
    sim: &mut Simulation,
    mut keep_going: impl FnMut(usize, &Simulation) -> bool,
) -> usize {
    for (k, seg) in sc.segments.iter().enumerate() {
        if !keep_going(k, sim) {
            return k;
        }
        let n = (seg.duration_s / sc.params.step.dt_s).round() as usize;
        for _ in 0..n {
            let input = sc.input_at(sim, seg, sim.time_s());
            sim.step(&input);
        }
    }
    sc.segments.len()
}

/// Runs `sc` with two Magnum arms from reset, collecting every post-processing row; checks
/// that no step went non-finite.
pub(crate) fn run_rows(
    sc: &Scenario,
) -> (
    seaarms_core::sim::scenario::Summary,
    Vec<seaarms_core::sim::scenario::Row>,
) {
    let m = super::builtin("magnum");
    let mut rows = Vec::new();
    let s = seaarms_core::sim::scenario::run(sc, &m, &m, |r| rows.push(r.clone())).expect("run");
    println!("{}: {s:?}", sc.name);
    assert_eq!(s.numerical_faults, 0);
    (s, rows)
}

/// Both jaws closed on the nominal box resting on the seabed (case study 3 stages A–B:
/// joint-space reach, then the open-loop grasp), with the finite grip, in `env`, the clamp
/// force built (0.5 s at rest after the last grasp segment closes the left jaw).
pub(crate) fn dual_grasp(env: Environment) -> Simulation {
    let (mut sc, _) = start("case3-dual-open-loop");
    sc.params.rigid_grasp = false;
    sc.params.control.moment_free_share = true;
    sc.params.step.environment = env;
    let m = super::builtin("magnum");
    let mut sim = Simulation::new(m.clone(), m, sc.params.clone()).expect("sim");
    run_while(&sc, &mut sim, |_, s| {
        !(s.arm(Arm::Left).holding && s.arm(Arm::Right).holding)
    });
    let rest = Input {
        speed_scale: 1.0,
        ..Input::default()
    };
    for _ in 0..500 {
        sim.step(&rest);
    }
    assert_eq!(sim.grasp_state(), GraspState::BothHolding);
    sim
}
