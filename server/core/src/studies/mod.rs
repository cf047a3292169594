//! Manipulability case studies of Lim 2005 §4.3 as pure functions producing rows, and a
//! workspace map of translational measures.
//!
//! **Frames and placement.** The single arm (and the right arm of a pair) has its base at the
//! world origin; the left arm's base is at Y = [`DualSetup::left_base_y_m`] (1.0 m, Lim
//! §4.3.2.2) with the same orientation, so both Jacobians are expressed in one world frame by
//! the base rotation (identity) alone. End-effector targets are given in each arm's own base
//! frame (the thesis moves both arms "under the same condition").
//!
//! **Fixed orientation.** The thesis keeps "pitch 90°, yaw 90°" (§4.3.1.3) without printing the
//! frame; we take pitch 90° / yaw 90° to be the posture at q = 0 of the Magnum model: approach
//! axis (tool z) horizontal along +X, away from the vehicle, tool x pointing down
//! ([`nominal_orientation`]). A pitch p and yaw y rotate it in the base frame:
//! R = Rz(y − 90°)·Ry(p − 90°)·R₀, so pitch > 90° tilts the approach axis **down** (towards
//! the seabed) and yaw > 90° turns it towards +Y.
//!
//! **Pitch sign.** The thesis prints no frame for pitch, only "pitch (90°)" for the start pose
//! and a study from 75° to 135° (§4.3.1.3). We read pitch as the polar angle of the approach
//! axis from the upward vertical (0° up, 90° horizontal, 180° down): it is the convention in
//! which 90° means horizontal, and the asymmetric range 75°–135° then reaches 45° below the
//! horizontal — the direction a subsea arm turns its jaw to work on the seabed — but only 15°
//! above. The thesis's result decides it (§4.3.1.3 and §4.3.3: "changing pitch increased the
//! manipulability based on Yoshikawa's method", Figs 4-53 to 4-58): with this convention the
//! Yoshikawa measure of the Magnum model grows from 75° to 135° at every point A–F; with the
//! opposite sign it falls (tested in `tests/manipulability_studies.rs`).
//!
//! **Placement and boundary.** Postures come from the closed-form Magnum IK
//! ([`crate::ik::magnum_ik`]), the branch closest to the previous row (the first row: closest
//! to an elbow-up reference), so sweeps are continuous; models without the Magnum structure use
//! [`crate::ik::dls_ik`] warm-started from the previous row. A sweep runs from its start
//! until IK has no solution within the joint limits: that first unreachable row is emitted
//! with `reachable = false` and marks the workspace boundary.
//!
//! **Measures.** Yoshikawa w = Πσᵢ, isotropy σ_min/σ_max and Hong w·isotropy (Lim eq. 4.1) of
//! the translational rows (vx vy vz) of the Jacobian; dual = the same of the dual-arm ellipsoid
//! of Lim eq. 3.68 ([`crate::manipulability::dual_measures`]) of the two arms' translational
//! Jacobians in the world frame.

//!
//! # Layout
//! * `specs`: the studies' parameters ([`SweepX`], [`SweepZ`], [`PitchYaw`],
//!   [`DistanceSweep`], [`DualSetup`]) with the thesis's defaults.
//! * `map`: [`workspace_map`].
//! * here: the rows ([`StudyRow`]), placing the arms and the sweeps.

mod map;
mod specs;

pub use map::{MAX_CELLS, MapCell, MapSpec, WorkspaceMap, workspace_map};
pub use specs::{DistanceSweep, DualSetup, PitchYaw, SweepX, SweepZ};

use nalgebra::{DMatrix, Isometry3, UnitQuaternion, Vector3};

use crate::Error;
use crate::ik::{IkOptions, IkTarget, MagnumLengths, dls_ik, magnum_ik};
use crate::kinematics::{end_effector_pose, jacobian_at};
use crate::manipulability::{Measures, dual_measures, measures};
use crate::model::Model;

