//! Singular-value measures of a Jacobian (Lim §2.4, §3.5; Jun §2.1; RX90 report part VI).

use nalgebra::{DMatrix, DVector, SymmetricEigen};

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
    if let Some(index) = j.iter().position(|v| !v.is_finite()) {
        return Err(Error::NonFinite {
            what: "jacobian",
            index,
        });
    }
    Ok(())
}

/// Relative rank tolerance of the eigenvalue routes: σ ≤ this·σ₁ counts as zero. Squaring
/// J into JᵀJ or JJᵀ leaves σᵢ an absolute error near √(nε)·σ₁ ≈ 4·10⁻⁸σ₁ for n ≤ 7, so the
/// threshold is set four times above that.
pub const EIGEN_RANK_TOLERANCE: f64 = 1.5e-7;

/// Full SVD of `j` (m×n) from the symmetric eigenproblem JᵀJ = VΛVᵀ: σᵢ = √λᵢ, the columns of
/// V as they come, uᵢ = Jvᵢ/σᵢ for σᵢ above the tolerance, and the remaining columns of U
/// completed to an orthonormal basis. One n×n eigen solve (stack-allocated for n = 6) gives
/// everything the analysis needs — measures, null space, range — at about a third of the
/// instructions of a Golub–Kahan SVD.
/// Rank tolerance: [`EIGEN_RANK_TOLERANCE`]·σ₁.
pub fn full_svd(j: &DMatrix<f64>) -> Result<FullSvd, Error> {
    let (m, n) = j.shape();
    check_jacobian(j)?;
    let (lambda, vectors): (Vec<f64>, DMatrix<f64>) = if n == 6 {
        let mut jtj = nalgebra::Matrix6::zeros();
        for r in j.row_iter() {
            let v = nalgebra::Vector6::new(r[0], r[1], r[2], r[3], r[4], r[5]);
            jtj += v * v.transpose();
        }
        let eig = nalgebra::SymmetricEigen::new(jtj);
        (
            eig.eigenvalues.iter().copied().collect(),
            DMatrix::from_column_slice(6, 6, eig.eigenvectors.as_slice()),
        )
    } else {
        let eig = SymmetricEigen::new(j.transpose() * j);
        (eig.eigenvalues.iter().copied().collect(), eig.eigenvectors)
    };
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| lambda[b].total_cmp(&lambda[a]));
    let mut v = DMatrix::zeros(n, n);
    for (dst, &src) in order.iter().enumerate() {
        v.set_column(dst, &vectors.column(src));
    }
    let k = m.min(n);
    let mut sigma = DVector::zeros(m);
    for i in 0..k {
        sigma[i] = lambda[order[i]].max(0.0).sqrt();
    }
    let tolerance = EIGEN_RANK_TOLERANCE * sigma[0];
    let rank = (0..k).filter(|&i| sigma[i] > tolerance).count();
    let mut u_r = DMatrix::zeros(m, rank);
    for i in 0..rank {
        u_r.column_mut(i).gemv(1.0 / sigma[i], j, &v.column(i), 0.0);
        // Modified Gram–Schmidt against the earlier columns: for σᵢ close to the tolerance,
        // Jvᵢ/σᵢ carries an error of order ε·σ₁/σᵢ that would spoil U's orthogonality.
        for k in 0..i {
            let d = u_r.column(k).dot(&u_r.column(i));
            let uk = u_r.column(k).into_owned();
            u_r.column_mut(i).axpy(-d, &uk, 1.0);
        }
        let norm = u_r.column(i).norm();
        if norm > 0.0 {
            u_r.column_mut(i).unscale_mut(norm);
        }
    }
    Ok(FullSvd {
        u: complete_basis(&u_r),
        sigma,
        v,
        tolerance,
    })
}

/// Extends the orthonormal columns of `b` (k×r, r ≤ k) to a k×k orthogonal matrix, using the
/// eigenvectors of the projector I − BBᵀ onto the complement.
pub fn complete_basis(b: &DMatrix<f64>) -> DMatrix<f64> {
    let (k, r) = b.shape();
    if r >= k {
        return b.columns(0, k).into_owned();
    }
    let p = DMatrix::identity(k, k) - b * b.transpose();
    let eig = SymmetricEigen::new(p);
    let mut idx: Vec<usize> = (0..k).collect();
    idx.sort_by(|&a, &c| eig.eigenvalues[c].total_cmp(&eig.eigenvalues[a]));
    let mut out = DMatrix::zeros(k, k);
    out.columns_mut(0, r).copy_from(b);
    for (dst, &src) in idx.iter().take(k - r).enumerate() {
        out.set_column(r + dst, &eig.eigenvectors.column(src));
    }
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
    /// σ₁ ≥ … ≥ σ_m ≥ 0 (m = number of rows).
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
    pub fn from_spectrum(sigma: &[f64], u: &DMatrix<f64>, tolerance: f64) -> Measures {
        let m = sigma.len();
        let rank = sigma.iter().filter(|&&s| s > tolerance).count();
        let full = rank == m;
        let s_max = sigma.first().copied().unwrap_or(0.0);
        let s_min = sigma.last().copied().unwrap_or(0.0);
        let w: f64 = sigma.iter().product();
        let isotropy = if s_max > 0.0 { s_min / s_max } else { 0.0 };
        let axes = u.columns(0, m).into_owned();
        let c_m = ellipsoid_volume_coefficient(m);
        let force_radii: Vec<Option<f64>> = sigma
            .iter()
            .map(|&s| if s > tolerance { Some(1.0 / s) } else { None })
            .collect();
        Measures {
            singular_values: sigma.to_vec(),
            rank,
            yoshikawa: w,
            condition_number: full.then(|| s_max / s_min),
            isotropy,
            hong: w * isotropy,
            force_manipulability: full.then(|| 1.0 / w),
            ellipsoid: Ellipsoid {
                radii: sigma.iter().map(|&s| Some(s)).collect(),
                axes: axes.clone(),
                volume: Some(c_m * w),
            },
            force_ellipsoid: Ellipsoid {
                radii: force_radii,
                axes,
                volume: full.then(|| c_m / w),
            },
        }
    }
}

