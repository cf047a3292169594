//! The geometric Jacobian of every built-in model equals finite-differenced forward
//! kinematics (linear rows: d p / d q; angular rows: the rotation-vector rate of R·R₀ᵀ), and
//! the end-effector-frame Jacobian is the base one rotated by Rᵀ.

#![allow(clippy::unwrap_used)]

mod common;

use nalgebra::{DMatrix, Matrix3};
use seaarms_core::kinematics::{
    KinData, end_effector_pose, jacobian, jacobian_in_end_effector_frame,
};

fn sample_q(model: &seaarms_core::Model, k: usize) -> Vec<f64> {
    // Deterministic spread of postures inside the limits (or ±2 rad when unlimited).
    model
        .joints
        .iter()
        .enumerate()
        .map(|(i, j)| {
            let (lo, hi) = if j.is_limited() {
                (j.limits[0], j.limits[1])
            } else {
                (-2.0, 2.0)
            };
            let t = (((i + 1) * 7919 + k * 104729) % 1000) as f64 / 1000.0;
            lo + (hi - lo) * (0.05 + 0.9 * t)
        })
        .collect()
}

#[test]
fn jacobian_matches_central_differences_for_every_model() {
    let h = 1e-6;
    for model in common::all_builtin() {
        for k in 0..20 {
            let q = sample_q(&model, k);
            let mut data = KinData::new(&model);
            jacobian(&model, &mut data, &q);
            let n = model.dof();
            let mut fd = DMatrix::zeros(6, n);
            for i in 0..n {
                let mut qp = q.clone();
                let mut qm = q.clone();
                qp[i] += h;
                qm[i] -= h;
                let tp = end_effector_pose(&model, &qp);
                let tm = end_effector_pose(&model, &qm);
                let dp = (tp.translation.vector - tm.translation.vector) / (2.0 * h);
                let dr = (tp.rotation * tm.rotation.inverse()).scaled_axis() / (2.0 * h);
                fd.fixed_view_mut::<3, 1>(0, i).copy_from(&dp);
                fd.fixed_view_mut::<3, 1>(3, i).copy_from(&dr);
            }
            let err = (&data.jacobian - &fd).abs().max();
            assert!(err < 1e-7, "{} q={q:?}: |J - FD| = {err:e}", model.name);

            let je = jacobian_in_end_effector_frame(&data);
            let r: Matrix3<f64> = data.flange.rotation.to_rotation_matrix().into_inner();
            for c in 0..n {
                let lin = r * je.fixed_view::<3, 1>(0, c);
                let ang = r * je.fixed_view::<3, 1>(3, c);
                assert!((lin - data.jacobian.fixed_view::<3, 1>(0, c)).norm() < 1e-12);
                assert!((ang - data.jacobian.fixed_view::<3, 1>(3, c)).norm() < 1e-12);
            }
        }
    }
}

#[test]
fn inline_modified_and_standard_dh_agree_on_a_planar_arm() {
    // A planar 2R arm written in both conventions must give the same tip (Craig §3 vs Lim eq. 2.1).
    let std_spec = r#"{"name":"s","dh":"standard","joints":[{"type":"revolute","a":0.7},{"type":"revolute","a":0.4}]}"#;
    let mod_spec = r#"{"name":"m","dh":"modified","joints":[{"type":"revolute"},{"type":"revolute","a":0.7}],"tool":[0.4,0,0]}"#;
    let s = seaarms_core::Model::from_spec(&serde_json::from_str(std_spec).unwrap()).unwrap();
    let m = seaarms_core::Model::from_spec(&serde_json::from_str(mod_spec).unwrap()).unwrap();
    for q in [[0.3, -0.4], [1.2, 2.0], [-2.0, 0.1]] {
        let ps = end_effector_pose(&s, &q).translation.vector;
        let pm = end_effector_pose(&m, &q).translation.vector;
        let closed = nalgebra::Vector3::new(
            0.7 * q[0].cos() + 0.4 * (q[0] + q[1]).cos(),
            0.7 * q[0].sin() + 0.4 * (q[0] + q[1]).sin(),
            0.0,
        );
        assert!(
            (ps - closed).norm() < 1e-12 && (pm - closed).norm() < 1e-12,
            "{ps} {pm} {closed}"
        );
    }
}

#[test]
fn prismatic_joint_column_is_its_axis() {
    let spec = r#"{"name":"p","dh":"standard","joints":[{"type":"revolute","a":0.5,"alpha":1.5707963267948966},{"type":"prismatic","d":0.2}]}"#;
    let model = seaarms_core::Model::from_spec(&serde_json::from_str(spec).unwrap()).unwrap();
    let q = [0.4, 0.3];
    let mut data = KinData::new(&model);
    jacobian(&model, &mut data, &q);
    let axis = data.joint_frames[1].rotation * nalgebra::Vector3::z();
    assert!((data.jacobian.fixed_view::<3, 1>(0, 1) - axis).norm() < 1e-12);
    assert!(data.jacobian.fixed_view::<3, 1>(3, 1).norm() < 1e-15);
    // The tool point sits d + q along that axis from DH frame 1's origin (0.5cos q1, 0.5 sin q1, 0).
    let tip = end_effector_pose(&model, &q).translation.vector;
    let frame1 = nalgebra::Vector3::new(0.5 * q[0].cos(), 0.5 * q[0].sin(), 0.0);
    assert!(
        ((tip - frame1) - axis * 0.5).norm() < 1e-12,
        "{tip} {frame1} {axis}"
    );
}
