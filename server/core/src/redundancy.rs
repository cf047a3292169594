//! Task-oriented redundancy resolution (Jun 2008 §4, eqs 19–24; Kilic 2005 §2.1, eqs 0.2–0.10).
//!
//! For a task J₁ (the selected rows of the 6×n base-frame Jacobian, rows vx vy vz wx wy wz):
//!
//! q̇ = J₁⁺ṙ₁ + (I − J₁⁺J₁)·y,  y = ε·∂P/∂qᵀ,  P = α·TOMM(J₁) + (1 − α)·JLM.
//!
//! **Sign.** P is a performance index to be *increased* (Kilic eqs 0.7–0.10: k₁ = ξ·k_p with
//! ξ = ∂V/∂q, and ṗ gains the non-negative term ξᵀ(I − J₁⁺J₁)ξ·k_p). Jun eq. 21 writes
//! y = −ε·∂p/∂q with p the *potential* of eq. 17, p = f = −P; both give y = +ε·∂P/∂q, which is
//! what this module uses, with ε > 0 ([`RedundancyParams::epsilon`]).
//!
//! * Near singularities J₁⁺ is the damped pseudo-inverse J₁ᵀ(J₁J₁ᵀ + λ²I)⁻¹ with
//!   λ² = λ_max²·(1 − (σ_min/σ_0)²) when σ_min < σ_0 and 0 otherwise (Chiaverini 1997, Jun
//!   ref. 6); with λ > 0 the null-space term is approximate, as usual.
//! * A second task (Kilic eq. 0.6): q̇ = b + J̄₂⁺(ṙ₂ − J₂b), b the solution above and
//!   J̄₂ = J₂(I − J₁⁺J₁) — algebraically eq. 0.6 with k₂ = y.
//! * Joint-velocity limits: the whole q̇ is scaled by one factor s ≤ 1 so that
//!   |q̇ᵢ| ≤ max_velocityᵢ; the direction (and so the task direction) is kept.
//! * Feedback form (Jun eqs 22–24): ṙ₁ = ṙ₁ᵈ + G(r₁ᵈ − r₁), q_r = q + q̇_rΔt; the reference
//!   r₁ᵈ (position and orientation) is integrated from ṙ₁ᵈ by the resolver itself.
//!
//! [`Redundancy`] holds all scratch space: a step does not allocate.

use nalgebra::{UnitQuaternion, Vector3};

use crate::Error;
use crate::kinematics::{KinData, jacobian};
use crate::manipulability::jlm;
use crate::model::Model;
use crate::optimize::objective::{MAX_ROWS, PerformanceIndex, check_rows, tomm_of_jacobian};
use crate::optimize::spd::{Square, cholesky, gram, solve_columns};

/// Settings of [`Redundancy`]; `Default` gives the values in each field's doc.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RedundancyParams {
    /// Weight α ∈ [0, 1] of TOMM in P (default 0.5, Jun §4.2).
    pub alpha: f64,
    /// Null-space gain ε ≥ 0 (default 1.0; (rad/s) per unit of ∂P/∂q). 0 gives the plain
    /// minimum-norm solution J₁⁺ṙ₁.
    pub epsilon: f64,
    /// σ_0: smallest singular value of J₁ below which damping starts (default 0.02).
    pub singular_threshold: f64,
    /// λ_max: damping at σ_min = 0 (default 0.05). 0 disables damping (plain pseudo-inverse,
    /// computed by the same normal equations; fails at an exact singularity).
    pub max_damping: f64,
    /// Scale q̇ uniformly so every joint respects its velocity limit (default true).
    pub limit_velocity: bool,
    /// Feedback gain G (scalar, 1/s) of eq. 22 for [`Redundancy::step_tracking`] (default 5).
    pub feedback_gain: f64,
}

impl Default for RedundancyParams {
    fn default() -> Self {
        RedundancyParams {
            alpha: 0.5,
            epsilon: 1.0,
            singular_threshold: 0.02,
            max_damping: 0.05,
            limit_velocity: true,
            feedback_gain: 5.0,
        }
    }
}

