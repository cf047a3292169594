//! The scalar functions of Jun 2008 and their gradients, allocation-free.
//!
//! * TOMM w = √det(J_r J_rᵀ) of the selected rows J_r of the 6×n base-frame Jacobian (Jun eq. 4,
//!   with eq. 9's row selection);
//! * JLM p_joint = Π(1 − xᵢ²) (Jun eq. 16, [`crate::manipulability::jlm()`]);
//! * the performance index P = α·TOMM + (1 − α)·JLM, which is to be *increased*; Jun's
//!   objective (eq. 17) is f = −P.
//!
//! The TOMM gradient is in closed form from the derivative of the geometric Jacobian
//! ([`tomm_gradient_analytic`]), with a central finite difference of the analytic Jacobian
//! ([`tomm_gradient`], step [`TOMM_FD_STEP`]) where J_rJ_rᵀ is singular; the JLM gradient is
//! analytic ([`crate::manipulability::jlm_gradient`]).

use super::spd::{Square, cholesky, gram, psd_determinant, solve_columns};
use crate::Error;
use crate::kinematics::{KinData, jacobian};
use crate::manipulability::{jlm, jlm_gradient};
use crate::model::Model;

/// Step of the central difference used for ∂TOMM/∂q (rad or m). The truncation error is
/// O(h²) ≈ 1e-12 relative; the round-off error O(ε/h) ≈ 1e-10 relative.
pub const TOMM_FD_STEP: f64 = 1e-6;

/// Largest number of task rows (rows of the 6×n Jacobian).
pub const MAX_ROWS: usize = 6;

/// Checks a task row selection: 1..=6 distinct rows, each in 0..6 (vx vy vz wx wy wz).
pub fn check_rows(rows: &[usize]) -> Result<(), Error> {
    if rows.is_empty() || rows.len() > MAX_ROWS {
        return Err(Error::InvalidRows {
            reason: format!("1 to {MAX_ROWS} rows are needed, {} given", rows.len()),
        });
    }
    let mut seen = [false; MAX_ROWS];
    for &r in rows {
        if r >= MAX_ROWS {
            return Err(Error::InvalidRows {
                reason: format!("row {r} is out of range 0..{MAX_ROWS}"),
            });
        }
        if seen[r] {
            return Err(Error::InvalidRows {
                reason: format!("row {r} is repeated"),
            });
        }
        seen[r] = true;
    }
    Ok(())
}

/// TOMM √det(J_r J_rᵀ) of the rows `rows` of the Jacobian held in `data` (call
/// [`jacobian`] first). `rows` must be valid ([`check_rows`]).
pub fn tomm_of_jacobian(data: &KinData, rows: &[usize]) -> f64 {
    psd_determinant(&mut task_gram(data, rows), rows.len()).sqrt()
}

/// M = J_r·J_rᵀ of the rows `rows` of the Jacobian in `data`.
fn task_gram(data: &KinData, rows: &[usize]) -> Square {
    let j = &data.jacobian;
    gram(rows.len(), j.ncols(), |a, c| j[(rows[a], c)])
}

/// TOMM at `q` (Jun eq. 4): fills `data` with the Jacobian at `q`.
pub fn tomm(model: &Model, data: &mut KinData, q: &[f64], rows: &[usize]) -> f64 {
    jacobian(model, data, q);
    tomm_of_jacobian(data, rows)
}

/// ∂TOMM/∂q by central differences of the analytic Jacobian, written into `grad` (length n).
/// `scratch_q` (length n) and `scratch` are overwritten; `data` is left untouched.
pub fn tomm_gradient(
    model: &Model,
    scratch: &mut KinData,
    scratch_q: &mut [f64],
    q: &[f64],
    rows: &[usize],
    grad: &mut [f64],
) {
    scratch_q.copy_from_slice(q);
    for i in 0..q.len() {
        scratch_q[i] = q[i] + TOMM_FD_STEP;
        let up = tomm(model, scratch, scratch_q, rows);
        scratch_q[i] = q[i] - TOMM_FD_STEP;
        let down = tomm(model, scratch, scratch_q, rows);
        scratch_q[i] = q[i];
        grad[i] = (up - down) / (2.0 * TOMM_FD_STEP);
    }
}

