//! Valve command generation (Lim §4.2 case studies; Zeng & Sepehri 2004 cooperative scheme).
//!
//! * Open loop ([`open_loop`]): each operator input drives one joint's valve, scaled by the arm
//!   speed setting — a joystick per function, as in Lim case studies 1–3.
//! * Joint-velocity servo ([`joint_servo`]): turns a joint-velocity reference (from a Cartesian
//!   teleoperation module) into valve commands: feedforward q̇_ref/q̇_nominal plus a
//!   proportional term on the integrated reference.
//! * Closed-loop cooperative ([`cooperative`]): the operator commands the object twist; the
//!   controller regulates the object pose, sends each arm the grasp-point twist of the desired
//!   object motion (Wⁱᵀ, equal sharing) and an admittance term that backs each arm off its
//!   share of the internal wrench ((I − W⁺W)F_c), so internal force stays low.

use nalgebra::{Isometry3, Matrix6, UnitQuaternion, Vector3, Vector6};

use crate::grasp::grasp_block;
use crate::hydraulics::N_ACT;
use crate::linalg::Cholesky;

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
    /// Internal-force admittance, translation (m/s per N): 1·10⁻⁵ (1 kN → 1 cm/s back-off).
    pub internal_admittance_lin: f64,
    /// Internal-torque admittance, rotation (rad/s per N·m): 1·10⁻⁴.
    pub internal_admittance_rot: f64,
    /// Damping of the damped-least-squares inverse Jacobian (m): 0.02.
    pub dls_damping: f64,
    /// Largest commanded object speed (m/s): 0.2; larger commands are scaled down.
    pub max_object_speed_m_s: f64,
    /// Largest commanded object angular speed (rad/s): 0.5.
    pub max_object_rate_rad_s: f64,
}

impl Default for ControlParams {
    fn default() -> Self {
        ControlParams {
            servo_kp: 5.0,
            servo_max_error_rad: 0.2,
            object_kp: 1.5,
            internal_admittance_lin: 1.0e-5,
            internal_admittance_rot: 1.0e-4,
            dls_damping: 0.02,
            max_object_speed_m_s: 0.2,
            max_object_rate_rad_s: 0.5,
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

/// Joint-velocity servo. `q_ref` is the servo's integrated reference (state), advanced by
/// `qd_ref`·dt here; returns spool commands (q̇_ref + k_p(q_ref − q))/q̇_nominal, clamped to ±1.
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

/// Damped-least-squares solve q̇ = Jᵀ(JJᵀ + λ²I)⁻¹ẋ for a 6×6 Jacobian.
pub fn dls(j: &Matrix6<f64>, xd: &Vector6<f64>, lambda: f64) -> Vector6<f64> {
    // Lower triangle of JJᵀ + λ²I only: the factorization reads no more.
    let mut a = Matrix6::identity() * (lambda * lambda);
    for c in 0..6 {
        for r in c..6 {
            a[(r, c)] += j.row(r).dot(&j.row(c));
        }
    }
    match Cholesky::factor(&a) {
        Some(ch) => j.transpose() * ch.solve(xd),
        None => Vector6::zeros(),
    }
}

/// Orientation error vector (rad, base frame) taking `actual` to `desired`.
#[inline]
pub fn rotation_error(desired: &UnitQuaternion<f64>, actual: &UnitQuaternion<f64>) -> Vector3<f64> {
    (desired * actual.inverse()).scaled_axis()
}

/// Inputs of the cooperative controller for one step.
#[derive(Debug, Clone, Copy)]
pub struct CoopInputs<'a> {
    /// Current object pose (COM frame, base frame of the world).
    pub object: &'a Isometry3<f64>,
    /// Grasp points relative to the object COM, base frame (m), per arm.
    pub r: &'a [Vector3<f64>; 2],
    /// World-frame Jacobians of the two tool points (6×6).
    pub jacobians: &'a [Matrix6<f64>; 2],
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
    desired.rotation = UnitQuaternion::from_scaled_axis(Vector3::new(tw[3], tw[4], tw[5]) * dt_s)
        * desired.rotation;
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
    // Equal-share decomposition of the measured contact wrenches.
    let w0 = grasp_block(&inp.r[0]);
    let w1 = grasp_block(&inp.r[1]);
    let fext = w0 * inp.contact[0] + w1 * inp.contact[1];
    let mut u = [[0.0; N_ACT]; 2];
    let mut peak: f64 = 1.0;
    for i in 0..2 {
        let wi = if i == 0 { &w0 } else { &w1 };
        // W⁺ⁱ·F_ext = ½[I 0; −Rⁱ I]F_ext.
        let f = Vector3::new(fext[0], fext[1], fext[2]) * 0.5;
        let m = Vector3::new(fext[3], fext[4], fext[5]) * 0.5 - inp.r[i].cross(&f);
        let c = inp.contact[i];
        let excess = Vector6::new(
            c[0] - f.x,
            c[1] - f.y,
            c[2] - f.z,
            c[3] - m.x,
            c[4] - m.y,
            c[5] - m.z,
        );
        let mut xd = wi.transpose() * v;
        for k in 0..3 {
            xd[k] -= p.internal_admittance_lin * excess[k];
            xd[k + 3] -= p.internal_admittance_rot * excess[k + 3];
        }
        let qd = dls(&inp.jacobians[i], &xd, p.dls_damping);
        for j in 0..N_ACT {
            u[i][j] = qd[j] / inp.nominal_speed[i][j];
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