/// Diagnostics of the last step.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StepInfo {
    /// Smallest singular value of J₁ at q when it is below the damping threshold σ_0 (then
    /// computed exactly, by Jacobi); `None` when σ_min ≥ σ_0 (one Cholesky of J₁J₁ᵀ − σ_0²I
    /// proves it, so a well-conditioned step needs no eigenvalue solve).
    pub sigma_min: Option<f64>,
    /// Damping λ used in J₁⁺.
    pub damping: f64,
    /// Uniform velocity scale applied (1 = none).
    pub velocity_scale: f64,
    /// TOMM of J₁ at q.
    pub tomm: f64,
    /// JLM at q.
    pub jlm: f64,
    /// P = α·TOMM + (1 − α)·JLM at q.
    pub performance_index: f64,
}

/// Preallocated redundancy resolver for one model (see the module doc).
#[derive(Debug, Clone)]
pub struct Redundancy {
    /// Settings; may be changed between steps.
    pub params: RedundancyParams,
    n: usize,
    data: KinData,
    index: PerformanceIndex,
    /// Task-1 rows (k₁×n, row-major).
    j1: Vec<f64>,
    /// J₁⁺ (n×k₁, row-major).
    p1: Vec<f64>,
    /// Task-2 rows, J̄₂ and J̄₂⁺.
    j2: Vec<f64>,
    j2bar: Vec<f64>,
    p2: Vec<f64>,
    grad: Vec<f64>,
    qdot: Vec<f64>,
    q_next: Vec<f64>,
    info: StepInfo,
    reference: Option<(Vector3<f64>, UnitQuaternion<f64>)>,
}

/// How a step forms and resolves its command (see [`Redundancy::step`],
/// [`Redundancy::step_priority`], [`Redundancy::step_tracking`]).
#[derive(Debug, Clone, Copy)]
enum Mode<'a> {
    /// Eq. 21 with the desired task velocity.
    Plain,
    /// Kilic eq. 0.6 with this second task.
    Priority(Task<'a>),
    /// Eqs 22–24: the desired velocity plus feedback to the reference.
    Tracking,
}

/// A task velocity: rows of the 6×n Jacobian and the desired velocity along each.
#[derive(Debug, Clone, Copy)]
pub struct Task<'a> {
    /// Rows (0..6: vx vy vz wx wy wz).
    pub rows: &'a [usize],
    /// Desired velocity, one entry per row (m/s or rad/s, base frame).
    pub velocity: &'a [f64],
}

impl Redundancy {
    /// Allocates the workspace for `model`.
    pub fn new(model: &Model, params: RedundancyParams) -> Redundancy {
        let n = model.dof();
        Redundancy {
            params,
            n,
            data: KinData::new(model),
            index: PerformanceIndex::new(model, params.alpha),
            j1: vec![0.0; MAX_ROWS * n],
            p1: vec![0.0; MAX_ROWS * n],
            j2: vec![0.0; MAX_ROWS * n],
            j2bar: vec![0.0; MAX_ROWS * n],
            p2: vec![0.0; MAX_ROWS * n],
            grad: vec![0.0; n],
            qdot: vec![0.0; n],
            q_next: vec![0.0; n],
            info: StepInfo::default(),
            reference: None,
        }
    }

    /// Diagnostics of the last step.
    pub fn info(&self) -> &StepInfo {
        &self.info
    }

    /// q_r = q + q̇·Δt of the last step (Jun eq. 24).
    pub fn q_next(&self) -> &[f64] {
        &self.q_next
    }

    /// Jun eq. 21 (with damping and velocity limits): joint velocity for the task velocity
    /// `r_dot_desired` (one entry per row of `rows`, base frame), also stored with
    /// q + q̇·dt in [`Redundancy::q_next`]. Does not allocate.
    pub fn step(
        &mut self,
        model: &Model,
        q: &[f64],
        r_dot_desired: &[f64],
        rows: &[usize],
        dt: f64,
    ) -> Result<&[f64], Error> {
        self.run(model, q, r_dot_desired, rows, Mode::Plain, dt)
    }

    /// Kilic eq. 0.6: task 1 (`rows`, `r_dot_desired`) has priority; `second` is met as well
    /// as the remaining freedom allows; what is left follows ε·∂P/∂q. Does not allocate.
    pub fn step_priority(
        &mut self,
        model: &Model,
        q: &[f64],
        r_dot_desired: &[f64],
        rows: &[usize],
        second: Task<'_>,
        dt: f64,
    ) -> Result<&[f64], Error> {
        self.run(model, q, r_dot_desired, rows, Mode::Priority(second), dt)
    }

