//! Forward kinematics and the geometric Jacobian.
//!
//! Algorithms follow the Model/Data split: [`KinData`] holds preallocated results, and
//! [`forward_kinematics`] / [`jacobian`] fill it without allocating, so they can run inside
//! the 1 kHz step.

use nalgebra::{
    DMatrix, Isometry3, IsometryMatrix3, Matrix3, Matrix6, Rotation3, UnitQuaternion, Vector3,
};

use crate::model::{Joint, JointKind, Model, turn_about_z};

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
    /// Filled by [`jacobian`]; [`jacobian6`] writes its result elsewhere and leaves this as is.
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
            JointKind::Prismatic => {
                p += r * (joint.axis.into_inner() * (qi + joint.offset));
            }
        }
        *frame = IsometryMatrix3::from_parts(p.into(), Rotation3::from_matrix_unchecked(r));
    }
    (data.tool_point, data.flange) = finish_chain(model, r, p);
}

/// The tool point and the flange pose from the last joint's frame (rotation `r`, origin `p`).
fn finish_chain(
    model: &Model,
    mut r: Matrix3<f64>,
    mut p: Vector3<f64>,
) -> (Vector3<f64>, Isometry3<f64>) {
    p += r * model.flange.translation.vector;
    r = model.flange_rotation.after(&r);
    let flange = Isometry3::from_parts(
        p.into(),
        UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r)),
    );
    (p + r * model.tool, flange)
}

/// Forward kinematics followed by the geometric Jacobian (Lim §2.3; RX90 report part II:
/// column k = [a_k × (P_n − P_k); a_k] for revolute joints, [a_k; 0] for prismatic ones).
pub fn jacobian(model: &Model, data: &mut KinData, q: &[f64]) {
    if let Some((mut chain, jm)) = Chain6::of(model, data, q) {
        if let Ok(out) = <&mut [f64; 36]>::try_from(jm.as_mut_slice()) {
            chain.fill(model, out);
            return;
        }
    }
    jacobian_general(model, data, q);
}

/// [`jacobian`] for any chain: joint by joint through [`forward_kinematics`].
fn jacobian_general(model: &Model, data: &mut KinData, q: &[f64]) {
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

/// [`jacobian`] for a six-joint model with the Jacobian written to `j` instead of
/// `data.jacobian` (left untouched): what the 1 kHz simulation step needs, without the
/// dynamic matrix and the copy out of it. Joint frames, flange and tool point are filled as
/// by [`forward_kinematics`]. Six revolute joints about +z (every DH model)
/// take a fixed-size path; anything else gives the same result through the general one
/// (which then also fills `data.jacobian`).
///
/// # Panics
/// When `model` does not have six joints or `data` was not allocated for it.
pub fn jacobian6(model: &Model, data: &mut KinData, q: &[f64; 6], j: &mut Matrix6<f64>) {
    match Chain6::of(model, data, q) {
        Some((mut chain, _)) => {
            let out: &mut [f64; 36] = j.as_mut_slice().try_into().unwrap_or_else(|_| {
                unreachable!("a 6×6 matrix has 36 entries");
            });
            chain.fill(model, out);
        }
        None => {
            jacobian(model, data, q);
            j.copy_from(&data.jacobian);
        }
    }
}

/// The fixed-size path's view of a model and its results: six revolute joints about +z with
/// results sized for them. Arrays instead of slices let the compiler unroll the chain and
/// drop every bounds check, and the joint kind and axis tests are made once per call.
struct Chain6<'a> {
    joints: &'a [Joint; 6],
    q: &'a [f64; 6],
    frames: &'a mut [IsometryMatrix3<f64>; 6],
    flange: &'a mut Isometry3<f64>,
    tool_point: &'a mut Vector3<f64>,
}

