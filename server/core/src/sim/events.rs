//! The step's events: what happened in the last step, typed, pushed once by the stage that
//! detects it (rapier's `EventHandler` is the model; here a preallocated list the caller
//! reads after each step, [`Simulation::events`]).
//!
//! Each happening has one detector:
//! * [`Event::Grasp`]: the grasp state (Lim §4.1 colour code, [`Simulation::grasp_state`])
//!   differs from the last step's — at the end of the step, after the seabed-contact
//!   debounce ([`super::SURFACE_DWELL_S`]);
//! * [`Event::Slip`]: a jaw's bar started slipping (its slip passed the notice threshold,
//!   [`super::SLIP_NOTICE_M`] / [`super::SLIP_NOTICE_RAD`]) — the slip stage
//!   (`constraint::slip_stage`), which also counts it in [`super::GripState::slips`];
//! * [`Event::SlidOut`]: the bar slid out of a slipping jaw, which lost its grasp — the slip
//!   stage, counted in [`super::GripState::slid_out`]. This is not the assessment's *drop*
//!   (the box let go of above the seabed, whatever the cause:
//!   [`crate::exercise::assess::DROP_HEIGHT_M`]);
//! * [`Event::Relief`]: an actuator's relief valve opened (a rising edge) — the outputs stage,
//!   counted in [`super::ArmState::relief_events`];
//! * [`Event::Strike`]: a part of an arm struck something (the seabed, the box, the panel, the
//!   vehicle, the other arm) at [`super::ContactParams::strike_speed_m_s`] or faster — the
//!   contact report (`contact.rs`), pushed once the strike's peak force is known (the contact
//!   ended, or [`super::STRIKE_WINDOW_S`] passed), counted per partner in
//!   [`super::ArmContacts::strikes`];
//! * [`Event::EndStop`]: a joint reached its end stop (the cylinder bottoming out: the joint
//!   angle left its limits) — the outputs stage. The assessment's *limit hit* is a different,
//!   exercise-set threshold (`thresholds.limit_hit_deg` before the stop).
//!
//! The exercise sampler ([`crate::exercise::ExerciseRun::sample`], 100 Hz) detects what needs
//! the exercise: exercise obstacles, jaw overloads, limit hits, drops, steps reached; it reads
//! this stream's counts (slips, relief, strikes) instead of detecting them again.

use super::{Arm, Strike};
use crate::grasp::GraspState;

/// Most events one step can push: a grasp change, and per arm a slip, a slide-out, six
/// relief openings, six end stops and two strikes per partner (one closing, one reported
/// early when another begins) (the list never grows past its preallocation).
pub const MAX_EVENTS_PER_STEP: usize = 1 + 2 * (1 + 1 + 6 + 6 + 2 * 5);

/// One thing that happened in a step (see the module docs for each detector).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Event {
    /// The grasp state changed to this.
    Grasp(GraspState),
    /// `arm`'s jaw started slipping with `load_fraction` (λ against the static limits).
    Slip {
        /// The arm.
        arm: Arm,
        /// Load fraction λ at the onset (1 = at the static friction limit).
        load_fraction: f64,
    },
    /// The bar slid out of `arm`'s jaw: its grasp is lost.
    SlidOut {
        /// The arm.
        arm: Arm,
    },
    /// `arm`'s relief valve on `actuator` (0-based) opened.
    Relief {
        /// The arm.
        arm: Arm,
        /// Actuator (joint) index, 0-based.
        actuator: usize,
    },
    /// `arm` struck something: partner, part, point, impact speed and peak force.
    Strike {
        /// The arm.
        arm: Arm,
        /// What, where, how fast and how hard.
        strike: Strike,
    },
    /// `arm`'s `joint` (0-based) reached its end stop.
    EndStop {
        /// The arm.
        arm: Arm,
        /// Joint index, 0-based.
        joint: usize,
    },
}
