//! Manipulability: ellipsoid measures, joint-limit measure, dual-arm ellipsoid, polytopes.
//!
//! * [`measures`](mod@measures): rank, Yoshikawa, condition number, isotropy, Hong, force measures,
//!   velocity and force ellipsoids, task rows (Lim §2.4, §3.5; Jun §2); it re-exports the
//!   full SVD and its subspaces (`svd`) and the inline task-space storage (`task`).
//! * `jacobi`: the one-sided Jacobi SVD behind them.
//! * [`jlm`](mod@jlm): joint-limit measure and gradient (Jun eqs 11–16).
//! * [`dual`]: dual-arm ellipsoid (Lim eq. 3.68).
//! * [`polytope`]: velocity polytopes, single and dual (Kilic §3.2).

pub mod dual;
mod jacobi;
pub mod jlm;
pub mod measures;
pub mod polytope;
mod svd;
mod task;

pub use dual::{dual_measures, dual_shape_matrix};
pub use jlm::{jlm, jlm_gradient};
pub use measures::{
    Ellipsoid, FullSvd, MAX_TASK_DIM, Measures, Subspaces, TaskMatrix, TaskVector, full_svd,
    measures, measures_from_svd, row_measures, row_measures_pair, select_rows, subspaces,
    subspaces_from_svd,
};
pub use polytope::{Polytope, convex_hull, dual_velocity_polytope, velocity_polytope};
