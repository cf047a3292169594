//! One full 1 ms step of the whole system (two arms' rigid-body dynamics, 12 actuators with
//! their valves and chambers, jaws, object, grasp constraint, control), in three situations:
//! arms moving open loop, both jaws holding the object open loop, and closed-loop cooperative
//! (the thesis's in-air setting of the case studies); and the arms moving open loop in sea
//! water, the training default (buoyancy, drag and added mass, docs/physics.md); and both arms
//! pressed into the seabed in water at full stick, every contact of the step in use (issue
//! 27's budget: ≤ 10 µs).

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use seaarms_core::sim::{ControlMethod, Input, SimParams, Simulation};
mod common;

use common::{holding_sim, magnum};

fn bench_step(c: &mut Criterion) {
    let m = magnum();
    let params = SimParams::case_study(&m, &m).expect("params");
    let mut free = Simulation::new(m.clone(), m.clone(), params).expect("sim");
    let mut moving = Input::default();
    moving.arms[0].valves = [0.5, 0.5, -0.5, 0.5, 0.5, 1.0];
    moving.arms[1].valves = [-0.5, 0.5, -0.5, 0.5, -0.5, -1.0];
    c.bench_function("step_free_open_loop", |b| {
        b.iter(|| {
            if free.time_s() > 2.0 {
                free.reset();
            }
            free.step(black_box(&moving));
        })
    });
    let mut wet = Simulation::new(
        m.clone(),
        m.clone(),
        SimParams::training(&m, &m).expect("params"),
    )
    .expect("sim");
    c.bench_function("step_free_open_loop_subsea", |b| {
        b.iter(|| {
            if wet.time_s() > 2.0 {
                wet.reset();
            }
            wet.step(black_box(&moving));
        })
    });
    // Both shoulders driven down at full stick: after 1.5 s every link and jaw that can
    // reaches the seabed, the stall holds them there (docs/physics.md "Contacts").
    let mut down = Input::default();
    down.arms[0].valves = [0.0, -1.0, 0.0, 0.0, 0.0, 0.0];
    down.arms[1].valves = [0.0, -1.0, 0.0, 0.0, 0.0, 0.0];
    let mut pressed = wet.clone();
    pressed.reset();
    for _ in 0..1500 {
        pressed.step(&down);
    }
    assert!(
        pressed.contacts().arms.iter().all(|c| c.points > 0),
        "both arms on the seabed"
    );
    let pressed_base = pressed.clone();
    c.bench_function("step_in_contact_subsea", |b| {
        b.iter(|| {
            if pressed.time_s() > pressed_base.time_s() + 2.0 {
                pressed = pressed_base.clone();
            }
            pressed.step(black_box(&down));
        })
    });
    let base = holding_sim(&m);
    let mut held = base.clone();
    let hold = Input::default();
    c.bench_function("step_both_holding_open_loop", |b| {
        b.iter(|| {
            if held.time_s() > base.time_s() + 5.0 {
                held = base.clone();
            }
            held.step(black_box(&hold));
        })
    });
    let mut coop = base.clone();
    let lift = Input {
        method: ControlMethod::Closed,
        object_velocity: [0.0, 0.0, 0.02, 0.0, 0.0, 0.0],
        ..Input::default()
    };
    c.bench_function("step_closed_loop_cooperative", |b| {
        b.iter(|| {
            if coop.time_s() > base.time_s() + 5.0 {
                coop = base.clone();
            }
            coop.step(black_box(&lift));
        })
    });
}

criterion_group!(benches, bench_step);
criterion_main!(benches);
