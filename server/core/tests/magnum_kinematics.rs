//! Magnum forward kinematics equals Lim eq. 3.9; closed-form IK (eqs 3.10–3.19) round-trips;
//! the case-study workspace (Lim §4.3.1: X 0.9–1.4 m, Z 0–0.5 m) is reachable within limits.

#![allow(clippy::unwrap_used)]

mod common;

use nalgebra::{Matrix3, Vector3};
use proptest::prelude::*;
use seaarms_core::ik::{IkOptions, IkTarget, MagnumLengths, dls_ik, magnum_ik};
use seaarms_core::kinematics::end_effector_pose;

/// Lim eq. 3.9, transcribed term by term: (n, o, a, p) of T6.
fn eq_3_9(l: &MagnumLengths, q: &[f64]) -> (Matrix3<f64>, Vector3<f64>) {
    let (s1, c1) = q[0].sin_cos();
    let (s2, c2) = q[1].sin_cos();
    let (s23, c23) = (q[1] + q[2]).sin_cos();
    let (s234, c234) = (q[1] + q[2] + q[3]).sin_cos();
    let (s5, c5) = q[4].sin_cos();
    let (s6, c6) = q[5].sin_cos();
    let nx = c1 * (s234 * c6 - c234 * s5 * s6) - s1 * (c5 * s6);
    let ny = s1 * (s234 * c6 - c234 * s5 * s6) + c1 * (c5 * s6);
    let nz = -c234 * c6 - s234 * s5 * s6;
    // Erratum: eq. 3.9 prints s5·c6 in the last terms of o_x and o_y; the product
    // A1···A6 (eqs 3.2–3.7) gives c5·c6 there (row 3 of eq. 3.12 has the same misprint).
    // The printed form fails o = a × n, e.g. o = 0 at q = 0.
    let ox = c1 * (-s234 * s6 - c234 * s5 * c6) - s1 * (c5 * c6);
    let oy = s1 * (-s234 * s6 - c234 * s5 * c6) + c1 * (c5 * c6);
    let oz = c234 * s6 - s234 * s5 * c6;
    let ax = c1 * (c234 * c5) - s1 * s5;
    let ay = s1 * (c234 * c5) + c1 * s5;
    let az = s234 * c5;
    let w = (l.l5 + l.l6) * c234 * c5 + l.l4 * c234 + l.l3 * c23 + l.l2 * c2;
    let px = c1 * w - s1 * (l.l5 + l.l6) * s5 + l.l1 * c1;
    let py = s1 * w + c1 * (l.l5 + l.l6) * s5 + l.l1 * s1;
    let pz = (l.l5 + l.l6) * s234 * c5 + l.l4 * s234 + l.l3 * s23 + l.l2 * s2;
    (
        Matrix3::new(nx, ox, ax, ny, oy, ay, nz, oz, az),
        Vector3::new(px, py, pz),
    )
}

fn magnum_q() -> impl Strategy<Value = Vec<f64>> {
    let m = common::builtin("magnum");
    m.joints
        .iter()
        .map(|j| {
            let (lo, hi) = if j.is_limited() {
                (j.limits[0], j.limits[1])
            } else {
                (-3.1, 3.1)
            };
            lo..hi
        })
        .collect::<Vec<_>>()
}

