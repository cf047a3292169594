//! Closed forms and invariants of the manipulability measures: planar 2R (Lim §2.4.2),
//! Πσ = √det(JJᵀ), sorted non-negative σ, ellipsoid volume coefficient (eq. 2.18), force
//! measures reciprocal, and the dual-arm ellipsoid of two identical arms (eq. 3.68).

#![allow(clippy::unwrap_used)]

mod common;

use nalgebra::{DMatrix, Rotation3, Vector3};
use proptest::prelude::*;
use seaarms_core::kinematics::jacobian_at;
use seaarms_core::manipulability::measures::ellipsoid_volume_coefficient;
use seaarms_core::manipulability::{
    dual_measures, full_svd, jlm, jlm_gradient, measures, select_rows, subspaces_from_svd,
};

proptest! {
    /// Lim eq. 2.27: w = l1·l2·|sin q2|; §2.4.2: λ₁,₂ = [3 + 2C2 ± √(5 + 12C2 + 8C2²)]/2 for l1 = l2 = 1.
    #[test]
    fn planar_2r_closed_forms(q1 in -3.0f64..3.0, q2 in -3.0f64..3.0) {
        let model = common::builtin("planar2r");
        let j = select_rows(&jacobian_at(&model, &[q1, q2]), &[0, 1]).unwrap();
        // Eq. 2.26 directly.
        let (s1, c1, s12, c12) = (q1.sin(), q1.cos(), (q1 + q2).sin(), (q1 + q2).cos());
        let j_eq = DMatrix::from_row_slice(2, 2, &[-s1 - s12, -s12, c1 + c12, c12]);
        prop_assert!((&j - &j_eq).abs().max() < 1e-12);
        let m = measures(&j).unwrap();
        // Near q2 = 0, σ₂ and w = σ₁σ₂ are accurate to a few ε·σ₁ (the rounding of J itself:
        // `measures` rotates J's rows instead of squaring them). Within the rank tolerance,
        // |q2| ≲ 1e-7 (chance ~1e-7 per case), σ₂ is reported as 0 and w would miss by ≤ 1e-7.
        prop_assert!((m.yoshikawa - q2.sin().abs()).abs() < 1e-10);
        let c2 = q2.cos();
        let root = (5.0 + 12.0 * c2 + 8.0 * c2 * c2).sqrt();
        let l1 = (3.0 + 2.0 * c2 + root) / 2.0;
        let l2 = ((3.0 + 2.0 * c2 - root) / 2.0).max(0.0);
        prop_assert!((m.singular_values[0] - l1.sqrt()).abs() < 1e-9);
        prop_assert!((m.singular_values[1] - l2.sqrt()).abs() < 1e-6);
    }

    #[test]
    fn singular_values_sorted_nonnegative_and_product_is_sqrt_det(
        vals in proptest::collection::vec(-2.0f64..2.0, 3 * 7),
        rows in 1usize..=3,
        cols in 3usize..=7,
    ) {
        let j = DMatrix::from_fn(rows, cols, |r, c| vals[r * 7 + c]);
        let m = measures(&j).unwrap();
        prop_assert_eq!(m.singular_values.len(), rows);
        for w in m.singular_values.windows(2) {
            prop_assert!(w[0] >= w[1]);
        }
        prop_assert!(m.singular_values.iter().all(|s| *s >= 0.0));
        let det = (&j * j.transpose()).determinant().max(0.0).sqrt();
        prop_assert!((m.yoshikawa - det).abs() < 1e-9 * (1.0 + det));
        prop_assert!((m.hong - m.yoshikawa * m.isotropy).abs() < 1e-12);
        prop_assert!(m.isotropy >= 0.0 && m.isotropy <= 1.0);
        if let (Some(c), Some(f)) = (m.condition_number, m.force_manipulability) {
            prop_assert!((c * m.isotropy - 1.0).abs() < 1e-9);
            prop_assert!((f * m.yoshikawa - 1.0).abs() < 1e-9);
        }
        // Each axis uᵢ satisfies JJᵀuᵢ = σᵢ²uᵢ.
        let jjt = &j * j.transpose();
        for (s, u) in m.singular_values.iter().zip(m.axes.view().column_iter()) {
            let u = u.into_owned();
            prop_assert!((&jjt * &u - &u * (s * s)).norm() < 1e-9);
        }
    }

    /// The two routes to σ — `measures` (J's rows rotated, U accumulated) and `full_svd`
    /// (J's columns rotated when it is tall or square, V accumulated) — agree, and both
    /// satisfy Σσᵢ² = ‖J‖_F² (trace identity).
    #[test]
    fn row_and_column_routes_agree_and_keep_the_frobenius_norm(vals in proptest::collection::vec(-2.0f64..2.0, 6 * 9), rows in 1usize..=6, extra in 0usize..=3) {
        let cols = rows + extra;
        let j = DMatrix::from_fn(rows, cols, |r, c| vals[r * 9 + c]);
        let by_measures = measures(&j).unwrap();
        let by_svd = full_svd(&j).unwrap();
        let fro2 = j.norm_squared();
        for (a, b) in by_measures.singular_values.iter().zip(by_svd.sigma.iter()) {
            prop_assert!((a - b).abs() < 1e-7 * (1.0 + by_svd.sigma[0]), "{:?} vs {}", by_measures.singular_values, by_svd.sigma);
        }
        let s2: f64 = by_measures.singular_values.iter().map(|s| s * s).sum();
        prop_assert!((s2 - fro2).abs() < 1e-9 * (1.0 + fro2));
    }

    /// The analysis's full decomposition is an SVD: U and V orthogonal, σ sorted and ≥ 0,
    /// J = UΣVᵀ (which with orthogonal U, V fixes σ uniquely), Σσᵢ² = ‖J‖_F², and a
    /// rank-deficient J has its null space found (J·N = 0).
    #[test]
    fn full_decomposition_is_an_svd(vals in proptest::collection::vec(-2.0f64..2.0, 6 * 8), cols in 2usize..=8, drop_rank in proptest::bool::ANY) {
        let mut j = DMatrix::from_fn(6, cols, |r, c| vals[r * 8 + c]);
        if drop_rank && cols >= 3 {
            // Make the last column a combination of the first two.
            let last = j.column(0) * 0.7 - j.column(1) * 1.3;
            j.set_column(cols - 1, &last);
        }
        let ours = full_svd(&j).unwrap();
        for w in ours.sigma.as_slice().windows(2) {
            prop_assert!(w[0] >= w[1] && w[1] >= 0.0);
        }
        let s2: f64 = ours.sigma.iter().map(|s| s * s).sum();
        prop_assert!((s2 - j.norm_squared()).abs() < 1e-9 * (1.0 + j.norm_squared()));
        let (m, n) = (6, cols);
        prop_assert!((ours.u.transpose() * &ours.u - DMatrix::identity(m, m)).abs().max() < 1e-9);
        prop_assert!((ours.v.transpose() * &ours.v - DMatrix::identity(n, n)).abs().max() < 1e-9);
        let mut s = DMatrix::zeros(m, n);
        for i in 0..m.min(n) {
            s[(i, i)] = ours.sigma[i];
        }
        prop_assert!((&ours.u * s * ours.v.transpose() - &j).abs().max() < 1e-7);
        let sub = subspaces_from_svd(&ours);
        prop_assert!((&j * &sub.null_space).abs().max() < 1e-6 || sub.null_space.ncols() == 0);
        if drop_rank && (3..=6).contains(&cols) {
            prop_assert!(sub.null_space.ncols() >= 1, "a dependent column leaves a null space");
        }
    }

    /// Two identical arms (same J in the common frame): M = JJᵀ/2, so every radius shrinks by
    /// √2: the dual ellipsoid's volume is 2^(−3/2) of one arm's and its isotropy is equal.
    #[test]
    fn identical_arms_dual_ellipsoid(qs in proptest::collection::vec(-1.0f64..1.0, 6), yaw in -3.0f64..3.0) {
        let model = common::builtin("magnum");
        let q: Vec<f64> = model.joints.iter().zip(&qs).map(|(j, t)| {
            if j.is_limited() { (j.limits[0] + j.limits[1]) / 2.0 + t * (j.limits[1] - j.limits[0]) * 0.45 } else { *t }
        }).collect();
        let jt = select_rows(&jacobian_at(&model, &q), &[0, 1, 2]).unwrap();
        // The same arm mounted elsewhere, rotated about z: its world Jacobian is R·Jt.
        let r = Rotation3::from_axis_angle(&Vector3::z_axis(), yaw);
        let rm = DMatrix::from_column_slice(3, 3, r.matrix().as_slice());
        let single = measures(&(&rm * &jt)).unwrap();
        let dual = dual_measures(&(&rm * &jt), &(&rm * &jt)).unwrap();
        let ratio = dual.ellipsoid().volume.unwrap() / single.ellipsoid().volume.unwrap();
        prop_assert!((ratio - 2f64.powf(-1.5)).abs() < 1e-9, "ratio {ratio}");
        prop_assert!((dual.isotropy - single.isotropy).abs() < 1e-9);
    }

    /// ∂JLM/∂q against central differences (Jun eq. 16).
    #[test]
    fn jlm_gradient_matches_finite_differences(qs in proptest::collection::vec(0.05f64..0.95, 6)) {
        let model = common::builtin("orion");
        let q: Vec<f64> = model.joints.iter().zip(&qs).map(|(j, t)| j.limits[0] + t * (j.limits[1] - j.limits[0])).collect();
        let mut g = vec![0.0; 6];
        jlm_gradient(&model, &q, &mut g);
        for i in 0..6 {
            let h = 1e-6;
            let mut qp = q.clone(); qp[i] += h;
            let mut qm = q.clone(); qm[i] -= h;
            let fd = (jlm(&model, &qp) - jlm(&model, &qm)) / (2.0 * h);
            prop_assert!((fd - g[i]).abs() < 1e-6, "joint {i}: {fd} vs {}", g[i]);
        }
    }
}

