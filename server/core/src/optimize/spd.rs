//! Small symmetric positive (semi-)definite matrices, k×k with k ≤ [`MAX_ROWS`], stored
//! row-major in a fixed array: the Gram matrix A·Aᵀ of a few Jacobian rows, its determinant,
//! its Cholesky factor and the solve A ↦ M⁻¹A. Shared by the TOMM gradient
//! ([`super::objective`]) and the damped pseudo-inverse of [`crate::redundancy`]; nothing here
//! allocates.
//!
//! The Cholesky factor here sits beside [`crate::linalg::Ldlt`] because the two serve
//! different shapes: k is chosen at run time (the task rows a caller selects, 1 to
//! [`MAX_ROWS`]) and the factor takes a shift (M − σ₀²I, the definiteness test of the damped
//! pseudo-inverse) and a pivot floor, while `Ldlt<N>` has its size fixed at compile time (N = 6 in
//! the allocation-free 1 kHz step: constant loop bounds, N×N arrays and nalgebra's static
//! matrices in and out).

use super::objective::MAX_ROWS;

/// A k×k matrix, row-major in the first k² entries.
pub(crate) type Square = [f64; MAX_ROWS * MAX_ROWS];

/// M = A·Aᵀ of the k×n matrix A whose entry (row a, column c) is `entry(a, c)`.
pub(crate) fn gram(k: usize, n: usize, entry: impl Fn(usize, usize) -> f64) -> Square {
    let mut m = [0.0; MAX_ROWS * MAX_ROWS];
    for a in 0..k {
        for b in a..k {
            let s: f64 = (0..n).map(|c| entry(a, c) * entry(b, c)).sum();
            m[a * k + b] = s;
            m[b * k + a] = s;
        }
    }
    m
}

/// Determinant of a symmetric positive semi-definite k×k matrix `a` (destroyed), by Gaussian
/// elimination with partial pivoting; clamped ≥ 0.
pub(crate) fn psd_determinant(a: &mut Square, k: usize) -> f64 {
    let mut det = 1.0;
    for c in 0..k {
        let mut p = c;
        for r in c + 1..k {
            if a[r * k + c].abs() > a[p * k + c].abs() {
                p = r;
            }
        }
        let pivot = a[p * k + c];
        if pivot == 0.0 {
            return 0.0;
        }
        if p != c {
            for j in 0..k {
                a.swap(c * k + j, p * k + j);
            }
            det = -det;
        }
        det *= pivot;
        for r in c + 1..k {
            let f = a[r * k + c] / pivot;
            if f != 0.0 {
                for j in c..k {
                    a[r * k + j] -= f * a[c * k + j];
                }
            }
        }
    }
    det.max(0.0)
}

/// Lower-triangular Cholesky factor L of M − shift·I (L·Lᵀ = M − shift·I) for the symmetric
/// k×k matrix `m`; `None` when a pivot L_aa² is not finite or not above `floor`, i.e. when
/// M − shift·I is not (numerically) positive definite.
pub(crate) fn cholesky(m: &Square, k: usize, shift: f64, floor: f64) -> Option<Square> {
    let mut l = [0.0; MAX_ROWS * MAX_ROWS];
    for a in 0..k {
        for b in 0..=a {
            let mut s = m[a * k + b] - if a == b { shift } else { 0.0 };
            for p in 0..b {
                s -= l[a * k + p] * l[b * k + p];
            }
            if a == b {
                if !(s > floor && s.is_finite()) {
                    return None;
                }
                l[a * k + a] = s.sqrt();
            } else {
                l[a * k + b] = s / l[b * k + b];
            }
        }
    }
    Some(l)
}

/// M⁻¹·a_c for every column c of the k×n matrix A given by `entry(row, column)`, with
/// M = L·Lᵀ from [`cholesky`] (forward then back substitution). Column c of the result is
/// written to `out[c·k..(c + 1)·k]`, so `out` holds (M⁻¹A)ᵀ = AᵀM⁻¹ row-major (n×k).
pub(crate) fn solve_columns(
    l: &Square,
    k: usize,
    n: usize,
    entry: impl Fn(usize, usize) -> f64,
    out: &mut [f64],
) {
    for c in 0..n {
        let mut x = [0.0; MAX_ROWS];
        for a in 0..k {
            let mut s = entry(a, c);
            for p in 0..a {
                s -= l[a * k + p] * x[p];
            }
            x[a] = s / l[a * k + a];
        }
        for a in (0..k).rev() {
            let mut s = x[a];
            for p in a + 1..k {
                s -= l[p * k + a] * x[p];
            }
            x[a] = s / l[a * k + a];
        }
        out[c * k..(c + 1) * k].copy_from_slice(&x[..k]);
    }
}

#[cfg(test)]
mod tests {
    //! Against nalgebra's dense determinant, inverse and eigenvalues (an independent
    //! implementation) on a fixed 3×5 matrix A.
    use super::*;
    use nalgebra::{DMatrix, SMatrix};

    const A: [[f64; 5]; 3] = [
        [0.3, -1.2, 0.5, 2.0, 0.1],
        [1.1, 0.4, -0.7, 0.2, 0.9],
        [-0.5, 0.8, 1.3, -0.6, 0.4],
    ];

    fn a_gram() -> (Square, SMatrix<f64, 3, 3>) {
        let a = SMatrix::<f64, 3, 5>::from_fn(|r, c| A[r][c]);
        (gram(3, 5, |r, c| A[r][c]), a * a.transpose())
    }

    #[test]
    fn gram_and_determinant_match_nalgebra() {
        let (mut m, reference) = a_gram();
        for r in 0..3 {
            for c in 0..3 {
                assert!((m[r * 3 + c] - reference[(r, c)]).abs() <= 1e-14);
            }
        }
        let det = psd_determinant(&mut m, 3);
        assert!((det - reference.determinant()).abs() <= 1e-12 * det);
    }

    #[test]
    fn cholesky_solve_matches_the_inverse() {
        let (m, reference) = a_gram();
        let l = cholesky(&m, 3, 0.0, 0.0).expect("A has full row rank");
        let mut out = [0.0; 15];
        solve_columns(&l, 3, 5, |r, c| A[r][c], &mut out);
        let inv = reference.try_inverse().expect("invertible");
        let expected = inv * SMatrix::<f64, 3, 5>::from_fn(|r, c| A[r][c]);
        for c in 0..5 {
            for r in 0..3 {
                assert!((out[c * 3 + r] - expected[(r, c)]).abs() <= 1e-12);
            }
        }
    }

    #[test]
    fn shifted_cholesky_fails_exactly_past_the_smallest_eigenvalue() {
        let (m, reference) = a_gram();
        let eig = DMatrix::from_fn(3, 3, |r, c| reference[(r, c)]).symmetric_eigenvalues();
        let min = eig.min();
        assert!(cholesky(&m, 3, 0.99 * min, 0.0).is_some());
        assert!(cholesky(&m, 3, 1.01 * min, 0.0).is_none());
    }
}
