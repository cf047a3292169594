//! The scalar functions of Jun 2008 and their gradients, allocation-free.
//!
//! * TOMM w = √det(J_r J_rᵀ) of the selected rows J_r of the 6×n base-frame Jacobian (Jun eq. 4,
//!   with eq. 9's row selection);
//! * JLM p_joint = Π(1 − xᵢ²) (Jun eq. 16, [`crate::manipulability::jlm`]);
//! * the performance index P = α·TOMM + (1 − α)·JLM, which is to be *increased*; Jun's
//!   objective (eq. 17) is f = −P.
//!
//! The TOMM gradient is a central finite difference of the analytic Jacobian (step
//! [`TOMM_FD_STEP`]); the JLM gradient is analytic ([`crate::manipulability::jlm_gradient`]).

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

/// Determinant of a symmetric positive semi-definite k×k matrix stored row-major in the first
/// k² entries of `a` (destroyed), by Gaussian elimination with partial pivoting; clamped ≥ 0.
pub(crate) fn psd_determinant(a: &mut [f64; MAX_ROWS * MAX_ROWS], k: usize) -> f64 {
    let mut det = 1.0;
    for c in 0..k {
        let mut p = c;
        for r in c + 1..k {
            if a[r * k + c].abs() > a[p * k + c].abs() {
                p = r;
            }
        }
        let pivot = a[p * k + c];
        if pivot == 0.0 {
            return 0.0;
        }
        if p != c {
            for j in 0..k {
                a.swap(c * k + j, p * k + j);
            }
            det = -det;
        }
        det *= pivot;
        for r in c + 1..k {
            let f = a[r * k + c] / pivot;
            if f != 0.0 {
                for j in c..k {
                    a[r * k + j] -= f * a[c * k + j];
                }
            }
        }
    }
    det.max(0.0)
}

/// TOMM √det(J_r J_rᵀ) of the rows `rows` of the Jacobian held in `data` (call
/// [`jacobian`] first). `rows` must be valid ([`check_rows`]).
pub fn tomm_of_jacobian(data: &KinData, rows: &[usize]) -> f64 {
    let j = &data.jacobian;
    let n = j.ncols();
    let k = rows.len();
    let mut g = [0.0; MAX_ROWS * MAX_ROWS];
    for (a, &ra) in rows.iter().enumerate() {
        for (b, &rb) in rows.iter().enumerate().skip(a) {
            let mut s = 0.0;
            for c in 0..n {
                s += j[(ra, c)] * j[(rb, c)];
            }
            g[a * k + b] = s;
            g[b * k + a] = s;
        }
    }
    psd_determinant(&mut g, k).sqrt()
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
        jlm_gradient(model, q, grad);
        let b = 1.0 - self.alpha;
        for g in grad.iter_mut() {
            *g *= b;
        }
        if self.alpha != 0.0 {
            tomm_gradient(
                model,
                &mut self.scratch,
                &mut self.scratch_q,
                q,
                rows,
                &mut self.tmp,
            );
            for (g, t) in grad.iter_mut().zip(&self.tmp) {
                *g += self.alpha * t;
            }
        }
    }
}