/// Yoshikawa, isotropy and Hong of one (translational) ellipsoid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeasureTriple {
    /// w = Πσᵢ (m³/s per unit joint speed for translation).
    pub yoshikawa: f64,
    /// σ_min/σ_max ∈ [0, 1].
    pub isotropy: f64,
    /// w·isotropy (Lim eq. 4.1).
    pub hong: f64,
}

impl From<&Measures> for MeasureTriple {
    fn from(m: &Measures) -> Self {
        MeasureTriple {
            yoshikawa: m.yoshikawa,
            isotropy: m.isotropy,
            hong: m.hong,
        }
    }
}

/// One row of a case study.
#[derive(Debug, Clone, PartialEq)]
pub struct StudyRow {
    /// The series the row belongs to, e.g. "z=0.20", "x=1.20", "A pitch", "x=1.40 swing".
    pub series: String,
    /// Value of the swept variable: X or Z (m), pitch or yaw (deg), swing δ (deg).
    pub parameter: f64,
    /// Target of the (right or single) arm's tool point, its base frame (m).
    pub position: [f64; 3],
    /// End-effector pitch of the (right or single) arm (deg; 90 = horizontal).
    pub pitch_deg: f64,
    /// End-effector yaw of the (right or single) arm (deg; 90 = along +X).
    pub yaw_deg: f64,
    /// Whether every arm of the row reached its target within its limits.
    pub reachable: bool,
    /// Joint values of the (right or single) arm (rad).
    pub q: Option<Vec<f64>>,
    /// Joint values of the left arm (dual studies).
    pub q_left: Option<Vec<f64>>,
    /// Measures of the (right or single) arm.
    pub single: Option<MeasureTriple>,
    /// Measures of the left arm (dual studies).
    pub left: Option<MeasureTriple>,
    /// Measures of the dual-arm ellipsoid (Lim eq. 3.68).
    pub dual: Option<MeasureTriple>,
    /// Distance between the two end-effectors, world frame (m; dual studies).
    pub distance_m: Option<f64>,
}

impl StudyRow {
    fn new(
        series: &str,
        parameter: f64,
        position: [f64; 3],
        pitch_deg: f64,
        yaw_deg: f64,
    ) -> StudyRow {
        StudyRow {
            series: series.to_string(),
            parameter,
            position,
            pitch_deg,
            yaw_deg,
            reachable: false,
            q: None,
            q_left: None,
            single: None,
            left: None,
            dual: None,
            distance_m: None,
        }
    }
}

/// Largest number of rows a study may produce.
pub const MAX_ROWS: usize = 100_000;

/// The fixed orientation "pitch 90°, yaw 90°": the flange orientation at q = 0.
pub fn nominal_orientation(model: &Model) -> UnitQuaternion<f64> {
    end_effector_pose(model, &vec![0.0; model.dof()]).rotation
}

/// The nominal orientation turned to `pitch_deg`, `yaw_deg` (see the module doc).
pub fn orientation(model: &Model, pitch_deg: f64, yaw_deg: f64) -> UnitQuaternion<f64> {
    let r0 = nominal_orientation(model);
    UnitQuaternion::from_axis_angle(&Vector3::z_axis(), (yaw_deg - 90.0).to_radians())
        * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), (pitch_deg - 90.0).to_radians())
        * r0
}

/// Reference posture for the first row: elbow up, mid-range where limited.
fn reference_posture(model: &Model) -> Vec<f64> {
    model
        .joints
        .iter()
        .map(|j| {
            if j.is_limited() {
                0.5 * (j.limits[0] + j.limits[1])
            } else {
                0.0
            }
        })
        .collect()
}

/// Places the tool at `pose`: closed-form Magnum IK (branch nearest `prev`) or DLS IK.
pub fn place(model: &Model, pose: &Isometry3<f64>, prev: Option<&[f64]>) -> Option<Vec<f64>> {
    let reference = prev
        .map(<[f64]>::to_vec)
        .unwrap_or_else(|| reference_posture(model));
    if MagnumLengths::from_model(model).is_ok() {
        let sols = magnum_ik(model, pose).ok()?;
        let dist =
            |s: &[f64; 6]| -> f64 { s.iter().zip(&reference).map(|(a, b)| (a - b).powi(2)).sum() };
        return sols
            .into_iter()
            .min_by(|a, b| dist(a).total_cmp(&dist(b)))
            .map(|s| s.to_vec());
    }
    dls_ik(
        model,
        &IkTarget::Pose(*pose),
        &reference,
        &IkOptions::default(),
    )
    .ok()
}

