//! Valve command generation (Lim §4.2 case studies; Zeng & Sepehri 2004 cooperative scheme).
//!
//! * Open loop ([`open_loop`]): each operator input drives one joint's valve, scaled by the arm
//!   speed setting — a joystick per function, as in Lim case studies 1–3.
//! * Joint-velocity servo ([`joint_servo`]): turns a joint-velocity reference (from a Cartesian
//!   teleoperation module) into valve commands: feedforward q̇_ref/q̇_nominal plus a
//!   proportional term on the integrated reference, for an arm on its own (in the closed
//!   chain the arms are rate-controlled, `sim::arm`).
//! * Closed-loop cooperative ([`cooperative`]): the operator commands the object twist; the
//!   controller regulates the object pose, sends each arm the grasp-point twist of the desired
//!   object motion (Wⁱᵀ, equal sharing) and an admittance term that backs each arm off its
//!   share of the internal wrench ((I − W⁺W)F_c), so internal force stays low.
//! * Cartesian teleoperation ([`teleop`]): an end-effector speed command to the joint-velocity
//!   reference the servo follows.

pub mod teleop;

use nalgebra::{Isometry3, Matrix6, UnitQuaternion, Vector3, Vector6};

use crate::grasp::{grasp_point_twist, moment_free_share, wrench_at_com};
use crate::hydraulics::N_ACT;
use crate::linalg::{Ldlt, gram_lower};

/// Controller gains (documented defaults in [`Default`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControlParams {
    /// Joint servo position gain on the integrated reference (1/s): 5.
    pub servo_kp: f64,
    /// Largest tracking error the servo integrator may build (rad): 0.2 (anti-windup).
    pub servo_max_error_rad: f64,
    /// Object pose gain of the cooperative controller (1/s): 1.5 (2 and above excite a slow limit
    /// cycle with the lightly damped oil-column resonance while holding).
    pub object_kp: f64,
    /// Internal-force admittance, translation (m/s per N): 1·10⁻⁴ (100 N → 1 cm/s back-off).
    /// In a steady move the internal force settles where the back-off cancels the two grasp
    /// points' velocity mismatch, F ≈ δv/k; at the former 1·10⁻⁵ a 1 cm/s mismatch cost 1 kN.
    /// Chosen with the rotational gain by a sweep of case 4 with the finite grip
    /// (docs/physics.md, "Case 4 stage D: the sideways move").
    pub internal_admittance_lin: f64,
    /// Internal-torque admittance, rotation (rad/s per N·m): 1·10⁻² (10 N·m → 0.1 rad/s).
    /// The jaw's tightest friction limit is the torsion about its closing axis, 15.2 N·m at
    /// the rated clamp (`grasp::grip`): at the former 1·10⁻⁴ a rotation-rate mismatch of
    /// only 1.5 mrad/s between the grasp frames used all of it, and case 4's sideways move
    /// slipped the box out of the jaws.
    pub internal_admittance_rot: f64,
    /// Damping of the damped-least-squares inverse Jacobian (m): 0.02.
    pub dls_damping: f64,
    /// Largest commanded object speed (m/s): 0.2; larger commands are scaled down.
    pub max_object_speed_m_s: f64,
    /// Largest commanded object angular speed (rad/s): 0.5.
    pub max_object_rate_rad_s: f64,
    /// The load share the cooperative controller drives the contact wrenches to: false (the
    /// default), Lim's equal share W⁺ (eq. 3.46), which gives each jaw a moment
    /// −rⁱ × F/2 about the object's handles; true, the moment-free share
    /// ([`crate::grasp::moment_free_share`]), which carries the load by forces wherever the
    /// two grasp points can — what a friction grip on a round handle needs
    /// (docs/physics.md, "Grasp and the dynamic case studies").
    pub moment_free_share: bool,
}