impl<'a> Chain6<'a> {
    /// `Some` when `model` (with `data` and `q` sized for it) takes the fixed-size path;
    /// `data.jacobian` comes back alongside for [`jacobian`] to fill.
    fn of(
        model: &'a Model,
        data: &'a mut KinData,
        q: &'a [f64],
    ) -> Option<(Chain6<'a>, &'a mut DMatrix<f64>)> {
        let joints: &[Joint; 6] = model.joints.as_slice().try_into().ok()?;
        // +z exactly (what every DH convention builds): the angle needs no sign and each
        // base-frame axis is a frame's z column as it stands.
        let axes_z = joints
            .iter()
            .all(|j| j.kind == JointKind::Revolute && j.axis.into_inner() == Vector3::z());
        if !axes_z {
            return None;
        }
        let chain = Chain6 {
            joints,
            q: q.try_into().ok()?,
            frames: data.joint_frames.as_mut_slice().try_into().ok()?,
            flange: &mut data.flange,
            tool_point: &mut data.tool_point,
        };
        Some((chain, &mut data.jacobian))
    }

    /// Forward kinematics and the Jacobian (column-major 6×6 into `out`): the same operations
    /// in the same order as [`forward_kinematics`] and [`jacobian`], so the same results.
    fn fill(&mut self, model: &Model, out: &mut [f64; 36]) {
        let mut r = Matrix3::identity();
        let mut p = Vector3::zeros();
        for k in 0..6 {
            let joint = &self.joints[k];
            p += r * joint.origin.translation.vector;
            r = joint.origin_rotation.after(&r);
            // Joint::rotate_frame for the +z axis.
            let (s, c) = (self.q[k] + joint.offset).sin_cos();
            r = turn_about_z(&r, s, c);
            self.frames[k] =
                IsometryMatrix3::from_parts(p.into(), Rotation3::from_matrix_unchecked(r));
        }
        let tool;
        (tool, *self.flange) = finish_chain(model, r, p);
        *self.tool_point = tool;
        for (k, frame) in self.frames.iter().enumerate() {
            // The axis in the base frame is the frame's z column (R·e_z).
            let axis = frame.rotation.matrix().column(2);
            let lin = axis.cross(&(tool - frame.translation.vector));
            out[6 * k..6 * k + 3].copy_from_slice(lin.as_slice());
            out[6 * k + 3..6 * k + 6].copy_from_slice(axis.as_slice());
        }
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

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion};

    use crate::model::ModelSpec;

    fn builtin(name: &str) -> Model {
        let text = crate::robots::builtin_text(name).unwrap_or_else(|| panic!("{name}"));
        let spec: ModelSpec = serde_json::from_str(text).unwrap_or_else(|e| panic!("{e}"));
        Model::from_spec(&spec).unwrap_or_else(|e| panic!("{e}"))
    }

