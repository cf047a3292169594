//! The one-sided Jacobi SVD behind `full_svd`, `measures` and `row_measures`, against
//! independent sources: nalgebra's own SVD (Golub–Kahan bidiagonalisation + implicit QR, a
//! different algorithm), closed forms (diagonal matrices; the planar 2R arm, whose σ follow
//! from ‖J‖_F² = σ₁² + σ₂² and |det J| = σ₁σ₂ = l₁l₂|sin q₂|, Lim eq. 2.27), relative
//! perturbation theory (Demmel & Veselić 1992: column-scaled orthogonal matrices) and the
//! defining invariants (UᵀU = I, VᵀV = I, UΣVᵀ = J).

#![allow(clippy::unwrap_used)]

mod common;

use nalgebra::DMatrix;
use proptest::prelude::*;
use seaarms_core::manipulability::measures::complete_basis;
use seaarms_core::manipulability::{
    FullSvd, full_svd, measures, row_measures, row_measures_pair, select_rows, subspaces_from_svd,
};

/// Singular values from nalgebra's SVD, sorted descending.
fn nalgebra_sigma(j: &DMatrix<f64>) -> Vec<f64> {
    let mut s: Vec<f64> = nalgebra::SVD::new(j.clone(), false, false)
        .singular_values
        .iter()
        .copied()
        .collect();
    s.sort_by(|a, b| b.total_cmp(a));
    s
}

/// max |entry| of UᵀU − I, VᵀV − I and of UΣVᵀ − J relative to σ₁ (or to 1 for J = 0).
fn invariant_errors(j: &DMatrix<f64>, svd: &FullSvd) -> (f64, f64, f64) {
    let (m, n) = j.shape();
    let u_err = (svd.u.transpose() * &svd.u - DMatrix::identity(m, m))
        .abs()
        .max();
    let v_err = (svd.v.transpose() * &svd.v - DMatrix::identity(n, n))
        .abs()
        .max();
    let mut s = DMatrix::zeros(m, n);
    for i in 0..m.min(n) {
        s[(i, i)] = svd.sigma[i];
    }
    let scale = if svd.sigma[0] > 0.0 {
        svd.sigma[0]
    } else {
        1.0
    };
    let r_err = (&svd.u * s * svd.v.transpose() - j).abs().max() / scale;
    (u_err, v_err, r_err)
}

/// A random m×n matrix (entries in [−2, 2]), optionally with its columns (or rows) scaled
/// by 10^e, e ∈ [−8, 8], and optionally made rank-deficient by one exact-up-to-rounding
/// dependent column (tall or square) or row (wide).
fn random_matrix(
    vals: &[f64],
    exps: &[i32],
    m: usize,
    n: usize,
    scale_cols: bool,
    scale_rows: bool,
    dependent: bool,
) -> DMatrix<f64> {
    let mut j = DMatrix::from_fn(m, n, |r, c| vals[r * 10 + c]);
    if scale_cols {
        for (c, e) in exps.iter().take(n).enumerate() {
            j.column_mut(c).scale_mut(10f64.powi(*e));
        }
    }
    if scale_rows {
        for (r, e) in exps[10..].iter().take(m).enumerate() {
            j.row_mut(r).scale_mut(10f64.powi(*e));
        }
    }
    if dependent {
        // The last column (tall or square) or row (wide) a combination of the first ones.
        if m >= n && n >= 3 {
            let c = j.column(0) * 0.7 - j.column(1) * 1.3;
            j.set_column(n - 1, &c);
        } else if m >= n && n == 2 {
            let c = j.column(0) * 0.7;
            j.set_column(1, &c);
        } else if m >= 3 {
            let r = j.row(0) * 0.7 - j.row(1) * 1.3;
            j.set_row(m - 1, &r);
        } else if m == 2 {
            let r = j.row(0) * 0.7;
            j.set_row(1, &r);
        }
    }
    j
}

