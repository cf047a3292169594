//! The grasp state (Lim §4.1's colour code) follows the seabed contact through a debounce
//! (`seaarms_core::sim::SURFACE_DWELL_S`): a box dragged on one corner while it slips in the
//! jaw makes and breaks contact many times a second, and without the debounce every flicker
//! was a grasp-state event. Checked on the `pick-and-place` autopilot on the finite grip, twice:
//! as shipped (the jaw kept at its attitude, a clean lift with one lift-off bounce: lifted 62 ms,
//! touching 8 ms) the colour sequence of a one-arm pick and place; and with the jaw left to the
//! translational-only resolver (the script's attitude and levelling removed), which turns the
//! jaw so the box's moment loads the pads' torsion: the box is dragged on one corner while the
//! bar slides out of the jaw (44 contact changes, gaps of 1–130 ms), and the grasp state goes
//! only from free to on-surface and back. In both, whenever the raw contact has held for longer
//! than the dwell, the reported state agrees with it.

mod common;
use common::magnum;

use std::sync::Arc;

use seaarms::catalogue::EXERCISES;
use seaarms::exercises::{Driver, run_recorded};
use seaarms_core::exercise::ExerciseSpec;
use seaarms_core::exercise::autopilot::Action;
use seaarms_core::grasp::GraspState;
use seaarms_core::sim::SURFACE_DWELL_S;

/// What one run showed: the grasp-state sequence, the number of raw seabed-contact changes,
/// and on how many steps the invariant was checked.
struct Observed {
    states: Vec<GraspState>,
    contact_changes: u32,
    checked: u64,
}

/// The shipped `pick-and-place` on the finite grip, its script changed by `edit`, checking at
/// every step that a one-jaw state agrees with any raw contact held longer than the dwell.
fn finite_grip_run(edit: impl Fn(&mut Action)) -> Observed {
    let mut spec: ExerciseSpec = (*EXERCISES.get("pick-and-place").expect("shipped")).clone();
    // The finite grip (the file keeps the rigid one for its pass mark; docs/physics.md).
    spec.scene.rigid_grasp = false;
    // The script's moves as they were written: translation leaves the jaw's orientation to
    // the redundancy resolution (its dragged variant relies on the jaw turning as it drags).
    spec.control.hold_orientation = Some(false);
    spec.autopilot.iter_mut().for_each(edit);
    let mut seen = Observed {
        states: Vec::new(),
        contact_changes: 0,
        checked: 0,
    };
    let (mut raw, mut raw_since) = (true, 0.0);
    run_recorded(
        Arc::new(spec),
        &magnum(),
        Driver::Autopilot,
        1,
        &mut |live| {
            let sim = live.sim();
            let g = sim.grasp_state();
            if seen.states.last() != Some(&g) {
                seen.states.push(g);
            }
            let touching = sim.object().seabed_force_n > 0.0;
            if touching != raw {
                (raw, raw_since) = (touching, sim.time_s());
                seen.contact_changes += 1;
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
                seen.checked += 1;
            }
        },
    )
    .expect("headless run");
    seen
}

#[test]
fn one_arm_pick_and_place_on_the_finite_grip_does_not_chatter() {
    let seen = finite_grip_run(|_| {});
    assert_eq!(
        seen.states,
        [
            GraspState::Free,
            GraspState::OneOnSurface,
            GraspState::OneLifted,
            GraspState::OneOnSurface,
            GraspState::Free
        ],
        "grasp states {:?}",
        seen.states
    );
    // Lift-off and set-down at least. (Before issue 27's seabed static friction and
    // closed-chain rate control the lift-off also bounced once — two more contact changes
    // the debounce hid; with them it lifts cleanly, 2 changes measured. The debounce under
    // many changes is checked by the dragged-corner test below.)
    assert!(seen.contact_changes >= 2, "{}", seen.contact_changes);
    assert!(
        seen.checked > 1000,
        "the invariant was checked on {} steps",
        seen.checked
    );
}

#[test]
fn a_box_dragged_on_one_corner_stays_on_surface() {
    let seen = finite_grip_run(|a| match a {
        Action::Move {
            attitude_rotvec, ..
        } => *attitude_rotvec = None,
        Action::Sticks { level, .. } => *level = false,
        _ => {}
    });
    assert_eq!(
        seen.states,
        [GraspState::Free, GraspState::OneOnSurface, GraspState::Free],
        "grasp states {:?}",
        seen.states
    );
    assert!(
        seen.contact_changes > 20,
        "the dragged box made and broke contact only {} times",
        seen.contact_changes
    );
    // Dragged, the contact seldom holds longer than the dwell (89 steps in this run).
    assert!(seen.checked > 0, "the invariant was never checked");
}
