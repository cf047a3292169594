//! The 1 kHz step allocates nothing (house style: Model vs Data, preallocated workspaces):
//! counted with the `allocation-counter` global allocator over steps in every mode (free arms, one and two
//! jaws holding, closed-loop cooperative control, joint servo).

mod common;

use common::scenario_util::{run_while, start};
use seaarms_core::sim::{Arm, ControlMethod, Input};

#[test]
fn step_does_not_allocate() {
    let (sc, mut sim) = start("case4-dual-closed-loop");
    let mut open = Input::default();
    open.arms[0].valves = [0.3, 0.2, -0.2, 0.1, 0.4, 1.0];
    open.arms[1].joint_velocity_ref = Some([0.1, -0.1, 0.1, 0.2, -0.2, 0.5]);
    let free = allocation_counter::measure(|| {
        for _ in 0..200 {
            sim.step(&open);
        }
    });
    assert_eq!(free.count_total, 0, "free arms");
    sim.reset();
    run_while(&sc, &mut sim, |_, s| {
        !(s.arm(Arm::Left).holding && s.arm(Arm::Right).holding)
    });
    let coop = Input {
        method: ControlMethod::Closed,
        object_velocity: [0.0, 0.0, 0.02, 0.0, 0.0, 0.0],
        ..Input::default()
    };
    let held = allocation_counter::measure(|| {
        for _ in 0..200 {
            sim.step(&coop);
        }
        for _ in 0..200 {
            sim.step(&Input::default());
        }
    });
    assert_eq!(held.count_total, 0, "holding, closed and open loop");
    // The counter works: a scenario row (manipulability SVDs) does allocate.
    let row = allocation_counter::measure(|| {
        std::hint::black_box(seaarms_core::sim::scenario::row(&sim, "x"));
    });
    assert!(row.count_total > 0);
}
