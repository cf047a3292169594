//! Fixtures shared by `benches/step.rs` and `examples/step_loop.rs` (included by path), so
//! the benchmark and the instruction-count workload step exactly the same states.

use seaarms_core::sim::scenario::scenario;
use seaarms_core::sim::{Arm, Simulation};
use seaarms_core::{Model, ModelSpec, robots};

/// The built-in Magnum model.
pub(crate) fn magnum() -> Model {
    let text = robots::builtin_text("magnum").expect("magnum");
    let spec: ModelSpec = serde_json::from_str(text).expect("json");
    Model::from_spec(&spec).expect("model")
}

/// `case4-dual-closed-loop` stepped until both jaws hold the object.
pub(crate) fn holding_sim(m: &Model) -> Simulation {
    let sc = scenario("case4-dual-closed-loop", m, m).expect("scenario");
    let mut sim = Simulation::new(m.clone(), m.clone(), sc.params.clone()).expect("sim");
    let mut t = 0.0;
    for seg in &sc.segments {
        if sim.arm(Arm::Left).holding && sim.arm(Arm::Right).holding {
            break;
        }
        let n = (seg.duration_s / 1e-3).round() as usize;
        for _ in 0..n {
            let inp = sc.input_at(&sim, seg, t);
            sim.step(&inp);
            t += 1e-3;
        }
    }
    sim
}
