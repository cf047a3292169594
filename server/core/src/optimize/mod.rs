//! Optimisation over joint space (Jun 2008 §3).
//!
//! * [`objective`]: TOMM, JLM and the performance index P = α·TOMM + (1 − α)·JLM with
//!   allocation-free gradients (shared with [`crate::redundancy`]).
//! * [`posture`]: task-oriented optimal posture, multi-start SLSQP with the end-effector
//!   position as an equality constraint (Jun eqs 10, 17, 18).

pub mod objective;
pub mod posture;
pub(crate) mod spd;

pub use objective::{
    PerformanceIndex, check_rows, performance_index, tomm, tomm_gradient, tomm_gradient_analytic,
    tomm_of_jacobian,
};
pub use posture::{
    PostureOptions, PostureResult, StartOutcome, initial_candidates, optimal_posture,
    posture_objective,
};
