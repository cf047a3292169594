//! Velocity polytope timings (Kilic §3.2): the 7-DOF PA10's translational polytope at Kilic's
//! §4.2 posture (target ≤ 100 µs; pycapacity takes 3.6 ms), and the dual-arm polytope of two
//! Magnum arms in one frame.

use std::f64::consts::FRAC_PI_4;
use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{DMatrix, Rotation3, Vector3};
use seaarms_core::kinematics::jacobian_at;
use seaarms_core::manipulability::{dual_velocity_polytope, select_rows, velocity_polytope};
use seaarms_core::{Model, ModelSpec, robots};

fn builtin(name: &str) -> Model {
    let text = robots::builtin_text(name).expect("built-in model");
    let spec: ModelSpec = serde_json::from_str(text).expect("model JSON parses");
    Model::from_spec(&spec).expect("model builds")
}

fn translational(model: &Model, q: &[f64]) -> DMatrix<f64> {
    select_rows(&jacobian_at(model, q), &[0, 1, 2]).expect("rows 0..3")
}

fn bench_polytope(c: &mut Criterion) {
    let pa10 = builtin("pa10");
    let q = [0.0, FRAC_PI_4, 0.0, FRAC_PI_4, 0.0, FRAC_PI_4, 0.0];
    let j = translational(&pa10, &q);
    let qmax = pa10.max_velocities();
    c.bench_function("velocity_polytope pa10 kilic posture", |b| {
        b.iter(|| velocity_polytope(black_box(&j), black_box(&qmax)).expect("polytope"))
    });
    // A generic PA10 posture: 7 pairwise non-coplanar generators, 44 corners.
    let q = [0.3, 0.7, -0.4, 1.1, 0.5, -0.6, 0.2];
    let j = translational(&pa10, &q);
    c.bench_function("velocity_polytope pa10 generic posture", |b| {
        b.iter(|| velocity_polytope(black_box(&j), black_box(&qmax)).expect("polytope"))
    });

    // Two Magnum arms facing each other: arm 2's base is turned by π about z and its
    // Jacobian rows are rotated into arm 1's base frame.
    let magnum = builtin("magnum");
    let qmax = magnum.max_velocities();
    let j1 = translational(&magnum, &[0.2, 0.4, -1.2, 0.3, -0.5, 0.8]);
    let r = Rotation3::from_axis_angle(&Vector3::z_axis(), std::f64::consts::PI);
    let r = DMatrix::from_column_slice(3, 3, r.matrix().as_slice());
    let j2 = &r * translational(&magnum, &[-0.1, 0.6, -1.0, -0.4, 0.6, -0.3]);
    c.bench_function("dual_velocity_polytope two magnum arms", |b| {
        b.iter(|| {
            dual_velocity_polytope(
                black_box(&j1),
                black_box(&qmax),
                black_box(&j2),
                black_box(&qmax),
            )
            .expect("dual polytope")
        })
    });
}

criterion_group!(benches, bench_polytope);
criterion_main!(benches);
