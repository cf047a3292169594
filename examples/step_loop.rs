//! Runs N one-millisecond steps (default 10 000) of the whole system in one of three
//! situations — `free` (both arms moving open loop), `holding` (both jaws on the object,
//! open loop) or `coop` (closed-loop cooperative lift) — a fixed workload for instruction
//! counting with `valgrind --tool=callgrind`, repeatable where wall-clock timing is not.
//! Prints the mean and the fastest and median 100-step batch.
//! `cargo build --release --example step_loop; valgrind --tool=callgrind --collect-atstart=no
//! --toggle-collect='*step_loop::run*' target/release/examples/step_loop coop 1000`.

use seaarms_core::sim::{ControlMethod, Input, SimParams, Simulation};
#[path = "../benches/common/mod.rs"]
mod common;

use common::{holding_sim, magnum};

/// The measured loop (callgrind: `--collect-atstart=no --toggle-collect='*step_loop::run*'`
/// counts only this, not the set-up).
#[inline(never)]
fn run(sim: &mut Simulation, input: &Input, n: usize) {
    for _ in 0..n {
        sim.step(input);
    }
}

fn main() {
    let mut args = std::env::args().skip(1);
    let what = args.next().unwrap_or_else(|| "coop".into());
    let n: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(10_000);
    let m = magnum();
    let (mut sim, input) = match what.as_str() {
        "free" => {
            let params = SimParams::case_study(&m, &m).expect("params");
            let mut input = Input::default();
            input.arms[0].valves = [0.5, 0.5, -0.5, 0.5, 0.5, 1.0];
            input.arms[1].valves = [-0.5, 0.5, -0.5, 0.5, -0.5, -1.0];
            (Simulation::new(m.clone(), m, params).expect("sim"), input)
        }
        "holding" => (holding_sim(&m), Input::default()),
        _ => (
            holding_sim(&m),
            Input {
                method: ControlMethod::Closed,
                object_velocity: [0.0, 0.0, 0.02, 0.0, 0.0, 0.0],
                ..Input::default()
            },
        ),
    };
    // Batches of 100 steps: on a shared machine the fastest batches show the step's own
    // speed, the median what a contended core gives.
    const BATCH: usize = 100;
    let start = sim.clone();
    let mut batches = Vec::with_capacity(n / BATCH + 1);
    let t0 = std::time::Instant::now();
    for b in 0..n.div_ceil(BATCH) {
        // Stay within 5 s of simulated time of the starting state, as the criterion bench.
        if b % 50 == 49 {
            sim = start.clone();
        }
        let tb = std::time::Instant::now();
        run(&mut sim, &input, BATCH);
        batches.push(tb.elapsed().as_secs_f64() * 1e6 / BATCH as f64);
    }
    let el = t0.elapsed();
    batches.sort_by(f64::total_cmp);
    println!(
        "{what}: {n} steps, mean {:.3} µs/step, fastest batch {:.3}, median batch {:.3}",
        el.as_secs_f64() * 1e6 / n as f64,
        batches[0],
        batches[batches.len() / 2],
    );
}
