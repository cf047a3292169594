//! Dual-arm manipulability ellipsoid (Lim §3.5.2, eq. 3.68).
//!
//! With both end-effectors rigidly holding the object, ẋ₁ = ẋ₂ = ẋ (eq. 3.65) and the unit
//! joint-velocity sphere maps to ẋᵀ[(J₁J₁ᵀ)⁻¹ + (J₂J₂ᵀ)⁻¹]ẋ ≤ 1. Its shape matrix is the
//! parallel sum M = (M₁⁻¹ + M₂⁻¹)⁻¹ = M₁(M₁ + M₂)⁻¹M₂ of Mᵢ = JᵢJᵢᵀ, which stays finite when
//! one arm is singular (that arm's lost direction then has radius 0). The radii are √eig(M).

use nalgebra::{DMatrix, Matrix3, SymmetricEigen};

use super::measures::{Measures, TaskMatrix, check_task_dim, default_tolerance};
use crate::Error;

/// Shape matrix M (m×m) of the dual-arm ellipsoid ẋᵀM⁻¹ẋ ≤ 1. Both Jacobians must be
/// expressed in the same frame and have the same number of rows.
pub fn dual_shape_matrix(j1: &DMatrix<f64>, j2: &DMatrix<f64>) -> Result<DMatrix<f64>, Error> {
    if j1.nrows() != j2.nrows() {
        return Err(Error::SizeMismatch {
            what: "second arm's jacobian rows",
            input: j2.nrows(),
            required: j1.nrows(),
        });
    }
    let m1 = j1 * j1.transpose();
    let m2 = j2 * j2.transpose();
    let sum = &m1 + &m2;
    let m = match sum.clone().cholesky() {
        Some(ch) => &m1 * ch.solve(&m2),
        // Both arms lose the same direction: pseudo-inverse of the (symmetric PSD) sum from
        // its eigen decomposition, eigenvalues below 1e-12·λ_max dropped.
        None => {
            let eig = SymmetricEigen::new(sum);
            let lmax = eig.eigenvalues.iter().fold(0.0f64, |a, &b| a.max(b));
            let inv = eig
                .eigenvalues
                .map(|l| if l > 1e-12 * lmax { 1.0 / l } else { 0.0 });
            let pinv =
                &eig.eigenvectors * DMatrix::from_diagonal(&inv) * eig.eigenvectors.transpose();
            &m1 * pinv * &m2
        }
    };
    Ok((&m + m.transpose()) * 0.5)
}

/// Measures of the dual-arm ellipsoid: σᵢ = √λᵢ(M), axes = eigenvectors of M.
pub fn dual_measures(j1: &DMatrix<f64>, j2: &DMatrix<f64>) -> Result<Measures, Error> {
    check_task_dim(j1.nrows())?;
    if j1.nrows() == 3
        && j2.nrows() == 3
        && let Some(m) = dual_measures_3(j1, j2)
    {
        return Ok(m);
    }
    dual_measures_general(j1, j2)
}

/// [`dual_measures`] of two 3-row Jacobians (the translational rows, as the scenario runner
/// calls it every 10 ms) on the stack: Mᵢ = JᵢJᵢᵀ as `Matrix3`, M = M₁(M₁ + M₂)⁻¹M₂ (Lim
/// eq. 3.68) by a static Cholesky solve and σ = √eig M by nalgebra's static symmetric eigen
/// solver — the same algorithms as the general path at a fixed size, without heap
/// allocation. `None` when M₁ + M₂ is singular (both arms lose the same direction): the
/// general path's pseudo-inverse then applies.
fn dual_measures_3(j1: &DMatrix<f64>, j2: &DMatrix<f64>) -> Option<Measures> {
    let gram = |j: &DMatrix<f64>| {
        let mut m = Matrix3::zeros();
        for c in 0..3 {
            for r in 0..3 {
                m[(r, c)] = j.row(r).dot(&j.row(c));
            }
        }
        m
    };
    let (m1, m2) = (gram(j1), gram(j2));
    let m = m1 * (m1 + m2).cholesky()?.solve(&m2);
    let eig = SymmetricEigen::new((m + m.transpose()) * 0.5);
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let sigma = idx.map(|i| eig.eigenvalues[i].max(0.0).sqrt());
    let mut u = [0.0; 9];
    for (dst, &src) in u.chunks_exact_mut(3).zip(&idx) {
        dst.copy_from_slice(eig.eigenvectors.column(src).as_slice());
    }
    // As the general path: σ carries √ε·σ_max of error.
    let tol = default_tolerance(3, 3, sigma[0]).max(1e-7 * sigma[0]);
    Some(Measures::from_parts(
        &sigma,
        TaskMatrix::from_column_slice(3, &u),
        tol,
    ))
}

