//! Singular-value measures of a Jacobian (Lim §2.4, §3.5; Jun §2.1; RX90 report part VI).

use nalgebra::{DMatrix, DMatrixView, DVector, Matrix6, U1, U6};

use super::jacobi;
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
fn check_jacobian(j: &DMatrix<f64>) -> Result<(), Error> {
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

/// Relative rank tolerance of every route ([`full_svd`], [`measures`], [`row_measures`]):
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

/// Volume coefficient c_m of an m-dimensional ellipsoid (Lim eq. 2.18): volume = c_m·Πσᵢ.
pub fn ellipsoid_volume_coefficient(m: usize) -> f64 {
    use std::f64::consts::PI;
    if m == 0 {
        return 1.0;
    }
    if m % 2 == 0 {
        // (2π)^{m/2} / (2·4·…·m)
        let denom: f64 = (1..=m / 2).map(|k| (2 * k) as f64).product();
        (2.0 * PI).powi((m / 2) as i32) / denom
    } else {
        // 2(2π)^{(m−1)/2} / (1·3·…·m)
        let denom: f64 = (0..=(m - 1) / 2).map(|k| (2 * k + 1) as f64).product();
        2.0 * (2.0 * PI).powi(((m - 1) / 2) as i32) / denom
    }
}

/// Largest task-space dimension: the rows of a spatial Jacobian (vx vy vz wx wy wz). The
/// measures of up to this many rows are stored inline, without heap allocation.
pub const MAX_TASK_DIM: usize = 6;

/// Up to [`MAX_TASK_DIM`] values stored inline, one per task-space dimension; it derefs to
/// the slice of its values.
#[derive(Clone, Copy)]
pub struct TaskVector<T> {
    len: usize,
    values: [T; MAX_TASK_DIM],
}

impl<T: Copy + Default> TaskVector<T> {
    /// The values of `s`.
    ///
    /// # Panics
    /// When `s` has more than [`MAX_TASK_DIM`] values.
    pub fn from_slice(s: &[T]) -> TaskVector<T> {
        assert!(
            s.len() <= MAX_TASK_DIM,
            "at most {MAX_TASK_DIM} task dimensions"
        );
        let mut values = [T::default(); MAX_TASK_DIM];
        values[..s.len()].copy_from_slice(s);
        TaskVector {
            len: s.len(),
            values,
        }
    }
}

impl<T> std::ops::Deref for TaskVector<T> {
    type Target = [T];
    fn deref(&self) -> &[T] {
        &self.values[..self.len]
    }
}

impl<T: PartialEq> PartialEq for TaskVector<T> {
    fn eq(&self, other: &Self) -> bool {
        **self == **other
    }
}

impl<T: std::fmt::Debug> std::fmt::Debug for TaskVector<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        (**self).fmt(f)
    }
}

/// An m×m matrix, m ≤ [`MAX_TASK_DIM`], stored inline as the leading block of a 6×6.
#[derive(Clone, Copy)]
pub struct TaskMatrix {
    dim: usize,
    data: Matrix6<f64>,
}

impl TaskMatrix {
    /// The m×m matrix stored column-major in `s` (m² entries).
    ///
    /// # Panics
    /// When m exceeds [`MAX_TASK_DIM`].
    pub fn from_column_slice(m: usize, s: &[f64]) -> TaskMatrix {
        assert!(m <= MAX_TASK_DIM, "at most {MAX_TASK_DIM} task dimensions");
        assert_eq!(s.len(), m * m, "an m×m matrix");
        let mut data = Matrix6::zeros();
        for (c, col) in s.chunks_exact(m).enumerate() {
            data.as_mut_slice()[c * MAX_TASK_DIM..c * MAX_TASK_DIM + m].copy_from_slice(col);
        }
        TaskMatrix { dim: m, data }
    }

    /// m.
    pub fn nrows(&self) -> usize {
        self.dim
    }

    /// m.
    pub fn ncols(&self) -> usize {
        self.dim
    }

    /// Column `i` (m entries).
    pub fn column(&self, i: usize) -> &[f64] {
        assert!(i < self.dim, "column {i} of {}", self.dim);
        &self.data.as_slice()[i * MAX_TASK_DIM..i * MAX_TASK_DIM + self.dim]
    }

    /// The matrix as a nalgebra view (for arithmetic).
    pub fn view(&self) -> DMatrixView<'_, f64, U1, U6> {
        self.data.view((0, 0), (self.dim, self.dim))
    }
}

impl PartialEq for TaskMatrix {
    fn eq(&self, other: &Self) -> bool {
        self.view() == other.view()
    }
}

impl std::fmt::Debug for TaskMatrix {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.view().fmt(f)
    }
}

