//! Setting a simulation up: the checks on its parameters ([`SimParams::check`]) and the
//! case-study setup of Lim §4.2–4.3 — where the two Magnum arms, the seabed and the 50 kg box
//! are ([`SimParams::case_study`]), and the arms' reset posture.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

use super::{ArmParams, ContactParams, Environment, SimParams, StepParams};
use crate::Error;
use crate::control::ControlParams;
use crate::dynamics::Inertials;
use crate::grasp::{GripParams, ObjectParams};
use crate::hydraulics::{Faults, HydraulicParams, N_ACT};
use crate::model::Model;
use crate::panel::PanelParams;

/// Right arm base at the world origin, left arm base 1.0 m to its left (+y), both facing +x
/// (Lim §4.3.2: "the Y coordinate of the right arm was 0.0 m and the left arm was 1.0 m").
pub const LEFT_BASE_Y_M: f64 = 1.0;
/// Seabed height below the arm bases (m): −0.45 (assumed: the 50 kg box's handles then sit
/// at z ≈ −0.22, inside the thesis's case-study workspace after a 0.2 m lift).
pub const SEABED_Z_M: f64 = -0.45;
/// Object centre (x, y) on the seabed (m): (1.0, 0.5), midway between the arms.
pub const OBJECT_XY_M: [f64; 2] = [1.0, 0.5];
/// Reset posture of both arms (rad): swing 0, shoulder 20°, elbow −70°, pitch 0, yaw 0,
/// rotate 0 — jaw centre at x ≈ 1.20 m, z ≈ −0.34 m in front of each arm (11 cm above the
/// seabed, clear of the object at x ≤ 1.15), the jaw pointing 50° below the horizontal: the
/// height and attitude of the reset posture on the issue-17 links, on the links of issue 27
/// (docs/physics.md, "Link lengths"). The case studies reach their grasp postures by
/// position IK from here.
pub const INITIAL_Q: [f64; N_ACT] = [0.0, 20.0 * DEG, -70.0 * DEG, 0.0, 0.0, 0.0];
const DEG: f64 = std::f64::consts::PI / 180.0;

impl SimParams {
    /// What [`super::Simulation::new`] requires of `left`, `right` and these parameters:
    /// 6-joint arms with 6 links of finite positive mass, finite initial angles, a step in
    /// (0, 10 ms] with 1..=1000 sub-steps, a positive object mass, and a panel (if any) that
    /// passes [`PanelParams::check`] with grips the jaws can open around, and water (if any)
    /// of positive finite density with a current within [`super::Current::new`]'s bounds.
    pub fn check(&self, left: &Model, right: &Model) -> Result<(), Error> {
        for m in [&left, &right] {
            if m.dof() != N_ACT {
                return Err(Error::InvalidModel {
                    reason: format!(
                        "the simulation needs 6-joint arms, {} has {}",
                        m.name,
                        m.dof()
                    ),
                });
            }
        }
        for (i, a) in self.arms.iter().enumerate() {
            if a.inertials.links.len() != N_ACT {
                return Err(Error::InvalidParameter {
                    what: "inertials",
                    reason: format!("arm {i} needs 6 links"),
                });
            }
            if a.inertials
                .links
                .iter()
                .any(|l| l.mass_kg.is_nan() || l.mass_kg <= 0.0 || !l.mass_kg.is_finite())
            {
                return Err(Error::InvalidParameter {
                    what: "inertials",
                    reason: "masses must be finite and > 0".into(),
                });
            }
            if a.initial_q.iter().any(|v| !v.is_finite()) {
                return Err(Error::NonFinite {
                    what: "initial_q",
                    index: i,
                });
            }
        }
        let s = &self.step;
        if !(s.dt_s > 0.0 && s.dt_s <= 0.01) || s.substeps == 0 || s.substeps > 1000 {
            return Err(Error::InvalidParameter {
                what: "step",
                reason: "dt_s in (0, 0.01] and 1..=1000 substeps".into(),
            });
        }
        if self.object.mass_kg.is_nan() || self.object.mass_kg <= 0.0 {
            return Err(Error::InvalidParameter {
                what: "object",
                reason: "mass must be > 0".into(),
            });
        }
        if let Some(w) = s.environment.water() {
            let c = &w.current;
            if !(w.density_kgm3.is_finite() && w.density_kgm3 > 0.0)
                || super::Current::new(c.speed_m_s, c.heading_deg).is_err()
            {
                return Err(Error::InvalidParameter {
                    what: "environment",
                    reason: "water density must be finite and > 0, the current within bounds"
                        .into(),
                });
            }
        }
        if let Some(p) = &self.panel {
            let jaw = self.arms[0]
                .hydraulics
                .jaw
                .max_opening_m
                .min(self.arms[1].hydraulics.jaw.max_opening_m);
            p.check(jaw)?;
        }
        Ok(())
    }

    /// The case-study setup: two Magnum arms ([`HydraulicParams::magnum`], [`Inertials::magnum`]),
    /// bases per [`LEFT_BASE_Y_M`], the 50 kg box at [`OBJECT_XY_M`] on the seabed at
    /// [`SEABED_Z_M`], default step and control parameters, the jaws' finite grip
    /// ([`GripParams::default`]) and the closed loop's moment-free load share
    /// ([`ControlParams::moment_free_share`]); the case-study scenarios switch both back to the
    /// thesis's rigid grasp and equal share W⁺.
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
            // Training: the jaws' finite grip, and the closed loop's share that it can carry.
            control: ControlParams {
                moment_free_share: true,
                ..ControlParams::default()
            },
            panel: None,
            rigid_grasp: false,
            grip: GripParams::default(),
            contact: ContactParams::default(),
        })
    }

    /// The training set-up: [`SimParams::case_study`] submerged in still sea water
    /// ([`Environment::subsea`]) — what sessions and exercises run unless they ask for air.
    pub fn training(left: &Model, right: &Model) -> Result<SimParams, Error> {
        Ok(Self::case_study(left, right)?.with_environment(Environment::subsea()))
    }

    /// These parameters in `environment`.
    pub fn with_environment(mut self, environment: Environment) -> SimParams {
        self.step.environment = environment;
        self
    }

    /// These parameters with the intervention panel `panel` (e.g. [`PanelParams::standard`],
    /// placed for the case-study arms and box).
    pub fn with_panel(mut self, panel: PanelParams) -> SimParams {
        self.panel = Some(panel);
        self
    }
}

/// Convenience: an isometry from a translation and a rotation vector.
pub fn pose(t: [f64; 3], r: [f64; 3]) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(t[0], t[1], t[2]),
        UnitQuaternion::from_scaled_axis(Vector3::new(r[0], r[1], r[2])),
    )
}