/// [`dual_measures`] for any number of rows (heap matrices; the pseudo-inverse fallback of
/// [`dual_shape_matrix`] when M₁ + M₂ is singular).
pub(crate) fn dual_measures_general(
    j1: &DMatrix<f64>,
    j2: &DMatrix<f64>,
) -> Result<Measures, Error> {
    check_task_dim(j1.nrows())?;
    let m = dual_shape_matrix(j1, j2)?;
    let k = m.nrows();
    let eig = SymmetricEigen::new(m);
    let mut idx: Vec<usize> = (0..k).collect();
    idx.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let sigma: Vec<f64> = idx
        .iter()
        .map(|&i| eig.eigenvalues[i].max(0.0).sqrt())
        .collect();
    let mut u = DMatrix::zeros(k, k);
    for (dst, &src) in idx.iter().enumerate() {
        u.set_column(dst, &eig.eigenvectors.column(src));
    }
    // eigenvalues of M carry ε·λ_max of error, so σ carries √ε·σ_max.
    let tol = default_tolerance(k, k, sigma[0]).max(1e-7 * sigma[0]);
    Ok(Measures::from_spectrum(&sigma, &u, tol))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    /// The 3-row fast path equals the general heap path to round-off on random Jacobians
    /// (3×n, n = 1…7, entries scaled over several decades), including rank-deficient arms
    /// (n < 3) and the singular fallback (both arms missing the same direction).
    #[test]
    fn three_row_fast_path_matches_general_path() {
        // A small deterministic generator (xorshift), so that the test needs no dependency.
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for case in 0..600 {
            let n = 1 + case % 7;
            let scale = 10f64.powi((case % 5) as i32 - 2);
            let j1 = DMatrix::from_fn(3, n, |_, _| scale * next());
            let mut j2 = DMatrix::from_fn(3, 6 - n % 3, |_, _| next());
            if case % 11 == 0 {
                // Both arms without the z direction: M₁ + M₂ singular.
                let mut j1z = j1.clone();
                j1z.row_mut(2).fill(0.0);
                j2.row_mut(2).fill(0.0);
                assert!(dual_measures_3(&j1z, &j2).is_none());
                assert_eq!(
                    dual_measures(&j1z, &j2).unwrap(),
                    dual_measures_general(&j1z, &j2).unwrap()
                );
                continue;
            }
            let (Some(fast), general) = (
                dual_measures_3(&j1, &j2),
                dual_measures_general(&j1, &j2).unwrap(),
            ) else {
                // Cholesky refused a numerically singular sum: the general path applies.
                continue;
            };
            let s_max = general.singular_values[0];
            assert_eq!(fast.rank, general.rank, "case {case}");
            for (a, b) in fast
                .singular_values
                .iter()
                .zip(general.singular_values.iter())
            {
                assert!((a - b).abs() <= 1e-12 * s_max, "case {case}: σ {a} vs {b}");
            }
            let rel = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(f64::MIN_POSITIVE);
            assert!(
                rel(fast.yoshikawa, general.yoshikawa) || general.rank < 3,
                "case {case}"
            );
            // Axes up to sign, where the σ are well separated.
            let s = &general.singular_values;
            for i in 0..3 {
                let gap = (0..3)
                    .filter(|&k| k != i)
                    .map(|k| (s[i] - s[k]).abs())
                    .fold(f64::INFINITY, f64::min);
                if gap > 1e-3 * s_max {
                    let d: f64 = fast
                        .axes
                        .column(i)
                        .iter()
                        .zip(general.axes.column(i))
                        .map(|(a, b)| a * b)
                        .sum();
                    assert!((d.abs() - 1.0).abs() < 1e-9, "case {case}: axis {i}");
                }
            }
        }
    }
}