/// A random 6×n Jacobian, n in `cols`, its rows optionally scaled by 10^e
/// ([`random_matrix`]).
fn six_row_matrix(cols: std::ops::RangeInclusive<usize>) -> impl Strategy<Value = DMatrix<f64>> {
    (
        proptest::collection::vec(-2.0f64..2.0, 100),
        proptest::collection::vec(-8i32..=8, 20),
        cols,
        proptest::bool::ANY,
    )
        .prop_map(|(vals, exps, n, scale_rows)| {
            random_matrix(&vals, &exps, 6, n, false, scale_rows, false)
        })
}

/// 1 to `most` distinct rows of a 6-row Jacobian, in order.
fn row_selection(most: usize) -> impl Strategy<Value = Vec<usize>> {
    proptest::sample::subsequence(vec![0usize, 1, 2, 3, 4, 5], 1..=most)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// Random m×n (1..=10 each: the stack path up to 64 entries and the heap path beyond),
    /// badly scaled and rank-deficient ones included: σ equal nalgebra's to 1e-12·σ₁,
    /// U and V orthogonal to 1e-12, UΣVᵀ = J to 1e-12·σ₁, σ sorted, ≥ 0 and zero-padded.
    #[test]
    fn agrees_with_nalgebra_svd_and_is_an_svd(
        vals in proptest::collection::vec(-2.0f64..2.0, 100),
        exps in proptest::collection::vec(-8i32..=8, 20),
        m in 1usize..=10,
        n in 1usize..=10,
        scale_cols in proptest::bool::ANY,
        scale_rows in proptest::bool::ANY,
        dependent in proptest::bool::ANY,
    ) {
        let j = random_matrix(&vals, &exps, m, n, scale_cols, scale_rows, dependent);
        let ours = full_svd(&j).unwrap();
        prop_assert_eq!(ours.sigma.len(), m);
        prop_assert_eq!(ours.u.shape(), (m, m));
        prop_assert_eq!(ours.v.shape(), (n, n));
        let reference = nalgebra_sigma(&j);
        let s1 = reference[0];
        for (i, r) in reference.iter().enumerate() {
            prop_assert!((ours.sigma[i] - r).abs() <= 1e-12 * s1, "σ{i}: {} vs nalgebra {r}\n{j}", ours.sigma[i]);
        }
        for i in m.min(n)..m {
            prop_assert_eq!(ours.sigma[i], 0.0);
        }
        for w in ours.sigma.as_slice().windows(2) {
            prop_assert!(w[0] >= w[1] && w[1] >= 0.0);
        }
        let (u_err, v_err, r_err) = invariant_errors(&j, &ours);
        prop_assert!(u_err <= 1e-12, "UᵀU − I: {u_err:e}");
        prop_assert!(v_err <= 1e-12, "VᵀV − I: {v_err:e}");
        prop_assert!(r_err <= 1e-12, "UΣVᵀ − J: {r_err:e}·σ₁");
        if dependent && m.min(n) >= 2 {
            // One exact dependency: σ_min is round-off, far below the rank tolerance.
            prop_assert!(ours.rank() < m.min(n), "rank {} of {j}", ours.rank());
            // J vᵢ = σᵢuᵢ: the null space and the unreachable directions carry at most the
            // largest σ counted as zero (the scaling can put genuine σ below the tolerance).
            let sub = subspaces_from_svd(&ours);
            let bound = ours.sigma[ours.rank()] + 1e-12 * s1;
            prop_assert!((&j * &sub.null_space).abs().max() <= bound);
            prop_assert!((sub.unreachable.transpose() * &j).abs().max() <= bound);
        }
    }

    /// `measures` (rows rotated, U accumulated) against nalgebra's σ, and `row_measures`
    /// identical to `measures` of the selected rows.
    #[test]
    fn measures_agree_with_nalgebra_and_row_selection(
        j in six_row_matrix(1..=10),
        rows in row_selection(6),
    ) {
        let sel = select_rows(&j, &rows).unwrap();
        let m = measures(&sel).unwrap();
        prop_assert_eq!(&row_measures(&j, &rows).unwrap(), &m);
        let reference = nalgebra_sigma(&sel);
        let tol = 1.5e-7 * reference[0];
        for (i, s) in m.singular_values.iter().enumerate() {
            let r = reference.get(i).copied().unwrap_or(0.0);
            // Below the rank tolerance σ is reported as 0.
            let r = if r <= tol { 0.0 } else { r };
            prop_assert!((s - r).abs() <= 1e-12 * reference[0], "σ{i}: {s} vs nalgebra {r}");
        }
        // Axes orthonormal, and each an eigenvector of JJᵀ: JJᵀuᵢ = σᵢ²uᵢ.
        let u = m.axes.view();
        let k = sel.nrows();
        prop_assert!((u.transpose() * u - DMatrix::identity(k, k)).abs().max() <= 1e-12);
        let jjt = &sel * sel.transpose();
        for (s, ui) in m.singular_values.iter().zip(u.column_iter()) {
            let ui = ui.into_owned();
            prop_assert!((&jjt * &ui - &ui * (s * s)).norm() <= 1e-10 * reference[0] * reference[0]);
        }
    }

    /// `row_measures_pair` (two selections swept in lockstep) gives exactly the two
    /// `row_measures`, also when one selection converges sweeps before the other, and when
    /// the selections differ in size or exceed the columns (the separate fallback).
    #[test]
    fn row_measures_pair_equals_two_row_measures(
        j in six_row_matrix(1..=8),
        a in row_selection(4),
        b in row_selection(4),
    ) {
        let [ma, mb] = row_measures_pair(&j, [&a, &b]).unwrap();
        prop_assert_eq!(ma, row_measures(&j, &a).unwrap());
        prop_assert_eq!(mb, row_measures(&j, &b).unwrap());
    }

    /// Relative accuracy (Demmel & Veselić 1992, Thm 4.2 and §4): for J = QD, Q orthogonal
    /// to working precision and D diagonal, JᵀJ = D(QᵀQ)D and every σᵢ(J) = |dᵢ|(1 + O(ε)),
    /// however small — σ down to 2⁻⁶⁰σ₁ ≈ 10⁻¹⁸σ₁ to 1e-13 relative. (The eigenvalues of JᵀJ
    /// could not resolve anything below about 10⁻⁸σ₁.) The same for DQᵀ (the rows path).
    #[test]
    fn relative_accuracy_for_scaled_orthogonal_matrices(
        vals in proptest::collection::vec(-1.0f64..1.0, 36),
        exps in proptest::collection::vec(0i32..=60, 6),
        n in 2usize..=6,
    ) {
        let q = DMatrix::from_fn(6, 6, |r, c| vals[r * 6 + c]).qr().q();
        let q = q.columns(0, n).into_owned();
        // Powers of two: D is applied exactly.
        let d: Vec<f64> = exps.iter().take(n).map(|&e| 2f64.powi(-e)).collect();
        let mut j = q.clone();
        for (c, di) in d.iter().enumerate() {
            j.column_mut(c).scale_mut(*di);
        }
        let mut expected = d.clone();
        expected.sort_by(|a, b| b.total_cmp(a));
        for (name, mat) in [("QD", j.clone()), ("DQᵀ", j.transpose())] {
            let svd = full_svd(&mat).unwrap();
            for (i, e) in expected.iter().enumerate() {
                prop_assert!((svd.sigma[i] - e).abs() <= 1e-13 * e, "{name} σ{i}: {} vs {e}", svd.sigma[i]);
            }
        }
    }

    /// Planar 2R, J = [[−l₁s₁ − l₂s₁₂, −l₂s₁₂], [l₁c₁ + l₂c₁₂, l₂c₁₂]] (Lim eq. 2.26) with
    /// l₁ = 1, l₂ = 0.8: D = σ₁σ₂ = |det J| = l₁l₂|sin q₂| and F = σ₁² + σ₂² = ‖J‖_F² =
    /// l₁² + 2l₂² + 2l₁l₂cos q₂, so σ₁ = ½(√(F + 2D) + √(F − 2D)) and σ₂ = D/σ₁. Accurate
    /// to a few ε·σ₁ — the rounding of J's own entries — even next to the stretched-out
    /// singularity (|q₂| down to 10⁻¹², where the eigenvalue route erred by ~10⁻⁸σ₁).
    #[test]
    fn planar_2r_closed_form(q1 in -3.0f64..3.0, log_q2 in -12.0f64..0.5, sign in proptest::bool::ANY) {
        let q2 = if sign { 10f64.powf(log_q2) } else { -(10f64.powf(log_q2)) };
        let (l1, l2) = (1.0, 0.8);
        let (s1, c1, s12, c12) = (q1.sin(), q1.cos(), (q1 + q2).sin(), (q1 + q2).cos());
        let j = DMatrix::from_row_slice(2, 2, &[-l1 * s1 - l2 * s12, -l2 * s12, l1 * c1 + l2 * c12, l2 * c12]);
        let f = l1 * l1 + l2 * l2 + l2 * l2 + 2.0 * l1 * l2 * q2.cos();
        let det = l1 * l2 * q2.sin().abs();
        let s1_ref = 0.5 * ((f + 2.0 * det).sqrt() + (f - 2.0 * det).max(0.0).sqrt());
        let s2_ref = det / s1_ref;
        let svd = full_svd(&j).unwrap();
        prop_assert!((svd.sigma[0] - s1_ref).abs() <= 1e-14 * s1_ref, "σ₁ {} vs {s1_ref}", svd.sigma[0]);
        prop_assert!((svd.sigma[1] - s2_ref).abs() <= 2e-15 * s1_ref, "σ₂ {} vs {s2_ref}", svd.sigma[1]);
        let m = measures(&j).unwrap();
        // measures: the same σ₂, or 0 below the rank tolerance.
        let s2_reported = if s2_ref > 1.5e-7 * s1_ref { s2_ref } else { 0.0 };
        prop_assert!((m.singular_values[1] - s2_reported).abs() <= 2e-15 * s1_ref, "{:?}", m.singular_values);
    }
}

