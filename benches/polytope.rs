//! Velocity polytope timings (Kilic §3.2): the 7-DOF PA10's translational polytope at Kilic's
//! §4.2 posture (target ≤ 100 µs; pycapacity takes 3.6 ms), and the dual-arm polytope of two
//! Magnum arms in one frame.

use std::f64::consts::FRAC_PI_4;
use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use seaarms_core::kinematics::jacobian_at;
use seaarms_core::manipulability::{dual_velocity_polytope, select_rows, velocity_polytope};
use seaarms_core::{Model, ModelSpec, robots};

fn builtin(name: &str) -> Model {
    let text = robots::builtin_text(name).expect("built-in model");
    let spec: ModelSpec = serde_json::from_str(text).expect("model JSON parses");
    Model::from_spec(&spec).expect("model builds")
}

fn bench_polytope(c: &mut Criterion) {
    let pa10 = builtin("pa10");
    let q = [0.0, FRAC_PI_4, 0.0, FRAC_PI_4, 0.0, FRAC_PI_4, 0.0];
    let j = select_rows(&jacobian_at(&pa10, &q), &[0, 1, 2]).expect("rows");
    let qmax = pa10.max_velocities();
    c.bench_function("velocity_polytope pa10 kilic posture", |b| {
        b.iter(|| velocity_polytope(black_box(&j), black_box(&qmax)).expect("polytope"))
    });
    // A generic PA10 posture (no coplanar joint columns).
    let q = [0.3, 0.7, -0.4, 1.1, 0.5, -0.6, 0.2];
    let j = select_rows(&jacobian_at(&pa10, &q), &[0, 1, 2]).expect("rows");
    c.bench_function("velocity_polytope pa10 generic posture", |b| {
        b.iter(|| velocity_polytope(black_box(&j), black_box(&qmax)).expect("polytope"))
    });

    // Two Magnum arms facing each other: arm 2's base is turned by π about z and its
    // Jacobian rows are rotated into arm 1's base frame.
    let magnum = builtin("magnum");
    let qmax = magnum.max_velocities();
    let j1 = select_rows(
        &jacobian_at(&magnum, &[0.2, 0.4, -1.2, 0.3, -0.5, 0.8]),
        &[0, 1, 2],
    )
    .expect("rows");
    let mut j2 = select_rows(
        &jacobian_at(&magnum, &[-0.1, 0.6, -1.0, -0.4, 0.6, -0.3]),
        &[0, 1, 2],
    )
    .expect("rows");
    // Rz(π): x → −x, y → −y.
    j2.rows_mut(0, 2).neg_mut();
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
