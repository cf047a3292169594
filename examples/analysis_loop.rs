//! Runs the full 6-DOF analysis N times (default 10 000): a fixed workload for instruction
//! counting with `valgrind --tool=callgrind`, which is repeatable on a busy machine where
//! wall-clock benchmarks are not. `cargo build --release --example analysis_loop`.
//!
//! `analysis_loop N [MODE]` with MODE one of `analysis` (default), `svd` (only `full_svd`
//! of the 6×6 Jacobian), `pair` (only the translational/rotational `row_measures_pair`) and
//! `dual` (only `dual_measures` of two 3×6 translational Jacobians, as the scenario runner
//! calls it), `rx90` (the full analysis of the RX90 at the benchmark's posture
//! q = [0.6, 1.25, −0.3, 0.6, 0.3, 2.0], q₁ nudged per call) and `svd-rx90` (only `full_svd`
//! of that RX90 Jacobian). The cost of one call is the difference of two runs divided by the difference
//! of their N.

use nalgebra::DMatrix;
use seaarms_core::analysis::{ROTATIONAL_ROWS, TRANSLATIONAL_ROWS, analyze};
use seaarms_core::kinematics::{KinData, jacobian};
use seaarms_core::manipulability::{dual_measures, full_svd, row_measures_pair, select_rows};
use seaarms_core::{Model, ModelSpec, robots};

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(10_000);
    let mode = std::env::args().nth(2).unwrap_or_else(|| "analysis".into());
    let spec: ModelSpec =
        serde_json::from_str(robots::builtin_text("magnum").expect("built-in")).expect("parses");
    let model = Model::from_spec(&spec).expect("builds");
    let spec_rx: ModelSpec =
        serde_json::from_str(robots::builtin_text("rx90").expect("built-in")).expect("parses");
    let rx90 = Model::from_spec(&spec_rx).expect("builds");
    let j_rx = {
        let mut data = KinData::new(&rx90);
        jacobian(&rx90, &mut data, &[0.6, 1.25, -0.3, 0.6, 0.3, 2.0]);
        data.jacobian
    };
    let mut q = [0.1, 0.6, -1.1, 0.4, 0.2, 0.3];
    let jac = |q: &[f64]| -> DMatrix<f64> {
        let mut data = KinData::new(&model);
        jacobian(&model, &mut data, q);
        data.jacobian
    };
    let j = jac(&q);
    let j1 = select_rows(&j, &TRANSLATIONAL_ROWS).expect("rows");
    let j2 = select_rows(
        &jac(&[-0.3, 0.9, -0.7, -0.5, 0.8, -0.2]),
        &TRANSLATIONAL_ROWS,
    )
    .expect("rows");
    let mut acc = 0.0;
    for i in 0..n {
        let e = 1e-6 * i as f64;
        match mode.as_str() {
            "svd" => {
                let mut ji = j.clone();
                ji[(0, 0)] += e;
                acc += full_svd(&ji).expect("svd").sigma[5];
            }
            "pair" => {
                let mut ji = j.clone();
                ji[(0, 0)] += e;
                let [t, r] =
                    row_measures_pair(&ji, [&TRANSLATIONAL_ROWS, &ROTATIONAL_ROWS]).expect("rows");
                acc += t.isotropy + r.isotropy;
            }
            "dual" => {
                let mut ji = j1.clone();
                ji[(0, 0)] += e;
                acc += dual_measures(&ji, &j2).expect("dual").yoshikawa;
            }
            "rx90" => {
                let q = [0.6 + e, 1.25, -0.3, 0.6, 0.3, 2.0];
                let a = analyze(&rx90, &q, None).expect("analysis");
                acc += a.full.yoshikawa + a.translational.isotropy;
            }
            "svd-rx90" => {
                let mut ji = j_rx.clone();
                ji[(0, 0)] += e;
                acc += full_svd(&ji).expect("svd").sigma[5];
            }
            _ => {
                q[0] = 0.1 + e;
                let a = analyze(&model, &q, None).expect("analysis");
                acc += a.full.yoshikawa + a.translational.isotropy;
            }
        }
    }
    println!("{acc}");
}
