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
//! R = Rz(y − 90°)·Ry(−(p − 90°))·R₀, so pitch > 90° tilts the approach axis up and
//! yaw > 90° turns it towards +Y.
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

/// §4.3.1.1 / §4.3.2.1: for each Z level, X from `start` towards the boundary.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepX {
    /// Z levels (m, default [0, 0.2, 0.4, 0.5]).
    pub z_levels: Vec<f64>,
    /// First X (m, default 0.9).
    pub start: f64,
    /// X step (m, default 0.01).
    pub step: f64,
    /// Last X tried if no boundary is met first (m, default 2.0).
    pub end: f64,
}

impl Default for SweepX {
    fn default() -> Self {
        SweepX {
            z_levels: vec![0.0, 0.2, 0.4, 0.5],
            start: 0.9,
            step: 0.01,
            end: 2.0,
        }
    }
}

/// §4.3.1.2: for each X level, Z from `start` upwards to the boundary.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepZ {
    /// X levels (m, default [0.9, 1.0, 1.1, 1.2, 1.3, 1.4]).
    pub x_levels: Vec<f64>,
    /// First Z (m, default 0.0).
    pub start: f64,
    /// Z step (m, default 0.01).
    pub step: f64,
    /// Last Z tried if no boundary is met first (m, default 1.5).
    pub end: f64,
}

impl Default for SweepZ {
    fn default() -> Self {
        SweepZ {
            x_levels: vec![0.9, 1.0, 1.1, 1.2, 1.3, 1.4],
            start: 0.0,
            step: 0.01,
            end: 1.5,
        }
    }
}

/// §4.3.1.3 / §4.3.2.2: pitch and yaw changed at named points.
#[derive(Debug, Clone, PartialEq)]
pub struct PitchYaw {
    /// Named points (base frame, m). Default: Fig. 4-51's points are not printed; we use
    /// A (0.9, 0, 0.1), B (1.1, 0, 0.1), C (1.3, 0, 0.1), D (0.9, 0, 0.3), E (1.1, 0, 0.3),
    /// F (1.3, 0, 0.3), inside the case-study workspace.
    pub points: Vec<(String, [f64; 3])>,
    /// Pitch range (deg, default [75, 135], the thesis's range), yaw held at 90°.
    pub pitch_deg: [f64; 2],
    /// Yaw range (deg, default [60, 120]; not printed in the thesis), pitch held at 90°.
    pub yaw_deg: [f64; 2],
    /// Angle step (deg, default 5).
    pub step_deg: f64,
}

impl Default for PitchYaw {
    fn default() -> Self {
        let p = |n: &str, x: f64, z: f64| (n.to_string(), [x, 0.0, z]);
        PitchYaw {
            points: vec![
                p("A", 0.9, 0.1),
                p("B", 1.1, 0.1),
                p("C", 1.3, 0.1),
                p("D", 0.9, 0.3),
                p("E", 1.1, 0.3),
                p("F", 1.3, 0.3),
            ],
            pitch_deg: [75.0, 135.0],
            yaw_deg: [60.0, 120.0],
            step_deg: 5.0,
        }
    }
}

/// §4.3.2.3 (Fig. 4-75): both end-effectors at X, then link 1 swung by ±δ.
#[derive(Debug, Clone, PartialEq)]
pub struct DistanceSweep {
    /// X levels (m, default [1.0, 1.2, 1.4]).
    pub x_levels: Vec<f64>,
    /// Z of both end-effectors (m, default 0.2; not printed in the thesis).
    pub z: f64,
    /// Largest swing δ (deg, default 25 = the Magnum swing limit). The right arm swings by +δ
    /// (towards the left arm), the left by −δ; δ runs from −max to +max, so the distance first
    /// grows, then equals the base spacing (parallel arms, δ = 0), then shrinks.
    pub swing_max_deg: f64,
    /// δ step (deg, default 1).
    pub step_deg: f64,
}

impl Default for DistanceSweep {
    fn default() -> Self {
        DistanceSweep {
            x_levels: vec![1.0, 1.2, 1.4],
            z: 0.2,
            swing_max_deg: 25.0,
            step_deg: 1.0,
        }
    }
}

/// Placement of the second arm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DualSetup {
    /// Y of the left arm's base in the world frame (m, default 1.0, Lim §4.3.2.2).
    pub left_base_y_m: f64,
}

impl Default for DualSetup {
    fn default() -> Self {
        DualSetup { left_base_y_m: 1.0 }
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
        * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), -(pitch_deg - 90.0).to_radians())
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

