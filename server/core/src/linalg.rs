//! Small dense factorizations for the 1 kHz step: a fixed-size factor of a symmetric
//! positive definite N×N matrix (the arms' 6×6 mass matrices, the 12×12 grasp constraint
//! matrix) kept in plain arrays, so that factor and solves compile to straight-line loops
//! without the generic machinery of a library decomposition.

// Triangular loops index several arrays by the same counters; iterators would hide that.
#![allow(clippy::needless_range_loop)]

use nalgebra::{SMatrix, SVector};

/// A = L·D·Lᵀ with L unit lower triangular and D diagonal positive, i.e. the Cholesky
/// factorization A = L̃·L̃ᵀ with L̃ = L·D^½ (Golub & Van Loan, Matrix Computations, 4th ed.,
/// §4.1.2 and Alg. 4.2.2), for a fixed N.
///
/// The LDLᵀ recurrence is used instead of the square-root form because it keeps the square
/// root off the critical path: each row waits only for one division (1/D of the row
/// before), and the √D_j needed by the half solves ([`Cholesky::forward`], [`Cholesky::backward`])
/// are computed independently of the recurrence. Rows are built left to right (Crout
/// order), so a row depends on the rows above it only.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cholesky<const N: usize> {
    /// Row-major strictly lower part of the unit lower triangular L (the diagonal is 1 and
    /// is not stored; entries on and above it are zero and never read).
    l: [[f64; N]; N],
    /// 1 / D_j.
    inv_d: [f64; N],
    /// 1 / √D_j (the diagonal of L̃⁻¹ up to the unit factor).
    inv_sqrt_d: [f64; N],
}

impl<const N: usize> Cholesky<N> {
    /// Factors `a` (only its lower triangle is read). `None` unless every pivot D_j is
    /// positive and finite, i.e. unless `a` is numerically positive definite.
    pub fn factor(a: &SMatrix<f64, N, N>) -> Option<Self> {
        // Built in place (no copy of the factor on return).
        let mut out = Cholesky {
            l: [[0.0; N]; N],
            inv_d: [0.0; N],
            inv_sqrt_d: [0.0; N],
        };
        let Cholesky {
            l,
            inv_d,
            inv_sqrt_d,
        } = &mut out;
        // Branch-free inside (the loops unroll); one verdict at the end. NaN fails `d > 0`.
        let mut positive = true;
        for i in 0..N {
            // u[j] = L[i][j]·D_j, the row before scaling (Crout: a_ij − Σ_k<j u_k·L[j][k]).
            let mut u = [0.0; N];
            for j in 0..i {
                let mut s = a[(i, j)];
                for k in 0..j {
                    s -= u[k] * l[j][k];
                }
                u[j] = s;
                l[i][j] = s * inv_d[j];
            }
            let mut d = a[(i, i)];
            for k in 0..i {
                d -= u[k] * l[i][k];
            }
            positive &= d > 0.0 && d < f64::INFINITY;
            inv_d[i] = 1.0 / d;
        }
        // Off the recurrence's critical path: independent square roots.
        for i in 0..N {
            inv_sqrt_d[i] = inv_d[i].sqrt();
        }
        positive.then_some(out)
    }

    /// L⁻¹·b with L unit lower triangular.
    #[inline]
    fn unit_forward(&self, b: &SVector<f64, N>) -> [f64; N] {
        let mut y = [0.0; N];
        for i in 0..N {
            let mut s = b[i];
            for k in 0..i {
                s -= self.l[i][k] * y[k];
            }
            y[i] = s;
        }
        y
    }

    /// L⁻ᵀ·y with L unit lower triangular.
    #[inline]
    fn unit_backward(&self, mut x: [f64; N]) -> SVector<f64, N> {
        for i in (0..N).rev() {
            let mut s = x[i];
            for k in i + 1..N {
                s -= self.l[k][i] * x[k];
            }
            x[i] = s;
        }
        SVector::from(x)
    }

    /// L̃⁻¹·b = D^-½·L⁻¹·b (forward substitution with the Cholesky factor L̃ = L·D^½).
    pub fn forward(&self, b: &SVector<f64, N>) -> SVector<f64, N> {
        let mut y = self.unit_forward(b);
        for i in 0..N {
            y[i] *= self.inv_sqrt_d[i];
        }
        SVector::from(y)
    }

    /// L̃⁻ᵀ·y = L⁻ᵀ·D^-½·y (back substitution with the Cholesky factor).
    pub fn backward(&self, y: &SVector<f64, N>) -> SVector<f64, N> {
        let x: [f64; N] = core::array::from_fn(|i| y[i] * self.inv_sqrt_d[i]);
        self.unit_backward(x)
    }

    /// x with A·x = b: L⁻ᵀ·D⁻¹·L⁻¹·b.
    pub fn solve(&self, b: &SVector<f64, N>) -> SVector<f64, N> {
        let mut y = self.unit_forward(b);
        for i in 0..N {
            y[i] *= self.inv_d[i];
        }
        self.unit_backward(y)
    }

    /// L̃⁻¹·B, column by column. With Z = L̃⁻¹·Jᵀ, J·A⁻¹·Jᵀ = ZᵀZ and A⁻¹·Jᵀ·f = L̃⁻ᵀ·(Z·f): one
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
                    // L̃ = L·D^½ (unit L, stored 1/√D).
                    let sqrt_d = 1.0 / ours.inv_sqrt_d[j];
                    let ours_ij = if i == j {
                        sqrt_d
                    } else {
                        ours.l[i][j] * sqrt_d
                    };
                    assert!((ours_ij - l[(i, j)]).abs() < 1e-12, "L[{i},{j}]");
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