    /// Sets the feedback reference r₁ᵈ of [`Redundancy::step_tracking`] to the current tool
    /// point and orientation at `q`.
    pub fn reset_reference(&mut self, model: &Model, q: &[f64]) -> Result<(), Error> {
        model.check_q(q)?;
        crate::kinematics::forward_kinematics(model, &mut self.data, q);
        self.reference = Some((self.data.tool_point, self.data.flange.rotation));
        Ok(())
    }

    /// Current feedback reference (tool point, orientation), base frame.
    pub fn reference(&self) -> Option<(Vector3<f64>, UnitQuaternion<f64>)> {
        self.reference
    }

    /// Jun eqs 22–24: ṙ₁ = ṙ₁ᵈ + G(r₁ᵈ − r₁) fed to eq. 21, then q_r = q + q̇_rΔt. The reference
    /// starts at the pose at `q` (or at [`Redundancy::reset_reference`]) and advances by
    /// ṙ₁ᵈ·dt each step (rows not in the task keep their reference). Orientation errors are
    /// the rotation vector of R_d·Rᵀ (base frame). Does not allocate.
    pub fn step_tracking(
        &mut self,
        model: &Model,
        q: &[f64],
        r_dot_desired: &[f64],
        rows: &[usize],
        dt: f64,
    ) -> Result<&[f64], Error> {
        self.run(model, q, r_dot_desired, rows, Mode::Tracking, dt)
    }

    /// The common path of the three steps: validate, Jacobian at q, task-1 command, eq. 21 (with
    /// the second task for [`Mode::Priority`]), velocity limits and q + q̇·dt.
    fn run(
        &mut self,
        model: &Model,
        q: &[f64],
        r_dot_desired: &[f64],
        rows: &[usize],
        mode: Mode<'_>,
        dt: f64,
    ) -> Result<&[f64], Error> {
        self.check(model, q, r_dot_desired, rows, dt)?;
        let second = match mode {
            Mode::Priority(second) => {
                check_task(second.rows, second.velocity)?;
                Some(second)
            }
            Mode::Plain | Mode::Tracking => None,
        };
        jacobian(model, &mut self.data, q);
        let k = rows.len();
        let mut cmd = [0.0; MAX_ROWS];
        cmd[..k].copy_from_slice(r_dot_desired);
        if let Mode::Tracking = mode {
            self.add_feedback(rows, r_dot_desired, dt, &mut cmd[..k]);
        }
        self.resolve(model, q, &cmd[..k], rows, second)?;
        Ok(self.finish(model, q, dt))
    }

    /// Jun eq. 22: adds G(r₁ᵈ − r₁) to `cmd` (one entry per task row) with the pose in
    /// `self.data`, then advances the reference r₁ᵈ by ṙ₁ᵈ·dt for the next step.
    fn add_feedback(&mut self, rows: &[usize], r_dot_desired: &[f64], dt: f64, cmd: &mut [f64]) {
        let (p_d, r_d) = self
            .reference
            .unwrap_or((self.data.tool_point, self.data.flange.rotation));
        let dp = p_d - self.data.tool_point;
        let dr = (r_d * self.data.flange.rotation.inverse()).scaled_axis();
        let err = [dp.x, dp.y, dp.z, dr.x, dr.y, dr.z];
        let mut v = [0.0; 6];
        for ((c, &r), &x) in cmd.iter_mut().zip(rows).zip(r_dot_desired) {
            *c += self.params.feedback_gain * err[r];
            v[r] = x;
        }
        self.reference = Some((
            p_d + Vector3::new(v[0], v[1], v[2]) * dt,
            UnitQuaternion::from_scaled_axis(Vector3::new(v[3], v[4], v[5]) * dt) * r_d,
        ));
    }

    fn check(
        &self,
        model: &Model,
        q: &[f64],
        r_dot: &[f64],
        rows: &[usize],
        dt: f64,
    ) -> Result<(), Error> {
        if model.dof() != self.n {
            return Err(Error::SizeMismatch {
                what: "model joints",
                input: model.dof(),
                required: self.n,
            });
        }
        model.check_q(q)?;
        check_task(rows, r_dot)?;
        if !(dt.is_finite() && dt >= 0.0) {
            return Err(Error::InvalidParameter {
                what: "dt",
                reason: "must be finite and ≥ 0".into(),
            });
        }
        let p = &self.params;
        let ok = (0.0..=1.0).contains(&p.alpha)
            && p.epsilon.is_finite()
            && p.epsilon >= 0.0
            && p.singular_threshold.is_finite()
            && p.singular_threshold >= 0.0
            && p.max_damping.is_finite()
            && p.max_damping >= 0.0
            && p.feedback_gain.is_finite();
        if !ok {
            return Err(Error::InvalidParameter {
                what: "redundancy params",
                reason: "alpha in [0, 1]; epsilon, thresholds, damping ≥ 0 and finite".into(),
            });
        }
        Ok(())
    }

