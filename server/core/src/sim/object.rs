//! The object's stages of the step: its inertia, weight and implicit seabed damping, held
//! over the step ([`ObjectTerms`]), and within a sub-step its free acceleration and the
//! integration of its pose.

use nalgebra::{Matrix3, Matrix6, UnitQuaternion, Vector3, Vector6};

use super::water::{BoxHydro, Environment, Flow};
use super::{ObjectState, StepParams};
use crate::grasp::{self, ObjectParams, SeabedAnchors};
use crate::linalg::Ldlt;

/// The object's terms computed once per step and held over its sub-steps.
#[derive(Debug, Clone, Copy)]
pub(super) struct ObjectTerms {
    /// Inertia about the COM, world frame (kg·m²).
    iw: Matrix3<f64>,
    /// Its inverse.
    iw_inv: Matrix3<f64>,
    /// 1 / (mass + added mass) (1/kg).
    inv_mass: f64,
    /// Weight less buoyancy (N), world frame.
    weight: Vector3<f64>,
    /// Object rotation (body to world) at the start of the step, for the drag's body axes.
    rot: Matrix3<f64>,
    /// Drag and current in water (`None` in air).
    hydro: Option<BoxHydro>,
    /// Seabed wrench and what the seabed leaves in the state at the start of the step (the
    /// first sub-step's).
    seabed0: (Vector6<f64>, Seabed),
    /// Factor of M̃ = M_o + h·C (C the seabed contact's damping matrix) while anything
    /// touches the seabed; `None` when nothing does (M̃ = M_o, applied blockwise).
    factor: Option<Ldlt<6>>,
    /// M̃⁻¹ itself when the object also touches the seabed and an arm holds it.
    mobility: Option<Matrix6<f64>>,
    /// The sub-step h (s), for the seabed's linearly implicit stick springs.
    h: f64,
}

/// What the seabed contact of a sub-step leaves in the object's state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Seabed {
    /// Total normal force (N).
    pub(super) normal_n: f64,
    /// The corners' friction anchors ([`grasp::seabed_contact`]).
    pub(super) anchors: SeabedAnchors,
}

impl ObjectTerms {
    /// Stage 5: the object's inertia (world), weight and seabed contact at the start of the
    /// step. The seabed dashpots (normal damping and the regularized friction) are stiff for a
    /// box touching on one corner or edge — there the effective mass is a few kg, and explicit
    /// damping of 2·10⁴ N·s/m at h = 1 ms injects energy — so they are treated implicitly
    /// (linearly implicit Euler): the mass matrix becomes M̃ = M_o + h·C, held over the step;
    /// the spring forces stay explicit (k·h²/m_eff ≈ 0.3). `held`: an arm holds the object
    /// (then M̃⁻¹ is formed for the grasp blocks); `flow`: the water's motion (unused in air).
    pub(super) fn new(
        op: &ObjectParams,
        sp: &StepParams,
        o: &ObjectState,
        flow: &Flow,
        held: bool,
        h: f64,
    ) -> ObjectTerms {
        // The body axes are principal, so with R's columns r_k: R·diag(d)·Rᵀ = Σ d_k·r_k·r_kᵀ,
        // and the inverse takes 1/d_k.
        let rot = o.pose.rotation.to_rotation_matrix();
        let d = op.principal_inertia();
        let d_inv = if d.iter().all(|&x| x > 0.0 && x.is_finite()) {
            d.map(|x| 1.0 / x)
        } else {
            Vector3::repeat(1.0)
        };
        let world = |e: &Vector3<f64>| -> Matrix3<f64> {
            let r = rot.matrix();
            let mut m = Matrix3::zeros();
            for k in 0..3 {
                let c = r.column(k);
                m += (c * e[k]) * c.transpose();
            }
            m
        };
        let iw = world(&d);
        let contact = grasp::seabed_contact(
            op,
            &o.pose,
            &o.velocity,
            &o.angular_velocity,
            &o.seabed_anchors,
            h,
        );
        let hydro = sp
            .environment
            .water()
            .map(|w| BoxHydro::new(&op.size_m, w, flow));
        // Effective translational mass: the body's and its added mass (isotropic).
        let mass = op.mass_kg + hydro.map_or(0.0, |b| b.added_mass_kg);
        let factor = contact.damping.and_then(|c| {
            let mut m = c * h;
            for k in 0..3 {
                m[(k, k)] += mass;
            }
            let mut rot_block = m.fixed_view_mut::<3, 3>(3, 3);
            rot_block += iw;
            Ldlt::factor(&m)
        });
        // M̃⁻¹ from the factor, L⁻ᵀ·D⁻¹·L⁻¹ (a third of the work of six solves on unit
        // vectors): the grasp blocks take it in 3×3 pieces.
        let mobility = match &factor {
            Some(f) if held => Some(f.inverse()),
            _ => None,
        };
        ObjectTerms {
            iw,
            iw_inv: world(&d_inv),
            inv_mass: 1.0 / mass,
            weight: sp.gravity * wet_mass_kg(op, &sp.environment),
            rot: *rot.matrix(),
            hydro,
            seabed0: (
                contact.wrench,
                Seabed {
                    normal_n: contact.normal_n,
                    anchors: contact.anchors,
                },
            ),
            h,
            factor,
            mobility,
        }
    }