/// An ellipsoid given by its semi-axes: radius i along unit vector `axes` column i (a view
/// of the [`Measures`] it comes from).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ellipsoid<'a> {
    /// Semi-axis lengths, descending for velocity ellipsoids; `None` = infinite.
    pub radii: TaskVector<Option<f64>>,
    /// Unit principal directions, m×m: column i is the axis of `radii[i]`.
    pub axes: &'a TaskMatrix,
    /// Volume c_m·Πradii (Lim eq. 2.18); `None` = infinite.
    pub volume: Option<f64>,
}

/// Every single-Jacobian measure of the source documents for one row selection of at most
/// [`MAX_TASK_DIM`] rows, stored inline (no heap). The velocity and force ellipsoids share
/// their axes and follow from σ: [`Measures::ellipsoid`], [`Measures::force_ellipsoid`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measures {
    /// σ₁ ≥ … ≥ σ_m ≥ 0 (m = number of rows); σ at or below the rank tolerance are 0.
    pub singular_values: TaskVector<f64>,
    /// Number of σ above the tolerance.
    pub rank: usize,
    /// Yoshikawa w = Πσᵢ = √det(JJᵀ) (Lim eqs 2.17, 2.19; Jun eq. 4 for a row selection).
    pub yoshikawa: f64,
    /// σ_max/σ_min ≥ 1 (Lim eq. 2.23, corrected); `None` when singular (infinite).
    pub condition_number: Option<f64>,
    /// σ_min/σ_max ∈ [0, 1] (Lim eq. 2.25).
    pub isotropy: f64,
    /// Hong's index w·isotropy (Lim eq. 4.1).
    pub hong: f64,
    /// Force manipulability √det((JJᵀ)⁻¹) = 1/w (Jun eq. 7); `None` when singular.
    pub force_manipulability: Option<f64>,
    /// Principal directions uᵢ (m×m, column i belongs to σᵢ): the axes of both ellipsoids.
    pub axes: TaskMatrix,
}

impl Measures {
    /// Measures from a spectrum: `sigma` descending (m ≤ [`MAX_TASK_DIM`] entries), `u`
    /// with m rows whose first m columns match σ. σ at or below `tolerance` (≥ 0) count as
    /// zero and are reported as 0.
    ///
    /// # Panics
    /// When m exceeds [`MAX_TASK_DIM`] or `u` has not m rows.
    pub fn from_spectrum(sigma: &[f64], u: &DMatrix<f64>, tolerance: f64) -> Measures {
        let m = sigma.len();
        assert_eq!(u.nrows(), m, "u has one row per σ");
        Measures::from_parts(
            sigma,
            TaskMatrix::from_column_slice(m, &u.as_slice()[..m * m]),
            tolerance,
        )
    }

    /// [`Measures::from_spectrum`] with the axes already in place.
    pub(crate) fn from_parts(sigma: &[f64], axes: TaskMatrix, tolerance: f64) -> Measures {
        let m = sigma.len();
        let mut sigma = TaskVector::from_slice(sigma);
        // σ at or below the tolerance are numerically zero: they are reported as 0, so that
        // a rank-deficient Jacobian has w = isotropy = Hong = 0 exactly rather than
        // round-off of order ε·σ₁ (the rank decision and these measures agree).
        for s in &mut sigma.values[..m] {
            if *s <= tolerance {
                *s = 0.0;
            }
        }
        let rank = sigma.iter().filter(|&&s| s > tolerance).count();
        let full = rank == m;
        let s_max = sigma.first().copied().unwrap_or(0.0);
        let s_min = sigma.last().copied().unwrap_or(0.0);
        let w: f64 = sigma.iter().product();
        let isotropy = if s_max > 0.0 { s_min / s_max } else { 0.0 };
        Measures {
            singular_values: sigma,
            rank,
            yoshikawa: w,
            condition_number: full.then(|| s_max / s_min),
            isotropy,
            hong: w * isotropy,
            force_manipulability: full.then(|| 1.0 / w),
            axes,
        }
    }

