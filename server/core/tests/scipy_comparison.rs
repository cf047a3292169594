//! Not a check: prints the ORION optimal-posture case (Jun Fig. 4(d), α = 0.8) as JSON for
//! `benches/scipy_slsqp.py`, with our objective and wall time, so scipy's SLSQP can be run on
//! the same objective, constraint and feasible starts. Run with
//! `cargo test --release -p seaarms-core --test scipy_comparison -- --ignored --nocapture`.

mod common;

use std::time::Instant;

use seaarms_core::kinematics::end_effector_pose;
use seaarms_core::optimize::{PostureOptions, optimal_posture};

#[test]
#[ignore = "prints benchmark data; run on demand"]
fn print_orion_case_for_scipy() {
    let model = common::builtin("orion");
    let q: Vec<f64> = [-15.3f64, 49.6, -31.0, 75.5, 85.2, -18.0]
        .iter()
        .map(|d| d.to_radians())
        .collect();
    let p = end_effector_pose(&model, &q).translation.vector;
    let target = [p.x, p.y, p.z];
    for alpha in [0.8, 1.0, 0.0] {
        let opts = PostureOptions {
            alpha,
            starts: 8,
            ..Default::default()
        };
        let r = optimal_posture(&model, &target, &opts).expect("reachable");
        let runs = 30;
        let t0 = Instant::now();
        for _ in 0..runs {
            std::hint::black_box(optimal_posture(&model, &target, &opts).expect("reachable"));
        }
        let ms = t0.elapsed().as_secs_f64() * 1e3 / runs as f64;
        let starts: Vec<Vec<f64>> = r.starts.iter().filter_map(|s| s.start.clone()).collect();
        let per_start: Vec<f64> = r.starts.iter().map(|s| s.objective).collect();
        let evals: usize = r.starts.iter().map(|s| s.evaluations).sum();
        let doc = serde_json::json!({
            "alpha": alpha,
            "rows": [0, 1, 2],
            "target": target,
            "starts": starts,
            "ours": {
                "objective": r.objective,
                "q": r.q,
                "tomm": r.tomm,
                "jlm": r.jlm,
                "per_start_objective": per_start,
                "evaluations": evals,
                "time_ms": ms,
                "note": "time includes the IK projection of the 8 candidates onto the constraint"
            }
        });
        println!("SCIPY_CASE {doc}");
    }
}