proptest! {
    #[test]
    fn forward_kinematics_equals_eq_3_9(q in magnum_q()) {
        let model = common::builtin("magnum");
        let l = MagnumLengths::from_model(&model).unwrap();
        let pose = end_effector_pose(&model, &q);
        let (r, p) = eq_3_9(&l, &q);
        let r_fk = pose.rotation.to_rotation_matrix().into_inner();
        prop_assert!((r_fk - r).abs().max() < 1e-12, "R fk {r_fk} vs eq 3.9 {r}");
        prop_assert!((pose.translation.vector - p).abs().max() < 1e-12);
    }

    /// Lim eq. 3.16 as printed, θ1 = atan2((l5+l6)a_y − p_y, (l5+l6)a_x − p_x), negates both
    /// arguments of the wrist-centre projection and so returns θ1 + π (mod 2π); the corrected
    /// form atan2(p_y − (l5+l6)a_y, p_x − (l5+l6)a_x), used by `magnum_ik`, returns θ1 (the
    /// README's errata list). The pose comes from forward kinematics at q (eq. 3.9).
    #[test]
    fn eq_3_16_as_printed_gives_theta1_plus_pi(q in magnum_q()) {
        let model = common::builtin("magnum");
        let l = MagnumLengths::from_model(&model).unwrap();
        let pose = end_effector_pose(&model, &q);
        let r = pose.rotation.to_rotation_matrix().into_inner();
        let (a, p) = (r.column(2), pose.translation.vector);
        let lw = l.l5 + l.l6;
        // Away from the shoulder axis, where θ1 is undefined, and with the wrist centre in
        // front of it (an arm raised past vertical with the wrist tilted back puts it behind,
        // where both forms name the π twin).
        prop_assume!((p.x - lw * a.x).hypot(p.y - lw * a.y) > 1e-6);
        prop_assume!((p.x - lw * a.x) * q[0].cos() + (p.y - lw * a.y) * q[0].sin() > 1e-6);
        let wrapped = |x: f64| {
            let d = x.rem_euclid(std::f64::consts::TAU);
            d.min(std::f64::consts::TAU - d)
        };
        let printed = (lw * a.y - p.y).atan2(lw * a.x - p.x);
        let corrected = (p.y - lw * a.y).atan2(p.x - lw * a.x);
        prop_assert!(wrapped(corrected - q[0]) < 1e-9, "corrected {corrected} vs θ1 {}", q[0]);
        prop_assert!(wrapped(printed - q[0] - std::f64::consts::PI) < 1e-9);
    }

    #[test]
    fn closed_form_ik_round_trips(q in magnum_q()) {
        let model = common::builtin("magnum");
        let target = end_effector_pose(&model, &q);
        let sols = magnum_ik(&model, &target).unwrap();
        prop_assert!(!sols.is_empty(), "no IK solution for q = {q:?}");
        // The generating posture is among the solutions (mod 2π for the continuous joint).
        let found = sols.iter().any(|s| s.iter().zip(&q).all(|(a, b)| {
            let d = (a - b).rem_euclid(std::f64::consts::TAU);
            d.min(std::f64::consts::TAU - d) < 1e-7
        }));
        prop_assert!(found, "q = {q:?} not in {sols:?}");
        for s in &sols {
            let t = end_effector_pose(&model, s);
            prop_assert!((t.translation.vector - target.translation.vector).norm() < 1e-9);
            prop_assert!(t.rotation.angle_to(&target.rotation) < 1e-9);
            for (v, j) in s.iter().zip(&model.joints) {
                prop_assert!(*v >= j.limits[0] - 1e-12 && *v <= j.limits[1] + 1e-12);
            }
        }
    }
}

#[test]
fn case_study_workspace_is_reachable_within_limits() {
    let model = common::builtin("magnum");
    // Damped least squares is local: near the inner boundary it can stall on a joint limit
    // from one start, so each target gets two (elbow half and well folded).
    let starts = [
        [0.0, 0.5, -1.2, 0.3, 0.0, 0.0],
        [0.0, 1.0, -1.9, 0.3, 0.0, 0.0],
    ];
    let mut worst: f64 = 0.0;
    for ix in 0..=5 {
        for iz in 0..=5 {
            let target = Vector3::new(0.9 + 0.1 * ix as f64, 0.0, 0.1 * iz as f64);
            let solve = |q0: &[f64; 6]| {
                dls_ik(
                    &model,
                    &IkTarget::Position(target),
                    q0,
                    &IkOptions::default(),
                )
            };
            let q = solve(&starts[0])
                .or_else(|_| solve(&starts[1]))
                .unwrap_or_else(|e| {
                    panic!("({:.2}, 0, {:.2}) unreachable: {e}", target.x, target.z)
                });
            let p = end_effector_pose(&model, &q).translation.vector;
            worst = worst.max((p - target).norm());
        }
    }
    assert!(worst < 1e-6, "worst miss {worst}");
}

#[test]
fn dls_ik_reaches_a_full_pose_and_reports_unreachable_targets() {
    let model = common::builtin("magnum");
    let q_true = [0.1, 0.4, -0.9, 0.2, 0.3, 0.5];
    let target = end_effector_pose(&model, &q_true);
    let q = dls_ik(
        &model,
        &IkTarget::Pose(target),
        &[0.0, 0.3, -0.8, 0.0, 0.0, 0.0],
        &IkOptions::default(),
    )
    .unwrap();
    let t = end_effector_pose(&model, &q);
    assert!((t.translation.vector - target.translation.vector).norm() < 1e-6);
    assert!(t.rotation.angle_to(&target.rotation) < 1e-6);
    // 3 m away: beyond the 1.5 m reach (Lim Table 1-1).
    let far = dls_ik(
        &model,
        &IkTarget::Position(Vector3::new(3.0, 0.0, 0.0)),
        &[0.0; 6],
        &IkOptions::default(),
    );
    assert!(
        matches!(far, Err(seaarms_core::Error::NotConverged { .. })),
        "{far:?}"
    );
}
