//! Grasp matrices of Lim eqs 3.40–3.47 checked against each other: W·W⁺ = I (equal sharing),
//! W·V = 0, F_c = W⁺F_ext + V·F_int recomposes any contact wrench pair, W⁺F_ext alone has no
//! internal part, and a pure squeeze is all internal. Plus the grasp-state colour code (§4.1).

use nalgebra::{SVector, Vector3, Vector6};
use seaarms_core::grasp::{
    GraspState, decompose, grasp_matrix, grasp_pinv_equal_share, internal_basis,
};

fn radii() -> [Vector3<f64>; 2] {
    [
        Vector3::new(0.02, 0.15, 0.13),
        Vector3::new(-0.01, -0.15, 0.13),
    ]
}

#[test]
fn w_wplus_is_identity_and_w_v_is_zero() {
    let r = radii();
    let w = grasp_matrix(&r);
    let wp = grasp_pinv_equal_share(&r);
    let v = internal_basis(&r);
    assert!((w * wp - nalgebra::Matrix6::identity()).abs().max() < 1e-14);
    assert!((w * v).abs().max() < 1e-14);
    // V has full column rank 6.
    assert!((v.transpose() * v).determinant().abs() > 1e-6);
}

#[test]
fn decomposition_recomposes_contact_wrenches() {
    let r = radii();
    let fc = SVector::<f64, 12>::from_fn(|i, _| ((i * 7 + 3) % 11) as f64 * 37.0 - 150.0);
    let (fext, fint) = decompose(&r, &fc);
    let back = grasp_pinv_equal_share(&r) * fext + internal_basis(&r) * fint;
    assert!(
        (back - fc).abs().max() < 1e-9,
        "F_c = W⁺F_ext + V F_int (eq. 3.41)"
    );
    assert!((grasp_matrix(&r) * fc - fext).abs().max() < 1e-12);
    // Equal sharing of an external wrench has no internal part.
    let f = Vector6::new(10.0, -20.0, 490.5, 3.0, 4.0, -5.0);
    let (_, zero) = decompose(&r, &(grasp_pinv_equal_share(&r) * f));
    assert!(zero.norm() < 1e-9);
}

#[test]
fn pure_squeeze_is_internal_force() {
    // Arms push towards each other along y with 100 N: no net wrench, |F_int| = 100 N.
    let r = [Vector3::new(0.0, 0.15, 0.0), Vector3::new(0.0, -0.15, 0.0)];
    let mut fc = SVector::<f64, 12>::zeros();
    fc[1] = -100.0;
    fc[7] = 100.0;
    let (fext, fint) = decompose(&r, &fc);
    assert!(fext.norm() < 1e-12);
    assert!((Vector3::new(fint[0], fint[1], fint[2]).norm() - 100.0).abs() < 1e-9);
}

#[test]
fn grasp_state_colour_code() {
    use GraspState::*;
    assert_eq!(
        GraspState::classify([false, false], [true, true], true),
        Free
    );
    assert_eq!(
        GraspState::classify([false, true], [false, true], true),
        OneOnSurface
    );
    assert_eq!(OneOnSurface.colour(), "black");
    assert_eq!(
        GraspState::classify([true, false], [true, false], false),
        OneLifted
    );
    assert_eq!(OneLifted.colour(), "lightblue");
    assert_eq!(
        GraspState::classify([false, true], [true, true], false),
        OneHoldingOtherContact
    );
    assert_eq!(OneHoldingOtherContact.colour(), "red");
    assert_eq!(
        GraspState::classify([true, true], [true, true], false),
        BothHolding
    );
    assert_eq!(BothHolding.colour(), "yellow");
}