/// Diagonal matrices (any signs, zeros, m ≠ n): σ = the sorted |dᵢ| exactly (no rotation is
/// needed and the power-of-two scaling is exact), U and V signed permutations.
#[test]
fn diagonal_matrices_give_their_absolute_entries() {
    let d = [3.0, -0.5, 0.0, 7.25, -1e-30, 2.0];
    for (m, n) in [(6, 6), (6, 4), (4, 6), (1, 1), (1, 3), (3, 1)] {
        let mut j = DMatrix::zeros(m, n);
        for i in 0..m.min(n) {
            j[(i, i)] = d[i];
        }
        let svd = full_svd(&j).unwrap();
        let mut expected: Vec<f64> = d.iter().take(m.min(n)).map(|x| x.abs()).collect();
        expected.sort_by(|a, b| b.total_cmp(a));
        expected.resize(m, 0.0);
        assert_eq!(svd.sigma.as_slice(), &expected[..], "{m}×{n}");
        for mat in [&svd.u, &svd.v] {
            for x in mat.iter() {
                assert!(
                    *x == 0.0 || x.abs() == 1.0,
                    "{m}×{n}: not a signed permutation\n{mat}"
                );
            }
        }
        let (u_err, v_err, r_err) = invariant_errors(&j, &svd);
        assert!(u_err == 0.0 && v_err == 0.0 && r_err == 0.0, "{m}×{n}");
    }
}

