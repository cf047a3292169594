//! Inverse kinematics: the Magnum closed form (Lim §3.2.2, eqs 3.10–3.19, completed for
//! θ2, θ3, θ4) and a damped-least-squares solver with joint limits for any model.

use nalgebra::{DMatrix, DVector, Isometry3, Matrix3, Vector3};

use crate::Error;
use crate::kinematics::{KinData, jacobian};
use crate::model::{JointKind, Model};

/// Link lengths l1..l6 of the Magnum (Lim Table 3-1), read from a model of that structure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MagnumLengths {
    /// Swing axis to shoulder (m).
    pub l1: f64,
    /// Shoulder to elbow (m).
    pub l2: f64,
    /// Elbow to pitch (m).
    pub l3: f64,
    /// Pitch to yaw (m).
    pub l4: f64,
    /// Yaw to rotate (m).
    pub l5: f64,
    /// Rotate to jaw centre (m).
    pub l6: f64,
}

impl MagnumLengths {
    /// Reads l1..l6 from a model built from a Table 3-1 style specification.
    pub fn from_model(model: &Model) -> Result<MagnumLengths, Error> {
        let s = &model.spec;
        let ok = s.joints.len() == 6
            && s.dh == crate::model::DhConvention::Standard
            && s.joints.iter().all(|j| j.kind == JointKind::Revolute)
            && s.joints[4].twist_axis == crate::model::TwistAxis::Y
            && model.tool == Vector3::zeros();
        if !ok {
            return Err(Error::InvalidModel {
                reason: format!(
                    "{} does not have the Magnum structure of Lim Table 3-1",
                    model.name
                ),
            });
        }
        let j = &s.joints;
        Ok(MagnumLengths {
            l1: j[0].a,
            l2: j[1].a,
            l3: j[2].a,
            l4: j[3].a,
            l5: j[4].a,
            l6: j[5].d,
        })
    }
}

/// All closed-form Magnum IK solutions for the end-effector pose `target` (base frame),
/// restricted to the model's joint limits (angles are wrapped by 2π into the limits where
/// possible; the continuous rotate joint is wrapped into (−π, π]). Up to 8 branches:
/// θ1 ± π, θ5 / π − θ5, elbow up / down. An empty list means the pose is out of reach or
/// outside the limits.
pub fn magnum_ik(model: &Model, target: &Isometry3<f64>) -> Result<Vec<[f64; 6]>, Error> {
    let l = MagnumLengths::from_model(model)?;
    let r: Matrix3<f64> = target.rotation.to_rotation_matrix().into_inner();
    let (n, o, a) = (r.column(0), r.column(1), r.column(2));
    let p = target.translation.vector;
    let lw = l.l5 + l.l6;
    let mut out = Vec::new();
    // Eq. 3.16: θ1 from the wrist-centre projection (and its π twin).
    let t1 = (p.y - lw * a.y).atan2(p.x - lw * a.x);
    for th1 in [t1, t1 + std::f64::consts::PI] {
        let (s1, c1) = th1.sin_cos();
        // Eq. 3.17: s5 = a_y c1 − a_x s1, two branches.
        let s5 = (a.y * c1 - a.x * s1).clamp(-1.0, 1.0);
        let t5 = s5.asin();
        for th5 in [t5, std::f64::consts::PI - t5] {
            let c5 = th5.cos();
            if c5.abs() < 1e-9 {
                continue; // eqs 3.18–3.19 need c5 ≠ 0 (wrist singularity)
            }
            // Eq. 3.18 (row 3 of A1⁻¹T6 = [−c5 s6, −c5 c6, −s5, ·]), with atan2 for the full range.
            let th6 = (-(n.x * s1 - n.y * c1) / c5).atan2(-(o.x * s1 - o.y * c1) / c5);
            // Eq. 3.19.
            let th234 = (a.z / c5).atan2((a.x * c1 + a.y * s1) / c5);
            // Completion: planar two-link problem for θ2, θ3 (rows 1–2, column 4 of eq. 3.12).
            let (s234, c234) = th234.sin_cos();
            let reach = lw * c5 + l.l4;
            let x = p.x * c1 + p.y * s1 - l.l1 - reach * c234;
            let z = p.z - reach * s234;
            let c3 = (x * x + z * z - l.l2 * l.l2 - l.l3 * l.l3) / (2.0 * l.l2 * l.l3);
            if c3.abs() > 1.0 + 1e-12 {
                continue;
            }
            let c3 = c3.clamp(-1.0, 1.0);
            for th3 in [c3.acos(), -c3.acos()] {
                let th2 = z.atan2(x) - (l.l3 * th3.sin()).atan2(l.l2 + l.l3 * th3.cos());
                let th4 = th234 - th2 - th3;
                if let Some(q) = within_limits(model, [th1, th2, th3, th4, th5, th6]) {
                    if !out
                        .iter()
                        .any(|s: &[f64; 6]| s.iter().zip(&q).all(|(u, v)| (u - v).abs() < 1e-9))
                    {
                        out.push(q);
                    }
                }
            }
        }
    }
    Ok(out)
}

/// Wraps each angle by multiples of 2π into its joint's limits; `None` if one cannot fit.
fn within_limits<const N: usize>(model: &Model, q: [f64; N]) -> Option<[f64; N]> {
    use std::f64::consts::{PI, TAU};
    let mut out = q;
    for (v, j) in out.iter_mut().zip(&model.joints) {
        let [lo, hi] = j.limits;
        if !(lo.is_finite() && hi.is_finite()) {
            *v = (*v + PI).rem_euclid(TAU) - PI;
            continue;
        }
        let k = ((lo - *v) / TAU).ceil();
        let w = *v + k * TAU;
        if w > hi + 1e-12 {
            return None;
        }
        *v = w.min(hi);
    }
    Some(out)
}

