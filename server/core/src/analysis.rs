//! One-call analysis of a posture: pose, Jacobians, every measure, JLM, SVD subspaces.
//! This is what `POST /api/analysis` returns and what the analysis benchmark times.

use nalgebra::{DMatrix, Isometry3, IsometryMatrix3};

use crate::Error;
use crate::kinematics::{KinData, jacobian, jacobian_in_end_effector_frame};
use crate::manipulability::{
    Measures, Subspaces, full_svd, jlm, jlm_gradient, row_measures, row_measures_pair,
};
use crate::model::Model;

/// Rows vx vy vz of the 6×n Jacobian.
pub const TRANSLATIONAL_ROWS: [usize; 3] = [0, 1, 2];
/// Rows wx wy wz of the 6×n Jacobian.
pub const ROTATIONAL_ROWS: [usize; 3] = [3, 4, 5];

/// Everything known about one posture.
#[derive(Debug, Clone)]
pub struct Analysis {
    /// End-effector pose (tool point, flange orientation), base frame.
    pub pose: Isometry3<f64>,
    /// Joint frames after their motion, base frame.
    pub joint_frames: Vec<IsometryMatrix3<f64>>,
    /// 6×n geometric Jacobian, base frame, rows vx vy vz wx wy wz.
    pub jacobian: DMatrix<f64>,
    /// The same in the end-effector frame.
    pub jacobian_end_effector: DMatrix<f64>,
    /// Measures of the full 6-row Jacobian.
    pub full: Measures,
    /// Measures of the translational rows (Lim eq. 3.62).
    pub translational: Measures,
    /// Measures of the rotational rows (Lim eq. 3.63).
    pub rotational: Measures,
    /// Measures of the task rows, when given (Jun's TOMM).
    pub task: Option<Measures>,
    /// Joint-limit measure (Jun eq. 16).
    pub jlm: f64,
    /// ∂JLM/∂q.
    pub jlm_gradient: Vec<f64>,
    /// SVD subspaces of the full Jacobian (RX90 report part VI).
    pub subspaces: Subspaces,
}

/// Analyses `model` at `q` (validated here); `rows` selects task rows of the 6×n Jacobian.
pub fn analyze(model: &Model, q: &[f64], rows: Option<&[usize]>) -> Result<Analysis, Error> {
    model.check_q(q)?;
    let mut data = KinData::new(model);
    jacobian(model, &mut data, q);
    let j = &data.jacobian;
    let (full, subspaces) = full_svd(j)?.into_measures_and_subspaces()?;
    let [translational, rotational] =
        row_measures_pair(j, [&TRANSLATIONAL_ROWS, &ROTATIONAL_ROWS])?;
    let task = match rows {
        Some(r) => Some(row_measures(j, r)?),
        None => None,
    };
    let mut grad = vec![0.0; model.dof()];
    jlm_gradient(model, q, &mut grad);
    let pose = data.end_effector();
    let jacobian_end_effector = jacobian_in_end_effector_frame(&data);
    let KinData {
        joint_frames,
        jacobian,
        ..
    } = data;
    Ok(Analysis {
        pose,
        jacobian_end_effector,
        joint_frames,
        jacobian,
        full,
        translational,
        rotational,
        task,
        jlm: jlm(model, q),
        jlm_gradient: grad,
        subspaces,
    })
}