/// The zero matrix: σ = 0, rank 0, U and V orthogonal (completed from unit vectors), every
/// measure zero or infinite.
#[test]
fn zero_matrix() {
    let j = DMatrix::zeros(6, 7);
    let svd = full_svd(&j).unwrap();
    assert!(svd.sigma.iter().all(|s| *s == 0.0));
    assert_eq!(svd.rank(), 0);
    let (u_err, v_err, _) = invariant_errors(&j, &svd);
    assert!(u_err <= 1e-15 && v_err <= 1e-15);
    let m = measures(&j).unwrap();
    assert_eq!(m.rank, 0);
    assert_eq!(m.yoshikawa, 0.0);
    assert_eq!(m.condition_number, None);
}

/// Planar 2R exactly stretched out (q₂ = 0) and folded (q₂ = π): rank 1 by both routes, and
/// the null space is the joint motion that keeps the tip still (Lim §2.4.2).
#[test]
fn planar_2r_singular_postures_are_rank_one() {
    for (q1, q2) in [(0.3, 0.0), (-1.2, 0.0), (0.7, std::f64::consts::PI)] {
        let (l1, l2) = (1.0, 0.8);
        let (s1, c1, s12, c12) = (
            f64::sin(q1),
            f64::cos(q1),
            f64::sin(q1 + q2),
            f64::cos(q1 + q2),
        );
        let j = DMatrix::from_row_slice(
            2,
            2,
            &[-l1 * s1 - l2 * s12, -l2 * s12, l1 * c1 + l2 * c12, l2 * c12],
        );
        let svd = full_svd(&j).unwrap();
        assert_eq!(svd.rank(), 1, "q = ({q1}, {q2}): σ = {}", svd.sigma);
        assert!(svd.sigma[1] <= 1e-15 * svd.sigma[0]);
        // With σ₂ = 0, σ₁² = ‖J‖_F².
        assert!((svd.sigma[0] - j.norm()).abs() <= 1e-15 * j.norm());
        let sub = subspaces_from_svd(&svd);
        assert!((&j * &sub.null_space).norm() <= 1e-15);
        let m = measures(&j).unwrap();
        assert_eq!(m.rank, 1);
        assert_eq!(m.singular_values[1], 0.0);
        assert_eq!(m.isotropy, 0.0);
    }
}