impl Default for ControlParams {
    fn default() -> Self {
        ControlParams {
            servo_kp: 5.0,
            servo_max_error_rad: 0.2,
            object_kp: 1.5,
            internal_admittance_lin: 1.0e-4,
            internal_admittance_rot: 1.0e-2,
            dls_damping: 0.02,
            max_object_speed_m_s: 0.2,
            max_object_rate_rad_s: 0.5,
            moment_free_share: false,
        }
    }
}

/// Open loop: spool = speed scale × joystick input (both already validated to their ranges).
#[inline]
pub fn open_loop(inputs: &[f64; N_ACT], speed_scale: f64) -> [f64; N_ACT] {
    let mut u = [0.0; N_ACT];
    for (o, i) in u.iter_mut().zip(inputs) {
        *o = (i * speed_scale).clamp(-1.0, 1.0);
    }
    u
}

/// Joint-velocity servo for an arm on its own. `q_ref` is the servo's integrated reference
/// (state), advanced by `qd_ref`·dt here; returns spool commands
/// (q̇_ref + k_p(q_ref − q))/q̇_nominal, clamped to ±1.
///
/// Not for a closed chain (both jaws on the object): there two position loops fight through
/// the rigid object — the chain has one pose, the two references disagree with it by the
/// arms' different sag under the shared load and the different flows their valves pass, and
/// a proportional term on a flow-control valve integrates the remaining error into pressure
/// (eqs 3.48–3.50: a steady opening s into a locked cylinder raises its pressure at
/// β·K·s·√ΔP/V), so the internal load ramps under any stick, however small. In the chain the
/// arms are rate-controlled instead ([`crate::hydraulics::steady_opening`], `sim::arm`):
/// valve opening ∝ commanded rate, no position term, centred valves lock the cylinders.
pub fn joint_servo(
    qd_ref: &[f64; N_ACT],
    q: &[f64; N_ACT],
    q_ref: &mut [f64; N_ACT],
    nominal_speed: &[f64; N_ACT],
    dt_s: f64,
    p: &ControlParams,
) -> [f64; N_ACT] {
    let mut u = [0.0; N_ACT];
    for j in 0..N_ACT {
        q_ref[j] += qd_ref[j] * dt_s;
        let e = (q_ref[j] - q[j]).clamp(-p.servo_max_error_rad, p.servo_max_error_rad);
        q_ref[j] = q[j] + e;
        u[j] = ((qd_ref[j] + p.servo_kp * e) / nominal_speed[j]).clamp(-1.0, 1.0);
    }
    u
}

/// Damped-least-squares solve q̇ = Jᵀ(JJᵀ + λ²I)⁻¹ẋ for a 6×6 Jacobian (zero if JJᵀ + λ²I is
/// not numerically positive definite, e.g. for a non-finite J).
pub fn dls(j: &Matrix6<f64>, xd: &Vector6<f64>, lambda: f64) -> Vector6<f64> {
    // JJᵀ = ZᵀZ with Z = Jᵀ; the factorization reads the lower triangle only.
    let a = gram_lower(&j.transpose()) + Matrix6::identity() * (lambda * lambda);
    match Ldlt::factor(&a) {
        Some(f) => j.tr_mul(&f.solve(xd)),
        None => Vector6::zeros(),
    }
}

/// Orientation difference (rad, world frame) of `to` relative to `from`: the rotation vector
/// θ·n of q = to·from⁻¹, the rotation taking `from` to `to` (the analogue of `to − from` for
/// positions), i.e. nalgebra's `UnitQuaternion::scaled_axis` of q with one norm instead of two:
/// θ = 2·atan2(|q_v|, |q_w|), n = ±q_v/|q_v| with the sign of q_w (the shorter of the two
/// equivalent rotations), and zero for |q_v| = 0.
pub fn rotation_error(to: &UnitQuaternion<f64>, from: &UnitQuaternion<f64>) -> Vector3<f64> {
    // q = to·from* (a unit quaternion's inverse is its conjugate).
    let q = to.quaternion() * from.quaternion().conjugate();
    let (w, v) = (q.w, q.imag());
    let n = v.norm();
    if n <= 0.0 {
        return Vector3::zeros();
    }
    let angle = n.atan2(w.abs()) * 2.0;
    (if w >= 0.0 { v } else { -v }) / n * angle
}