/// What the damped-least-squares solver should reach.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum IkTarget {
    /// Tool-point position only (m, base frame).
    Position(Vector3<f64>),
    /// Full pose (tool point and flange orientation, base frame).
    Pose(Isometry3<f64>),
}

/// Settings of [`dls_ik`]; `Default` gives the values in each field's doc.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IkOptions {
    /// Iteration cap (default 300).
    pub max_iterations: usize,
    /// Position tolerance (m, default 1e-6).
    pub tolerance_m: f64,
    /// Orientation tolerance (rad, default 1e-6).
    pub tolerance_rad: f64,
    /// Initial Levenberg–Marquardt damping λ (default 1e-2); adapted each iteration.
    pub damping: f64,
}

impl Default for IkOptions {
    fn default() -> Self {
        IkOptions {
            max_iterations: 300,
            tolerance_m: 1e-6,
            tolerance_rad: 1e-6,
            damping: 1e-2,
        }
    }
}

fn task_error(data: &KinData, target: &IkTarget) -> DVector<f64> {
    match target {
        IkTarget::Position(p) => DVector::from_column_slice((p - data.tool_point).as_slice()),
        IkTarget::Pose(t) => {
            let dp = t.translation.vector - data.tool_point;
            // Rotation error as the axis-angle of R_target·Rᵀ (base frame).
            let dr = (t.rotation * data.flange.rotation.inverse()).scaled_axis();
            DVector::from_iterator(6, dp.iter().chain(dr.iter()).copied())
        }
    }
}

/// Damped-least-squares (Levenberg–Marquardt) IK from `q0`, clamping to joint limits every
/// iteration: Δq = Jᵀ(JJᵀ + λ²I)⁻¹e, λ halved after an improving step and doubled after a
/// rejected one. Returns [`Error::NotConverged`] with the final residual when the tolerance
/// is not met (e.g. a target out of reach).
pub fn dls_ik(
    model: &Model,
    target: &IkTarget,
    q0: &[f64],
    opts: &IkOptions,
) -> Result<Vec<f64>, Error> {
    model.check_q(q0)?;
    let rows: &[usize] = match target {
        IkTarget::Position(p) => {
            if p.iter().any(|v| !v.is_finite()) {
                return Err(Error::NonFinite {
                    what: "target",
                    index: 0,
                });
            }
            &[0, 1, 2]
        }
        IkTarget::Pose(t) => {
            if t.translation.vector.iter().any(|v| !v.is_finite())
                || t.rotation.coords.iter().any(|v| !v.is_finite())
            {
                return Err(Error::NonFinite {
                    what: "target",
                    index: 0,
                });
            }
            &[0, 1, 2, 3, 4, 5]
        }
    };
    let n = model.dof();
    let clamp = |q: &mut [f64]| {
        for (v, j) in q.iter_mut().zip(&model.joints) {
            *v = v.clamp(j.limits[0], j.limits[1]);
        }
    };
    let mut q = q0.to_vec();
    clamp(&mut q);
    let mut data = KinData::new(model);
    jacobian(model, &mut data, &q);
    let mut e = task_error(&data, target);
    let cost = |e: &DVector<f64>| e.norm_squared();
    let converged = |e: &DVector<f64>| {
        e.rows(0, 3).norm() <= opts.tolerance_m
            && (e.nrows() == 3 || e.rows(3, 3).norm() <= opts.tolerance_rad)
    };
    let mut lambda = opts.damping;
    let mut trial = q.clone();
    for _ in 0..opts.max_iterations {
        if converged(&e) {
            return Ok(q);
        }
        // Active set: a joint resting on a limit whose step would push it further out is
        // frozen (its column zeroed) and the step recomputed, so clamping never stalls LM.
        let mut j: DMatrix<f64> = data.jacobian.select_rows(rows);
        let mut dq = DVector::zeros(n);
        let mut solved = false;
        for _ in 0..=n {
            let a =
                &j * j.transpose() + DMatrix::identity(rows.len(), rows.len()) * (lambda * lambda);
            let Some(chol) = a.cholesky() else { break };
            dq = j.transpose() * chol.solve(&e);
            solved = true;
            let mut frozen = false;
            for i in 0..n {
                let [lo, hi] = model.joints[i].limits;
                let pushes_out = (q[i] <= lo && dq[i] < 0.0) || (q[i] >= hi && dq[i] > 0.0);
                if pushes_out && j.column(i).iter().any(|v| *v != 0.0) {
                    j.column_mut(i).fill(0.0);
                    frozen = true;
                }
            }
            if !frozen {
                break;
            }
        }
        if !solved {
            lambda = (lambda * 10.0).min(1e6);
            continue;
        }
        for i in 0..n {
            trial[i] = q[i] + dq[i];
        }
        clamp(&mut trial);
        let mut trial_data = data.clone();
        jacobian(model, &mut trial_data, &trial);
        let e_trial = task_error(&trial_data, target);
        if cost(&e_trial) < cost(&e) {
            q.copy_from_slice(&trial);
            data = trial_data;
            e = e_trial;
            lambda = (lambda * 0.5).max(1e-9);
        } else {
            lambda = (lambda * 2.0).min(1e6);
        }
    }
    if converged(&e) {
        return Ok(q);
    }
    Err(Error::NotConverged {
        what: "damped least-squares IK",
        iterations: opts.max_iterations,
        residual: e.norm(),
    })
}