/// ∂TOMM/∂q in closed form from the Jacobian in `data` (call [`jacobian`] first), written into
/// `grad`; returns false (leaving `grad` unspecified) when J_rJ_rᵀ is singular, where TOMM is
/// not differentiable.
///
/// ∂w/∂q_k = w·tr(M⁻¹J_r ∂J_rᵀ/∂q_k), M = J_rJ_rᵀ, with the derivative of the geometric
/// Jacobian's columns (base frame, z_i joint axis, o_i a point on it, p the tool point):
/// revolute k < i: ∂J_i/∂q_k = z_k × J_i (both halves); prismatic k < i: 0; k ≥ i:
/// ∂J_vi/∂q_k = z_i × J_vk for revolute i (∂J_ωi = 0), 0 for prismatic i.
pub fn tomm_gradient_analytic(
    model: &Model,
    data: &KinData,
    rows: &[usize],
    grad: &mut [f64],
) -> bool {
    use crate::model::JointKind;
    use nalgebra::Vector3;
    let j = &data.jacobian;
    let n = j.ncols();
    let k = rows.len();
    // M = J_r J_rᵀ = L·Lᵀ; det M = Π L_aa². Singular (relative to its largest diagonal entry):
    // TOMM is not differentiable there.
    let m = task_gram(data, rows);
    let scale = (0..k).map(|i| m[i * k + i]).fold(0.0, f64::max);
    let Some(l) = cholesky(&m, k, 0.0, 1e-10 * scale) else {
        return false;
    };
    let w: f64 = (0..k).map(|a| l[a * k + a]).product();
    // B = M⁻¹ J_r (k×n), column c stored at bm[c·k..].
    let mut bm = [0.0; MAX_ROWS * crate::model::MAX_JOINTS];
    solve_columns(&l, k, n, |a, c| j[(rows[a], c)], &mut bm);
    let axis = |i: usize| -> Vector3<f64> {
        data.joint_frames[i].rotation * model.joints[i].axis.into_inner()
    };
    for (kk, g) in grad.iter_mut().enumerate().take(n) {
        let zk = axis(kk);
        let revolute_k = model.joints[kk].kind == JointKind::Revolute;
        let jvk = Vector3::new(j[(0, kk)], j[(1, kk)], j[(2, kk)]);
        let mut s = 0.0;
        for i in 0..n {
            let mut d = [0.0; 6];
            if i > kk {
                if revolute_k {
                    let lin = zk.cross(&Vector3::new(j[(0, i)], j[(1, i)], j[(2, i)]));
                    let ang = zk.cross(&Vector3::new(j[(3, i)], j[(4, i)], j[(5, i)]));
                    d = [lin.x, lin.y, lin.z, ang.x, ang.y, ang.z];
                }
            } else if model.joints[i].kind == JointKind::Revolute {
                let lin = axis(i).cross(&jvk);
                d[0] = lin.x;
                d[1] = lin.y;
                d[2] = lin.z;
            }
            for (a, &r) in rows.iter().enumerate() {
                s += bm[i * k + a] * d[r];
            }
        }
        *g = w * s;
    }
    true
}

/// Performance index P = α·TOMM + (1 − α)·JLM (to be increased; Jun eq. 17's f = −P).
pub fn performance_index(
    model: &Model,
    data: &mut KinData,
    q: &[f64],
    rows: &[usize],
    alpha: f64,
) -> f64 {
    let t = if alpha != 0.0 {
        tomm(model, data, q, rows)
    } else {
        0.0
    };
    alpha * t + (1.0 - alpha) * jlm(model, q)
}

/// Scratch space for [`PerformanceIndex::gradient`]: one kinematic buffer and two joint vectors.
#[derive(Debug, Clone)]
pub struct PerformanceIndex {
    /// Weight α ∈ [0, 1] of TOMM (1 − α weighs JLM).
    pub alpha: f64,
    scratch: KinData,
    scratch_q: Vec<f64>,
    tmp: Vec<f64>,
}

impl PerformanceIndex {
    /// Allocates scratch space for `model`.
    pub fn new(model: &Model, alpha: f64) -> PerformanceIndex {
        let n = model.dof();
        PerformanceIndex {
            alpha,
            scratch: KinData::new(model),
            scratch_q: vec![0.0; n],
            tmp: vec![0.0; n],
        }
    }

    /// P(q) = α·TOMM + (1 − α)·JLM, with TOMM of the Jacobian already in `data` (at `q`).
    pub fn value_from(&self, model: &Model, data: &KinData, q: &[f64], rows: &[usize]) -> f64 {
        let t = if self.alpha != 0.0 {
            tomm_of_jacobian(data, rows)
        } else {
            0.0
        };
        self.alpha * t + (1.0 - self.alpha) * jlm(model, q)
    }

    /// ∂P/∂q written into `grad` (length n). Does not allocate.
    pub fn gradient(&mut self, model: &Model, q: &[f64], rows: &[usize], grad: &mut [f64]) {
        if self.alpha != 0.0 {
            jacobian(model, &mut self.scratch, q);
        }
        self.combine(model, None, q, rows, grad);
    }

    /// As [`PerformanceIndex::gradient`], reusing the Jacobian at `q` already in `data`.
    pub fn gradient_from(
        &mut self,
        model: &Model,
        data: &KinData,
        q: &[f64],
        rows: &[usize],
        grad: &mut [f64],
    ) {
        self.combine(model, Some(data), q, rows, grad);
    }

    /// ∂P/∂q with the Jacobian at q in `data` (or, for `None`, in `self.scratch`).
    fn combine(
        &mut self,
        model: &Model,
        data: Option<&KinData>,
        q: &[f64],
        rows: &[usize],
        grad: &mut [f64],
    ) {
        jlm_gradient(model, q, grad);
        let b = 1.0 - self.alpha;
        for g in grad.iter_mut() {
            *g *= b;
        }
        if self.alpha != 0.0 {
            // Closed form; central differences where J_rJ_rᵀ is singular.
            let ok =
                tomm_gradient_analytic(model, data.unwrap_or(&self.scratch), rows, &mut self.tmp);
            if !ok {
                tomm_gradient(
                    model,
                    &mut self.scratch,
                    &mut self.scratch_q,
                    q,
                    rows,
                    &mut self.tmp,
                );
            }
            for (g, t) in grad.iter_mut().zip(&self.tmp) {
                *g += self.alpha * t;
            }
        }
    }
}