/// `complete_basis` keeps the given orthonormal columns and completes them to an orthogonal
/// matrix, for every number of given columns including none.
#[test]
fn complete_basis_extends_to_an_orthogonal_matrix() {
    let seed = DMatrix::from_fn(7, 7, |r, c| ((r * 7 + c) as f64 * 0.77).sin());
    let q = seed.qr().q();
    for r in 0..=7 {
        let b = q.columns(0, r).into_owned();
        let full = complete_basis(&b);
        assert_eq!(full.shape(), (7, 7));
        assert_eq!(full.columns(0, r), b.columns(0, r));
        let err = (full.transpose() * &full - DMatrix::identity(7, 7))
            .abs()
            .max();
        assert!(err <= 1e-14, "r = {r}: {err:e}");
    }
}

/// The analysis's translational and rotational measures (computed as a lockstep pair) equal
/// `row_measures` of rows 0–2 and 3–5 of its Jacobian, for every built-in 6-DOF arm at a few
/// postures, and its full measures those of `full_svd`.
#[test]
fn analysis_measures_equal_the_separate_routes() {
    use seaarms_core::analysis::analyze;
    use seaarms_core::manipulability::measures_from_svd;
    for name in ["magnum", "rx90", "orion", "puma560"] {
        let model = common::builtin(name);
        for t in [0.2, 0.5, 0.8] {
            let q: Vec<f64> = model
                .joints
                .iter()
                .enumerate()
                .map(|(i, j)| {
                    let (lo, hi) = (j.limits[0].max(-3.0), j.limits[1].min(3.0));
                    lo + (hi - lo) * (t + 0.07 * i as f64).fract()
                })
                .collect();
            let a = analyze(&model, &q, Some(&[0, 1, 5])).unwrap();
            let j = &a.jacobian;
            assert_eq!(
                a.translational,
                row_measures(j, &[0, 1, 2]).unwrap(),
                "{name}"
            );
            assert_eq!(a.rotational, row_measures(j, &[3, 4, 5]).unwrap(), "{name}");
            assert_eq!(
                a.task.unwrap(),
                measures(&select_rows(j, &[0, 1, 5]).unwrap()).unwrap()
            );
            assert_eq!(
                a.full,
                measures_from_svd(&full_svd(j).unwrap()).unwrap(),
                "{name}"
            );
        }
    }
}