    /// Velocity ellipsoid ẋᵀ(JJᵀ)⁻¹ẋ ≤ 1: radii σᵢ along uᵢ, volume c_m·w (Lim §2.4.1.1,
    /// eq. 2.18).
    pub fn ellipsoid(&self) -> Ellipsoid<'_> {
        let c_m = ellipsoid_volume_coefficient(self.singular_values.len);
        self.ellipsoid_with(Some, Some(c_m * self.yoshikawa))
    }

    /// Force ellipsoid Fᵀ(JJᵀ)F ≤ 1 (Jun eq. 8, corrected): radii 1/σᵢ along uᵢ (`None`,
    /// infinite, where σᵢ is zero), volume c_m/w (`None` when singular).
    pub fn force_ellipsoid(&self) -> Ellipsoid<'_> {
        let c_m = ellipsoid_volume_coefficient(self.singular_values.len);
        self.ellipsoid_with(
            |s| (s > 0.0).then(|| 1.0 / s),
            self.force_manipulability.map(|_| c_m / self.yoshikawa),
        )
    }

    /// An ellipsoid on the singular directions uᵢ with radii `radius(σᵢ)`.
    fn ellipsoid_with(
        &self,
        radius: impl Fn(f64) -> Option<f64>,
        volume: Option<f64>,
    ) -> Ellipsoid<'_> {
        let mut radii = TaskVector::from_slice(&[None; MAX_TASK_DIM][..self.singular_values.len]);
        for (r, &s) in radii.values.iter_mut().zip(&*self.singular_values) {
            *r = radius(s);
        }
        Ellipsoid {
            radii,
            axes: &self.axes,
            volume,
        }
    }
}

/// A measured task space has at most [`MAX_TASK_DIM`] rows.
pub(crate) fn check_task_dim(m: usize) -> Result<(), Error> {
    if m > MAX_TASK_DIM {
        return Err(Error::InvalidRows {
            reason: format!("{m} rows; the measures take at most {MAX_TASK_DIM}"),
        });
    }
    Ok(())
}

/// Measures of a Jacobian (m×n with m ≤ [`MAX_TASK_DIM`], e.g. a row selection).
///
/// For m ≤ n (every task selection of a 6-row Jacobian) the m rows of J are rotated by
/// one-sided Jacobi until orthogonal (`jacobi`): the accumulated rotations are U (the
/// ellipsoid axes) and the row lengths are σ; V is never formed. For m > n, [`full_svd`].
/// Rank tolerance: [`RANK_TOLERANCE`]·σ₁, as [`full_svd`].
pub fn measures(j: &DMatrix<f64>) -> Result<Measures, Error> {
    check_jacobian(j)?;
    check_task_dim(j.nrows())?;
    if j.nrows() > j.ncols() {
        return measures_from_svd(&full_svd(j)?);
    }
    Ok(wide_measures(j, j.nrows(), |p| p))
}

/// Measures of the rows `rows` of `j` (Jun eq. 9), as [`measures`] of [`select_rows`] but
/// without forming the selection.
pub fn row_measures(j: &DMatrix<f64>, rows: &[usize]) -> Result<Measures, Error> {
    check_rows(j, rows)?;
    check_jacobian(j)?;
    check_task_dim(rows.len())?;
    if rows.len() > j.ncols() {
        return measures_from_svd(&full_svd(&j.select_rows(rows))?);
    }
    Ok(wide_measures(j, rows.len(), |p| rows[p]))
}

/// [`row_measures`] of two row selections of the same size at once (the analysis's
/// translational and rotational rows), with identical results: the two independent Jacobi
/// problems are swept in lockstep, so the processor overlaps their rotations, which within
/// one 3-row problem all depend on each other.
pub fn row_measures_pair(j: &DMatrix<f64>, rows: [&[usize]; 2]) -> Result<[Measures; 2], Error> {
    check_rows(j, rows[0])?;
    check_rows(j, rows[1])?;
    check_jacobian(j)?;
    let (g, n) = (rows[0].len(), j.ncols());
    if rows[1].len() != g || g > n || g > MAX_TASK_DIM {
        return Ok([row_measures(j, rows[0])?, row_measures(j, rows[1])?]);
    }
    let k = 2 * g;
    jacobi::with_scratch(k * n + 2 * g * g + k, |scratch: &mut [f64]| {
        let (a, rest) = scratch.split_at_mut(k * n);
        let (w, sigma) = rest.split_at_mut(2 * g * g);
        for (v, &r) in a
            .chunks_exact_mut(n)
            .zip(rows[0].iter().chain(rows[1].iter()))
        {
            for (c, x) in v.iter_mut().enumerate() {
                *x = j[(r, c)];
            }
        }
        jacobi::with_scratch(k, |order: &mut [usize]| {
            jacobi::decompose(a, n, 2, w, sigma, order);
        });
        let measures = |grp: usize| {
            let tol = RANK_TOLERANCE * sigma[grp * g];
            Measures::from_parts(
                &sigma[grp * g..(grp + 1) * g],
                TaskMatrix::from_column_slice(g, &w[grp * g * g..(grp + 1) * g * g]),
                tol,
            )
        };
        Ok([measures(0), measures(1)])
    })
}

