//! JSON shapes shared by several routes (measures, ellipsoids, poses, polytopes).
//! Infinite values are `null`, never NaN.

use nalgebra::DMatrix;
use seaarms_core::manipulability::{Ellipsoid, Measures};
use serde::Serialize;

/// The pose wire type, shared with the session socket ([`crate::protocol`]).
pub use crate::protocol::PoseOut;

/// The columns of a matrix, each as a list (bases of subspaces, ellipsoid axes).
pub fn columns(m: &DMatrix<f64>) -> Vec<Vec<f64>> {
    m.column_iter()
        .map(|c| c.iter().copied().collect())
        .collect()
}

/// A matrix as a list of rows.
pub fn rows(m: &DMatrix<f64>) -> Vec<Vec<f64>> {
    (0..m.nrows())
        .map(|r| m.row(r).iter().copied().collect())
        .collect()
}

/// An ellipsoid: radii (null = infinite), unit axes (one per radius), volume.
#[derive(Debug, Clone, Serialize)]
pub struct EllipsoidOut {
    /// Semi-axis lengths.
    pub radii: Vec<Option<f64>>,
    /// Unit principal directions.
    pub axes: Vec<Vec<f64>>,
    /// c_m·Πradii (Lim eq. 2.18); null when infinite.
    pub volume: Option<f64>,
}

impl From<&Ellipsoid<'_>> for EllipsoidOut {
    fn from(e: &Ellipsoid<'_>) -> EllipsoidOut {
        EllipsoidOut {
            radii: e.radii.to_vec(),
            axes: (0..e.axes.ncols())
                .map(|i| e.axes.column(i).to_vec())
                .collect(),
            volume: e.volume,
        }
    }
}

/// The measures of one Jacobian (or row selection).
#[derive(Debug, Clone, Serialize)]
pub struct MeasuresOut {
    /// σ₁ ≥ … ≥ σ_m.
    pub singular_values: Vec<f64>,
    /// Numerical rank.
    pub rank: usize,
    /// √det(JJᵀ).
    pub yoshikawa: f64,
    /// σmax/σmin; null at a singularity.
    pub condition_number: Option<f64>,
    /// σmin/σmax.
    pub isotropy: f64,
    /// Yoshikawa × isotropy (Lim eq. 4.1).
    pub hong: f64,
    /// √det((JJᵀ)⁻¹) (Jun eq. 7); null at a singularity.
    pub force_manipulability: Option<f64>,
    /// Velocity ellipsoid.
    pub ellipsoid: EllipsoidOut,
    /// Force ellipsoid (Jun eq. 8, corrected).
    pub force_ellipsoid: EllipsoidOut,
}

impl From<&Measures> for MeasuresOut {
    fn from(m: &Measures) -> MeasuresOut {
        MeasuresOut {
            singular_values: m.singular_values.to_vec(),
            rank: m.rank,
            yoshikawa: m.yoshikawa,
            condition_number: m.condition_number,
            isotropy: m.isotropy,
            hong: m.hong,
            force_manipulability: m.force_manipulability,
            ellipsoid: (&m.ellipsoid()).into(),
            force_ellipsoid: (&m.force_ellipsoid()).into(),
        }
    }
}