/// Inputs of the cooperative controller for one step.
#[derive(Debug, Clone, Copy)]
pub struct CoopInputs<'a> {
    /// Current object pose (COM frame, base frame of the world).
    pub object: &'a Isometry3<f64>,
    /// Grasp points relative to the object COM, base frame (m), per arm.
    pub r: &'a [Vector3<f64>; 2],
    /// World-frame Jacobians of the two tool points (6×6).
    pub jacobians: [&'a Matrix6<f64>; 2],
    /// Last contact wrenches of the two arms on the object.
    pub contact: &'a [Vector6<f64>; 2],
    /// Commanded object twist (m/s, rad/s), already scaled and clamped.
    pub twist: &'a Vector6<f64>,
    /// Nominal joint speeds per arm (rad/s).
    pub nominal_speed: &'a [[f64; N_ACT]; 2],
}

/// Closed-loop cooperative control (after Zeng & Sepehri 2004, Lim §3.4 and case study 4).
/// `desired` is the controller's object pose reference (state), advanced by the commanded twist.
/// Returns both arms' spool commands; if any exceeds ±1 both arms are scaled by the same factor
/// so their motions stay consistent.
#[allow(clippy::needless_range_loop)]
pub fn cooperative(
    inp: &CoopInputs<'_>,
    desired: &mut Isometry3<f64>,
    dt_s: f64,
    p: &ControlParams,
) -> [[f64; N_ACT]; 2] {
    let tw = inp.twist;
    desired.translation.vector += Vector3::new(tw[0], tw[1], tw[2]) * dt_s;
    let turn = Vector3::new(tw[3], tw[4], tw[5]) * dt_s;
    if turn != Vector3::zeros() {
        desired.rotation = UnitQuaternion::from_scaled_axis(turn) * desired.rotation;
    }
    let ep = desired.translation.vector - inp.object.translation.vector;
    let er = rotation_error(&desired.rotation, &inp.object.rotation);
    let v = Vector6::new(
        tw[0] + p.object_kp * ep.x,
        tw[1] + p.object_kp * ep.y,
        tw[2] + p.object_kp * ep.z,
        tw[3] + p.object_kp * er.x,
        tw[4] + p.object_kp * er.y,
        tw[5] + p.object_kp * er.z,
    );
    // Equal-share decomposition of the measured contact wrenches: F_ext = W¹F¹ + W²F²
    // (eq. 3.40), each Wⁱ applied in closed form ([f; m + rⁱ×f]) instead of as a 6×6 product.
    let fext =
        wrench_at_com(&inp.r[0], &inp.contact[0]) + wrench_at_com(&inp.r[1], &inp.contact[1]);
    let moment_free = p.moment_free_share.then(|| moment_free_share(inp.r, &fext));
    let xd: [Vector6<f64>; 2] = core::array::from_fn(|i| {
        // W⁺ⁱ·F_ext = ½[I 0; −Rⁱ I]F_ext, or the moment-free share.
        let (f, m) = match &moment_free {
            Some(s) => (
                Vector3::new(s[i][0], s[i][1], s[i][2]),
                Vector3::new(s[i][3], s[i][4], s[i][5]),
            ),
            None => {
                let f = Vector3::new(fext[0], fext[1], fext[2]) * 0.5;
                (
                    f,
                    Vector3::new(fext[3], fext[4], fext[5]) * 0.5 - inp.r[i].cross(&f),
                )
            }
        };
        let c = inp.contact[i];
        let excess = Vector6::new(
            c[0] - f.x,
            c[1] - f.y,
            c[2] - f.z,
            c[3] - m.x,
            c[4] - m.y,
            c[5] - m.z,
        );
        // Wⁱᵀ·v = [v + ω×rⁱ; ω], the grasp point's twist.
        let mut xd = grasp_point_twist(&inp.r[i], &v);
        for k in 0..3 {
            xd[k] -= p.internal_admittance_lin * excess[k];
            xd[k + 3] -= p.internal_admittance_rot * excess[k + 3];
        }
        xd
    });
    let qd = [
        dls(inp.jacobians[0], &xd[0], p.dls_damping),
        dls(inp.jacobians[1], &xd[1], p.dls_damping),
    ];
    let mut u = [[0.0; N_ACT]; 2];
    let mut peak: f64 = 1.0;
    for i in 0..2 {
        for j in 0..N_ACT {
            u[i][j] = qd[i][j] / inp.nominal_speed[i][j];
            if u[i][j].is_finite() {
                peak = peak.max(u[i][j].abs());
            } else {
                u[i][j] = 0.0;
            }
        }
    }
    for ui in u.iter_mut() {
        for x in ui.iter_mut() {
            *x /= peak;
        }
    }
    u
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grasp::grasp_block;

    /// Reproducible uniform numbers in [−0.5, 0.5) (the LCG of the `linalg` tests).
    struct Lcg(u64);

    impl Lcg {
        fn next(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((self.0 >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        }
        fn matrix(&mut self, scale: f64) -> Matrix6<f64> {
            Matrix6::from_fn(|_, _| self.next() * scale)
        }
        fn vector(&mut self, scale: f64) -> Vector6<f64> {
            Vector6::from_fn(|_, _| self.next() * scale)
        }
        fn vector3(&mut self, scale: f64) -> Vector3<f64> {
            Vector3::new(self.next(), self.next(), self.next()) * scale
        }
        fn rotation(&mut self) -> UnitQuaternion<f64> {
            UnitQuaternion::from_scaled_axis(self.vector3(6.0))
        }
    }

    /// The servo's law by hand: u = (q̇_ref + k_p·e)/q̇_nominal with e = q_ref + q̇_ref·dt − q;
    /// a zero reference holds the reference.
    #[test]
    fn servo_follows_its_law() {
        let p = ControlParams::default();
        let nominal = [0.2; N_ACT];
        let q = [0.1, -0.2, 0.3, 0.0, 0.05, -0.05];
        let r0 = [0.1 + 1e-3, -0.2, 0.3 - 2e-3, 0.0, 0.05, -0.05];
        let mut r = r0;
        let u = joint_servo(&[0.0; N_ACT], &q, &mut r, &nominal, 1e-3, &p);
        assert!((u[0] - 5.0 * 1e-3 / 0.2).abs() < 1e-12);
        assert!((u[2] + 5.0 * 2e-3 / 0.2).abs() < 1e-12);
        assert_eq!(r, r0);
        let qd = [0.01, 0.0, 0.0, 0.0, 0.0, 0.0];
        let mut b = r0;
        let v = joint_servo(&qd, &q, &mut b, &nominal, 1e-3, &p);
        let e0 = r0[0] + 0.01 * 1e-3 - q[0];
        assert!((v[0] - (0.01 + 5.0 * e0) / 0.2).abs() < 1e-12);
    }

    /// Reference DLS: Jᵀ(JJᵀ + λ²I)⁻¹ẋ formed with nalgebra's own matrix products and Cholesky
    /// (products and factorization independent of [`dls`]'s).
    fn dls_nalgebra(j: &Matrix6<f64>, xd: &Vector6<f64>, lambda: f64) -> Vector6<f64> {
        let a = j * j.transpose() + Matrix6::identity() * (lambda * lambda);
        match a.cholesky() {
            Some(ch) => j.transpose() * ch.solve(xd),
            None => Vector6::zeros(),
        }
    }

    fn rel_err(a: &Vector6<f64>, b: &Vector6<f64>) -> f64 {
        (a - b).norm() / b.norm().max(1e-300)
    }

    #[test]
    fn dls_matches_the_nalgebra_reference() {
        let mut g = Lcg(7);
        for case in 0..300 {
            // Well and badly conditioned Jacobians (a scaled-down row makes JJᵀ nearly
            // singular, so the damping matters), several dampings.
            let mut j = g.matrix(2.0);
            if case % 3 == 0 {
                let row = j.row(2) * 1e-6;
                j.set_row(4, &row);
            }
            let xd = g.vector(1.0);
            let lambda = [0.02, 0.5, 1e-4][case % 3];
            let ours = dls(&j, &xd, lambda);
            let reference = dls_nalgebra(&j, &xd, lambda);
            // JJᵀ + λ²I has condition number up to ~10⁸ here.
            assert!(
                rel_err(&ours, &reference) < 1e-7,
                "case {case}: {ours} vs {reference}"
            );
            // The damped normal equations hold: (JᵀJ + λ²I)q̇ = Jᵀẋ.
            let lhs = (j.transpose() * j + Matrix6::identity() * (lambda * lambda)) * ours;
            let rhs = j.transpose() * xd;
            assert!(rel_err(&lhs, &rhs) < 1e-7, "case {case}");
        }
    }

    #[test]
    fn dls_refuses_non_finite_jacobians() {
        let mut g = Lcg(11);
        let xd = g.vector(1.0);
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let mut j = g.matrix(1.0);
            j[(3, 1)] = bad;
            assert_eq!(dls(&j, &xd, 0.02), Vector6::zeros());
        }
        // Zero damping and a singular J: a zero pivot, refused by `Ldlt::factor`.
        assert_eq!(dls(&Matrix6::zeros(), &xd, 0.0), Vector6::zeros());
    }

    /// nalgebra's `scaled_axis` of to·from⁻¹ (an independent implementation) to 4 ulp of the
    /// angle, over random rotations (both signs of q_w), tiny errors and none.
    #[test]
    fn rotation_error_matches_nalgebra_scaled_axis() {
        let mut g = Lcg(5);
        let check = |d: &UnitQuaternion<f64>, a: &UnitQuaternion<f64>| {
            let ours = rotation_error(d, a);
            let reference = (d * a.inverse()).scaled_axis();
            assert!(
                (ours - reference).norm() <= 4.0 * f64::EPSILON * reference.norm(),
                "{ours} vs {reference}"
            );
        };
        for _ in 0..500 {
            let (d, a) = (g.rotation(), g.rotation());
            check(&d, &a);
            // The same rotation from the other hemisphere (q and −q).
            let neg = UnitQuaternion::new_unchecked(-d.into_inner());
            check(&neg, &a);
            let small = UnitQuaternion::from_scaled_axis(g.vector3(1e-9)) * a;
            check(&small, &a);
        }
        let a = g.rotation();
        check(&a, &a);
        assert_eq!(
            rotation_error(&UnitQuaternion::identity(), &UnitQuaternion::identity()),
            Vector3::zeros()
        );
    }

    /// The controller as first written, with the 6×6 grasp blocks Wⁱ (eq. 3.40) formed and
    /// multiplied, nalgebra's `scaled_axis` and the nalgebra DLS reference: the closed forms
    /// must reproduce it to round-off.
    fn cooperative_reference(
        inp: &CoopInputs<'_>,
        desired: &mut Isometry3<f64>,
        dt_s: f64,
        p: &ControlParams,
    ) -> [[f64; N_ACT]; 2] {
        let tw = inp.twist;
        desired.translation.vector += Vector3::new(tw[0], tw[1], tw[2]) * dt_s;
        desired.rotation =
            UnitQuaternion::from_scaled_axis(Vector3::new(tw[3], tw[4], tw[5]) * dt_s)
                * desired.rotation;
        let ep = desired.translation.vector - inp.object.translation.vector;
        let er = (desired.rotation * inp.object.rotation.inverse()).scaled_axis();
        let v = Vector6::new(
            tw[0] + p.object_kp * ep.x,
            tw[1] + p.object_kp * ep.y,
            tw[2] + p.object_kp * ep.z,
            tw[3] + p.object_kp * er.x,
            tw[4] + p.object_kp * er.y,
            tw[5] + p.object_kp * er.z,
        );
        let w = [grasp_block(&inp.r[0]), grasp_block(&inp.r[1])];
        let fext = w[0] * inp.contact[0] + w[1] * inp.contact[1];
        let mut u = [[0.0; N_ACT]; 2];
        let mut peak: f64 = 1.0;
        for i in 0..2 {
            let f = Vector3::new(fext[0], fext[1], fext[2]) * 0.5;
            let m = Vector3::new(fext[3], fext[4], fext[5]) * 0.5 - inp.r[i].cross(&f);
            let c = inp.contact[i];
            let excess = c - Vector6::new(f.x, f.y, f.z, m.x, m.y, m.z);
            let mut xd = w[i].transpose() * v;
            for k in 0..3 {
                xd[k] -= p.internal_admittance_lin * excess[k];
                xd[k + 3] -= p.internal_admittance_rot * excess[k + 3];
            }
            let qd = dls_nalgebra(inp.jacobians[i], &xd, p.dls_damping);
            for j in 0..N_ACT {
                u[i][j] = qd[j] / inp.nominal_speed[i][j];
                if u[i][j].is_finite() {
                    peak = peak.max(u[i][j].abs());
                } else {
                    u[i][j] = 0.0;
                }
            }
        }
        u.map(|ui| ui.map(|x| x / peak))
    }

    #[test]
    fn cooperative_matches_the_matrix_form_reference() {
        let mut g = Lcg(13);
        let p = ControlParams::default();
        for case in 0..300 {
            let object = Isometry3::from_parts(g.vector3(2.0).into(), g.rotation());
            // Desired pose near the object (the controller's regime) or far from it.
            let near = case % 2 == 0;
            let mut desired = Isometry3::from_parts(
                (object.translation.vector + g.vector3(if near { 0.01 } else { 1.0 })).into(),
                UnitQuaternion::from_scaled_axis(g.vector3(if near { 0.01 } else { 3.0 }))
                    * object.rotation,
            );
            let r = [g.vector3(0.6), g.vector3(0.6)];
            let jacobians = [g.matrix(2.0), g.matrix(2.0)];
            let contact = [g.vector(400.0), g.vector(400.0)];
            let mut twist = g.vector(0.2);
            if case % 3 == 0 {
                // Pure translation: the skipped identity rotation increment.
                twist.fixed_rows_mut::<3>(3).fill(0.0);
            }
            let nominal_speed = [
                [0.5, 0.6, 0.7, 1.0, 1.5, 2.0],
                [0.4, 0.5, 0.6, 0.9, 1.2, 2.5],
            ];
            let inp = CoopInputs {
                object: &object,
                r: &r,
                jacobians: [&jacobians[0], &jacobians[1]],
                contact: &contact,
                twist: &twist,
                nominal_speed: &nominal_speed,
            };
            let mut desired_ref = desired;
            let ours = cooperative(&inp, &mut desired, 1e-3, &p);
            let reference = cooperative_reference(&inp, &mut desired_ref, 1e-3, &p);
            for i in 0..2 {
                for j in 0..N_ACT {
                    assert!(
                        (ours[i][j] - reference[i][j]).abs() < 1e-9,
                        "case {case} arm {i} joint {j}: {} vs {}",
                        ours[i][j],
                        reference[i][j]
                    );
                }
            }
            assert!((desired.translation.vector - desired_ref.translation.vector).norm() < 1e-15);
            assert!(desired.rotation.angle_to(&desired_ref.rotation) < 1e-12);
        }
    }
}