fn translational(model: &Model, q: &[f64]) -> DMatrix<f64> {
    jacobian_at(model, q).rows(0, 3).into_owned()
}

fn triple(j: &DMatrix<f64>) -> Option<MeasureTriple> {
    measures(j).ok().map(|m| MeasureTriple::from(&m))
}

/// Samples `start, start + step, …` up to `end` of a study's sweep, ⌊(end − start)/step⌋ + 1
/// (the 1e-9 keeps an end point that rounding puts a hair beyond), in f64 so a caller can
/// compare it with a limit before converting: a huge span over a tiny step is +∞ or huge
/// here, where `as usize` would saturate. Needs finite inputs, `step > 0`, `start ≤ end`.
pub fn sample_count(start: f64, end: f64, step: f64) -> f64 {
    ((end - start) / step + 1e-9).floor() + 1.0
}

fn check_step(what: &'static str, start: f64, end: f64, step: f64) -> Result<usize, Error> {
    if !(start.is_finite() && end.is_finite() && step.is_finite() && step > 0.0 && end >= start) {
        return Err(Error::InvalidParameter {
            what,
            reason: "start ≤ end, step > 0, all finite".into(),
        });
    }
    let n = sample_count(start, end, step);
    if n > MAX_ROWS as f64 {
        return Err(Error::InvalidParameter {
            what,
            reason: format!("more than {MAX_ROWS} rows"),
        });
    }
    Ok(n as usize)
}

fn check_finite(what: &'static str, v: &[f64]) -> Result<(), Error> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(index) => Err(Error::NonFinite { what, index }),
        None => Ok(()),
    }
}

/// The tool pose at `p` (base frame, m) with orientation `rot`.
fn pose_at(p: [f64; 3], rot: UnitQuaternion<f64>) -> Isometry3<f64> {
    Isometry3::from_parts(Vector3::new(p[0], p[1], p[2]).into(), rot)
}

/// Fills the left arm's and the pair's measures of `row` and the distance between the
/// end-effectors (world frame) for the right arm at `qr` (translational Jacobian `jr`) and
/// the left one at `ql`, its base at Y = `setup.left_base_y_m`; returns the right arm's
/// tool point (its base frame = the world frame).
fn fill_pair(
    model: &Model,
    row: &mut StudyRow,
    qr: &[f64],
    jr: &DMatrix<f64>,
    ql: &[f64],
    setup: &DualSetup,
) -> Vector3<f64> {
    let jl = translational(model, ql);
    row.left = triple(&jl);
    row.dual = dual_measures(jr, &jl).ok().map(|m| MeasureTriple::from(&m));
    let pr = end_effector_pose(model, qr).translation.vector;
    let pl = end_effector_pose(model, ql).translation.vector
        + Vector3::new(0.0, setup.left_base_y_m, 0.0);
    row.distance_m = Some((pr - pl).norm());
    pr
}

/// One arm or two: fills a row at `pos` (each arm's base frame) with the given orientations.
struct Rig<'a> {
    model: &'a Model,
    dual: Option<DualSetup>,
}

