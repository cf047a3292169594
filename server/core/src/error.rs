//! The core's one error type.

use thiserror::Error;

/// Everything that can go wrong in the core; each variant names what was wrong.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum Error {
    /// A vector or matrix has the wrong size.
    #[error("{what} has {input} entries, {required} required")]
    SizeMismatch {
        /// What was checked.
        what: &'static str,
        /// Size given.
        input: usize,
        /// Size required.
        required: usize,
    },
    /// A number is NaN or infinite.
    #[error("{what}[{index}] is not a finite number")]
    NonFinite {
        /// What was checked.
        what: &'static str,
        /// Index of the first bad entry.
        index: usize,
    },
    /// A model specification is invalid.
    #[error("invalid model: {reason}")]
    InvalidModel {
        /// Why.
        reason: String,
    },
    /// A task row selection is invalid.
    #[error("invalid rows: {reason}")]
    InvalidRows {
        /// Why.
        reason: String,
    },
    /// An iterative method did not converge.
    #[error("{what} did not converge after {iterations} iterations (residual {residual:e})")]
    NotConverged {
        /// Which method.
        what: &'static str,
        /// Iterations run.
        iterations: usize,
        /// Final residual.
        residual: f64,
    },
    /// A target cannot be reached.
    #[error("unreachable: {reason}")]
    Unreachable {
        /// Why.
        reason: String,
    },
    /// A parameter is out of its valid range.
    #[error("invalid {what}: {reason}")]
    InvalidParameter {
        /// Which parameter.
        what: &'static str,
        /// Why.
        reason: String,
    },
    /// A geometric object spans fewer dimensions than required (e.g. a velocity polytope at a
    /// singular posture is flat and has zero volume).
    #[error("{what} is degenerate: it spans only {dimension} dimension(s)")]
    Degenerate {
        /// Which object.
        what: &'static str,
        /// Dimension it spans.
        dimension: usize,
    },
    /// Rounding broke a geometric construction (should not happen for finite inputs).
    #[error("{what} failed numerically: {reason}")]
    Numerical {
        /// Which computation.
        what: &'static str,
        /// Why.
        reason: String,
    },
}
