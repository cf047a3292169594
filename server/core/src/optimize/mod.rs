//! Optimisation over joint space (Jun 2008 §3).
//!
//! * [`objective`]: TOMM, JLM and the performance index P = α·TOMM + (1 − α)·JLM with
//!   allocation-free gradients (shared with [`crate::redundancy`]).
//! * [`posture`]: task-oriented optimal posture, multi-start SLSQP (the pure-Rust `slsqp`
//!   crate) with the end-effector position constraint (Jun eqs 10, 17, 18).
//! * `spd` (crate-internal): k×k symmetric positive-definite helpers (Gram matrix,
//!   determinant, Cholesky, solve), shared with [`crate::redundancy`].

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
