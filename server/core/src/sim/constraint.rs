//! The closed kinematic chain while jaws hold the object: the grasp constraint system of one
//! step ([`Constraint::new`]) and, per sub-step, the contact wrenches that keep each holding
//! tool on its grasp point ([`Constraint::apply`]): an exact acceleration-level solve with
//! Baumgarte position/velocity stabilization (critically damped, k_p = ω², k_d = 2ω).

use nalgebra::{Isometry3, Matrix6, Vector3, Vector6};

use super::arm::ArmTerms;
use super::object::ObjectTerms;
use super::{ArmState, ObjectState, StepParams};
use crate::control::rotation_error;
use crate::grasp;
use crate::hydraulics::N_ACT;
use crate::linalg::{BlockLdlt, Ldlt, gram_lower};

/// Factor of the constraint matrix: one 6×6 block per arm holding the object. Lives on the
/// stack for one step, so the variants' different sizes cost nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, Copy)]
enum Factor {
    /// Only this arm holds.
    One(usize, Ldlt<6>),
    /// Both arms hold: the 12×12 system in 6×6 blocks.
    Both(BlockLdlt<6>),
}

/// The grasp constraint system of one step, held over its sub-steps.
#[derive(Debug, Clone, Copy)]
pub(super) struct Constraint {
    /// Factor of Σ blocks Wⁱᵀ·M̃⁻¹·Wᵏ + Z_iᵀZ_i + εI; `None` when no arm holds (or the
    /// system is not positive definite).
    factor: Option<Factor>,
    /// Arm i holds the object and its H̃ factored: it enters the solve.
    pub(super) active: [bool; 2],
    /// Grasp points relative to the object COM (m, world).
    r: [Vector3<f64>; 2],
    /// Per active arm: −J̇q̇ + centripetal term − k_p·(position, orientation error).
    c_const: [Vector6<f64>; 2],
    /// Velocity gain k_d = 2ω (1/s).
    kd: f64,
}

impl Constraint {
    /// Stage 6: the constraint matrix — diagonal blocks Wⁱᵀ·M̃⁻¹·Wⁱ + ZᵢᵀZᵢ + εI and the
    /// coupling W¹ᵀ·M̃⁻¹·W⁰ — factored, and the Baumgarte terms of each holding arm
    /// (`tools`: world tool poses; `r`: grasp points from the COM).
    pub(super) fn new(
        arms: [(&ArmState, &ArmTerms); 2],
        object: (&ObjectState, &ObjectTerms),
        tools: [&Isometry3<f64>; 2],
        r: &[Vector3<f64>; 2],
        sp: &StepParams,
    ) -> Constraint {
        let (o, ot) = object;
        let active = [0, 1].map(|i| arms[i].0.holding && arms[i].1.factor.is_some());
        // The factorizations read lower triangles only.
        let diag = |i: usize| {
            ot.grasp_mobility_diag(&r[i])
                + gram_lower(&arms[i].1.z)
                + Matrix6::identity() * sp.constraint_compliance
        };
        let factor = match active {
            [true, true] => BlockLdlt::factor(&diag(0), &ot.grasp_mobility(&r[1], &r[0]), &diag(1))
                .map(Factor::Both),
            [true, false] => Ldlt::factor(&diag(0)).map(|f| Factor::One(0, f)),
            [false, true] => Ldlt::factor(&diag(1)).map(|f| Factor::One(1, f)),
            [false, false] => None,
        };
        let kp = sp.constraint_omega * sp.constraint_omega;
        let mut c_const = [Vector6::zeros(); 2];
        for i in 0..2 {
            if !active[i] {
                continue;
            }
            let desired = o.pose * arms[i].0.grasp_rel;
            let t = tools[i];
            let ep = t.translation.vector - desired.translation.vector;
            let er = rotation_error(&t.rotation, &desired.rotation);
            let w = o.angular_velocity;
            let cen = w.cross(&w.cross(&r[i]));
            c_const[i] = -arms[i].1.jdqd
                + Vector6::new(
                    cen.x - kp * ep.x,
                    cen.y - kp * ep.y,
                    cen.z - kp * ep.z,
                    -kp * er.x,
                    -kp * er.y,
                    -kp * er.z,
                );
        }
        Constraint {
            factor,
            active,
            r: *r,
            c_const,
            kd: 2.0 * sp.constraint_omega,
        }
    }

    /// Sub-step: the contact wrenches f (on the object, at the grasp points, world) that
    /// make each active arm's tool acceleration match its grasp point's, with the arms' free
    /// accelerations `qdd` and the object's free acceleration `acc_o`; adds their effect to
    /// both (q̈ −= H̃⁻¹Jᵀf, a_o += M̃⁻¹Wf). `jw`, `qd`: the arms' world Jacobians and joint
    /// rates; `vo`: the object's twist. Zero for an arm not holding.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn apply(
        &self,
        arms: [&ArmTerms; 2],
        object: &ObjectTerms,
        jw: [&Matrix6<f64>; 2],
        qd: [&[f64; N_ACT]; 2],
        vo: &Vector6<f64>,
        qdd: &mut [Vector6<f64>; 2],
        acc_o: &mut Vector6<f64>,
    ) -> [Vector6<f64>; 2] {
        let Some(factor) = &self.factor else {
            return [Vector6::zeros(); 2];
        };
        let mut b = [Vector6::zeros(); 2];
        for i in 0..2 {
            if self.active[i] {
                let r = &self.r[i];
                let ev = jw[i] * Vector6::from(*qd[i]) - grasp::grasp_point_twist(r, vo);
                let ci = self.c_const[i] - ev * self.kd;
                b[i] = jw[i] * qdd[i] - grasp::grasp_point_twist(r, acc_o) - ci;
            }
        }
        let f = match factor {
            Factor::One(i, f) => {
                let mut out = [Vector6::zeros(); 2];
                out[*i] = f.solve(&b[*i]);
                out
            }
            Factor::Both(f) => {
                let (f0, f1) = f.solve(&b[0], &b[1]);
                [f0, f1]
            }
        };
        for i in 0..2 {
            if self.active[i] {
                if let Some(h) = &arms[i].factor {
                    qdd[i] -= h.backward(&(arms[i].z * f[i]));
                }
                *acc_o += object.mobility_times(&grasp::wrench_at_com(&self.r[i], &f[i]));
            }
        }
        f
    }

    /// The internal wrench F_int (eq. 3.41) of contact wrenches `fc` while both arms hold;
    /// zero otherwise.
    pub(super) fn internal_wrench(&self, fc: &[Vector6<f64>; 2]) -> Vector6<f64> {
        if self.active[0] && self.active[1] {
            grasp::internal_wrench(&self.r, fc)
        } else {
            Vector6::zeros()
        }
    }
}
