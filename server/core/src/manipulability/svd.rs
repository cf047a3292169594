//! The full singular value decomposition of a Jacobian and its four fundamental subspaces
//! (RX90 report part VI), by the one-sided Jacobi SVD of module `jacobi`.

use nalgebra::{DMatrix, DVector};

use super::jacobi;
use super::measures::{Measures, measures_from_svd};
use crate::Error;

/// Full singular value decomposition J = U Σ Vᵀ with U m×m, V n×n, σ sorted descending and
/// padded with zeros to m entries when m > n.
#[derive(Debug, Clone)]
pub struct FullSvd {
    /// m×m orthogonal; column i is the i-th principal direction in task space.
    pub u: DMatrix<f64>,
    /// m singular values, descending, ≥ 0.
    pub sigma: DVector<f64>,
    /// n×n orthogonal; column i is the i-th joint-space direction.
    pub v: DMatrix<f64>,
    /// Singular values at or below this count as zero (rank, subspaces, measures).
    pub tolerance: f64,
}

/// A Jacobian must be non-empty and finite.
pub(super) fn check_jacobian(j: &DMatrix<f64>) -> Result<(), Error> {
    if j.is_empty() {
        return Err(Error::SizeMismatch {
            what: "jacobian",
            input: 0,
            required: 1,
        });
    }
    if let Some(index) = j.as_slice().iter().position(|v| !v.is_finite()) {
        return Err(Error::NonFinite {
            what: "jacobian",
            index,
        });
    }
    Ok(())
}

/// Relative rank tolerance of every route ([`full_svd`], [`measures`](super::measures::measures), [`row_measures`](super::measures::row_measures)):
/// σ ≤ this·σ₁ counts as zero.
///
/// The one-sided Jacobi SVD itself is accurate to a few ε·σ₁ (relatively accurate, even),
/// so this is a modelling choice rather than a round-off floor: a Jacobian computed from
/// joint angles is only as good as those angles, and a posture whose smallest σ is below
/// 1.5·10⁻⁷σ₁ (about 0.01 millidegree of joint motion from the singular posture at unit
/// lever arms) is reported as singular — rank, null space, infinite condition number and
/// force measures — rather than as conditioned 10⁷. It is the value the earlier eigenvalue
/// route through JᵀJ needed for its own round-off, kept so that the reported rank of the
/// full Jacobian does not change (that route's `measures` used √(mε)σ₁ ≈ 3·10⁻⁸σ₁).
pub const RANK_TOLERANCE: f64 = 1.5e-7;

/// Full SVD of `j` (m×n) by one-sided Jacobi rotations (module `jacobi`; Hestenes 1958,
/// Demmel & Veselić 1992): the shorter family of vectors of J — its columns when m ≥ n, its
/// rows when m < n — is rotated until mutually orthogonal. The accumulated rotations are V
/// (resp. U), the vector lengths are σ and the normalised vectors the leading columns of U
/// (resp. V), completed to an orthogonal matrix by Gram–Schmidt on unit vectors where a
/// vector is zero (or shorter than 10⁻⁶⁰σ₁). No squaring of J, so σ keeps full relative
/// accuracy, and no heap beyond the outputs up to 7×7.
/// Rank tolerance: [`RANK_TOLERANCE`]·σ₁.
pub fn full_svd(j: &DMatrix<f64>) -> Result<FullSvd, Error> {
    let (m, n) = j.shape();
    check_jacobian(j)?;
    let wide = m < n;
    let (k, l) = if wide { (m, n) } else { (n, m) };
    let mut w = DMatrix::<f64>::zeros(k, k);
    let mut sigma = DVector::<f64>::zeros(m);
    let mut q = DMatrix::<f64>::zeros(l, l);
    let kept = jacobi::with_scratch(k * l, |a: &mut [f64]| {
        if wide {
            // a holds the rows of J: vector p is row p.
            for (p, row) in a.chunks_exact_mut(l).enumerate() {
                for (x, &v) in row.iter_mut().zip(j.row(p).iter()) {
                    *x = v;
                }
            }
        } else {
            // Column-major storage: vector p is column p.
            a.copy_from_slice(j.as_slice());
        }
        jacobi::with_scratch(k, |order: &mut [usize]| {
            let s = &mut sigma.as_mut_slice()[..k];
            jacobi::decompose(a, l, 1, w.as_mut_slice(), s, order);
            // Every vector that is not negligible is normalised, including those below the
            // rank tolerance: Jacobi leaves them orthogonal to the others to working
            // precision relative to their own length, so UΣVᵀ = J holds to round-off. Only
            // vectors shorter than 10⁻⁶⁰σ₁ — where the products of squares in the stopping
            // test could underflow, so that orthogonality is no longer checked — and zero
            // ones are replaced by the completion.
            let negligible = 1e-60 * s[0];
            let kept = s.iter().filter(|&&x| x > negligible).count();
            for (dst, &o) in q
                .as_mut_slice()
                .chunks_exact_mut(l)
                .zip(order.iter())
                .take(kept)
            {
                let src = &a[o * l..(o + 1) * l];
                let norm = src.iter().map(|x| x * x).sum::<f64>().sqrt();
                for (d, x) in dst.iter_mut().zip(src) {
                    *d = x / norm;
                }
            }
            kept
        })
    });
    jacobi::complete_columns(q.as_mut_slice(), l, kept);
    let (u, v) = if wide { (w, q) } else { (q, w) };
    Ok(FullSvd {
        u,
        tolerance: RANK_TOLERANCE * sigma[0],
        sigma,
        v,
    })
}