    /// q̇ into `self.qdot` from the Jacobian in `self.data`.
    fn resolve(
        &mut self,
        model: &Model,
        q: &[f64],
        r_dot: &[f64],
        rows: &[usize],
        second: Option<Task<'_>>,
    ) -> Result<(), Error> {
        let n = self.n;
        let k = rows.len();
        copy_rows(&self.data, rows, &mut self.j1);
        let (sigma_min, lambda) = damped_pinv(
            &self.j1[..k * n],
            k,
            n,
            self.params.singular_threshold,
            self.params.max_damping,
            &mut self.p1[..n * k],
        )?;
        // Performance index and y = ε ∂P/∂q.
        self.index.alpha = self.params.alpha;
        let t = tomm_of_jacobian(&self.data, rows);
        let l = jlm(model, q);
        self.info = StepInfo {
            sigma_min,
            damping: lambda,
            velocity_scale: 1.0,
            tomm: t,
            jlm: l,
            performance_index: self.params.alpha * t + (1.0 - self.params.alpha) * l,
        };
        if self.params.epsilon > 0.0 {
            self.index
                .gradient_from(model, &self.data, q, rows, &mut self.grad);
            for g in self.grad.iter_mut() {
                *g *= self.params.epsilon;
            }
        } else {
            self.grad.fill(0.0);
        }
        // b = y + J₁⁺(ṙ₁ − J₁y)  (= J₁⁺ṙ₁ + (I − J₁⁺J₁)y).
        let mut e = [0.0; MAX_ROWS];
        for i in 0..k {
            e[i] = r_dot[i] - dot(&self.j1[i * n..(i + 1) * n], &self.grad);
        }
        for c in 0..n {
            self.qdot[c] = self.grad[c] + dot(&self.p1[c * k..(c + 1) * k], &e[..k]);
        }
        if let Some(task) = second {
            let k2 = task.rows.len();
            copy_rows(&self.data, task.rows, &mut self.j2);
            // J̄₂ = J₂ − (J₂J₁⁺)J₁.
            let mut c21 = [0.0; MAX_ROWS * MAX_ROWS];
            for a in 0..k2 {
                for b in 0..k {
                    let mut s = 0.0;
                    for c in 0..n {
                        s += self.j2[a * n + c] * self.p1[c * k + b];
                    }
                    c21[a * k + b] = s;
                }
            }
            for a in 0..k2 {
                for c in 0..n {
                    let mut s = self.j2[a * n + c];
                    for b in 0..k {
                        s -= c21[a * k + b] * self.j1[b * n + c];
                    }
                    self.j2bar[a * n + c] = s;
                }
            }
            damped_pinv(
                &self.j2bar[..k2 * n],
                k2,
                n,
                self.params.singular_threshold,
                self.params.max_damping,
                &mut self.p2[..n * k2],
            )?;
            // q̇ = b + J̄₂⁺(ṙ₂ − J₂b).
            let mut e2 = [0.0; MAX_ROWS];
            for (a, e) in e2.iter_mut().enumerate().take(k2) {
                *e = task.velocity[a] - dot(&self.j2[a * n..(a + 1) * n], &self.qdot);
            }
            for c in 0..n {
                self.qdot[c] += dot(&self.p2[c * k2..(c + 1) * k2], &e2[..k2]);
            }
        }
        Ok(())
    }

    fn finish(&mut self, model: &Model, q: &[f64], dt: f64) -> &[f64] {
        if self.params.limit_velocity {
            let mut s: f64 = 1.0;
            for (v, j) in self.qdot.iter().zip(&model.joints) {
                if v.abs() > j.max_velocity {
                    s = s.min(j.max_velocity / v.abs());
                }
            }
            if s < 1.0 {
                for v in self.qdot.iter_mut() {
                    *v *= s;
                }
            }
            self.info.velocity_scale = s;
        }
        for ((qn, &qi), &v) in self.q_next.iter_mut().zip(q).zip(&self.qdot) {
            *qn = qi + v * dt;
        }
        &self.qdot
    }
}

