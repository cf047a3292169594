//! Runs the full 6-DOF analysis N times (default 10 000): a fixed workload for instruction
//! counting with `valgrind --tool=callgrind`, which is repeatable on a busy machine where
//! wall-clock benchmarks are not. `cargo build --release --example analysis_loop`.

use seaarms_core::analysis::analyze;
use seaarms_core::{Model, ModelSpec, robots};

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(10_000);
    let spec: ModelSpec =
        serde_json::from_str(robots::builtin_text("magnum").expect("built-in")).expect("parses");
    let model = Model::from_spec(&spec).expect("builds");
    let mut q = [0.1, 0.6, -1.1, 0.4, 0.2, 0.3];
    let mut acc = 0.0;
    for i in 0..n {
        q[0] = 0.1 + 1e-6 * i as f64;
        let a = analyze(&model, &q, None).expect("analysis");
        acc += a.full.yoshikawa + a.translational.isotropy;
    }
    println!("{acc}");
}