#[test]
fn ellipsoid_volume_coefficient_is_the_unit_ball_volume() {
    // Lim eq. 2.18 against π^{m/2}/Γ(m/2 + 1): 2, π, 4π/3, π²/2, 8π²/15, π³/6.
    use std::f64::consts::PI;
    let expected = [
        2.0,
        PI,
        4.0 * PI / 3.0,
        PI * PI / 2.0,
        8.0 * PI * PI / 15.0,
        PI.powi(3) / 6.0,
    ];
    for (m, e) in (1..=6).zip(expected) {
        assert!(
            (ellipsoid_volume_coefficient(m) - e).abs() < 1e-12,
            "m = {m}"
        );
    }
}

#[test]
fn singular_jacobian_reports_infinite_values_as_none() {
    // Planar 2R stretched out (q2 = 0) is singular (Lim eq. 2.27: w = 0).
    let model = common::builtin("planar2r");
    let j = select_rows(&jacobian_at(&model, &[0.3, 0.0]), &[0, 1]).unwrap();
    let m = measures(&j).unwrap();
    assert_eq!(m.rank, 1);
    assert!(m.yoshikawa.abs() < 1e-15);
    assert_eq!(m.condition_number, None);
    assert_eq!(m.force_manipulability, None);
    assert_eq!(m.force_ellipsoid().radii[1], None);
    assert_eq!(m.isotropy, 0.0);
}