/// Extends the orthonormal columns of `b` (k×r, r ≤ k) to a k×k orthogonal matrix by
/// Gram–Schmidt on unit vectors (`jacobi::complete_columns`).
pub fn complete_basis(b: &DMatrix<f64>) -> DMatrix<f64> {
    let (k, r) = b.shape();
    if r >= k {
        return b.columns(0, k).into_owned();
    }
    let mut out = DMatrix::zeros(k, k);
    out.columns_mut(0, r).copy_from(b);
    jacobi::complete_columns(out.as_mut_slice(), k, r);
    out
}

/// Default rank tolerance: max(m, n)·ε·σ₁ (as numpy's `matrix_rank`).
pub fn default_tolerance(m: usize, n: usize, sigma_max: f64) -> f64 {
    (m.max(n) as f64) * f64::EPSILON * sigma_max
}

/// The four fundamental subspaces from the SVD (RX90 report part VI), each an orthonormal
/// basis stored as the columns of a matrix.
#[derive(Debug, Clone, PartialEq)]
pub struct Subspaces {
    /// Rank used to split them.
    pub rank: usize,
    /// V_{r+1..n} (n×(n−r)): joint velocities giving no end-effector motion (null space of J).
    pub null_space: DMatrix<f64>,
    /// V_{1..r} (n×r): joint velocities that generate end-effector motion.
    pub generating: DMatrix<f64>,
    /// U_{1..r} (m×r): achievable end-effector velocities (range of J).
    pub range: DMatrix<f64>,
    /// U_{r+1..m} (m×(m−r)): end-effector velocities that cannot be generated.
    pub unreachable: DMatrix<f64>,
}

/// Splits the SVD of `j` into its subspaces with the default rank tolerance.
pub fn subspaces(j: &DMatrix<f64>) -> Result<Subspaces, Error> {
    Ok(subspaces_from_svd(&full_svd(j)?))
}

/// Subspaces from a full SVD (with `v`).
pub fn subspaces_from_svd(svd: &FullSvd) -> Subspaces {
    let (m, n) = (svd.u.nrows(), svd.v.nrows());
    let rank = svd.rank();
    Subspaces {
        rank,
        null_space: columns(&svd.v, rank..n),
        generating: columns(&svd.v, 0..rank),
        range: columns(&svd.u, 0..rank),
        unreachable: columns(&svd.u, rank..m),
    }
}

/// Columns `range` of `mat` (a contiguous copy of its column-major storage).
fn columns(mat: &DMatrix<f64>, range: std::ops::Range<usize>) -> DMatrix<f64> {
    let r = mat.nrows();
    DMatrix::from_column_slice(
        r,
        range.len(),
        &mat.as_slice()[range.start * r..range.end * r],
    )
}

impl FullSvd {
    /// Number of σ above the tolerance.
    pub fn rank(&self) -> usize {
        let k = self.u.nrows().min(self.v.nrows());
        self.sigma
            .iter()
            .take(k)
            .filter(|&&s| s > self.tolerance)
            .count()
    }

    /// [`measures_from_svd`] and [`subspaces_from_svd`] at once, reusing the storage of U
    /// and V instead of copying it where possible.
    pub fn into_measures_and_subspaces(self) -> Result<(Measures, Subspaces), Error> {
        let measures = measures_from_svd(&self)?;
        let (m, n) = (self.u.nrows(), self.v.nrows());
        let rank = self.rank();
        let whole_or = |mat: DMatrix<f64>, range: std::ops::Range<usize>| {
            if range.len() == mat.ncols() {
                mat
            } else {
                columns(&mat, range)
            }
        };
        let subspaces = Subspaces {
            rank,
            null_space: columns(&self.v, rank..n),
            unreachable: columns(&self.u, rank..m),
            generating: whole_or(self.v, 0..rank),
            range: whole_or(self.u, 0..rank),
        };
        Ok((measures, subspaces))
    }
}
