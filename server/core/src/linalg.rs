//! Small dense factorizations for the 1 kHz step: [`Ldlt`], a fixed-size LDLᵀ factor of a
//! symmetric positive definite N×N matrix (the arms' 6×6 mass matrices, the DLS matrix
//! JJᵀ + λ²I of the cooperative controller, the 6×6 blocks of the grasp constraint system),
//! and [`BlockLdlt`], the same factor of a 2B×2B matrix built from B×B blocks.
//!
//! Hand-written rather than nalgebra's `Cholesky` because the step needs what that type does
//! not offer: the half solves with the Cholesky factor (Z = L̃⁻¹Jᵀ, so J·H̃⁻¹·Jᵀ = ZᵀZ), the
//! explicit inverse from the factor, the two-block factor, and a refusal (`None`) for a
//! non-finite pivot as well as a non-positive one. It is the only LDLᵀ in the crate.

// Triangular loops index several arrays by the same counters; iterators would hide that.
#![allow(clippy::needless_range_loop)]

use nalgebra::{SMatrix, SVector};

/// A = L·D·Lᵀ with L unit lower triangular and D diagonal positive, i.e. the Cholesky
/// factorization A = L̃·L̃ᵀ with L̃ = L·D^½ (Golub & Van Loan, Matrix Computations, 4th ed.,
/// §4.1.2 and Alg. 4.2.2), for a fixed N.
///
/// The LDLᵀ recurrence is used instead of the square-root form because it keeps the square
/// root off the critical path: each row waits only for one division (1/D of the row
/// before), and the √D_j needed by the half solves ([`Ldlt::forward`], [`Ldlt::backward`])
/// are computed independently of the recurrence. Rows are built left to right (Crout
/// order), so a row depends on the rows above it only.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ldlt<const N: usize> {
    /// Row-major strictly lower part of the unit lower triangular L (the diagonal is 1 and
    /// is not stored; entries on and above it are zero and never read).
    l: [[f64; N]; N],
    /// 1 / D_j.
    inv_d: [f64; N],
    /// 1 / √D_j (the diagonal of L̃⁻¹ up to the unit factor).
    inv_sqrt_d: [f64; N],
}

