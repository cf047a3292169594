//! Grasp matrices of Lim eqs 3.40–3.47 checked against each other: W·W⁺ = I (equal sharing),
//! W·V = 0, F_c = W⁺F_ext + V·F_int recomposes any contact wrench pair, W⁺F_ext alone has no
//! internal part, and a pure squeeze is all internal. Plus the grasp-state colour code (§4.1).

use nalgebra::{SVector, Vector3, Vector6};
use seaarms_core::grasp::{
    GraspState, decompose, grasp_block, grasp_matrix, grasp_pinv_equal_share, grasp_point_twist,
    internal_basis, internal_wrench, mobility_block, mobility_block_general,
    mobility_block_general_lower, wrench_at_com,
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
    // (holding, contact, on the seabed) → state and its colour (Lim §4.1, Fig. 4-4).
    for (holding, contact, on_surface, state, colour) in [
        ([false, false], [true, true], true, Free, ""),
        ([false, true], [false, true], true, OneOnSurface, "black"),
        ([true, false], [true, false], false, OneLifted, "lightblue"),
        (
            [false, true],
            [true, true],
            false,
            OneHoldingOtherContact,
            "red",
        ),
        ([true, true], [true, true], false, BothHolding, "yellow"),
    ] {
        assert_eq!(
            GraspState::classify(holding, contact, on_surface),
            state,
            "{holding:?} {contact:?} {on_surface}"
        );
        assert_eq!(state.colour(), colour);
    }
}

/// A free 50 kg object's mobility M⁻¹ = diag(I/m, Q) with a symmetric positive definite Q:
/// (Q, M⁻¹).
fn free_object_mobility() -> (nalgebra::Matrix3<f64>, nalgebra::Matrix6<f64>) {
    let q = nalgebra::Matrix3::new(2.0, 0.1, -0.2, 0.1, 3.0, 0.3, -0.2, 0.3, 4.0);
    let mut m_inv = nalgebra::Matrix6::zeros();
    m_inv
        .fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(nalgebra::Matrix3::identity() / 50.0));
    m_inv.fixed_view_mut::<3, 3>(3, 3).copy_from(&q);
    (q, m_inv)
}

/// The step's structured products (eq. 3.40 blocks applied without forming them) equal the
/// explicit matrix products: Wⁱᵀt, WⁱF and Wⁱᵀ·M⁻¹·Wᵏ with M⁻¹ = diag(I/m, Q).
#[test]
fn structured_grasp_products_equal_explicit_matrices() {
    let r = radii();
    let t = Vector6::new(0.1, -0.2, 0.3, 0.4, -0.5, 0.6);
    let f = Vector6::new(10.0, -20.0, 30.0, 4.0, -5.0, 6.0);
    let (q, m_inv) = free_object_mobility();
    for ri in &r {
        let w = grasp_block(ri);
        assert!((grasp_point_twist(ri, &t) - w.transpose() * t).norm() < 1e-14);
        assert!((wrench_at_com(ri, &f) - w * f).norm() < 1e-12);
        for rk in &r {
            let explicit = w.transpose() * m_inv * grasp_block(rk);
            let b = mobility_block(ri, rk, 1.0 / 50.0, &q);
            assert!((b - explicit).abs().max() < 1e-14, "{b} vs {explicit}");
        }
    }
}

/// The step's closed-form internal wrench equals the least-squares F_int = V⁺(I − W⁺W)F_c of
/// `decompose` (eq. 3.41) for arbitrary contact wrench pairs.
#[test]
fn closed_form_internal_wrench_equals_least_squares() {
    let r = radii();
    for k in 0..20 {
        let fc = SVector::<f64, 12>::from_fn(|i, _| 100.0 * ((k * 12 + i) as f64 * 0.7).sin());
        let (_, fint) = decompose(&r, &fc);
        let pair = [
            Vector6::from_fn(|i, _| fc[i]),
            Vector6::from_fn(|i, _| fc[6 + i]),
        ];
        let ours = internal_wrench(&r, &pair);
        assert!(
            (ours - fint).norm() < 1e-10 * (1.0 + fint.norm()),
            "{ours} vs {fint}"
        );
    }
}

/// The general mobility block equals the explicit product Wⁱᵀ·X·Wᵏ for a full symmetric X
/// (an object mass matrix with seabed dashpots, inverted), and reduces to `mobility_block`
/// for X = blockdiag(I/m, Q).
#[test]
fn general_mobility_block_is_the_product() {
    let r = radii();
    let b = nalgebra::Matrix6::from_fn(|i, j| ((i * 7 + j * 3) as f64 * 0.37).sin());
    let x = (b * b.transpose() + nalgebra::Matrix6::identity() * 0.5)
        .try_inverse()
        .expect("SPD");
    let (q, block_diag) = free_object_mobility();
    for ri in &r {
        for rk in &r {
            let explicit = grasp_block(ri).transpose() * x * grasp_block(rk);
            let ours = mobility_block_general(ri, rk, &x);
            assert!(
                (ours - explicit).abs().max() < 1e-13 * x.norm(),
                "{ours} vs {explicit}"
            );
            let special = mobility_block(ri, rk, 1.0 / 50.0, &q);
            let general = mobility_block_general(ri, rk, &block_diag);
            assert!((special - general).abs().max() < 1e-14);
        }
        // The diagonal block's lower triangle, zero above the diagonal.
        let explicit = grasp_block(ri).transpose() * x * grasp_block(ri);
        let lower = mobility_block_general_lower(ri, &x);
        for j in 0..6 {
            for i in 0..6 {
                if i >= j {
                    assert!(
                        (lower[(i, j)] - explicit[(i, j)]).abs() < 1e-13 * x.norm(),
                        "({i}, {j}): {lower} vs {explicit}"
                    );
                } else {
                    assert_eq!(lower[(i, j)], 0.0);
                }
            }
        }
    }
}
