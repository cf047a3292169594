//! The object, its contact with the seabed, grasp detection and the grasp matrices
//! (Lim §3.4.2, eqs 3.39–3.47).
//!
//! Wrench convention: a contact wrench F_c^i = [f; m] (6: force N, moment N·m, base frame) is
//! what end-effector i exerts on the object at its grasp point. The object twist is
//! [v; ω] of its centre of mass, base frame.
//!
//! # Layout
//! * `object`: [`ObjectParams`], the 50 kg box with two handles and a lifting point.
//! * `handle`: [`Handle`], a handle bar, and [`Alignment`]: when a jaw lies on it so that it
//!   can take it.
//! * `seabed`: [`seabed_contact`], [`seabed_wrench`]: the seabed's push on the box and its
//!   damping matrix.
//! * `matrices`: [`grasp_block`], [`grasp_matrix`], [`grasp_pinv_equal_share`],
//!   [`internal_basis`]: W = [W¹ W²] (eq. 3.40), the equal-load-sharing W⁺ (eq. 3.46) and V
//!   (eq. 3.47); the object mobility at the grasp points ([`mobility_block`]); [`decompose`]
//!   and [`internal_wrench`]: external and internal force/torque of a pair of contact wrenches;
//!   [`moment_free_share`]: a share of the object wrench that the jaws carry by forces.
//! * `grip`: [`GripParams`], [`GripCapacity`]: the finite grip of a jaw on a handle bar —
//!   friction limits from the clamp force, the limit-surface load fraction, the kinetic
//!   wrench of a slipping jaw.
//! * here: [`GraspState`], the colour code of Lim §4.1.

mod grip;
mod handle;
mod matrices;
mod object;
mod seabed;

pub use grip::{GripCapacity, GripParams, from_jaw, kinetic_wrench, mean_radius, to_jaw};
pub use handle::{Alignment, Handle, Posts};
pub use matrices::{
    decompose, grasp_block, grasp_matrix, grasp_pinv_equal_share, grasp_point_twist,
    internal_basis, internal_wrench, mobility_block, mobility_block_general,
    mobility_block_general_lower, moment_free_share, wrench_at_com,
};
pub use object::{LIFTING_POINT, LIFTING_POINT_RISE_M, N_HANDLES, ObjectParams};
pub use seabed::{
    STICK_STIFFNESS_N_M, SeabedAnchors, SeabedContact, corner_friction, seabed_contact,
    seabed_wrench,
};

use serde::{Deserialize, Serialize};

/// Grasp state, with the colour code of Lim §4.1 (Fig. 4-4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GraspState {
    /// No jaw holds the object.
    Free,
    /// One jaw holds it and it still touches the seabed (black).
    OneOnSurface,
    /// One jaw holds it clear of the seabed (light blue).
    OneLifted,
    /// One jaw holds it and the other arm touches it (red).
    OneHoldingOtherContact,
    /// Both jaws hold it (yellow).
    BothHolding,
}

impl GraspState {
    /// Snake-case name used in CSV and JSON.
    pub fn as_str(self) -> &'static str {
        match self {
            GraspState::Free => "free",
            GraspState::OneOnSurface => "one_on_surface",
            GraspState::OneLifted => "one_lifted",
            GraspState::OneHoldingOtherContact => "one_holding_other_contact",
            GraspState::BothHolding => "both_holding",
        }
    }

    /// Colour of the object in the GUI (Lim §4.1): "" (default colour), black, light blue, red, yellow.
    pub fn colour(self) -> &'static str {
        match self {
            GraspState::Free => "",
            GraspState::OneOnSurface => "black",
            GraspState::OneLifted => "lightblue",
            GraspState::OneHoldingOtherContact => "red",
            GraspState::BothHolding => "yellow",
        }
    }

    /// Classifies from per-arm holding/contact flags and seabed contact.
    pub fn classify(holding: [bool; 2], contact: [bool; 2], on_surface: bool) -> GraspState {
        match (holding[0], holding[1]) {
            (true, true) => GraspState::BothHolding,
            (false, false) => GraspState::Free,
            (h0, _) => {
                let other = if h0 { contact[1] } else { contact[0] };
                if other {
                    GraspState::OneHoldingOtherContact
                } else if on_surface {
                    GraspState::OneOnSurface
                } else {
                    GraspState::OneLifted
                }
            }
        }
    }
}
