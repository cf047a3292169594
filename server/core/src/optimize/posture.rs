//! Task-oriented optimal posture (Jun 2008 §3, eqs 10, 17, 18) by multi-start SQP.
//!
//! minimise f(q) = −α·TOMM(q) − (1 − α)·JLM(q)
//! subject to r_p(q) − r_p⁰ = 0 (tool-point position, base frame, eq. 18) and q_l ≤ q ≤ q_u (eq. 11).
//!
//! The SQP is SLSQP (Kraft's sequential least-squares QP, the algorithm behind scipy's
//! `method='SLSQP'`) from the pure-Rust `slsqp` crate, a translation of NLopt 2.10's
//! implementation. That crate takes inequality constraints only, so eq. 18 enters as a thin
//! slab of pairs of inequalities (the private function `slsqp` below explains the formulation
//! and why it converges as the equality would).
//!
//! SQP finds a local minimum, so — as in the paper — several initial candidates are used: the
//! mid-range posture and a Halton sequence over the joint ranges.
//! Each candidate is first moved onto the constraint by damped-least-squares IK
//! ([`crate::ik::dls_ik`]) so every SQP run starts feasible; the result of a run replaces its
//! start only if it is feasible and not worse. A posture whose tool point misses the target by
//! more than [`PostureOptions::constraint_tolerance_m`] is never returned: when no start
//! reaches the target, the call fails with [`Error::Unreachable`].

use std::cell::RefCell;

use nalgebra::Vector3;
use slsqp::{StopTols, minimize};

use super::objective::{PerformanceIndex, check_rows, tomm_of_jacobian};
use crate::Error;
use crate::ik::{IkOptions, IkTarget, dls_ik};
use crate::kinematics::{KinData, forward_kinematics, jacobian};
use crate::manipulability::jlm;
use crate::model::Model;

/// Settings of [`optimal_posture`]; `Default` gives the values in each field's doc.
#[derive(Debug, Clone, PartialEq)]
pub struct PostureOptions {
    /// Weight α ∈ [0, 1] of TOMM in eq. 17 (default 0.8, Jun Fig. 4(d)).
    pub alpha: f64,
    /// Task rows of the Jacobian for TOMM (default `[0, 1, 2]`, translational, as in Jun §3.3).
    pub rows: Vec<usize>,
    /// Number of generated initial candidates, 1..=64 (default 8): the mid-range posture and
    /// then Halton points (see [`initial_candidates`]).
    pub starts: usize,
    /// Extra initial candidates tried before the generated ones (each of length n).
    pub initial: Vec<Vec<f64>>,
    /// Largest accepted distance between tool point and target (m, default 1e-6).
    pub constraint_tolerance_m: f64,
    /// Objective-evaluation cap per SQP run (default 400).
    pub max_evaluations: u32,
    /// Relative tolerance on q that stops an SQP run (default 1e-9).
    pub xtol_rel: f64,
}

impl Default for PostureOptions {
    fn default() -> Self {
        PostureOptions {
            alpha: 0.8,
            rows: vec![0, 1, 2],
            starts: 8,
            initial: Vec::new(),
            constraint_tolerance_m: 1e-6,
            max_evaluations: 400,
            xtol_rel: 1e-9,
        }
    }
}

/// Largest number of generated starts.
pub const MAX_STARTS: usize = 64;

/// What happened to one initial candidate.
#[derive(Debug, Clone, PartialEq)]
pub struct StartOutcome {
    /// The candidate as given or generated.
    pub candidate: Vec<f64>,
    /// The feasible start reached by IK from the candidate, if IK converged.
    pub start: Option<Vec<f64>>,
    /// f at the feasible start.
    pub start_objective: Option<f64>,
    /// Posture at the end of the SQP run (or the feasible start if that was better).
    pub q: Vec<f64>,
    /// f at `q`.
    pub objective: f64,
    /// |r_p(q) − r_p⁰| (m).
    pub constraint_violation_m: f64,
    /// Objective (with gradient) evaluations of the SQP run.
    pub evaluations: usize,
}

