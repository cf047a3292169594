//! Dual-arm manipulability ellipsoid (Lim §3.5.2, eq. 3.68).
//!
//! With both end-effectors rigidly holding the object, ẋ₁ = ẋ₂ = ẋ (eq. 3.65) and the unit
//! joint-velocity sphere maps to ẋᵀ[(J₁J₁ᵀ)⁻¹ + (J₂J₂ᵀ)⁻¹]ẋ ≤ 1. Its shape matrix is the
//! parallel sum M = (M₁⁻¹ + M₂⁻¹)⁻¹ = M₁(M₁ + M₂)⁻¹M₂ of Mᵢ = JᵢJᵢᵀ, which stays finite when
//! one arm is singular (that arm's lost direction then has radius 0). The radii are √eig(M).

use nalgebra::{DMatrix, SymmetricEigen};

use super::measures::{Measures, check_task_dim, default_tolerance};
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
