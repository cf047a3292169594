//! Singular-value measures of a Jacobian (Lim §2.4, §3.5; Jun §2.1; RX90 report part VI):
//! Yoshikawa, condition number, isotropy, Hong, force manipulability and the velocity and
//! force ellipsoids, of the whole Jacobian or of a selection of its rows.
//!
//! The full SVD and the subspaces live in `svd`, the inline storage in `task`; both are
//! re-exported here.

use nalgebra::DMatrix;

use super::jacobi;
use super::svd::check_jacobian;
pub use super::svd::{
    FullSvd, RANK_TOLERANCE, Subspaces, complete_basis, default_tolerance, full_svd, subspaces,
    subspaces_from_svd,
};
pub(crate) use super::task::check_task_dim;
pub use super::task::{MAX_TASK_DIM, TaskMatrix, TaskVector};
use crate::Error;

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
    let [m] = wide_measures(j, j.nrows(), |p| p);
    Ok(m)
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
    let [m] = wide_measures(j, rows.len(), |p| rows[p]);
    Ok(m)
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
    Ok(wide_measures(j, g, |p| {
        if p < g { rows[0][p] } else { rows[1][p - g] }
    }))
}

/// Measures of `N` m×n matrices, m ≤ n (the callers check; m ≤ [`MAX_TASK_DIM`]), whose
/// rows are rows of `j`: row p of problem G is row `row(G·m + p)` of `j`. One-sided Jacobi
/// on the rows, the `N` problems swept in lockstep.
fn wide_measures<const N: usize>(
    j: &DMatrix<f64>,
    m: usize,
    row: impl Fn(usize) -> usize,
) -> [Measures; N] {
    let (n, k) = (j.ncols(), N * m);
    jacobi::with_scratch(k * n, |a: &mut [f64]| {
        for (p, v) in a.chunks_exact_mut(n).enumerate() {
            let r = row(p);
            for (c, x) in v.iter_mut().enumerate() {
                *x = j[(r, c)];
            }
        }
        jacobi::with_scratch(k * m + k, |out: &mut [f64]| {
            let (u, sigma) = out.split_at_mut(k * m);
            jacobi::with_scratch(k, |order: &mut [usize]| {
                jacobi::decompose(a, n, N, u, sigma, order);
            });
            std::array::from_fn(|grp| {
                Measures::from_parts(
                    &sigma[grp * m..(grp + 1) * m],
                    TaskMatrix::from_column_slice(m, &u[grp * m * m..(grp + 1) * m * m]),
                    RANK_TOLERANCE * sigma[grp * m],
                )
            })
        })
    })
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