/// The best posture over all starts.
#[derive(Debug, Clone, PartialEq)]
pub struct PostureResult {
    /// Optimal joint values (rad or m).
    pub q: Vec<f64>,
    /// TOMM of the task rows at `q`.
    pub tomm: f64,
    /// JLM at `q`.
    pub jlm: f64,
    /// f(q) = −α·TOMM − (1 − α)·JLM.
    pub objective: f64,
    /// Objective evaluations of the winning SQP run (SLSQP evaluates once per iteration and
    /// once per line-search step).
    pub iterations: usize,
    /// |r_p(q) − r_p⁰| (m), ≤ the tolerance.
    pub constraint_violation_m: f64,
    /// Index of the winning candidate (extra candidates first, then generated ones).
    pub start: usize,
    /// Every candidate's outcome, in order.
    pub starts: Vec<StartOutcome>,
}

/// Initial candidates: the mid-range posture, then Halton points (bases 2, 3, 5, …) over the
/// inner 80 % of each joint's range; an unlimited joint uses [−π, π].
pub fn initial_candidates(model: &Model, count: usize) -> Vec<Vec<f64>> {
    const PRIMES: [u32; 32] = [
        2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53, 59, 61, 67, 71, 73, 79, 83, 89,
        97, 101, 103, 107, 109, 113, 127, 131,
    ];
    let ranges: Vec<(f64, f64)> = model
        .joints
        .iter()
        .map(|j| {
            if j.is_limited() {
                (j.limits[0], j.limits[1])
            } else {
                (-std::f64::consts::PI, std::f64::consts::PI)
            }
        })
        .collect();
    (0..count)
        .map(|s| {
            ranges
                .iter()
                .enumerate()
                .map(|(i, &(lo, hi))| {
                    let u = if s == 0 {
                        0.5
                    } else {
                        halton(s as u32, PRIMES[i % PRIMES.len()])
                    };
                    lo + (hi - lo) * (0.1 + 0.8 * u)
                })
                .collect()
        })
        .collect()
}

fn halton(mut index: u32, base: u32) -> f64 {
    let mut f = 1.0;
    let mut r = 0.0;
    while index > 0 {
        f /= base as f64;
        r += f * (index % base) as f64;
        index /= base;
    }
    r
}

/// Checks α, the rows, the start count and the target; returns the target as a vector.
fn validate(
    model: &Model,
    target: &[f64; 3],
    opts: &PostureOptions,
) -> Result<Vector3<f64>, Error> {
    if !(0.0..=1.0).contains(&opts.alpha) {
        return Err(Error::InvalidParameter {
            what: "alpha",
            reason: format!("{} is not in [0, 1]", opts.alpha),
        });
    }
    check_rows(&opts.rows)?;
    if opts.starts > MAX_STARTS || (opts.starts == 0 && opts.initial.is_empty()) {
        return Err(Error::InvalidParameter {
            what: "starts",
            reason: format!("{} is not in 1..={MAX_STARTS}", opts.starts),
        });
    }
    if let Some(index) = target.iter().position(|v| !v.is_finite()) {
        return Err(Error::NonFinite {
            what: "target_position",
            index,
        });
    }
    if !(opts.constraint_tolerance_m > 0.0 && opts.constraint_tolerance_m.is_finite()) {
        return Err(Error::InvalidParameter {
            what: "constraint_tolerance_m",
            reason: "must be > 0".into(),
        });
    }
    for q in &opts.initial {
        model.check_q(q)?;
    }
    Ok(Vector3::new(target[0], target[1], target[2]))
}

/// Scratch shared by the objective and constraint callbacks of one SLSQP run (the callbacks
/// are `Fn` closures, so they share it through a `RefCell`).
struct RunState {
    index: PerformanceIndex,
    /// Kinematics (tool point, Jacobian) at `at`.
    data: KinData,
    at: Vec<f64>,
    fresh: bool,
    evaluations: usize,
}

impl RunState {
    /// Fills `data` at `q` unless it already holds it: SLSQP evaluates the objective and then
    /// each constraint at the same posture, so one Jacobian serves all seven callbacks.
    fn kinematics_at(&mut self, model: &Model, q: &[f64]) {
        if !(self.fresh && self.at == q) {
            jacobian(model, &mut self.data, q);
            self.at.copy_from_slice(q);
            self.fresh = true;
        }
    }
}

