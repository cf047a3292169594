//! Forward kinematics and the geometric Jacobian.
//!
//! Algorithms follow the Model/Data split: [`KinData`] holds preallocated results, and
//! [`forward_kinematics`] / [`jacobian`] fill it without allocating, so they can run inside
//! the 1 kHz step.

use nalgebra::{DMatrix, Isometry3, IsometryMatrix3, Matrix3, Rotation3, UnitQuaternion, Vector3};

use crate::model::{JointKind, Model};

/// Preallocated kinematic results for one model.
#[derive(Debug, Clone)]
pub struct KinData {
    /// Pose of each joint's frame after its motion, base frame (its z axis is the joint axis
    /// for every DH convention; its origin lies on the axis). Rotations are matrices: the
    /// dynamics and the Jacobian read axes and rotate inertias with them directly.
    pub joint_frames: Vec<IsometryMatrix3<f64>>,
    /// Pose of the last link frame (flange), base frame.
    pub flange: Isometry3<f64>,
    /// Tool point (the Jacobian's reference point), base frame (m).
    pub tool_point: Vector3<f64>,
    /// Geometric Jacobian, 6×n, base frame, rows vx vy vz wx wy wz, reference point = tool point.
    pub jacobian: DMatrix<f64>,
}

impl KinData {
    /// Allocates results for `model`.
    pub fn new(model: &Model) -> KinData {
        let n = model.dof();
        KinData {
            joint_frames: vec![IsometryMatrix3::identity(); n],
            flange: Isometry3::identity(),
            tool_point: Vector3::zeros(),
            jacobian: DMatrix::zeros(6, n),
        }
    }

    /// End-effector pose: the flange orientation with the tool point as position.
    pub fn end_effector(&self) -> Isometry3<f64> {
        Isometry3::from_parts(self.tool_point.into(), self.flange.rotation)
    }
}

/// Forward kinematics of every frame. `q` must have `model.dof()` entries (unchecked here;
/// validate at the edge with [`Model::check_q`]).
pub fn forward_kinematics(model: &Model, data: &mut KinData, q: &[f64]) {
    // Rotation matrix and origin of the current frame, composed joint by joint.
    let mut r = Matrix3::identity();
    let mut p = Vector3::zeros();
    for ((joint, frame), &qi) in model.joints.iter().zip(data.joint_frames.iter_mut()).zip(q) {
        p += r * joint.origin.translation.vector;
        r = joint.origin_rotation.after(&r);
        match joint.kind {
            JointKind::Revolute => r = joint.rotate_frame(&r, qi),
            JointKind::Prismatic => p += r * (joint.axis.into_inner() * (qi + joint.offset)),
        }
        *frame = IsometryMatrix3::from_parts(p.into(), Rotation3::from_matrix_unchecked(r));
    }
    p += r * model.flange.translation.vector;
    r = model.flange_rotation.after(&r);
    data.tool_point = p + r * model.tool;
    data.flange = Isometry3::from_parts(
        p.into(),
        UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r)),
    );
}

/// Forward kinematics followed by the geometric Jacobian (Lim §2.3; RX90 report part II:
/// column k = [a_k × (P_n − P_k); a_k] for revolute joints, [a_k; 0] for prismatic ones).
pub fn jacobian(model: &Model, data: &mut KinData, q: &[f64]) {
    forward_kinematics(model, data, q);
    let p = data.tool_point;
    for (k, (joint, frame)) in model.joints.iter().zip(&data.joint_frames).enumerate() {
        let axis = frame.rotation * joint.axis.into_inner();
        let (lin, ang) = match joint.kind {
            JointKind::Revolute => (axis.cross(&(p - frame.translation.vector)), axis),
            JointKind::Prismatic => (axis, Vector3::zeros()),
        };
        let mut col = data.jacobian.column_mut(k);
        col.fixed_rows_mut::<3>(0).copy_from(&lin);
        col.fixed_rows_mut::<3>(3).copy_from(&ang);
    }
}

/// The Jacobian expressed in the end-effector frame: blockdiag(Rᵀ, Rᵀ)·J (6×n; rows
/// vx vy vz wx wy wz in the flange axes; same reference point). Call after [`jacobian`].
pub fn jacobian_in_end_effector_frame(data: &KinData) -> DMatrix<f64> {
    let rt: Matrix3<f64> = data
        .flange
        .rotation
        .to_rotation_matrix()
        .matrix()
        .transpose();
    let mut out = data.jacobian.clone();
    for k in 0..out.ncols() {
        let lin: Vector3<f64> = rt * data.jacobian.fixed_view::<3, 1>(0, k);
        let ang: Vector3<f64> = rt * data.jacobian.fixed_view::<3, 1>(3, k);
        out.fixed_view_mut::<3, 1>(0, k).copy_from(&lin);
        out.fixed_view_mut::<3, 1>(3, k).copy_from(&ang);
    }
    out
}

/// Allocating convenience: end-effector pose for `q`.
pub fn end_effector_pose(model: &Model, q: &[f64]) -> Isometry3<f64> {
    let mut data = KinData::new(model);
    forward_kinematics(model, &mut data, q);
    data.end_effector()
}

/// Allocating convenience: 6×n Jacobian (base frame) for `q`.
pub fn jacobian_at(model: &Model, q: &[f64]) -> DMatrix<f64> {
    let mut data = KinData::new(model);
    jacobian(model, &mut data, q);
    data.jacobian
}
