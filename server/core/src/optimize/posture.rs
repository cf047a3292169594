//! Task-oriented optimal posture (Jun 2008 §3, eqs 10, 17, 18) by multi-start SQP.
//!
//! minimise f(q) = −α·TOMM(q) − (1 − α)·JLM(q)
//! subject to r_p(q) − r_p⁰ = 0 (tool-point position, base frame, eq. 18) and q_l ≤ q ≤ q_u (eq. 11).
//!
//! The SQP is NLopt's SLSQP (Kraft's sequential least-squares QP, the algorithm behind scipy's
//! `method='SLSQP'`). SQP finds a local minimum, so — as in the paper — several initial
//! candidates are used: the mid-range posture and a Halton sequence over the joint ranges.
//! Each candidate is first moved onto the constraint by damped-least-squares IK
//! ([`crate::ik::dls_ik`]) so every SQP run starts feasible; the result of a run replaces its
//! start only if it is feasible and not worse. A posture whose tool point misses the target by
//! more than [`PostureOptions::constraint_tolerance_m`] is never returned: when no start
//! reaches the target, the call fails with [`Error::Unreachable`].

use nalgebra::Vector3;
use nlopt::{Algorithm, Nlopt, Target};

use super::objective::{PerformanceIndex, check_rows, tomm, tomm_of_jacobian};
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

/// Scratch state shared by the objective callback.
struct ObjectiveState {
    index: PerformanceIndex,
    data: KinData,
    rows: Vec<usize>,
    evaluations: usize,
}

/// f(q) = −α·TOMM − (1 − α)·JLM and (optionally) its gradient.
fn objective(model: &Model, st: &mut ObjectiveState, q: &[f64], grad: Option<&mut [f64]>) -> f64 {
    st.evaluations += 1;
    let alpha = st.index.alpha;
    let t = if alpha != 0.0 {
        tomm(model, &mut st.data, q, &st.rows)
    } else {
        0.0
    };
    let f = -(alpha * t + (1.0 - alpha) * jlm(model, q));
    if let Some(g) = grad {
        st.index.gradient(model, q, &st.rows, g);
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

/// One SLSQP run from `q` (overwritten with the result); returns the evaluation count.
fn slsqp(model: &Model, target: &Vector3<f64>, opts: &PostureOptions, q: &mut [f64]) -> usize {
    let n = model.dof();
    let state = ObjectiveState {
        index: PerformanceIndex::new(model, opts.alpha),
        data: KinData::new(model),
        rows: opts.rows.clone(),
        evaluations: 0,
    };
    let mut opt = Nlopt::new(
        Algorithm::Slsqp,
        n,
        |x: &[f64], g: Option<&mut [f64]>, st: &mut ObjectiveState| objective(model, st, x, g),
        Target::Minimize,
        state,
    );
    let (lo, hi) = model.limits();
    // Settings are validated by NLopt; a rejected one only leaves its default in place.
    let _ = opt.set_lower_bounds(&lo);
    let _ = opt.set_upper_bounds(&hi);
    let _ = opt.set_xtol_rel(opts.xtol_rel);
    let _ = opt.set_ftol_rel(1e-12);
    let _ = opt.set_maxeval(opts.max_evaluations);
    let tol = [opts.constraint_tolerance_m * 1e-3; 3];
    let t = *target;
    let _ = opt.add_equality_mconstraint(
        3,
        move |result: &mut [f64], x: &[f64], grad: Option<&mut [f64]>, data: &mut KinData| {
            jacobian(model, data, x);
            for i in 0..3 {
                result[i] = data.tool_point[i] - t[i];
            }
            if let Some(g) = grad {
                for i in 0..3 {
                    for k in 0..n {
                        g[i * n + k] = data.jacobian[(i, k)];
                    }
                }
            }
        },
        KinData::new(model),
        &tol,
    );
    // SLSQP may stop with a failure code (e.g. round-off limited) after useful progress; the
    // caller checks feasibility and the objective of whatever posture it leaves.
    let _ = opt.optimize(q);
    opt.recover_user_data().evaluations
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
