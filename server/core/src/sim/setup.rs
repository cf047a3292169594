//! The case-study setup of Lim §4.2–4.3: where the two Magnum arms, the seabed and the 50 kg
//! box are ([`SimParams::case_study`]), and the arms' reset posture.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

use super::{ArmParams, SimParams, StepParams};
use crate::Error;
use crate::control::ControlParams;
use crate::dynamics::Inertials;
use crate::grasp::ObjectParams;
use crate::hydraulics::{Faults, HydraulicParams, N_ACT};
use crate::model::Model;

/// Right arm base at the world origin, left arm base 1.0 m to its left (+y), both facing +x
/// (Lim §4.3.2: "the Y coordinate of the right arm was 0.0 m and the left arm was 1.0 m").
pub const LEFT_BASE_Y_M: f64 = 1.0;
/// Seabed height below the arm bases (m): −0.45 (assumed: the 50 kg box's handles then sit
/// at z ≈ −0.22, inside the thesis's case-study workspace after a 0.2 m lift).
pub const SEABED_Z_M: f64 = -0.45;
/// Object centre (x, y) on the seabed (m): (1.0, 0.5), midway between the arms.
pub const OBJECT_XY_M: [f64; 2] = [1.0, 0.5];
/// Reset posture of both arms (rad): swing 0, shoulder 30°, elbow −70°, pitch −20°, yaw 0,
/// rotate 0 — jaws raised in front of the arm, clear of the object.
pub const INITIAL_Q: [f64; N_ACT] = [0.0, 30.0 * DEG, -70.0 * DEG, -20.0 * DEG, 0.0, 0.0];
const DEG: f64 = std::f64::consts::PI / 180.0;

impl SimParams {
    /// The case-study setup: two Magnum arms ([`HydraulicParams::magnum`], [`Inertials::magnum`]),
    /// bases per [`LEFT_BASE_Y_M`], the 50 kg box at [`OBJECT_XY_M`] on the seabed at
    /// [`SEABED_Z_M`], default step and control parameters.
    pub fn case_study(left: &Model, right: &Model) -> Result<SimParams, Error> {
        let arm = |m: &Model, y: f64| -> Result<ArmParams, Error> {
            let inertials = Inertials::magnum(m)?;
            let hydraulics = HydraulicParams::magnum(m, &inertials)?;
            Ok(ArmParams {
                base: Isometry3::translation(0.0, y, 0.0),
                inertials,
                hydraulics,
                initial_q: INITIAL_Q,
                faults: Faults::default(),
            })
        };
        Ok(SimParams {
            arms: [arm(left, LEFT_BASE_Y_M)?, arm(right, 0.0)?],
            object: ObjectParams::case_study_box(OBJECT_XY_M[0], OBJECT_XY_M[1], SEABED_Z_M),
            step: StepParams::default(),
            control: ControlParams::default(),
        })
    }
}

/// Convenience: an isometry from a translation and a rotation vector.
pub fn pose(t: [f64; 3], r: [f64; 3]) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(t[0], t[1], t[2]),
        UnitQuaternion::from_scaled_axis(Vector3::new(r[0], r[1], r[2])),
    )
}