impl<const N: usize> Ldlt<N> {
    /// Factors `a` (only its lower triangle is read). `None` unless every pivot D_j is
    /// positive and finite, i.e. unless `a` is numerically positive definite.
    pub fn factor(a: &SMatrix<f64, N, N>) -> Option<Self> {
        // Built inside the `Option` it is returned in, so the factor is written once, in
        // place (a `Self` moved into `Some` at the end costs a copy of its N² + 2N numbers).
        let mut out = Some(Ldlt {
            l: [[0.0; N]; N],
            inv_d: [0.0; N],
            inv_sqrt_d: [0.0; N],
        });
        let Some(Ldlt {
            l,
            inv_d,
            inv_sqrt_d,
        }) = &mut out
        else {
            unreachable!("constructed as Some just above")
        };
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
        if !positive {
            out = None;
        }
        out
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

    /// A⁻¹ = L⁻ᵀ·D⁻¹·L⁻¹ (symmetric, both triangles filled), from the factor instead of N
    /// solves on unit vectors. X = L⁻¹ is unit lower triangular, by forward substitution on
    /// the identity column by column (Golub & Van Loan §3.1.1):
    /// X_ij = −L_ij − Σ_{j<k<i} L_ik·X_kj for i > j. Then (A⁻¹)_ij = Σ_{k ≥ max(i,j)}
    /// X_ki·X_kj / D_k: each entry of the lower triangle is one short dot product over the
    /// rows k ≥ i where both columns of X can be non-zero, and the upper one is its mirror.
    /// About N³/3 multiply-adds instead of the 2N³ of N full solves.
    pub fn inverse(&self) -> SMatrix<f64, N, N> {
        // x[i][j] = X_ij, zero above the diagonal.
        let mut x = [[0.0; N]; N];
        for j in 0..N {
            x[j][j] = 1.0;
            for i in j + 1..N {
                let mut s = -self.l[i][j];
                for k in j + 1..i {
                    s -= self.l[i][k] * x[k][j];
                }
                x[i][j] = s;
            }
        }
        // y = D⁻¹·X (row k scaled by 1/D_k), so that (A⁻¹)_ij = Σ_{k ≥ i} X_ki·y_kj (i ≥ j).
        let mut y = x;
        for k in 0..N {
            for j in 0..=k {
                y[k][j] *= self.inv_d[k];
            }
        }
        let mut out = SMatrix::<f64, N, N>::zeros();
        for j in 0..N {
            for i in j..N {
                // k = i: X_ii = 1.
                let mut s = y[i][j];
                for k in i + 1..N {
                    s += x[k][i] * y[k][j];
                }
                out[(i, j)] = s;
                out[(j, i)] = s;
            }
        }
        out
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

/// The lower triangle of ZᵀZ (the part above the diagonal left zero: the factorizations read
/// no more), from dot products of Z's contiguous columns.
#[inline]
pub fn gram_lower<const N: usize>(z: &SMatrix<f64, N, N>) -> SMatrix<f64, N, N> {
    let mut g = SMatrix::<f64, N, N>::zeros();
    for c in 0..N {
        let zc = z.column(c);
        for r in c..N {
            g[(r, c)] = z.column(r).dot(&zc);
        }
    }
    g
}

/// The Cholesky factor of a symmetric positive definite 2B×2B matrix given by its lower
/// blocks, [[A₀₀, A₁₀ᵀ], [A₁₀, A₁₁]] = L̃·L̃ᵀ with L̃ = [[L̃₀₀, 0], [L̃₁₀, L̃₁₁]] (block
/// Cholesky, Golub & Van Loan §4.2.9): L̃₀₀ = chol(A₀₀), W = L̃₁₀ᵀ = L̃₀₀⁻¹·A₁₀ᵀ,
/// L̃₁₁ = chol(A₁₁ − WᵀW). The same factor as [`Ldlt`] of the whole matrix, computed
/// from fixed B×B pieces whose loops unroll (the grasp constraint system of two arms).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlockLdlt<const B: usize> {
    l00: Ldlt<B>,
    /// W = L̃₁₀ᵀ.
    w: SMatrix<f64, B, B>,
    l11: Ldlt<B>,
}

impl<const B: usize> BlockLdlt<B> {
    /// Factors the matrix with lower blocks `a00`, `a10`, `a11` (only the lower triangles of
    /// the diagonal blocks are read). `None` unless it is numerically positive definite.
    pub fn factor(
        a00: &SMatrix<f64, B, B>,
        a10: &SMatrix<f64, B, B>,
        a11: &SMatrix<f64, B, B>,
    ) -> Option<Self> {
        let l00 = Ldlt::factor(a00)?;
        let w = l00.forward_columns(&a10.transpose());
        // Schur complement A₁₁ − WᵀW, lower triangle only.
        let s = a11 - gram_lower(&w);
        let l11 = Ldlt::factor(&s)?;
        Some(BlockLdlt { l00, w, l11 })
    }

    /// (x₀, x₁) with A·[x₀; x₁] = [b₀; b₁]: y₀ = L̃₀₀⁻¹b₀, y₁ = L̃₁₁⁻¹(b₁ − Wᵀy₀),
    /// x₁ = L̃₁₁⁻ᵀy₁, x₀ = L̃₀₀⁻ᵀ(y₀ − W·x₁).
    pub fn solve(
        &self,
        b0: &SVector<f64, B>,
        b1: &SVector<f64, B>,
    ) -> (SVector<f64, B>, SVector<f64, B>) {
        let y0 = self.l00.forward(b0);
        let y1 = self.l11.forward(&(b1 - self.w.tr_mul(&y0)));
        let x1 = self.l11.backward(&y1);
        let x0 = self.l00.backward(&(y0 - self.w * x1));
        (x0, x1)
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

    /// `gram_lower` is the lower triangle of nalgebra's ZᵀZ (to round-off) and zero above.
    #[test]
    fn gram_lower_is_the_lower_triangle_of_ztz() {
        let z = Matrix6::from_fn(|i, j| ((i * 6 + j) as f64 * 0.61).sin() * (1.0 + i as f64));
        let full = z.tr_mul(&z);
        let g = gram_lower(&z);
        for c in 0..6 {
            for r in 0..6 {
                if r >= c {
                    assert!((g[(r, c)] - full[(r, c)]).abs() < 1e-13 * full.norm());
                } else {
                    assert_eq!(g[(r, c)], 0.0);
                }
            }
        }
    }

    /// Against nalgebra's own Cholesky (an independent implementation): the same factor,
    /// solves that reproduce the right-hand side.
    #[test]
    fn agrees_with_nalgebra_and_solves() {
        for seed in 1..50 {
            let a: Matrix6<f64> = spd(seed, 1e-3);
            let ours = Ldlt::factor(&a).expect("SPD");
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
            let x12 = Ldlt::factor(&a12).expect("SPD").solve(&b12);
            let x12_ref = a12.cholesky().expect("SPD").solve(&b12);
            assert!((x12 - x12_ref).norm() < 1e-8 * x12_ref.norm());
        }
    }

    /// `inverse` against nalgebra's LU-based `try_inverse` (an independent algorithm) on
    /// random SPD matrices, ill-conditioned ones included, and exactly symmetric.
    #[test]
    fn inverse_agrees_with_nalgebra() {
        for seed in 1..60 {
            for delta in [1.0, 1e-3, 1e-6] {
                let a: Matrix6<f64> = spd(seed + 500, delta);
                let ours = Ldlt::factor(&a).expect("SPD").inverse();
                let theirs = a.try_inverse().expect("invertible");
                assert!(
                    (ours - theirs).norm() <= 1e-10 * theirs.norm() * (1.0 + 1.0 / delta),
                    "seed {seed}, δ {delta}: {ours} vs {theirs}"
                );
                assert_eq!(ours, ours.transpose());
                assert!((a * ours - Matrix6::identity()).norm() < 1e-12 / delta);
            }
            let a12: SMatrix<f64, 12, 12> = spd(seed + 700, 1e-2);
            let inv12 = Ldlt::factor(&a12).expect("SPD").inverse();
            let ref12 = a12.try_inverse().expect("invertible");
            assert!((inv12 - ref12).norm() < 1e-10 * ref12.norm());
        }
        // N = 1: 1/a.
        let one = SMatrix::<f64, 1, 1>::new(4.0);
        assert_eq!(Ldlt::factor(&one).expect("SPD").inverse()[(0, 0)], 0.25);
    }

    /// The block factor solves the same systems as the whole-matrix factor (and nalgebra's
    /// Cholesky, the independent reference) and refuses what they refuse.
    #[test]
    fn block_factor_agrees_with_the_whole_matrix() {
        for seed in 1..40 {
            let a: SMatrix<f64, 12, 12> = spd(seed + 300, 1e-4);
            let a00: Matrix6<f64> = a.fixed_view::<6, 6>(0, 0).into_owned();
            let a10: Matrix6<f64> = a.fixed_view::<6, 6>(6, 0).into_owned();
            let a11: Matrix6<f64> = a.fixed_view::<6, 6>(6, 6).into_owned();
            let blk = BlockLdlt::factor(&a00, &a10, &a11).expect("SPD");
            let b = SVector::<f64, 12>::from_fn(|i, _| (i as f64 * 0.7).sin() + 0.1);
            let b0: Vector6<f64> = b.fixed_rows::<6>(0).into_owned();
            let b1: Vector6<f64> = b.fixed_rows::<6>(6).into_owned();
            let (x0, x1) = blk.solve(&b0, &b1);
            let x_ref = a.cholesky().expect("SPD").solve(&b);
            let x_whole = Ldlt::factor(&a).expect("SPD").solve(&b);
            for i in 0..6 {
                assert!((x0[i] - x_ref[i]).abs() < 1e-9 * x_ref.norm());
                assert!((x1[i] - x_ref[i + 6]).abs() < 1e-9 * x_ref.norm());
                assert!((x0[i] - x_whole[i]).abs() < 1e-9 * x_ref.norm());
            }
        }
        // Indefinite in the Schur complement only: A₀₀ = I, A₁₀ = 2I, A₁₁ = I.
        let i6 = Matrix6::<f64>::identity();
        assert!(BlockLdlt::factor(&i6, &(i6 * 2.0), &i6).is_none());
        assert!(BlockLdlt::factor(&(i6 * f64::NAN), &i6, &i6).is_none());
    }

    /// Indefinite, singular and non-finite matrices are refused, never factored into NaN.
    #[test]
    fn refuses_non_positive_definite() {
        let mut a = Matrix6::<f64>::identity();
        a[(3, 3)] = -1.0;
        assert!(Ldlt::factor(&a).is_none());
        a[(3, 3)] = 0.0;
        assert!(Ldlt::factor(&a).is_none());
        a[(3, 3)] = f64::NAN;
        assert!(Ldlt::factor(&a).is_none());
        // Rank one: the second pivot vanishes.
        let v = Vector6::new(1.0, 2.0, 3.0, 4.0, 5.0, 6.0);
        assert!(Ldlt::factor(&(v * v.transpose())).is_none());
    }
}