fn check_step(what: &'static str, start: f64, end: f64, step: f64) -> Result<usize, Error> {
    if !(start.is_finite() && end.is_finite() && step.is_finite() && step > 0.0 && end >= start) {
        return Err(Error::InvalidParameter {
            what,
            reason: "start ≤ end, step > 0, all finite".into(),
        });
    }
    // Counted in f64 (finite inputs, step > 0: n ≥ 1 or +∞, never NaN): a huge span over a
    // tiny step is refused, not overflowed.
    let n = ((end - start) / step + 1e-9).floor() + 1.0;
    if n > MAX_ROWS as f64 {
        return Err(Error::InvalidParameter {
            what,
            reason: format!("more than {MAX_ROWS} rows"),
        });
    }
    Ok(n as usize)
}

/// `series` series of up to `rows` rows each: at most [`MAX_ROWS`] rows in all.
fn check_total(what: &'static str, series: usize, rows: usize) -> Result<(), Error> {
    if series.saturating_mul(rows) > MAX_ROWS {
        return Err(Error::InvalidParameter {
            what,
            reason: format!("{series} series of {rows} rows: more than {MAX_ROWS} rows in all"),
        });
    }
    Ok(())
}

fn check_finite(what: &'static str, v: &[f64]) -> Result<(), Error> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(index) => Err(Error::NonFinite { what, index }),
        None => Ok(()),
    }
}

/// One arm or two: fills a row at `pos` (each arm's base frame) with the given orientations.
struct Rig<'a> {
    model: &'a Model,
    dual: Option<DualSetup>,
}

impl Rig<'_> {
    /// Places the right arm at (pos, rot_r) and, for a pair, the left one at (pos_l, rot_l);
    /// fills the measures. Returns false when an arm cannot be placed.
    #[allow(clippy::too_many_arguments)]
    fn fill(
        &self,
        row: &mut StudyRow,
        rot_r: UnitQuaternion<f64>,
        pos_l: [f64; 3],
        rot_l: UnitQuaternion<f64>,
        prev_r: &mut Option<Vec<f64>>,
        prev_l: &mut Option<Vec<f64>>,
    ) -> bool {
        let p = row.position;
        let pose_r = Isometry3::from_parts(Vector3::new(p[0], p[1], p[2]).into(), rot_r);
        let Some(qr) = place(self.model, &pose_r, prev_r.as_deref()) else {
            return false;
        };
        let jr = translational(self.model, &qr);
        row.single = triple(&jr);
        if let Some(setup) = self.dual {
            let pose_l =
                Isometry3::from_parts(Vector3::new(pos_l[0], pos_l[1], pos_l[2]).into(), rot_l);
            let Some(ql) = place(self.model, &pose_l, prev_l.as_deref()) else {
                return false;
            };
            let jl = translational(self.model, &ql);
            row.left = triple(&jl);
            row.dual = dual_measures(&jr, &jl)
                .ok()
                .map(|m| MeasureTriple::from(&m));
            let pr = end_effector_pose(self.model, &qr).translation.vector;
            let pl = end_effector_pose(self.model, &ql).translation.vector
                + Vector3::new(0.0, setup.left_base_y_m, 0.0);
            row.distance_m = Some((pr - pl).norm());
            row.q_left = Some(ql.clone());
            *prev_l = Some(ql);
        }
        row.q = Some(qr.clone());
        *prev_r = Some(qr);
        row.reachable = true;
        true
    }

    fn sweep_x(&self, spec: &SweepX) -> Result<Vec<StudyRow>, Error> {
        let n = check_step("x sweep", spec.start, spec.end, spec.step)?;
        check_finite("z_levels", &spec.z_levels)?;
        check_total("z_levels", spec.z_levels.len(), n)?;
        let rot = nominal_orientation(self.model);
        let mut rows = Vec::new();
        for &z in &spec.z_levels {
            let series = format!("z={z:.2}");
            let (mut pr, mut pl) = (None, None);
            for i in 0..n {
                let x = spec.start + spec.step * i as f64;
                let mut row = StudyRow::new(&series, x, [x, 0.0, z], 90.0, 90.0);
                let ok = self.fill(&mut row, rot, [x, 0.0, z], rot, &mut pr, &mut pl);
                rows.push(row);
                if !ok && pr.is_some() {
                    break; // boundary reached
                }
            }
        }
        Ok(rows)
    }

    fn sweep_z(&self, spec: &SweepZ) -> Result<Vec<StudyRow>, Error> {
        let n = check_step("z sweep", spec.start, spec.end, spec.step)?;
        check_finite("x_levels", &spec.x_levels)?;
        check_total("x_levels", spec.x_levels.len(), n)?;
        let rot = nominal_orientation(self.model);
        let mut rows = Vec::new();
        for &x in &spec.x_levels {
            let series = format!("x={x:.2}");
            let (mut pr, mut pl) = (None, None);
            for i in 0..n {
                let z = spec.start + spec.step * i as f64;
                let mut row = StudyRow::new(&series, z, [x, 0.0, z], 90.0, 90.0);
                let ok = self.fill(&mut row, rot, [x, 0.0, z], rot, &mut pr, &mut pl);
                rows.push(row);
                if !ok && pr.is_some() {
                    break;
                }
            }
        }
        Ok(rows)
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
        check_total("points", spec.points.len(), np + ny)?;
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
                    self.fill(
                        &mut row,
                        orientation(self.model, pitch, yaw),
                        *p,
                        nominal,
                        &mut pr,
                        &mut pl,
                    );
                    rows.push(row);
                }
            }
        }
        Ok(rows)
    }
}