/// f(q) = −α·TOMM − (1 − α)·JLM and (optionally) its gradient.
fn objective(
    model: &Model,
    st: &mut RunState,
    rows: &[usize],
    q: &[f64],
    grad: Option<&mut [f64]>,
) -> f64 {
    st.evaluations += 1;
    st.kinematics_at(model, q);
    let f = -st.index.value_from(model, &st.data, q, rows);
    if let Some(g) = grad {
        st.index.gradient_from(model, &st.data, q, rows, g);
        for v in g.iter_mut() {
            *v = -*v;
        }
    }
    f
}

/// f at `q` (allocating convenience).
pub fn posture_objective(
    model: &Model,
    q: &[f64],
    rows: &[usize],
    alpha: f64,
) -> Result<f64, Error> {
    model.check_q(q)?;
    check_rows(rows)?;
    let mut data = KinData::new(model);
    jacobian(model, &mut data, q);
    Ok(-(alpha * tomm_of_jacobian(&data, rows) + (1.0 - alpha) * jlm(model, q)))
}

fn violation(model: &Model, data: &mut KinData, q: &[f64], target: &Vector3<f64>) -> f64 {
    forward_kinematics(model, data, q);
    (data.tool_point - target).norm()
}

/// One SLSQP run from `q` (overwritten with the result); returns the objective evaluations.
///
/// The `slsqp` crate takes inequality constraints c(q) ≤ 0 only, so each component
/// e_i = r_p,i(q) − r_p,i⁰ of eq. 18 becomes the pair e_i − s ≤ 0 and −e_i − s ≤ 0: a slab
/// of half-width s = 10⁻³·[`PostureOptions::constraint_tolerance_m`] (1 nm by default), so
/// |r_p − r_p⁰| ≤ √3·s at a feasible point, far inside the tolerance. With s > 0 at most one
/// side of each pair is active, so the active constraint gradients (rows of J_v) stay
/// independent; with s = 0 both sides would be active with opposite gradients.
///
/// The crate counts a point as feasible only if every c ≤ 0 exactly (its constraint tolerance
/// is fixed at 0), while SLSQP converges onto the active faces, where c is 0 up to round-off
/// of either sign. Unhandled, a converged point is then infeasible for the crate by chance:
/// its ftol/xtol stops (which require a feasible point) rarely fire, the run goes on until
/// round-off or the evaluation cap, and the point it returns (its best *feasible* point) may
/// be an early iterate far from the optimum. So a value 0 < c ≤ τ, τ = 10⁻³·s, is reported
/// as 0, which is the per-constraint tolerance τ of NLopt's own interface: far below s, far
/// above the round-off of the tool point (≈ 10⁻¹⁶ m). Measured on the 50 runs of
/// `tests/optimal_posture.rs` when this was written: runs stopped by ftol 9 → 48, evaluations
/// 6103 → 1159, and every start ends at a KKT point (that test checks it).
fn slsqp(model: &Model, target: &Vector3<f64>, opts: &PostureOptions, q: &mut [f64]) -> usize {
    let n = model.dof();
    let slack_m = opts.constraint_tolerance_m * 1e-3;
    let snap_m = slack_m * 1e-3;
    let state = RefCell::new(RunState {
        index: PerformanceIndex::new(model, opts.alpha),
        data: KinData::new(model),
        at: vec![0.0; n],
        fresh: false,
        evaluations: 0,
    });
    let rows = opts.rows.as_slice();
    let f = |x: &[f64], g: Option<&mut [f64]>, _: &mut ()| {
        objective(model, &mut state.borrow_mut(), rows, x, g)
    };
    // sign·e_i − s ≤ 0, gradient sign·(row i of J_v).
    let side = |i: usize, sign: f64| {
        let state = &state;
        move |x: &[f64], g: Option<&mut [f64]>, _: &mut ()| {
            let mut st = state.borrow_mut();
            st.kinematics_at(model, x);
            if let Some(g) = g {
                for (k, v) in g.iter_mut().enumerate() {
                    *v = sign * st.data.jacobian[(i, k)];
                }
            }
            let c = sign * (st.data.tool_point[i] - target[i]) - slack_m;
            if c > 0.0 && c <= snap_m { 0.0 } else { c }
        }
    };
    let constraints: [_; 6] =
        std::array::from_fn(|c| side(c / 2, if c % 2 == 0 { 1.0 } else { -1.0 }));
    let bounds: Vec<(f64, f64)> = model
        .joints
        .iter()
        .map(|j| (j.limits[0], j.limits[1]))
        .collect();
    let stop = StopTols {
        xtol_rel: opts.xtol_rel,
        ftol_rel: 1e-12,
        ..StopTols::default()
    };
    // SLSQP may stop with a failure status (e.g. round-off limited) after useful progress; the
    // caller checks feasibility and the objective of the best point it returns either way.
    let (Ok((_, x, _)) | Err((_, x, _))) = minimize(
        f,
        q,
        &bounds,
        &constraints,
        (),
        opts.max_evaluations as usize,
        Some(stop),
    );
    q.copy_from_slice(&x);
    state.into_inner().evaluations
}

