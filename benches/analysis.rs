//! Speed of the stateless analysis: one full analysis (FK, Jacobian, SVD, every measure, JLM
//! and its gradient, SVD subspaces) of a 6-DOF arm. Target ≤ 5 µs (issue: analysis core).
//! The HTTP throughput of `POST /api/analysis` is measured with `benches/analysis_load.sh`.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use seaarms_core::analysis::analyze;
use seaarms_core::kinematics::{KinData, jacobian};
use seaarms_core::manipulability::{measures, row_measures_pair, select_rows};
use seaarms_core::{Model, ModelSpec, robots};

fn model(name: &str) -> Model {
    let spec: ModelSpec =
        serde_json::from_str(robots::builtin_text(name).expect("built-in")).expect("parses");
    Model::from_spec(&spec).expect("builds")
}

fn bench(c: &mut Criterion) {
    let magnum = model("magnum");
    let q = [0.1, 0.6, -1.1, 0.4, 0.2, 0.3];
    c.bench_function("full analysis, magnum (6 DOF)", |b| {
        b.iter(|| analyze(black_box(&magnum), black_box(&q), None).expect("analysis"))
    });
    let rx90 = model("rx90");
    let q_rx = [0.6, 1.25, -0.3, 0.6, 0.3, 2.0];
    c.bench_function("full analysis, rx90 (6 DOF)", |b| {
        b.iter(|| analyze(black_box(&rx90), black_box(&q_rx), None).expect("analysis"))
    });
    let mut data = KinData::new(&magnum);
    c.bench_function("FK + Jacobian, magnum", |b| {
        b.iter(|| jacobian(black_box(&magnum), &mut data, black_box(&q)))
    });
    jacobian(&magnum, &mut data, &q);
    let jt = select_rows(&data.jacobian, &[0, 1, 2]).expect("rows");
    c.bench_function("translational measures (3x6)", |b| {
        b.iter(|| measures(black_box(&jt)).expect("measures"))
    });
    let jfull = data.jacobian.clone();
    c.bench_function("translational + rotational measures (lockstep pair)", |b| {
        b.iter(|| row_measures_pair(black_box(&jfull), [&[0, 1, 2], &[3, 4, 5]]).expect("measures"))
    });
    let j6 = data.jacobian.clone();
    // One-sided Jacobi (ours) against nalgebra's Golub–Kahan SVD and the eigen solve of JJᵀ
    // that the analysis used before.
    c.bench_function("full SVD with U and V (6x6, dynamic)", |b| {
        b.iter(|| seaarms_core::manipulability::full_svd(black_box(&j6)).expect("svd"))
    });
    let s6 = nalgebra::Matrix6::from_iterator(j6.iter().copied());
    c.bench_function("nalgebra SVD (6x6, static)", |b| {
        b.iter(|| nalgebra::SVD::new(black_box(s6), true, true))
    });
    c.bench_function("nalgebra symmetric eigen of JJt (6x6, static)", |b| {
        b.iter(|| nalgebra::SymmetricEigen::new(black_box(s6) * s6.transpose()))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
