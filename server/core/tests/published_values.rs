//! Jacobians and measures against numbers printed in the source documents.

#![allow(clippy::unwrap_used)]
#![allow(clippy::approx_constant)] // 0.7071 is the value printed in the RX90 report

mod common;

use nalgebra::{DMatrix, DVector};
use seaarms_core::kinematics::jacobian_at;
use seaarms_core::manipulability::{jlm, measures, select_rows, subspaces};

/// RX90 lab report, part III: printed J at q = [0.6 1.25 -0.3 0.6 0.3 2.0] (4 decimals).
#[test]
fn rx90_jacobian_matches_the_printed_matrix() {
    let model = common::builtin("rx90");
    let q = [0.6, 1.25, -0.3, 0.6, 0.3, 2.0];
    let j = jacobian_at(&model, &q);
    #[rustfmt::skip]
    let printed = DMatrix::from_row_slice(6, 6, &[
        0.1266, -0.5685, -0.2160, 0.0, 0.0, 0.0,
        -0.1850, -0.3889, -0.1478, 0.0, 0.0, 0.0,
        0.0, -0.2241, -0.3660, 0.0, 0.0, 0.0,
        0.0, 0.5646, 0.5646, -0.6713, 0.7371, -0.6642,
        0.0, -0.8253, -0.8253, -0.4593, -0.4957, -0.6566,
        1.0, 0.0, 0.0, 0.5817, 0.4593, 0.3573,
    ]);
    let err = (&j - &printed).abs().max();
    assert!(err <= 5e-5, "max |J - printed| = {err:e}\n{j}");
    // Part III a: dX = J dq, printed as [0.0076 -0.0165 0.0046 -0.0506 -0.0010 0.0804].
    let dq = DVector::from_row_slice(&[0.08, 0.012, -0.02, 0.006, -0.03, 0.03]);
    let dx = &j * dq;
    let printed_dx = [0.0076, -0.0165, 0.0046, -0.0506, -0.0010, 0.0804];
    for (a, b) in dx.iter().zip(printed_dx) {
        assert!((a - b).abs() <= 5e-5, "dX = {dx}");
    }
}

/// RX90 lab report, part VI: singular values at q = [0.2 -0.3 -pi/2 0.6 0 0.7] are
/// 1.8760 1.5290 1.2439 0.5693 0.1521 0, with a one-dimensional null space
/// (printed basis [0 0 0 -0.7071 0 0.7071]: joints 4 and 6 counter-rotating).
#[test]
fn rx90_singular_values_and_null_space() {
    let model = common::builtin("rx90");
    let q = [0.2, -0.3, -std::f64::consts::FRAC_PI_2, 0.6, 0.0, 0.7];
    let j = jacobian_at(&model, &q);
    let m = measures(&j).unwrap();
    let printed = [1.8760, 1.5290, 1.2439, 0.5693, 0.1521, 0.0];
    for (s, p) in m.singular_values.iter().zip(printed) {
        assert!((s - p).abs() <= 5e-5, "sigma = {:?}", m.singular_values);
    }
    assert_eq!(m.rank, 5);
    assert_eq!(m.condition_number, None);
    let sub = subspaces(&j).unwrap();
    assert_eq!(sub.null_space.ncols(), 1);
    let n: Vec<f64> = sub.null_space.column(0).iter().copied().collect();
    let sign = n[5].signum();
    let expected = [0.0, 0.0, 0.0, -0.7071, 0.0, 0.7071];
    for (a, b) in n.iter().zip(expected) {
        assert!((a * sign - b).abs() <= 5e-5, "null space = {n:?}");
    }
    // J times the null vector vanishes.
    let v = DVector::from_row_slice(&n);
    assert!((&j * v).norm() < 1e-12);
    assert_eq!(sub.unreachable.ncols(), 1);
    assert_eq!(sub.range.ncols(), 5);
}

/// Jun 2008 §2.2 and seeds README: ORION at [-15.3, 49.6, -31.0, 75.5, 85.2, -18.0] deg gives
/// translational TOMM = 0.41 and JLM = 0.09.
#[test]
fn orion_example_posture_tmm_and_jlm() {
    let model = common::builtin("orion");
    let q: Vec<f64> = [-15.3f64, 49.6, -31.0, 75.5, 85.2, -18.0]
        .iter()
        .map(|d| d.to_radians())
        .collect();
    let j = jacobian_at(&model, &q);
    let jt = select_rows(&j, &[0, 1, 2]).unwrap();
    let tmm = measures(&jt).unwrap().yoshikawa;
    assert!((tmm - 0.41).abs() < 0.005, "TMM = {tmm}");
    let p = jlm(&model, &q);
    assert!((p - 0.09).abs() < 0.005, "JLM = {p}");
}