fn check_task(rows: &[usize], velocity: &[f64]) -> Result<(), Error> {
    check_rows(rows)?;
    if velocity.len() != rows.len() {
        return Err(Error::SizeMismatch {
            what: "task velocity",
            input: velocity.len(),
            required: rows.len(),
        });
    }
    if let Some(index) = velocity.iter().position(|v| !v.is_finite()) {
        return Err(Error::NonFinite {
            what: "task velocity",
            index,
        });
    }
    Ok(())
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn copy_rows(data: &KinData, rows: &[usize], out: &mut [f64]) {
    let n = data.jacobian.ncols();
    for (i, &r) in rows.iter().enumerate() {
        for c in 0..n {
            out[i * n + c] = data.jacobian[(r, c)];
        }
    }
}

/// Damped pseudo-inverse of `a` (k×n row-major) into `out` (n×k row-major):
/// Aᵀ(AAᵀ + λ²I)⁻¹ with λ² = λ_max²(1 − (σ_min/σ_0)²) below σ_0. Returns (σ_min if below
/// σ_0, λ).
/// Allocation-free (k ≤ 6).
pub fn damped_pinv(
    a: &[f64],
    k: usize,
    n: usize,
    sigma_0: f64,
    lambda_max: f64,
    out: &mut [f64],
) -> Result<(Option<f64>, f64), Error> {
    let row = |i: usize, c: usize| a[i * n + c];
    let mut m = gram(k, n, row);
    // σ_min ≥ σ_0 ⟺ AAᵀ − σ_0²I ≻ 0: one Cholesky attempt instead of an eigenvalue solve.
    let (sigma_min, lambda2) =
        if sigma_0 <= 0.0 || cholesky(&m, k, sigma_0 * sigma_0, 0.0).is_some() {
            (None, 0.0)
        } else {
            let s = symmetric_min_eigenvalue(&m, k).max(0.0).sqrt();
            (
                Some(s),
                lambda_max * lambda_max * (1.0 - (s / sigma_0).powi(2)).max(0.0),
            )
        };
    let scale = (0..k).map(|i| m[i * k + i]).fold(0.0, f64::max);
    for i in 0..k {
        m[i * k + i] += lambda2;
    }
    // M = AAᵀ + λ²I = LLᵀ; row c of Aᵀ M⁻¹ is (M⁻¹ A[:, c])ᵀ.
    let l = cholesky(&m, k, 0.0, 64.0 * f64::EPSILON * scale).ok_or(Error::NotConverged {
        what: "pseudo-inverse (singular task Jacobian; enable damping)",
        iterations: 0,
        residual: sigma_min.unwrap_or(0.0),
    })?;
    solve_columns(&l, k, n, row, out);
    Ok((sigma_min, lambda2.sqrt()))
}

/// Smallest eigenvalue of a symmetric k×k matrix (row-major, k ≤ 6) by cyclic Jacobi.
fn symmetric_min_eigenvalue(m: &Square, k: usize) -> f64 {
    let mut a = *m;
    for _sweep in 0..30 {
        let mut off = 0.0;
        for i in 0..k {
            for j in i + 1..k {
                off += a[i * k + j] * a[i * k + j];
            }
        }
        let scale: f64 = (0..k).map(|i| a[i * k + i].abs()).sum::<f64>() + f64::MIN_POSITIVE;
        if off.sqrt() <= 1e-14 * scale {
            break;
        }
        for p in 0..k {
            for q in p + 1..k {
                let apq = a[p * k + q];
                // Negligible against the diagonal: treat as converged (no rotation).
                if apq.abs() <= 1e-15 * (a[p * k + p].abs() + a[q * k + q].abs()) {
                    a[p * k + q] = 0.0;
                    a[q * k + p] = 0.0;
                    continue;
                }
                let theta = (a[q * k + q] - a[p * k + p]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for r in 0..k {
                    let arp = a[r * k + p];
                    let arq = a[r * k + q];
                    a[r * k + p] = c * arp - s * arq;
                    a[r * k + q] = s * arp + c * arq;
                }
                for r in 0..k {
                    let apr = a[p * k + r];
                    let aqr = a[q * k + r];
                    a[p * k + r] = c * apr - s * aqr;
                    a[q * k + r] = s * apr + c * aqr;
                }
            }
        }
    }
    (0..k).map(|i| a[i * k + i]).fold(f64::INFINITY, f64::min)
}