/// Measures of the m×n matrix whose row p is row `row(p)` of `j`, for m ≤ n (the callers
/// check; m ≤ [`MAX_TASK_DIM`]), by one-sided Jacobi on its rows.
fn wide_measures(j: &DMatrix<f64>, m: usize, row: impl Fn(usize) -> usize) -> Measures {
    let n = j.ncols();
    let mut u = [0.0; MAX_TASK_DIM * MAX_TASK_DIM];
    let mut sigma = [0.0; MAX_TASK_DIM];
    let (u, sigma) = (&mut u[..m * m], &mut sigma[..m]);
    jacobi::with_scratch(m * n, |a: &mut [f64]| {
        for (p, v) in a.chunks_exact_mut(n).enumerate() {
            let r = row(p);
            for (c, x) in v.iter_mut().enumerate() {
                *x = j[(r, c)];
            }
        }
        jacobi::with_scratch(m, |order: &mut [usize]| {
            jacobi::decompose(a, n, 1, u, sigma, order);
        });
    });
    Measures::from_parts(
        sigma,
        TaskMatrix::from_column_slice(m, u),
        RANK_TOLERANCE * sigma[0],
    )
}

/// Measures from an SVD already computed of an m×`n` Jacobian (m ≤ [`MAX_TASK_DIM`]).
pub fn measures_from_svd(svd: &FullSvd) -> Result<Measures, Error> {
    check_task_dim(svd.u.nrows())?;
    Ok(Measures::from_spectrum(
        svd.sigma.as_slice(),
        &svd.u,
        svd.tolerance,
    ))
}

/// The rows of `j` listed in `rows` (Jun eq. 9: the task-oriented Jacobian).
pub fn select_rows(j: &DMatrix<f64>, rows: &[usize]) -> Result<DMatrix<f64>, Error> {
    check_rows(j, rows)?;
    Ok(j.select_rows(rows))
}

/// `rows` must be a non-empty list of distinct rows of `j`.
fn check_rows(j: &DMatrix<f64>, rows: &[usize]) -> Result<(), Error> {
    if rows.is_empty() {
        return Err(Error::InvalidRows {
            reason: "at least one row is needed".into(),
        });
    }
    for (i, &r) in rows.iter().enumerate() {
        if r >= j.nrows() {
            return Err(Error::InvalidRows {
                reason: format!("row {r} is out of range 0..{}", j.nrows()),
            });
        }
        if rows[..i].contains(&r) {
            return Err(Error::InvalidRows {
                reason: format!("row {r} is repeated"),
            });
        }
    }
    Ok(())
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

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    /// The inline storage holds exactly what the heap matrices did: the m×m axes (against
    /// nalgebra's DMatrix of the same column-major data) and σ, and the two ellipsoids follow
    /// Lim eq. 2.18 (velocity: radii σᵢ, volume c_m·w) and Jun eq. 8 corrected (force:
    /// radii 1/σᵢ, volume c_m/w; infinite where σ = 0).
    #[test]
    fn inline_measures_match_heap_matrices_and_closed_forms() {
        for m in 1..=MAX_TASK_DIM {
            let data: Vec<f64> = (0..m * m).map(|i| (i as f64 * 0.37).sin()).collect();
            let heap = DMatrix::from_column_slice(m, m, &data);
            let sigma: Vec<f64> = (0..m).map(|i| 3.0 - 0.4 * i as f64).collect();
            let full = Measures::from_spectrum(&sigma, &heap, 0.0);
            assert_eq!(full.axes.view(), heap);
            for i in 0..m {
                assert_eq!(full.axes.column(i), heap.column(i).as_slice());
            }
            assert_eq!(&*full.singular_values, &sigma[..]);
            let c_m = ellipsoid_volume_coefficient(m);
            let w: f64 = sigma.iter().product();
            let e = full.ellipsoid();
            assert_eq!(e.volume, Some(c_m * w));
            assert!(e.radii.iter().zip(&sigma).all(|(r, s)| *r == Some(*s)));
            let f = full.force_ellipsoid();
            assert_eq!(f.volume, Some(c_m / w));
            assert!(f.radii.iter().zip(&sigma).all(|(r, s)| *r == Some(1.0 / s)));
            // The last σ below the tolerance: rank m − 1, force radius and volume infinite.
            let singular = Measures::from_spectrum(&sigma, &heap, sigma[m - 1]);
            assert_eq!(singular.rank, m - 1);
            assert_eq!(singular.force_ellipsoid().radii[m - 1], None);
            assert_eq!(singular.force_ellipsoid().volume, None);
            assert_eq!(singular.ellipsoid().volume, Some(0.0));
        }
    }

    /// More task rows than a spatial Jacobian has are refused, not truncated.
    #[test]
    fn more_than_six_rows_is_an_error() {
        let j = DMatrix::from_fn(7, 8, |r, c| (r + 2 * c) as f64);
        assert!(measures(&j).is_err());
        assert!(measures_from_svd(&full_svd(&j).unwrap()).is_err());
    }
}