    /// M̃⁻¹ applied to a wrench (force, moment about the COM); blockwise
    /// M_o⁻¹ = blockdiag(1/m, I_w⁻¹) when nothing touches the seabed.
    pub(super) fn mobility_times(&self, w: &Vector6<f64>) -> Vector6<f64> {
        match (&self.mobility, &self.factor) {
            (Some(x), _) => x * w,
            (None, Some(f)) => f.solve(w),
            (None, None) => {
                let a = self.iw_inv * Vector3::new(w[3], w[4], w[5]);
                let m = self.inv_mass;
                Vector6::new(w[0] * m, w[1] * m, w[2] * m, a.x, a.y, a.z)
            }
        }
    }

    /// Wⁱᵀ·M̃⁻¹·Wᵏ for grasp points `ri`, `rk` (m, from the COM, world frame). Used only while
    /// an arm holds, when M̃⁻¹ has been formed if anything touches the seabed.
    pub(super) fn grasp_mobility(&self, ri: &Vector3<f64>, rk: &Vector3<f64>) -> Matrix6<f64> {
        debug_assert!(self.mobility.is_some() || self.factor.is_none());
        match &self.mobility {
            Some(x) => grasp::mobility_block_general(ri, rk, x),
            None => grasp::mobility_block(ri, rk, self.inv_mass, &self.iw_inv),
        }
    }

    /// Wⁱᵀ·M̃⁻¹·Wⁱ, a diagonal block: with the general M̃⁻¹ only its lower triangle.
    pub(super) fn grasp_mobility_diag(&self, ri: &Vector3<f64>) -> Matrix6<f64> {
        match &self.mobility {
            Some(x) => grasp::mobility_block_general_lower(ri, x),
            None => self.grasp_mobility(ri, ri),
        }
    }

    /// Sub-step: the object's acceleration (linear; angular, world) from weight, seabed
    /// contact and the gyroscopic term, without the arms, and what the seabed leaves in the
    /// state (normal force, friction anchors). The first sub-step reuses the contact
    /// evaluated by [`ObjectTerms::new`].
    pub(super) fn free_acceleration(
        &self,
        op: &ObjectParams,
        o: &ObjectState,
        first: bool,
    ) -> (Vector6<f64>, Seabed) {
        let (sea, seabed) = if first {
            self.seabed0
        } else {
            let c = grasp::seabed_wrench(
                op,
                &o.pose,
                &o.velocity,
                &o.angular_velocity,
                &o.seabed_anchors,
                self.h,
            );
            (
                c.wrench,
                Seabed {
                    normal_n: c.normal_n,
                    anchors: c.anchors,
                },
            )
        };
        let gyro = o.angular_velocity.cross(&(self.iw * o.angular_velocity));
        // Drag on the velocity relative to the current, explicit (h·λ ≪ 2: see
        // [`super::water`]), and the accelerating current's inertia force, through the COM
        // (no moment: the box is symmetric).
        let drag = self.hydro.map_or(Vector3::zeros(), |b| {
            b.drag(&self.rot, &o.velocity) + b.inertia_n
        });
        let wrench = Vector6::new(
            self.weight.x + sea[0] + drag.x,
            self.weight.y + sea[1] + drag.y,
            self.weight.z + sea[2] + drag.z,
            sea[3] - gyro.x,
            sea[4] - gyro.y,
            sea[5] - gyro.z,
        );
        (self.mobility_times(&wrench), seabed)
    }
}

/// The object's mass less the water it displaces (kg): its weight in the medium over g.
pub(super) fn wet_mass_kg(op: &ObjectParams, env: &Environment) -> f64 {
    op.mass_kg - env.density_kgm3() * op.size_m.x * op.size_m.y * op.size_m.z
}

/// The object's twist [v; ω] (world).
pub(super) fn twist(o: &ObjectState) -> Vector6<f64> {
    let (v, w) = (o.velocity, o.angular_velocity);
    Vector6::new(v.x, v.y, v.z, w.x, w.y, w.z)
}

/// Sub-step: semi-implicit Euler of the object's twist and pose (the rotation by the
/// exponential map of ω·h), with the seabed normal force and friction anchors recorded.
pub(super) fn integrate(o: &mut ObjectState, acc: &Vector6<f64>, seabed: &Seabed, h: f64) {
    o.velocity += h * Vector3::new(acc[0], acc[1], acc[2]);
    o.angular_velocity += h * Vector3::new(acc[3], acc[4], acc[5]);
    o.pose.translation.vector += h * o.velocity;
    o.pose.rotation = UnitQuaternion::from_scaled_axis(o.angular_velocity * h) * o.pose.rotation;
    o.pose.rotation.renormalize();
    o.seabed_force_n = seabed.normal_n;
    o.seabed_anchors = seabed.anchors;
}