/// Measures of a Jacobian (any m×n, e.g. a row selection).
///
/// For m ≤ n (every task selection of a 6-row Jacobian) the spectrum comes from the
/// symmetric eigenproblem JJᵀ = UΛUᵀ, σᵢ = √λᵢ — Yoshikawa's own route (w = √det JJᵀ, Lim
/// eq. 2.19) and several times faster than a general SVD. Squaring costs accuracy only for
/// σᵢ below √ε·σ₁ ≈ 1.5·10⁻⁸σ₁, so the rank tolerance on this path is √(mε)·σ₁: a posture
/// within that of a singularity is reported as singular. For m > n, [`full_svd`].
pub fn measures(j: &DMatrix<f64>) -> Result<Measures, Error> {
    let (m, n) = j.shape();
    check_jacobian(j)?;
    if m > n {
        return Ok(measures_from_svd(&full_svd(j)?));
    }
    let (lambda, vectors): (Vec<f64>, DMatrix<f64>) = if m == 3 {
        // Static 3×3 path: JJᵀ as a sum of column outer products, no heap.
        let mut a = nalgebra::Matrix3::zeros();
        for c in j.column_iter() {
            let v = nalgebra::Vector3::new(c[0], c[1], c[2]);
            a += v * v.transpose();
        }
        let eig = nalgebra::SymmetricEigen::new(a);
        (
            eig.eigenvalues.iter().copied().collect(),
            DMatrix::from_column_slice(3, 3, eig.eigenvectors.as_slice()),
        )
    } else {
        let eig = SymmetricEigen::new(j * j.transpose());
        (eig.eigenvalues.iter().copied().collect(), eig.eigenvectors)
    };
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&a, &b| lambda[b].total_cmp(&lambda[a]));
    let sigma: Vec<f64> = order.iter().map(|&i| lambda[i].max(0.0).sqrt()).collect();
    let mut u = DMatrix::zeros(m, m);
    for (dst, &src) in order.iter().enumerate() {
        u.set_column(dst, &vectors.column(src));
    }
    let tol = ((m as f64) * f64::EPSILON).sqrt() * sigma[0];
    Ok(Measures::from_spectrum(&sigma, &u, tol))
}

/// Measures from an SVD already computed of an m×`n` Jacobian.
pub fn measures_from_svd(svd: &FullSvd) -> Measures {
    Measures::from_spectrum(svd.sigma.as_slice(), &svd.u, svd.tolerance)
}

/// The rows of `j` listed in `rows` (Jun eq. 9: the task-oriented Jacobian).
pub fn select_rows(j: &DMatrix<f64>, rows: &[usize]) -> Result<DMatrix<f64>, Error> {
    if rows.is_empty() {
        return Err(Error::InvalidRows {
            reason: "at least one row is needed".into(),
        });
    }
    let mut seen = [false; 64];
    for &r in rows {
        if r >= j.nrows() {
            return Err(Error::InvalidRows {
                reason: format!("row {r} is out of range 0..{}", j.nrows()),
            });
        }
        if seen[r] {
            return Err(Error::InvalidRows {
                reason: format!("row {r} is repeated"),
            });
        }
        seen[r] = true;
    }
    Ok(j.select_rows(rows))
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
    let tol = svd.tolerance;
    let rank = svd
        .sigma
        .iter()
        .take(m.min(n))
        .filter(|&&s| s > tol)
        .count();
    let cols = |mat: &DMatrix<f64>, range: std::ops::Range<usize>| -> DMatrix<f64> {
        mat.columns(range.start, range.end - range.start)
            .into_owned()
    };
    Subspaces {
        rank,
        null_space: cols(&svd.v, rank..n),
        generating: cols(&svd.v, 0..rank),
        range: cols(&svd.u, 0..rank),
        unreachable: cols(&svd.u, rank..m),
    }
}
