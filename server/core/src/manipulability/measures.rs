//! Singular-value measures of a Jacobian (Lim §2.4, §3.5; Jun §2.1; RX90 report part VI).

use nalgebra::{DMatrix, DVector};

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

/// An ellipsoid given by its semi-axes: radius i along unit vector `axes[i]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Ellipsoid {
    /// Semi-axis lengths, descending for velocity ellipsoids; `None` = infinite.
    pub radii: Vec<Option<f64>>,
    /// Unit principal directions, m×m: column i is the axis of `radii[i]`.
    pub axes: DMatrix<f64>,
    /// Volume c_m·Πradii (Lim eq. 2.18); `None` = infinite.
    pub volume: Option<f64>,
}

/// Every single-Jacobian measure of the source documents for one row selection.
#[derive(Debug, Clone, PartialEq)]
pub struct Measures {
    /// σ₁ ≥ … ≥ σ_m ≥ 0 (m = number of rows); σ at or below the rank tolerance are 0.
    pub singular_values: Vec<f64>,
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
    /// Velocity ellipsoid ẋᵀ(JJᵀ)⁻¹ẋ ≤ 1: radii σᵢ along uᵢ (Lim §2.4.1.1).
    pub ellipsoid: Ellipsoid,
    /// Force ellipsoid Fᵀ(JJᵀ)F ≤ 1 (Jun eq. 8, corrected): radii 1/σᵢ along uᵢ.
    pub force_ellipsoid: Ellipsoid,
}

impl Measures {
    /// Measures from a spectrum: `sigma` descending (m entries), `u` m×m with matching columns.
    /// σ at or below `tolerance` count as zero and are reported as 0.
    pub fn from_spectrum(sigma: &[f64], u: &DMatrix<f64>, tolerance: f64) -> Measures {
        Measures::from_owned_spectrum(
            sigma.to_vec(),
            u.columns(0, sigma.len()).into_owned(),
            tolerance,
        )
    }

    /// [`Measures::from_spectrum`] taking ownership (`u` is exactly m×m).
    fn from_owned_spectrum(mut sigma: Vec<f64>, u: DMatrix<f64>, tolerance: f64) -> Measures {
        let m = sigma.len();
        // σ at or below the tolerance are numerically zero: they are reported as 0, so that
        // a rank-deficient Jacobian has w = isotropy = Hong = 0 exactly rather than
        // round-off of order ε·σ₁ (the rank decision and these measures agree).
        for s in &mut sigma {
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
        let c_m = ellipsoid_volume_coefficient(m);
        let force_radii: Vec<Option<f64>> = sigma
            .iter()
            .map(|&s| if s > tolerance { Some(1.0 / s) } else { None })
            .collect();
        let radii = sigma.iter().map(|&s| Some(s)).collect();
        Measures {
            singular_values: sigma,
            rank,
            yoshikawa: w,
            condition_number: full.then(|| s_max / s_min),
            isotropy,
            hong: w * isotropy,
            force_manipulability: full.then(|| 1.0 / w),
            ellipsoid: Ellipsoid {
                radii,
                axes: u.clone(),
                volume: Some(c_m * w),
            },
            force_ellipsoid: Ellipsoid {
                radii: force_radii,
                axes: u,
                volume: full.then(|| c_m / w),
            },
        }
    }
}

/// Measures of a Jacobian (any m×n, e.g. a row selection).
///
/// For m ≤ n (every task selection of a 6-row Jacobian) the m rows of J are rotated by
/// one-sided Jacobi until orthogonal (`jacobi`): the accumulated rotations are U (the
/// ellipsoid axes) and the row lengths are σ; V is never formed. For m > n, [`full_svd`].
/// Rank tolerance: [`RANK_TOLERANCE`]·σ₁, as [`full_svd`].
pub fn measures(j: &DMatrix<f64>) -> Result<Measures, Error> {
    check_jacobian(j)?;
    if j.nrows() > j.ncols() {
        return Ok(measures_from_svd(&full_svd(j)?));
    }
    Ok(wide_measures(j, j.nrows(), |p| p))
}

/// Measures of the rows `rows` of `j` (Jun eq. 9), as [`measures`] of [`select_rows`] but
/// without forming the selection.
pub fn row_measures(j: &DMatrix<f64>, rows: &[usize]) -> Result<Measures, Error> {
    check_rows(j, rows)?;
    check_jacobian(j)?;
    if rows.len() > j.ncols() {
        return Ok(measures_from_svd(&full_svd(&j.select_rows(rows))?));
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
    if rows[1].len() != g || g > n {
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
            Measures::from_owned_spectrum(
                sigma[grp * g..(grp + 1) * g].to_vec(),
                DMatrix::from_column_slice(g, g, &w[grp * g * g..(grp + 1) * g * g]),
                tol,
            )
        };
        Ok([measures(0), measures(1)])
    })
}

/// Measures of the m×n matrix whose row p is row `row(p)` of `j`, for m ≤ n (the callers
/// check), by one-sided Jacobi on its rows.
fn wide_measures(j: &DMatrix<f64>, m: usize, row: impl Fn(usize) -> usize) -> Measures {
    let n = j.ncols();
    let mut u = DMatrix::<f64>::zeros(m, m);
    let mut sigma = vec![0.0; m];
    jacobi::with_scratch(m * n, |a: &mut [f64]| {
        for (p, v) in a.chunks_exact_mut(n).enumerate() {
            let r = row(p);
            for (c, x) in v.iter_mut().enumerate() {
                *x = j[(r, c)];
            }
        }
        jacobi::with_scratch(m, |order: &mut [usize]| {
            jacobi::decompose(a, n, 1, u.as_mut_slice(), &mut sigma, order);
        });
    });
    let tol = RANK_TOLERANCE * sigma[0];
    Measures::from_owned_spectrum(sigma, u, tol)
}

/// Measures from an SVD already computed of an m×`n` Jacobian.
pub fn measures_from_svd(svd: &FullSvd) -> Measures {
    Measures::from_owned_spectrum(svd.sigma.as_slice().to_vec(), svd.u.clone(), svd.tolerance)
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
    pub fn into_measures_and_subspaces(self) -> (Measures, Subspaces) {
        let (m, n) = (self.u.nrows(), self.v.nrows());
        let rank = self.rank();
        let null_space = columns(&self.v, rank..n);
        let generating = if rank == n {
            self.v
        } else {
            columns(&self.v, 0..rank)
        };
        let subspaces = Subspaces {
            rank,
            null_space,
            generating,
            range: columns(&self.u, 0..rank),
            unreachable: columns(&self.u, rank..m),
        };
        let measures =
            Measures::from_owned_spectrum(Vec::from(self.sigma.data), self.u, self.tolerance);
        (measures, subspaces)
    }
}
