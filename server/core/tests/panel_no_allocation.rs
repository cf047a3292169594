//! The step with the intervention panel allocates nothing either (house style: Model vs Data):
//! counted with the `allocation-counter` global allocator over steps holding the valve and
//! holding the stab against the panel face.

mod common;

use common::panel_util::{insert_pose, jaw, run_toward, sim_at, stab_in_hand, tool_at, toward};
use nalgebra::Vector3;
use seaarms_core::panel::PanelParams;
use seaarms_core::sim::Arm;

#[test]
fn panel_steps_do_not_allocate() {
    let panel = PanelParams::standard();
    let mut valve = sim_at(Arm::Left, &tool_at(panel.valve_grip_m()));
    for _ in 0..800 {
        valve.step(&jaw(Arm::Left, -1.0));
    }
    assert!(valve.panel().expect("panel").valve_holder.is_some());
    let mut turn = jaw(Arm::Left, -0.3);
    turn.arms[0].valves[5] = -0.5;
    let turning = allocation_counter::measure(|| {
        for _ in 0..500 {
            valve.step(&turn);
        }
    });
    assert_eq!(turning.count_total, 0, "turning the valve");
    let (mut stab, panel) = stab_in_hand(Arm::Right);
    let target = insert_pose(&panel, 0.02, Vector3::new(0.0, 0.0, 0.02), 0.0);
    // The target is 0.16 m from the pulled-clear stab and `toward` moves at ≤ 5 cm/s: 1.5 s
    // brings the stab to the face with margin.
    run_toward(&mut stab, Arm::Right, &target, 1500);
    let input = toward(&stab, Arm::Right, &target, -0.2);
    let pressing = allocation_counter::measure(|| {
        for _ in 0..500 {
            stab.step(&input);
        }
    });
    assert!(
        stab.panel().expect("panel").face_force_n > 0.0,
        "pressing on the face"
    );
    assert_eq!(
        pressing.count_total, 0,
        "the stab pressing on the panel face"
    );
    // The counter works: a Vec does allocate.
    let control = allocation_counter::measure(|| {
        std::hint::black_box(vec![1u8; 16]);
    });
    assert!(control.count_total > 0);
}
