//! Helpers to advance a simulation through a scripted scenario.
#![allow(dead_code)]

use seaarms_core::sim::Simulation;
use seaarms_core::sim::scenario::{Scenario, scenario};

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
