//! Core-only timing of the 1 ms step (a quick stand-in for the top-level
//! `cargo bench --bench step`, which builds the server crate): the mean wall time per step
//! of the arms moving open loop in sea water (the bench's `step_free_open_loop_subsea`
//! input), in air, and with both arms driven down into the seabed in water.
//! Run: `cargo run --release -p seaarms-core --example step_cost [air|subsea|down]` (one case
//! by name, e.g. under `perf stat`, or all three). 102 000 steps per case (2 000 warm-up).

use std::time::Instant;

use seaarms_core::sim::{Input, SimParams, Simulation};
use seaarms_core::{Model, ModelSpec, robots};

fn magnum() -> Model {
    let text = robots::builtin_text("magnum").expect("magnum");
    let spec: ModelSpec = serde_json::from_str(text).expect("parses");
    Model::from_spec(&spec).expect("builds")
}

/// Mean µs per step over `n` steps (after a warm-up), resetting every 2 s of simulated time.
fn time(sim: &mut Simulation, input: &Input, n: usize) -> f64 {
    for _ in 0..2000 {
        sim.step(input);
    }
    let mut best = f64::INFINITY;
    for _ in 0..5 {
        let t = Instant::now();
        for _ in 0..n {
            if sim.time_s() > 2.0 {
                sim.reset();
            }
            sim.step(input);
        }
        best = best.min(t.elapsed().as_secs_f64() * 1e6 / n as f64);
    }
    best
}

fn main() {
    let m = magnum();
    let mut moving = Input::default();
    moving.arms[0].valves = [0.5, 0.5, -0.5, 0.5, 0.5, 1.0];
    moving.arms[1].valves = [-0.5, 0.5, -0.5, 0.5, -0.5, -1.0];
    let mut down = Input::default();
    down.arms[0].valves = [0.0, -1.0, 0.0, 0.0, 0.0, 0.0];
    down.arms[1].valves = [0.0, -1.0, 0.0, 0.0, 0.0, 0.0];
    let air = SimParams::case_study(&m, &m).expect("params");
    let wet = SimParams::training(&m, &m).expect("params");
    let mut a = Simulation::new(m.clone(), m.clone(), air).expect("sim");
    let mut w = Simulation::new(m.clone(), m.clone(), wet).expect("sim");
    let n = 20_000;
    // One case by name (for `perf stat`), or all three.
    let only = std::env::args().nth(1).unwrap_or_default();
    if only.is_empty() || only == "air" {
        println!(
            "step, free open loop, air:        {:.2} µs",
            time(&mut a, &moving, n)
        );
    }
    if only.is_empty() || only == "subsea" {
        println!(
            "step, free open loop, subsea:     {:.2} µs",
            time(&mut w, &moving, n)
        );
    }
    if only.is_empty() || only == "down" {
        println!(
            "step, shoulders down, subsea:     {:.2} µs",
            time(&mut w, &down, n)
        );
    }
}