    /// Deterministic uniform numbers in [lo, hi) (a 64-bit LCG: no dependency for a test).
    struct Lcg(u64);
    impl Lcg {
        fn next(&mut self, lo: f64, hi: f64) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            lo + (hi - lo) * ((self.0 >> 11) as f64 / (1u64 << 53) as f64)
        }
    }

    /// Every result of `a` equals that of `b` (== on each number: the fixed-size path does
    /// the general path's operations in its order, so they agree to the last bit, up to the
    /// sign of zeros).
    fn assert_same(a: &KinData, b: &KinData, what: &str) {
        for (k, (fa, fb)) in a.joint_frames.iter().zip(&b.joint_frames).enumerate() {
            assert_eq!(
                fa.rotation.matrix(),
                fb.rotation.matrix(),
                "{what} frame {k}"
            );
            assert_eq!(fa.translation, fb.translation, "{what} frame {k}");
        }
        assert_eq!(a.tool_point, b.tool_point, "{what}");
        assert_eq!(a.flange.translation, b.flange.translation, "{what}");
        assert_eq!(a.flange.rotation, b.flange.rotation, "{what}");
        assert_eq!(a.jacobian, b.jacobian, "{what}");
    }

    /// The fixed-size path (through [`jacobian`] and [`jacobian6`]) gives the general path's
    /// results for the six-joint built-in models, standard and modified DH, bare and placed at
    /// random bases, in random postures (including angles outside the limits).
    #[test]
    fn fixed_size_path_matches_the_general_one() {
        let mut rng = Lcg(0x5ea_a4b5);
        let mut models = 0;
        for name in ["magnum", "orion", "rx90", "puma560"] {
            let bare = builtin(name);
            if bare.dof() != 6 {
                continue;
            }
            models += 1;
            for trial in 0..50 {
                let model = if trial % 2 == 0 {
                    bare.clone()
                } else {
                    let base = Isometry3::from_parts(
                        Translation3::new(
                            rng.next(-2.0, 2.0),
                            rng.next(-2.0, 2.0),
                            rng.next(-2.0, 2.0),
                        ),
                        UnitQuaternion::from_euler_angles(
                            rng.next(-3.0, 3.0),
                            rng.next(-1.5, 1.5),
                            rng.next(-3.0, 3.0),
                        ),
                    );
                    bare.based_at(&base)
                };
                let q: [f64; 6] = std::array::from_fn(|_| rng.next(-4.0, 4.0));
                let what = format!("{name} trial {trial} q={q:?}");
                assert!(
                    Chain6::of(&model, &mut KinData::new(&model), &q).is_some(),
                    "{what}"
                );

                let mut general = KinData::new(&model);
                jacobian_general(&model, &mut general, &q);
                let mut fast = KinData::new(&model);
                jacobian(&model, &mut fast, &q);
                assert_same(&fast, &general, &what);

                let mut direct = KinData::new(&model);
                let mut j6 = Matrix6::from_element(f64::NAN);
                jacobian6(&model, &mut direct, &q, &mut j6);
                assert_eq!(
                    DMatrix::from_column_slice(6, 6, j6.as_slice()),
                    general.jacobian
                );
                // jacobian6 leaves data.jacobian alone; everything else matches.
                assert_eq!(direct.jacobian, DMatrix::zeros(6, 6), "{what}");
                direct.jacobian = general.jacobian.clone();
                assert_same(&direct, &general, &what);
            }
        }
        assert!(models >= 3, "too few six-joint models tested");
    }

    /// Six-joint chains the fixed-size path does not take (a prismatic joint, a −z axis)
    /// still give [`jacobian`]'s results through [`jacobian6`].
    #[test]
    fn jacobian6_falls_back_for_other_chains() {
        let spec = r#"{"name":"p","dh":"standard","joints":[
            {"type":"revolute","a":0.1,"alpha":1.5707963267948966},
            {"type":"revolute","a":0.5},
            {"type":"prismatic","d":0.2,"theta":0.3},
            {"type":"revolute","alpha":-1.5707963267948966,"theta":0.2},
            {"type":"revolute","alpha":1.5707963267948966,"d":0.1},
            {"type":"revolute","d":0.2}],"tool":[0.0,0.0,0.1]}"#;
        let spec: ModelSpec = serde_json::from_str(spec).unwrap_or_else(|e| panic!("{e}"));
        let prismatic = Model::from_spec(&spec).unwrap_or_else(|e| panic!("{e}"));
        let mut minus_z = builtin("magnum");
        minus_z.joints[3].axis = -Vector3::z_axis();
        let mut rng = Lcg(7);
        for model in [prismatic, minus_z] {
            for _ in 0..20 {
                let q: [f64; 6] = std::array::from_fn(|_| rng.next(-3.0, 3.0));
                assert!(Chain6::of(&model, &mut KinData::new(&model), &q).is_none());
                let mut general = KinData::new(&model);
                jacobian(&model, &mut general, &q);
                let mut direct = KinData::new(&model);
                let mut j6 = Matrix6::zeros();
                jacobian6(&model, &mut direct, &q, &mut j6);
                assert_same(&direct, &general, &model.name);
                assert_eq!(
                    DMatrix::from_column_slice(6, 6, j6.as_slice()),
                    general.jacobian
                );
            }
        }
    }
}
