//! The posture measures of a simulation's current state, computed by one function
//! ([`measures`], per arm [`arm_measures`]): each arm's translational manipulability
//! ellipsoid and its measures (Lim eqs 3.62, 3.68; Hong eq. 4.1), its joint-limit measure (Jun
//! eq. 16), its warnings (near a singularity, joints near a limit) against the one set of
//! warning thresholds, and the dual-arm ellipsoid while both jaws hold. The state frame, the
//! instructor's summary and the assessment read these.

use nalgebra::{DMatrix, Matrix6};

use super::{Arm, Simulation};
use crate::hydraulics::N_ACT;
use crate::manipulability::{Measures, dual_measures, jlm, measures as ellipsoid_measures};
use crate::model::Model;

/// Translational isotropy (σ_min/σ_max) below which an arm is near a singularity: 0.05 (the
/// state frame's `near_singularity` warning and the exercises' default).
pub const NEAR_SINGULAR_ISOTROPY: f64 = 0.05;
/// A joint within this fraction of its range from a limit is near the limit: 0.05 (the state
/// frame's `near_joint_limit` warning and the exercises' default).
pub const NEAR_LIMIT_FRACTION: f64 = 0.05;

/// One arm's measures.
#[derive(Debug, Clone, PartialEq)]
pub struct ArmMeasures {
    /// Translational manipulability (the first three rows of the world-frame Jacobian).
    pub translational: Measures,
    /// Joint-limit measure (Jun eq. 16).
    pub jlm: f64,
    /// Isotropy below [`NEAR_SINGULAR_ISOTROPY`].
    pub near_singularity: bool,
    /// Per joint: within [`NEAR_LIMIT_FRACTION`] of its range from a limit.
    pub near_limits: [bool; N_ACT],
}

/// Both arms' measures and the dual-arm one.
#[derive(Debug, Clone, PartialEq)]
pub struct SimMeasures {
    /// Left, right.
    pub arms: [ArmMeasures; 2],
    /// The dual-arm translational ellipsoid (Lim eq. 3.68) while both jaws hold; `None`
    /// otherwise (or when it cannot be computed).
    pub dual: Option<Measures>,
}

/// Translational manipulability measures of a world-frame 6×6 Jacobian's first three rows
/// (zeros when they cannot be computed).
pub fn translational_measures(jw: &Matrix6<f64>) -> Measures {
    ellipsoid_measures(&translational_rows(jw))
        .unwrap_or_else(|_| Measures::from_spectrum(&[0.0; 3], &DMatrix::identity(3, 3), 0.0))
}

/// The first three rows of a 6×6 Jacobian (3×6).
fn translational_rows(jw: &Matrix6<f64>) -> DMatrix<f64> {
    DMatrix::from_fn(3, 6, |r, c| jw[(r, c)])
}

/// Per joint: whether `q` lies within `fraction` of the joint's range from a limit.
pub fn near_limits(model: &Model, q: &[f64; N_ACT], fraction: f64) -> [bool; N_ACT] {
    let mut out = [false; N_ACT];
    for ((o, q), joint) in out.iter_mut().zip(q).zip(&model.joints) {
        if joint.is_limited() {
            let margin = fraction * (joint.limits[1] - joint.limits[0]);
            *o = q - joint.limits[0] < margin || joint.limits[1] - q < margin;
        }
    }
    out
}

/// `arm`'s measures in `sim`'s current state.
pub fn arm_measures(sim: &Simulation, arm: Arm) -> ArmMeasures {
    let translational = translational_measures(sim.jacobian_world(arm));
    let (model, q) = (sim.model(arm), &sim.arm(arm).q);
    ArmMeasures {
        near_singularity: translational.isotropy < NEAR_SINGULAR_ISOTROPY,
        translational,
        jlm: jlm(model, q),
        near_limits: near_limits(model, q, NEAR_LIMIT_FRACTION),
    }
}

/// Every measure of `sim`'s current state (see the module docs).
pub fn measures(sim: &Simulation) -> SimMeasures {
    let arms = Arm::BOTH.map(|a| arm_measures(sim, a));
    let holding = Arm::BOTH.iter().all(|&a| sim.arm(a).holding);
    let dual = holding
        .then(|| {
            let [l, r] = Arm::BOTH.map(|a| translational_rows(sim.jacobian_world(a)));
            dual_measures(&l, &r).ok()
        })
        .flatten();
    SimMeasures { arms, dual }
}
