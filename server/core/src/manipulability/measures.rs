//! Singular-value measures of a Jacobian (Lim §2.4, §3.5; Jun §2.1; RX90 report part VI).

use nalgebra::{DMatrix, DVector, SVD, SymmetricEigen};

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
}

/// Computes the full SVD of `j` (m×n).
pub fn full_svd(j: &DMatrix<f64>) -> Result<FullSvd, Error> {
    svd_with(j, true)
}

/// SVD of `j`; when `want_v` is false, `v` is left empty (0×0), which saves the null-space
/// completion when only the measures are needed.
pub fn svd_with(j: &DMatrix<f64>, want_v: bool) -> Result<FullSvd, Error> {
    let (m, n) = j.shape();
    if m == 0 || n == 0 {
        return Err(Error::SizeMismatch {
            what: "jacobian",
            input: 0,
            required: 1,
        });
    }
    if j.iter().any(|v| !v.is_finite()) {
        return Err(Error::NonFinite {
            what: "jacobian",
            index: 0,
        });
    }
    let not_converged = Error::NotConverged {
        what: "svd",
        iterations: 200,
        residual: f64::NAN,
    };
    // 6×6 (every 6-DOF arm's full Jacobian) takes nalgebra's stack-allocated path, about a
    // third faster than the heap one; results are converted to the common dynamic form.
    let svd = if (m, n) == (6, 6) {
        let s6 = nalgebra::Matrix6::from_iterator(j.iter().copied());
        let s = nalgebra::SVD::try_new(s6, true, want_v, f64::EPSILON, 200)
            .ok_or(not_converged.clone())?;
        SVD {
            u: s.u.map(|u| DMatrix::from_column_slice(6, 6, u.as_slice())),
            v_t: s
                .v_t
                .map(|v| DMatrix::from_column_slice(6, 6, v.as_slice())),
            singular_values: DVector::from_column_slice(s.singular_values.as_slice()),
        }
    } else {
        SVD::try_new(j.clone(), true, want_v, f64::EPSILON, 200).ok_or(not_converged.clone())?
    };
    let Some(u) = svd.u else {
        return Err(not_converged);
    };
    let k = svd.singular_values.len();
    let mut order: Vec<usize> = (0..k).collect();
    order.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]));
    let mut u_sorted = DMatrix::zeros(m, k);
    let mut v_sorted = DMatrix::zeros(if want_v { n } else { 0 }, if want_v { k } else { 0 });
    let mut sigma = DVector::zeros(m);
    for (dst, &src) in order.iter().enumerate() {
        u_sorted.set_column(dst, &u.column(src));
        if let Some(v_t) = &svd.v_t {
            v_sorted.set_column(dst, &v_t.row(src).transpose());
        }
        sigma[dst] = svd.singular_values[src].max(0.0);
    }
    Ok(FullSvd {
        u: complete_basis(&u_sorted),
        sigma,
        v: if want_v {
            complete_basis(&v_sorted)
        } else {
            v_sorted
        },
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
    /// Unit principal directions (each of length m), matching `radii`.
    pub axes: Vec<Vec<f64>>,
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
        let axes: Vec<Vec<f64>> = (0..m)
            .map(|i| u.column(i).iter().copied().collect())
            .collect();
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
/// within that of a singularity is reported as singular. For m > n the SVD is used
/// ([`svd_with`]), with the default tolerance.
pub fn measures(j: &DMatrix<f64>) -> Result<Measures, Error> {
    let (m, n) = j.shape();
    if m == 0 || n == 0 {
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
    if m > n {
        let svd = svd_with(j, false)?;
        return Ok(measures_from_svd(&svd, n));
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
pub fn measures_from_svd(svd: &FullSvd, n: usize) -> Measures {
    let tol = default_tolerance(svd.sigma.len(), n, svd.sigma[0]);
    Measures::from_spectrum(svd.sigma.as_slice(), &svd.u, tol)
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

/// The four fundamental subspaces from the SVD (RX90 report part VI), each a list of
/// orthonormal vectors.
#[derive(Debug, Clone, PartialEq)]
pub struct Subspaces {
    /// Rank used to split them.
    pub rank: usize,
    /// V_{r+1..n}: joint velocities giving no end-effector motion (null space of J).
    pub null_space: Vec<Vec<f64>>,
    /// V_{1..r}: joint velocities that generate end-effector motion.
    pub generating: Vec<Vec<f64>>,
    /// U_{1..r}: achievable end-effector velocities (range of J).
    pub range: Vec<Vec<f64>>,
    /// U_{r+1..m}: end-effector velocities that cannot be generated.
    pub unreachable: Vec<Vec<f64>>,
}

/// Splits the SVD of `j` into its subspaces with the default rank tolerance.
pub fn subspaces(j: &DMatrix<f64>) -> Result<Subspaces, Error> {
    Ok(subspaces_from_svd(&full_svd(j)?))
}

/// Subspaces from a full SVD (with `v`).
pub fn subspaces_from_svd(svd: &FullSvd) -> Subspaces {
    let (m, n) = (svd.u.nrows(), svd.v.nrows());
    let tol = default_tolerance(m, n, svd.sigma[0]);
    let rank = svd
        .sigma
        .iter()
        .take(m.min(n))
        .filter(|&&s| s > tol)
        .count();
    let cols = |mat: &DMatrix<f64>, range: std::ops::Range<usize>| -> Vec<Vec<f64>> {
        range
            .map(|i| mat.column(i).iter().copied().collect())
            .collect()
    };
    Subspaces {
        rank,
        null_space: cols(&svd.v, rank..n),
        generating: cols(&svd.v, 0..rank),
        range: cols(&svd.u, 0..rank),
        unreachable: cols(&svd.u, rank..m),
    }
}
