//! The grasp state (Lim §4.1's colour code) follows the seabed contact through a debounce
//! (`seaarms_core::sim::SURFACE_DWELL_S`): a box dragged on one corner while it slips in the
//! jaw makes and breaks contact many times a second, and without the debounce every flicker
//! was a grasp-state event (35 in the `pick-and-place` autopilot run on the finite grip,
//! gaps of 10–200 ms). Checked on that run: the colour sequence of a one-arm pick and place,
//! and the invariant that whenever the raw contact has held for longer than the dwell, the
//! reported state agrees with it.

use std::sync::Arc;

use seaarms::exercises::{Driver, EXERCISES, run_recorded};
use seaarms_core::exercise::ExerciseSpec;
use seaarms_core::grasp::GraspState;
use seaarms_core::sim::SURFACE_DWELL_S;

#[test]
fn one_arm_pick_and_place_on_the_finite_grip_does_not_chatter() {
    let robots = seaarms::robots::Robots::load().expect("built-in robots");
    let m = robots.get("magnum").expect("magnum");
    let mut spec: ExerciseSpec = (*EXERCISES.get("pick-and-place").expect("shipped")).clone();
    // The finite grip (the file keeps the rigid one for its pass mark; docs/physics.md).
    spec.scene.rigid_grasp = false;
    let mut seq: Vec<GraspState> = Vec::new();
    let (mut raw, mut raw_since) = (true, 0.0);
    let mut checked = 0u64;
    run_recorded(
        Arc::new(spec),
        &[m.clone(), m],
        Driver::Autopilot,
        1,
        &mut |live| {
            let sim = live.sim();
            let g = sim.grasp_state();
            if seq.last() != Some(&g) {
                seq.push(g);
            }
            let touching = sim.object().seabed_force_n > 0.0;
            if touching != raw {
                (raw, raw_since) = (touching, sim.time_s());
            }
            let one_jaw = matches!(g, GraspState::OneOnSurface | GraspState::OneLifted);
            if one_jaw && sim.time_s() - raw_since > SURFACE_DWELL_S + 0.002 {
                let want = if raw {
                    GraspState::OneOnSurface
                } else {
                    GraspState::OneLifted
                };
                assert_eq!(
                    g,
                    want,
                    "t = {:.3} s: contact held since {raw_since:.3} s",
                    sim.time_s()
                );
                checked += 1;
            }
        },
    )
    .expect("headless run");
    assert_eq!(
        seq,
        [
            GraspState::Free,
            GraspState::OneOnSurface,
            GraspState::OneLifted,
            GraspState::OneOnSurface,
            GraspState::Free
        ],
        "grasp states {seq:?}"
    );
    assert!(
        checked > 1000,
        "the invariant was checked on {checked} steps"
    );
}