/// Optimal posture for the tool-point position `target` (m, base frame): multi-start SLSQP
/// (see the module doc). Errors: invalid options ([`Error::InvalidParameter`],
/// [`Error::InvalidRows`], [`Error::NonFinite`]) and a target no start can reach within the
/// joint limits ([`Error::Unreachable`]).
pub fn optimal_posture(
    model: &Model,
    target: &[f64; 3],
    opts: &PostureOptions,
) -> Result<PostureResult, Error> {
    let target = validate(model, target, opts)?;
    let mut candidates = opts.initial.clone();
    candidates.extend(initial_candidates(model, opts.starts));
    let ik_opts = IkOptions {
        tolerance_m: opts.constraint_tolerance_m * 1e-2,
        max_iterations: 200,
        ..IkOptions::default()
    };
    let mut data = KinData::new(model);
    let mut outcomes = Vec::with_capacity(candidates.len());
    let mut closest = f64::INFINITY;
    for candidate in &candidates {
        let start = dls_ik(model, &IkTarget::Position(target), candidate, &ik_opts).ok();
        let mut q = start.clone().unwrap_or_else(|| candidate.clone());
        let start_objective = match &start {
            Some(s) => Some(posture_objective(model, s, &opts.rows, opts.alpha)?),
            None => None,
        };
        let evaluations = slsqp(model, &target, opts, &mut q);
        // Keep q within the limits exactly (SLSQP honours bounds up to round-off).
        for (v, j) in q.iter_mut().zip(&model.joints) {
            *v = v.clamp(j.limits[0], j.limits[1]);
        }
        let mut objective = posture_objective(model, &q, &opts.rows, opts.alpha)?;
        let mut viol = violation(model, &mut data, &q, &target);
        if let (Some(s), Some(fs)) = (&start, start_objective) {
            let s_viol = violation(model, &mut data, s, &target);
            if viol > opts.constraint_tolerance_m || !objective.is_finite() || objective > fs {
                q.clone_from(s);
                objective = fs;
                viol = s_viol;
            }
        }
        closest = closest.min(viol);
        outcomes.push(StartOutcome {
            candidate: candidate.clone(),
            start,
            start_objective,
            q,
            objective,
            constraint_violation_m: viol,
            evaluations,
        });
    }
    let best = outcomes
        .iter()
        .enumerate()
        .filter(|(_, o)| {
            o.constraint_violation_m <= opts.constraint_tolerance_m && o.objective.is_finite()
        })
        .min_by(|a, b| a.1.objective.total_cmp(&b.1.objective))
        .map(|(i, _)| i);
    let Some(best) = best else {
        return Err(Error::Unreachable {
            reason: format!(
                "target [{:.4}, {:.4}, {:.4}] m is outside the workspace of {} within its joint limits: \
                 from {} starts the tool point came no closer than {closest:.3e} m (tolerance {:.0e} m)",
                target.x,
                target.y,
                target.z,
                model.name,
                candidates.len(),
                opts.constraint_tolerance_m
            ),
        });
    };
    let w = &outcomes[best];
    let q = w.q.clone();
    jacobian(model, &mut data, &q);
    Ok(PostureResult {
        tomm: tomm_of_jacobian(&data, &opts.rows),
        jlm: jlm(model, &q),
        objective: w.objective,
        iterations: w.evaluations,
        constraint_violation_m: w.constraint_violation_m,
        start: best,
        q,
        starts: outcomes,
    })
}
