//! Workspace map: translational Yoshikawa, isotropy and Hong over an X–Z grid.

use nalgebra::{Isometry3, UnitQuaternion, Vector3};

use super::{MeasureTriple, check_finite, nominal_orientation, place, reference_posture};
use super::{translational, triple};
use crate::Error;
use crate::ik::{IkOptions, IkTarget, MagnumLengths, dls_ik};
use crate::model::Model;

/// Grid of the workspace map: X–Z plane at a fixed Y, base frame.
#[derive(Debug, Clone, PartialEq)]
pub struct MapSpec {
    /// X range (m).
    pub x_range: [f64; 2],
    /// Z range (m).
    pub z_range: [f64; 2],
    /// Number of X samples (≥ 1).
    pub nx: usize,
    /// Number of Z samples (≥ 1).
    pub nz: usize,
    /// Plane's Y (m).
    pub y: f64,
    /// Fixed end-effector orientation; `None` = position only (the posture then comes from
    /// DLS IK warm-started from the neighbouring cell, so the measures of a redundant task
    /// depend on that continuation; the scan order is deterministic).
    pub orientation: Option<UnitQuaternion<f64>>,
}

impl MapSpec {
    /// The Lim §4.3 case-study window (X 0.5–1.6 m, Z −0.5–1.0 m, Y 0) at 50×50, nominal orientation.
    pub fn case_study(model: &Model) -> MapSpec {
        MapSpec {
            x_range: [0.5, 1.6],
            z_range: [-0.5, 1.0],
            nx: 50,
            nz: 50,
            y: 0.0,
            orientation: Some(nominal_orientation(model)),
        }
    }
}

/// Largest number of map cells.
pub const MAX_CELLS: usize = 250_000;

/// One map cell; measures are `None` when the cell is unreachable (never NaN).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapCell {
    /// X (m).
    pub x: f64,
    /// Z (m).
    pub z: f64,
    /// Translational measures, `None` when unreachable.
    pub measures: Option<MeasureTriple>,
}

/// Workspace map: `cells[iz * nx + ix]`.
#[derive(Debug, Clone, PartialEq)]
pub struct WorkspaceMap {
    /// X samples (m).
    pub x: Vec<f64>,
    /// Z samples (m).
    pub z: Vec<f64>,
    /// Y of the plane (m).
    pub y: f64,
    /// Row-major cells (Z rows, X columns).
    pub cells: Vec<MapCell>,
}

/// Upper bound of the distance from the base to the tool point: Σ(|a| + |d|) + |tool|.
fn reach_bound(model: &Model) -> f64 {
    let links: f64 = model
        .spec
        .joints
        .iter()
        .map(|j| j.a.abs() + j.d.abs())
        .sum();
    links + model.tool.norm() + 1e-9
}

fn samples(range: [f64; 2], n: usize) -> Vec<f64> {
    if n == 1 {
        return vec![0.5 * (range[0] + range[1])];
    }
    (0..n)
        .map(|i| range[0] + (range[1] - range[0]) * i as f64 / (n - 1) as f64)
        .collect()
}

/// Translational Yoshikawa / isotropy / Hong over an X–Z grid (serpentine scan, each cell
/// warm-started from the previous reachable one).
pub fn workspace_map(model: &Model, spec: &MapSpec) -> Result<WorkspaceMap, Error> {
    check_finite("x_range", &spec.x_range)?;
    check_finite("z_range", &spec.z_range)?;
    check_finite("y", &[spec.y])?;
    if spec.nx == 0 || spec.nz == 0 || spec.nx.saturating_mul(spec.nz) > MAX_CELLS {
        return Err(Error::InvalidParameter {
            what: "grid",
            reason: format!("nx, nz ≥ 1 and nx·nz ≤ {MAX_CELLS}"),
        });
    }
    if spec.x_range[0] > spec.x_range[1] || spec.z_range[0] > spec.z_range[1] {
        return Err(Error::InvalidParameter {
            what: "grid",
            reason: "ranges must be [min, max]".into(),
        });
    }
    let xs = samples(spec.x_range, spec.nx);
    let zs = samples(spec.z_range, spec.nz);
    let reach = reach_bound(model);
    let mut cells = vec![
        MapCell {
            x: 0.0,
            z: 0.0,
            measures: None
        };
        spec.nx * spec.nz
    ];
    let magnum = MagnumLengths::from_model(model).is_ok();
    let fallback = reference_posture(model);
    // A warm start from the neighbouring cell converges in a few iterations when the cell is
    // reachable; the mid-range restart gets more. Unreachable cells cost both caps.
    let warm_opts = IkOptions {
        max_iterations: 15,
        ..IkOptions::default()
    };
    let cold_opts = IkOptions {
        max_iterations: 30,
        ..IkOptions::default()
    };
    let mut prev: Option<Vec<f64>> = None;
    for (iz, &z) in zs.iter().enumerate() {
        for k in 0..spec.nx {
            let ix = if iz % 2 == 0 { k } else { spec.nx - 1 - k };
            let x = xs[ix];
            let p = Vector3::new(x, spec.y, z);
            let cell = &mut cells[iz * spec.nx + ix];
            *cell = MapCell {
                x,
                z,
                measures: None,
            };
            if p.norm() > reach {
                continue;
            }
            let q = match spec.orientation {
                Some(rot) if magnum => place(
                    model,
                    &Isometry3::from_parts(p.into(), rot),
                    prev.as_deref(),
                ),
                _ => {
                    let target = match spec.orientation {
                        Some(rot) => IkTarget::Pose(Isometry3::from_parts(p.into(), rot)),
                        None => IkTarget::Position(p),
                    };
                    let seed = prev.as_deref().unwrap_or(&fallback);
                    dls_ik(model, &target, seed, &warm_opts)
                        .or_else(|_| dls_ik(model, &target, &fallback, &cold_opts))
                        .ok()
                }
            };
            if let Some(q) = q {
                cell.measures = triple(&translational(model, &q))
                    .filter(|t| t.yoshikawa.is_finite() && t.isotropy.is_finite());
                prev = Some(q);
            }
        }
    }
    Ok(WorkspaceMap {
        x: xs,
        z: zs,
        y: spec.y,
        cells,
    })
}
