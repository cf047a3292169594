//! Small dense factorizations for the 1 kHz step: a fixed-size Cholesky factor of a symmetric
//! positive definite N×N matrix (the arms' 6×6 mass matrices, the 12×12 grasp constraint
//! matrix) kept in plain arrays, so that factor and solves compile to straight-line loops
//! without the generic machinery of a library decomposition.

// Triangular loops index several arrays by the same counters; iterators would hide that.
#![allow(clippy::needless_range_loop)]

use nalgebra::{SMatrix, SVector};

/// A = L·Lᵀ with L lower triangular (Golub & Van Loan, Matrix Computations, 4th ed., Alg. 4.2.2,
/// the outer-product/column form), for a fixed N.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cholesky<const N: usize> {
    /// Row-major lower triangle of L (entries above the diagonal are zero).
    l: [[f64; N]; N],
    /// 1 / L[i][i].
    inv_diag: [f64; N],
}

impl<const N: usize> Cholesky<N> {
    /// Factors `a` (only its lower triangle is read). `None` unless every pivot is positive
    /// and finite, i.e. unless `a` is numerically positive definite.
    pub fn factor(a: &SMatrix<f64, N, N>) -> Option<Self> {
        // Built in place (no copy of the factor on return).
        let mut out = Cholesky {
            l: [[0.0; N]; N],
            inv_diag: [0.0; N],
        };
        let Cholesky { l, inv_diag } = &mut out;
        // Branch-free inside (the loops unroll); one verdict at the end. NaN fails `d > 0`.
        let mut positive = true;
        for j in 0..N {
            let mut d = a[(j, j)];
            for k in 0..j {
                d -= l[j][k] * l[j][k];
            }
            positive &= d > 0.0 && d < f64::INFINITY;
            let ljj = d.sqrt();
            let inv = 1.0 / ljj;
            l[j][j] = ljj;
            inv_diag[j] = inv;
            for i in j + 1..N {
                let mut s = a[(i, j)];
                for k in 0..j {
                    s -= l[i][k] * l[j][k];
                }
                l[i][j] = s * inv;
            }
        }
        positive.then_some(out)
    }

    /// L⁻¹·b (forward substitution).
    pub fn forward(&self, b: &SVector<f64, N>) -> SVector<f64, N> {
        let mut y = [0.0; N];
        for i in 0..N {
            let mut s = b[i];
            for k in 0..i {
                s -= self.l[i][k] * y[k];
            }
            y[i] = s * self.inv_diag[i];
        }
        SVector::from(y)
    }

    /// L⁻ᵀ·y (back substitution).
    pub fn backward(&self, y: &SVector<f64, N>) -> SVector<f64, N> {
        let mut x = [0.0; N];
        for i in (0..N).rev() {
            let mut s = y[i];
            for k in i + 1..N {
                s -= self.l[k][i] * x[k];
            }
            x[i] = s * self.inv_diag[i];
        }
        SVector::from(x)
    }

    /// x with A·x = b.
    pub fn solve(&self, b: &SVector<f64, N>) -> SVector<f64, N> {
        self.backward(&self.forward(b))
    }

    /// L⁻¹·B, column by column. With Z = L⁻¹·Jᵀ, J·A⁻¹·Jᵀ = ZᵀZ and A⁻¹·Jᵀ·f = L⁻ᵀ·(Z·f): one
    /// triangular solve per column instead of two.
    pub fn forward_columns<const K: usize>(&self, b: &SMatrix<f64, N, K>) -> SMatrix<f64, N, K> {
        let mut x = SMatrix::<f64, N, K>::zeros();
        for c in 0..K {
            let col: SVector<f64, N> = b.column(c).into_owned();
            x.set_column(c, &self.forward(&col));
        }
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix6, SMatrix, Vector6};

    /// A reproducible SPD matrix B·Bᵀ + δI.
    fn spd<const N: usize>(seed: u64, delta: f64) -> SMatrix<f64, N, N> {
        let mut s = seed;
        let b = SMatrix::<f64, N, N>::from_fn(|_, _| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        });
        b * b.transpose() + SMatrix::<f64, N, N>::identity() * delta
    }

    /// Against nalgebra's own Cholesky (an independent implementation): the same factor,
    /// solves that reproduce the right-hand side.
    #[test]
    fn agrees_with_nalgebra_and_solves() {
        for seed in 1..50 {
            let a: Matrix6<f64> = spd(seed, 1e-3);
            let ours = Cholesky::factor(&a).expect("SPD");
            let theirs = a.cholesky().expect("SPD");
            let l = theirs.l();
            for i in 0..6 {
                for j in 0..=i {
                    assert!((ours.l[i][j] - l[(i, j)]).abs() < 1e-12, "L[{i},{j}]");
                }
            }
            let b = Vector6::new(1.0, -2.0, 3.0, 0.5, -0.25, 4.0);
            let x = ours.solve(&b);
            assert!((a * x - b).norm() < 1e-9 * b.norm() * a.norm());
            let bm = Matrix6::from_fn(|r, c| (r as f64 + 1.0) * (c as f64 - 2.5));
            let xm = Matrix6::from_columns(&core::array::from_fn::<_, 6, _>(|c| {
                ours.solve(&bm.column(c).into_owned())
            }));
            assert!((a * xm - bm).norm() < 1e-9 * bm.norm() * a.norm());
            // Congruence through the half solve: B·A⁻¹·Bᵀ = ZᵀZ with Z = L⁻¹Bᵀ.
            let z = ours.forward_columns(&bm.transpose());
            let reference = bm * a.try_inverse().expect("invertible") * bm.transpose();
            assert!((z.transpose() * z - reference).norm() < 1e-8 * reference.norm());
            assert!((ours.backward(&ours.forward(&b)) - x).norm() < 1e-12 * x.norm());
            let a12: SMatrix<f64, 12, 12> = spd(seed + 100, 1e-6);
            let b12 = SVector::<f64, 12>::from_fn(|i, _| (i as f64).cos());
            let x12 = Cholesky::factor(&a12).expect("SPD").solve(&b12);
            let x12_ref = a12.cholesky().expect("SPD").solve(&b12);
            assert!((x12 - x12_ref).norm() < 1e-8 * x12_ref.norm());
        }
    }

    /// Indefinite, singular and non-finite matrices are refused, never factored into NaN.
    #[test]
    fn refuses_non_positive_definite() {
        let mut a = Matrix6::<f64>::identity();
        a[(3, 3)] = -1.0;
        assert!(Cholesky::factor(&a).is_none());
        a[(3, 3)] = 0.0;
        assert!(Cholesky::factor(&a).is_none());
        a[(3, 3)] = f64::NAN;
        assert!(Cholesky::factor(&a).is_none());
        // Rank one: the second pivot vanishes.
        let v = Vector6::new(1.0, 2.0, 3.0, 4.0, 5.0, 6.0);
        assert!(Cholesky::factor(&(v * v.transpose())).is_none());
    }
}
