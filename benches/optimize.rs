//! Speed of the optimisation module: optimal posture (8 starts, 6-DOF ORION), one
//! redundancy-resolution step, and 50×50 workspace maps.
//! Targets: ≤ 20 ms, ≤ 10 µs, ≤ 1 s.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use seaarms_core::kinematics::end_effector_pose;
use seaarms_core::optimize::{PostureOptions, optimal_posture};
use seaarms_core::redundancy::{Redundancy, RedundancyParams};
use seaarms_core::studies::{MapSpec, workspace_map};
use seaarms_core::{Model, ModelSpec};

fn model(name: &str) -> Model {
    let text = seaarms_core::robots::builtin_text(name).expect("built-in model");
    let spec: ModelSpec = serde_json::from_str(text).expect("model JSON");
    Model::from_spec(&spec).expect("model builds")
}

/// Jun Fig. 3's example posture (deg → rad).
fn example_q() -> Vec<f64> {
    [-15.3f64, 49.6, -31.0, 75.5, 85.2, -18.0]
        .iter()
        .map(|d| d.to_radians())
        .collect()
}

fn bench_optimal_posture(c: &mut Criterion) {
    let orion = model("orion");
    let p = end_effector_pose(&orion, &example_q()).translation.vector;
    let target = [p.x, p.y, p.z];
    for alpha in [0.8, 0.0] {
        let opts = PostureOptions {
            alpha,
            starts: 8,
            ..Default::default()
        };
        c.bench_function(
            &format!("optimal_posture/orion_8_starts_alpha_{alpha}"),
            |b| {
                b.iter(|| {
                    optimal_posture(black_box(&orion), black_box(&target), &opts)
                        .expect("reachable")
                })
            },
        );
    }
}

fn bench_redundancy_step(c: &mut Criterion) {
    let orion = model("orion");
    let q = example_q();
    let rows = [0usize, 1, 2];
    let v = [0.1, 0.08, -0.08];
    // Baseline: one forward kinematics + geometric Jacobian.
    let mut data = seaarms_core::kinematics::KinData::new(&orion);
    c.bench_function("redundancy/baseline_jacobian_orion", |b| {
        b.iter(|| {
            seaarms_core::kinematics::jacobian(&orion, &mut data, black_box(&q));
            data.jacobian[(0, 0)]
        })
    });
    let mut r = Redundancy::new(&orion, RedundancyParams::default());
    c.bench_function("redundancy/step_eq21_orion_translational", |b| {
        b.iter(|| {
            r.step(&orion, black_box(&q), black_box(&v), &rows, 0.001)
                .expect("step")[0]
        })
    });
    let mut r = Redundancy::new(&orion, RedundancyParams::default());
    r.reset_reference(&orion, &q).expect("q");
    c.bench_function("redundancy/step_tracking_eq23_orion_translational", |b| {
        b.iter(|| {
            r.step_tracking(&orion, black_box(&q), black_box(&[0.0; 3]), &rows, 0.001)
                .expect("step")[0]
        })
    });
    let mut r = Redundancy::new(
        &orion,
        RedundancyParams {
            epsilon: 0.0,
            ..Default::default()
        },
    );
    c.bench_function("redundancy/step_plain_pinv_orion_6rows", |b| {
        b.iter(|| {
            r.step(
                &orion,
                black_box(&q),
                black_box(&[0.1, 0.08, -0.08, 0.0, 0.0, 0.0]),
                &[0, 1, 2, 3, 4, 5],
                0.001,
            )
            .expect("step")[0]
        })
    });
}

fn bench_workspace_map(c: &mut Criterion) {
    let magnum = model("magnum");
    let spec = MapSpec::case_study(&magnum);
    let mut g = c.benchmark_group("workspace_map");
    g.sample_size(10);
    g.bench_function("magnum_50x50_nominal_orientation", |b| {
        b.iter(|| workspace_map(&magnum, black_box(&spec)).expect("map"))
    });
    let orion = model("orion");
    let spec = MapSpec {
        x_range: [-1.2, 1.4],
        z_range: [-1.2, 1.4],
        nx: 50,
        nz: 50,
        y: 0.0,
        orientation: None,
    };
    g.bench_function("orion_50x50_position_only", |b| {
        b.iter(|| workspace_map(&orion, black_box(&spec)).expect("map"))
    });
    g.finish();
}

criterion_group!(
    benches,
    bench_optimal_posture,
    bench_redundancy_step,
    bench_workspace_map
);
criterion_main!(benches);