impl<'a> Rig<'a> {
    /// A single arm.
    fn single(model: &'a Model) -> Rig<'a> {
        Rig { model, dual: None }
    }

    /// Two identical, parallel arms placed by `setup`.
    fn dual(model: &'a Model, setup: &DualSetup) -> Result<Rig<'a>, Error> {
        check_finite("left_base_y_m", &[setup.left_base_y_m])?;
        Ok(Rig {
            model,
            dual: Some(*setup),
        })
    }

    /// Places the right arm at (pos, rot_r) and, for a pair, the left one at (pos_l, rot_l);
    /// fills the measures. Returns false when an arm cannot be placed.
    fn fill(
        &self,
        row: &mut StudyRow,
        rot_r: UnitQuaternion<f64>,
        (pos_l, rot_l): ([f64; 3], UnitQuaternion<f64>),
        prev_r: &mut Option<Vec<f64>>,
        prev_l: &mut Option<Vec<f64>>,
    ) -> bool {
        let Some(qr) = place(self.model, &pose_at(row.position, rot_r), prev_r.as_deref()) else {
            return false;
        };
        let jr = translational(self.model, &qr);
        row.single = triple(&jr);
        if let Some(setup) = &self.dual {
            let Some(ql) = place(self.model, &pose_at(pos_l, rot_l), prev_l.as_deref()) else {
                return false;
            };
            fill_pair(self.model, row, &qr, &jr, &ql, setup);
            row.q_left = Some(ql.clone());
            *prev_l = Some(ql);
        }
        row.q = Some(qr.clone());
        *prev_r = Some(qr);
        row.reachable = true;
        true
    }

    /// One series per value of `levels` (the other coordinate, named `axis` in the series
    /// name), the swept coordinate from `range` = (start, end, step) until the boundary,
    /// the tool at `at(level, value)` with the nominal orientation.
    fn sweep_line(
        &self,
        (what, levels_what): (&'static str, &'static str),
        levels: &[f64],
        (start, end, step): (f64, f64, f64),
        axis: char,
        at: impl Fn(f64, f64) -> [f64; 3],
    ) -> Result<Vec<StudyRow>, Error> {
        let n = check_step(what, start, end, step)?;
        check_finite(levels_what, levels)?;
        let rot = nominal_orientation(self.model);
        let mut rows = Vec::new();
        for &level in levels {
            let series = format!("{axis}={level:.2}");
            let (mut pr, mut pl) = (None, None);
            for i in 0..n {
                let value = start + step * i as f64;
                let pos = at(level, value);
                let mut row = StudyRow::new(&series, value, pos, 90.0, 90.0);
                let ok = self.fill(&mut row, rot, (pos, rot), &mut pr, &mut pl);
                rows.push(row);
                if !ok && pr.is_some() {
                    break; // boundary reached
                }
            }
        }
        Ok(rows)
    }

    fn sweep_x(&self, spec: &SweepX) -> Result<Vec<StudyRow>, Error> {
        let (names, range) = (("x sweep", "z_levels"), (spec.start, spec.end, spec.step));
        self.sweep_line(names, &spec.z_levels, range, 'z', |z, x| [x, 0.0, z])
    }

    fn sweep_z(&self, spec: &SweepZ) -> Result<Vec<StudyRow>, Error> {
        let (names, range) = (("z sweep", "x_levels"), (spec.start, spec.end, spec.step));
        self.sweep_line(names, &spec.x_levels, range, 'x', |x, z| [x, 0.0, z])
    }

    /// Pitch then yaw at each point; for a pair only the right arm turns.
    fn pitch_yaw(&self, spec: &PitchYaw) -> Result<Vec<StudyRow>, Error> {
        let np = check_step(
            "pitch range",
            spec.pitch_deg[0],
            spec.pitch_deg[1],
            spec.step_deg,
        )?;
        let ny = check_step("yaw range", spec.yaw_deg[0], spec.yaw_deg[1], spec.step_deg)?;
        let nominal = nominal_orientation(self.model);
        let mut rows = Vec::new();
        for (name, p) in &spec.points {
            check_finite("point", p)?;
            for (kind, count, range) in [("pitch", np, spec.pitch_deg), ("yaw", ny, spec.yaw_deg)] {
                let series = format!("{name} {kind}");
                let (mut pr, mut pl) = (None, None);
                for i in 0..count {
                    let a = range[0] + spec.step_deg * i as f64;
                    let (pitch, yaw) = if kind == "pitch" {
                        (a, 90.0)
                    } else {
                        (90.0, a)
                    };
                    let mut row = StudyRow::new(&series, a, *p, pitch, yaw);
                    let rot = orientation(self.model, pitch, yaw);
                    self.fill(&mut row, rot, (*p, nominal), &mut pr, &mut pl);
                    rows.push(row);
                }
            }
        }
        Ok(rows)
    }
}

/// §4.3.1.1: single arm, X towards the boundary at several Z, fixed orientation.
pub fn single_x(model: &Model, spec: &SweepX) -> Result<Vec<StudyRow>, Error> {
    Rig::single(model).sweep_x(spec)
}

/// §4.3.1.2: single arm, Z towards the boundary at several X, fixed orientation.
pub fn single_z(model: &Model, spec: &SweepZ) -> Result<Vec<StudyRow>, Error> {
    Rig::single(model).sweep_z(spec)
}

/// §4.3.1.3: single arm, pitch and yaw changes at named points.
pub fn single_pitch_yaw(model: &Model, spec: &PitchYaw) -> Result<Vec<StudyRow>, Error> {
    Rig::single(model).pitch_yaw(spec)
}

/// §4.3.2.1: two identical, parallel arms doing the X sweep together.
pub fn dual_x(model: &Model, spec: &SweepX, setup: &DualSetup) -> Result<Vec<StudyRow>, Error> {
    Rig::dual(model, setup)?.sweep_x(spec)
}

/// §4.3.2.2: both arms at each point; the right arm's pitch, then yaw, changes.
pub fn dual_pitch_yaw(
    model: &Model,
    spec: &PitchYaw,
    setup: &DualSetup,
) -> Result<Vec<StudyRow>, Error> {
    Rig::dual(model, setup)?.pitch_yaw(spec)
}

/// §4.3.2.3 (Fig. 4-75): both end-effectors at (X, 0, z) in their base frames, then link 1 of
/// the right arm swung by +δ and of the left by −δ (other joints fixed); the distance between
/// the end-effectors changes with δ.
pub fn dual_distance(
    model: &Model,
    spec: &DistanceSweep,
    setup: &DualSetup,
) -> Result<Vec<StudyRow>, Error> {
    check_finite("left_base_y_m", &[setup.left_base_y_m])?;
    check_finite("x_levels", &spec.x_levels)?;
    check_finite("z", &[spec.z])?;
    let n = check_step(
        "swing",
        -spec.swing_max_deg,
        spec.swing_max_deg,
        spec.step_deg,
    )?;
    let rot = nominal_orientation(model);
    let within = |q: &[f64]| {
        q.iter()
            .zip(&model.joints)
            .all(|(v, j)| *v >= j.limits[0] - 1e-12 && *v <= j.limits[1] + 1e-12)
    };
    let mut rows = Vec::new();
    for &x in &spec.x_levels {
        let series = format!("x={x:.2} swing");
        let q0 = place(model, &pose_at([x, 0.0, spec.z], rot), None);
        for i in 0..n {
            let delta = -spec.swing_max_deg + spec.step_deg * i as f64;
            let mut row = StudyRow::new(&series, delta, [x, 0.0, spec.z], 90.0, 90.0);
            if let Some(q0) = &q0 {
                let mut qr = q0.clone();
                let mut ql = q0.clone();
                qr[0] += delta.to_radians();
                ql[0] -= delta.to_radians();
                if within(&qr) && within(&ql) {
                    let jr = translational(model, &qr);
                    row.single = triple(&jr);
                    let pr = fill_pair(model, &mut row, &qr, &jr, &ql, setup);
                    row.position = [pr.x, pr.y, pr.z];
                    row.q = Some(qr);
                    row.q_left = Some(ql);
                    row.reachable = true;
                }
            }
            rows.push(row);
        }
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn row_counts_are_exact_and_huge_ones_are_refused() {
        // 0, 0.1, …, 1.0: eleven rows (the 1e-9 guard keeps the end point).
        assert!(matches!(check_step("x", 0.0, 1.0, 0.1), Ok(11)));
        // A span of 2e300 over a step of 1e-300 once saturated the cast and wrapped to 0 rows.
        assert!(check_step("x", -1e300, 1e300, 1e-300).is_err());
        assert!(check_step("x", 0.0, MAX_ROWS as f64, 1.0).is_err());
        assert!(matches!(check_step("x", 0.0, (MAX_ROWS - 1) as f64, 1.0), Ok(n) if n == MAX_ROWS));
    }
}