/// §4.3.1.1: single arm, X towards the boundary at several Z, fixed orientation.
pub fn single_x(model: &Model, spec: &SweepX) -> Result<Vec<StudyRow>, Error> {
    Rig { model, dual: None }.sweep_x(spec)
}

/// §4.3.1.2: single arm, Z towards the boundary at several X, fixed orientation.
pub fn single_z(model: &Model, spec: &SweepZ) -> Result<Vec<StudyRow>, Error> {
    Rig { model, dual: None }.sweep_z(spec)
}

/// §4.3.1.3: single arm, pitch and yaw changes at named points.
pub fn single_pitch_yaw(model: &Model, spec: &PitchYaw) -> Result<Vec<StudyRow>, Error> {
    Rig { model, dual: None }.pitch_yaw(spec)
}

/// §4.3.2.1: two identical, parallel arms doing the X sweep together.
pub fn dual_x(model: &Model, spec: &SweepX, setup: &DualSetup) -> Result<Vec<StudyRow>, Error> {
    check_finite("left_base_y_m", &[setup.left_base_y_m])?;
    Rig {
        model,
        dual: Some(*setup),
    }
    .sweep_x(spec)
}

/// §4.3.2.2: both arms at each point; the right arm's pitch, then yaw, changes.
pub fn dual_pitch_yaw(
    model: &Model,
    spec: &PitchYaw,
    setup: &DualSetup,
) -> Result<Vec<StudyRow>, Error> {
    check_finite("left_base_y_m", &[setup.left_base_y_m])?;
    Rig {
        model,
        dual: Some(*setup),
    }
    .pitch_yaw(spec)
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
    check_total("x_levels", spec.x_levels.len(), n)?;
    let rot = nominal_orientation(model);
    let offset = Vector3::new(0.0, setup.left_base_y_m, 0.0);
    let mut rows = Vec::new();
    for &x in &spec.x_levels {
        let series = format!("x={x:.2} swing");
        let pose = Isometry3::from_parts(Vector3::new(x, 0.0, spec.z).into(), rot);
        let q0 = place(model, &pose, None);
        for i in 0..n {
            let delta = -spec.swing_max_deg + spec.step_deg * i as f64;
            let mut row = StudyRow::new(&series, delta, [x, 0.0, spec.z], 90.0, 90.0);
            if let Some(q0) = &q0 {
                let mut qr = q0.clone();
                let mut ql = q0.clone();
                qr[0] += delta.to_radians();
                ql[0] -= delta.to_radians();
                let within = |q: &[f64]| {
                    q.iter()
                        .zip(&model.joints)
                        .all(|(v, j)| *v >= j.limits[0] - 1e-12 && *v <= j.limits[1] + 1e-12)
                };
                if within(&qr) && within(&ql) {
                    let (jr, jl) = (translational(model, &qr), translational(model, &ql));
                    let pr = end_effector_pose(model, &qr).translation.vector;
                    let pl = end_effector_pose(model, &ql).translation.vector + offset;
                    row.position = [pr.x, pr.y, pr.z];
                    row.single = triple(&jr);
                    row.left = triple(&jl);
                    row.dual = dual_measures(&jr, &jl)
                        .ok()
                        .map(|m| MeasureTriple::from(&m));
                    row.distance_m = Some((pr - pl).norm());
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