/// Every joint at the fraction `t` of its range: (1 − t)·lower + t·upper.
fn posture_at_fraction(model: &seaarms_core::Model, t: f64) -> Vec<f64> {
    model
        .joints
        .iter()
        .map(|j| (1.0 - t) * j.limits[0] + t * j.limits[1])
        .collect()
}

#[test]
fn jlm_is_one_at_mid_range_and_zero_at_a_limit() {
    let model = common::builtin("orion");
    let mid = posture_at_fraction(&model, 0.5);
    assert!((jlm(&model, &mid) - 1.0).abs() < 1e-12);
    let mut at = mid.clone();
    at[2] = model.joints[2].limits[1];
    assert_eq!(jlm(&model, &at), 0.0);
}

/// With joint 2 at its upper limit the JLM is 0 and so is its whole gradient: every other
/// joint's ∂p/∂qᵢ carries the zero factor of joint 2 (Jun eq. 16), and joint 2's own is that
/// of a factor clamped at 0. A step inside the limit makes them finite again, against
/// central differences.
#[test]
fn jlm_gradient_at_a_limit_is_zero() {
    let model = common::builtin("orion");
    let mut at = posture_at_fraction(&model, 0.7);
    at[2] = model.joints[2].limits[1];
    let mut g = vec![1.0; 6];
    jlm_gradient(&model, &at, &mut g);
    assert!(g.iter().all(|x| *x == 0.0), "{g:?}");
    at[2] -= 1e-3;
    jlm_gradient(&model, &at, &mut g);
    assert!(g.iter().all(|x| *x != 0.0), "{g:?}");
    for i in 0..6 {
        let h = 1e-7;
        let mut qp = at.clone();
        qp[i] += h;
        let mut qm = at.clone();
        qm[i] -= h;
        let fd = (jlm(&model, &qp) - jlm(&model, &qm)) / (2.0 * h);
        assert!((fd - g[i]).abs() < 1e-6, "joint {i}: {fd} vs {}", g[i]);
    }
}
