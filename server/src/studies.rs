//! Manipulability studies at the server edge (`POST /api/studies/{name}`, `seaarms study`):
//! the Lim 2005 §4.3 case studies and the workspace map.
//!
//! * [`plan`] parses a study's JSON parameters into the core's typed inputs (unknown fields
//!   are rejected) and checks them against [`crate::limits`] — series, total rows, cells,
//!   coordinate and angle ranges — before anything is computed; a request over a limit is a
//!   400 naming it.
//! * [`StudyPlan::run`] runs it, one series at a time (each series of a sweep starts afresh
//!   in the core, so the rows are those of one call), checking its [`Cancel`] in between.
//! * [`StudyOutput`] renders the JSON document (rows + summary, or the map's grids) or the
//!   same rows as CSV, straight to bytes.

use serde::{Deserialize, Serialize};
use serde_json::{Value, json};

use seaarms_core::studies::{
    self, DistanceSweep, DualSetup, MapSpec, PitchYaw, StudyRow, SweepX, SweepZ, WorkspaceMap,
};
use seaarms_core::{Model, ModelSpec};

use crate::compute::{Cancel, ComputeError};
use crate::error::ApiError;
use crate::limits::{
    self, MAX_MAP_CELLS, MAX_STUDY_ANGLE_DEG, MAX_STUDY_COORDINATE_M, MAX_STUDY_ROWS,
    MAX_STUDY_SERIES,
};

/// (name, description) of every study [`plan`] accepts.
pub const STUDIES: &[(&str, &str)] = &[
    (
        "single-x",
        "Lim §4.3.1.1: single arm, end-effector along X to the workspace boundary at several Z, fixed orientation",
    ),
    (
        "single-z",
        "Lim §4.3.1.2: single arm, end-effector along Z to the workspace boundary at several X, fixed orientation",
    ),
    (
        "single-pitch-yaw",
        "Lim §4.3.1.3: single arm, pitch then yaw changed at six points A-F",
    ),
    (
        "dual-x",
        "Lim §4.3.2.1: two parallel arms (bases at Y = 0 and 1 m) doing the X sweep together",
    ),
    (
        "dual-pitch-yaw",
        "Lim §4.3.2.2: both arms at points A-F, right arm's pitch then yaw changed",
    ),
    (
        "dual-distance",
        "Lim §4.3.2.3 (Fig. 4-75): both end-effectors at X = 1.0/1.2/1.4 m, link 1 swung so their distance changes",
    ),
    (
        "workspace-map",
        "Translational Yoshikawa / isotropy / Hong over an X-Z grid (unreachable cells null)",
    ),
];

/// Parses `params` (null or an object) into `T`, defaults for missing fields.
fn parse<T: for<'de> Deserialize<'de> + Default>(params: &Value) -> Result<T, ApiError> {
    if params.is_null() {
        return Ok(T::default());
    }
    T::deserialize(params)
        .map_err(|e| ApiError::bad_request(format!("invalid study parameters: {e}")))
}

fn builtin_model(name: &str) -> Result<Model, ApiError> {
    let text = seaarms_core::robots::builtin_text(name)
        .ok_or_else(|| ApiError::bad_request(format!("unknown built-in robot {name:?}")))?;
    let spec: ModelSpec = serde_json::from_str(text)
        .map_err(|e| ApiError::bad_request(format!("built-in robot {name}: {e}")))?;
    Ok(Model::from_spec(&spec)?)
}

#[derive(Debug, Default, Deserialize)]
#[serde(default, deny_unknown_fields)]
struct SweepXParams {
    z_levels: Option<Vec<f64>>,
    x_start: Option<f64>,
    x_step: Option<f64>,
    x_end: Option<f64>,
    left_base_y_m: Option<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(default, deny_unknown_fields)]
struct SweepZParams {
    x_levels: Option<Vec<f64>>,
    z_start: Option<f64>,
    z_step: Option<f64>,
    z_end: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PointParam {
    name: String,
    position: [f64; 3],
}

#[derive(Debug, Default, Deserialize)]
#[serde(default, deny_unknown_fields)]
struct PitchYawParams {
    points: Option<Vec<PointParam>>,
    pitch_deg: Option<[f64; 2]>,
    yaw_deg: Option<[f64; 2]>,
    step_deg: Option<f64>,
    left_base_y_m: Option<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(default, deny_unknown_fields)]
struct DistanceParams {
    x_levels: Option<Vec<f64>>,
    z: Option<f64>,
    swing_max_deg: Option<f64>,
    step_deg: Option<f64>,
    left_base_y_m: Option<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(default, deny_unknown_fields)]
struct MapParams {
    robot: Option<String>,
    x_range: Option<[f64; 2]>,
    z_range: Option<[f64; 2]>,
    nx: Option<usize>,
    nz: Option<usize>,
    y: Option<f64>,
    /// "nominal" (the studies' fixed orientation) or "free" (position only).
    orientation: Option<String>,
}

impl SweepXParams {
    fn spec(&self) -> SweepX {
        let d = SweepX::default();
        SweepX {
            z_levels: self.z_levels.clone().unwrap_or(d.z_levels),
            start: self.x_start.unwrap_or(d.start),
            step: self.x_step.unwrap_or(d.step),
            end: self.x_end.unwrap_or(d.end),
        }
    }
}

impl SweepZParams {
    fn spec(&self) -> SweepZ {
        let d = SweepZ::default();
        SweepZ {
            x_levels: self.x_levels.clone().unwrap_or(d.x_levels),
            start: self.z_start.unwrap_or(d.start),
            step: self.z_step.unwrap_or(d.step),
            end: self.z_end.unwrap_or(d.end),
        }
    }
}

impl PitchYawParams {
    fn spec(&self) -> PitchYaw {
        let d = PitchYaw::default();
        PitchYaw {
            points: match &self.points {
                Some(p) => p.iter().map(|p| (p.name.clone(), p.position)).collect(),
                None => d.points,
            },
            pitch_deg: self.pitch_deg.unwrap_or(d.pitch_deg),
            yaw_deg: self.yaw_deg.unwrap_or(d.yaw_deg),
            step_deg: self.step_deg.unwrap_or(d.step_deg),
        }
    }
}

impl DistanceParams {
    fn spec(&self) -> DistanceSweep {
        let d = DistanceSweep::default();
        DistanceSweep {
            x_levels: self.x_levels.clone().unwrap_or(d.x_levels),
            z: self.z.unwrap_or(d.z),
            swing_max_deg: self.swing_max_deg.unwrap_or(d.swing_max_deg),
            step_deg: self.step_deg.unwrap_or(d.step_deg),
        }
    }
}

impl MapParams {
    /// The grid (checked against [`MAX_MAP_CELLS`] and the coordinate limit) and the
    /// orientation's name.
    fn spec(&self, model: &Model) -> Result<(MapSpec, String), ApiError> {
        let d = MapSpec::case_study(model);
        let (nx, nz) = (self.nx.unwrap_or(d.nx), self.nz.unwrap_or(d.nz));
        if nx == 0 || nz == 0 {
            return Err(ApiError::bad_request("nx and nz must be ≥ 1"));
        }
        let cells = nx.saturating_mul(nz);
        if cells > MAX_MAP_CELLS {
            return Err(limits::exceeded(
                "max_map_cells",
                MAX_MAP_CELLS,
                cells,
                "map cells nx·nz",
            ));
        }
        let (x_range, z_range) = (
            self.x_range.unwrap_or(d.x_range),
            self.z_range.unwrap_or(d.z_range),
        );
        let y = self.y.unwrap_or(d.y);
        for (what, v) in [
            ("x_range[0]", x_range[0]),
            ("x_range[1]", x_range[1]),
            ("z_range[0]", z_range[0]),
            ("z_range[1]", z_range[1]),
            ("y", y),
        ] {
            coordinate(what, v)?;
        }
        let magnum = seaarms_core::ik::MagnumLengths::from_model(model).is_ok();
        let orientation = self
            .orientation
            .clone()
            .unwrap_or_else(|| if magnum { "nominal" } else { "free" }.to_string());
        let fixed = match orientation.as_str() {
            "nominal" => Some(studies::nominal_orientation(model)),
            "free" => None,
            other => {
                return Err(ApiError::bad_request(format!(
                    "orientation {other:?} is not \"nominal\" or \"free\""
                )));
            }
        };
        let spec = MapSpec {
            x_range,
            z_range,
            nx,
            nz,
            y,
            orientation: fixed,
        };
        Ok((spec, orientation))
    }
}

/// Checks a position-like value against [`MAX_STUDY_COORDINATE_M`].
fn coordinate(what: &str, v: f64) -> Result<(), ApiError> {
    limits::within("max_study_coordinate_m", MAX_STUDY_COORDINATE_M, what, v)
}

/// Checks an angle against [`MAX_STUDY_ANGLE_DEG`].
fn angle(what: &str, v: f64) -> Result<(), ApiError> {
    limits::within("max_study_angle_deg", MAX_STUDY_ANGLE_DEG, what, v)
}

/// Checks `series` series of at most `per_series` rows each against [`MAX_STUDY_SERIES`] and
/// [`MAX_STUDY_ROWS`].
fn total_rows(what: &str, series: usize, per_series: usize) -> Result<usize, ApiError> {
    if series > MAX_STUDY_SERIES {
        return Err(limits::exceeded(
            "max_study_series",
            MAX_STUDY_SERIES,
            series,
            what,
        ));
    }
    let rows = series.saturating_mul(per_series);
    if rows > MAX_STUDY_ROWS {
        return Err(limits::exceeded(
            "max_study_rows",
            MAX_STUDY_ROWS,
            rows,
            &format!("rows ({series} series × up to {per_series} rows)"),
        ));
    }
    Ok(rows)
}

/// An X or Z sweep: levels × samples from start to end.
fn check_sweep(
    axis: &str,
    levels: &[f64],
    start: f64,
    step: f64,
    end: f64,
) -> Result<usize, ApiError> {
    for (i, &v) in levels.iter().enumerate().take(MAX_STUDY_SERIES + 1) {
        coordinate(&format!("levels[{i}]"), v)?;
    }
    coordinate(&format!("{axis}_start"), start)?;
    coordinate(&format!("{axis}_end"), end)?;
    let n = limits::samples(&format!("{axis} sweep"), start, end, step)?;
    total_rows("levels", levels.len(), n)
}

fn dual_setup(left_base_y_m: Option<f64>) -> Result<DualSetup, ApiError> {
    let setup = DualSetup {
        left_base_y_m: left_base_y_m.unwrap_or(DualSetup::default().left_base_y_m),
    };
    coordinate("left_base_y_m", setup.left_base_y_m)?;
    Ok(setup)
}

/// What a plan computes.
#[derive(Debug, Clone)]
enum Kind {
    SweepX(SweepX, Option<DualSetup>),
    SweepZ(SweepZ),
    PitchYaw(PitchYaw, Option<DualSetup>),
    Distance(DistanceSweep, DualSetup),
    Map(MapSpec, String),
}

/// A study whose parameters passed every limit, ready to [`run`](StudyPlan::run).
#[derive(Debug, Clone)]
pub struct StudyPlan {
    name: &'static str,
    params: Value,
    model: Model,
    kind: Kind,
    /// Upper bound of the rows (cells for the map) it produces.
    pub rows: usize,
}

/// Parses and checks the parameters of study `name` (see [`STUDIES`]; fields:
/// `single-x`/`dual-x`: `z_levels, x_start, x_step, x_end, left_base_y_m`; `single-z`:
/// `x_levels, z_start, z_step, z_end`; `*-pitch-yaw`: `points [{name, position}],
/// pitch_deg [a, b], yaw_deg [a, b], step_deg, left_base_y_m`; `dual-distance`: `x_levels, z,
/// swing_max_deg, step_deg, left_base_y_m`; `workspace-map`: `robot, x_range, z_range, nx, nz,
/// y, orientation ("nominal" | "free")`). Nothing is computed yet.
pub fn plan(name: &str, params: &Value) -> Result<StudyPlan, ApiError> {
    let Some(&(name, _)) = STUDIES.iter().find(|(n, _)| *n == name) else {
        let names: Vec<&str> = STUDIES.iter().map(|(n, _)| *n).collect();
        return Err(ApiError::bad_request(format!(
            "unknown study {name:?}; known: {}",
            names.join(", ")
        )));
    };
    if !(params.is_null() || params.is_object()) {
        return Err(ApiError::bad_request("study parameters must be an object"));
    }
    let (kind, rows, robot) = match name {
        "single-x" | "dual-x" => {
            let p: SweepXParams = parse(params)?;
            let spec = p.spec();
            let rows = check_sweep("x", &spec.z_levels, spec.start, spec.step, spec.end)?;
            let dual = (name == "dual-x")
                .then(|| dual_setup(p.left_base_y_m))
                .transpose()?;
            (Kind::SweepX(spec, dual), rows, None)
        }
        "single-z" => {
            let p: SweepZParams = parse(params)?;
            let spec = p.spec();
            let rows = check_sweep("z", &spec.x_levels, spec.start, spec.step, spec.end)?;
            (Kind::SweepZ(spec), rows, None)
        }
        "single-pitch-yaw" | "dual-pitch-yaw" => {
            let p: PitchYawParams = parse(params)?;
            let spec = p.spec();
            let rows = check_pitch_yaw(&spec)?;
            let dual = (name == "dual-pitch-yaw")
                .then(|| dual_setup(p.left_base_y_m))
                .transpose()?;
            (Kind::PitchYaw(spec, dual), rows, None)
        }
        "dual-distance" => {
            let p: DistanceParams = parse(params)?;
            let spec = p.spec();
            let rows = check_distance(&spec)?;
            (
                Kind::Distance(spec, dual_setup(p.left_base_y_m)?),
                rows,
                None,
            )
        }
        _ => {
            let p: MapParams = parse(params)?;
            let model = builtin_model(p.robot.as_deref().unwrap_or("magnum"))?;
            let (spec, orientation) = p.spec(&model)?;
            let cells = spec.nx * spec.nz;
            (Kind::Map(spec, orientation), cells, Some(model))
        }
    };
    let model = match robot {
        Some(m) => m,
        None => builtin_model("magnum")?,
    };
    Ok(StudyPlan {
        name,
        params: params.clone(),
        model,
        kind,
        rows,
    })
}

fn check_pitch_yaw(spec: &PitchYaw) -> Result<usize, ApiError> {
    for (name, p) in spec.points.iter().take(MAX_STUDY_SERIES + 1) {
        for (i, &v) in p.iter().enumerate() {
            coordinate(&format!("points {name:?} position[{i}]"), v)?;
        }
    }
    for v in spec.pitch_deg.iter().chain(&spec.yaw_deg) {
        angle("pitch_deg / yaw_deg", *v)?;
    }
    angle("step_deg", spec.step_deg)?;
    let pitch = limits::samples(
        "pitch range",
        spec.pitch_deg[0],
        spec.pitch_deg[1],
        spec.step_deg,
    )?;
    let yaw = limits::samples("yaw range", spec.yaw_deg[0], spec.yaw_deg[1], spec.step_deg)?;
    total_rows("points", spec.points.len(), pitch + yaw)
}

fn check_distance(spec: &DistanceSweep) -> Result<usize, ApiError> {
    for (i, &v) in spec.x_levels.iter().enumerate().take(MAX_STUDY_SERIES + 1) {
        coordinate(&format!("x_levels[{i}]"), v)?;
    }
    coordinate("z", spec.z)?;
    angle("swing_max_deg", spec.swing_max_deg)?;
    angle("step_deg", spec.step_deg)?;
    let n = limits::samples(
        "swing",
        -spec.swing_max_deg,
        spec.swing_max_deg,
        spec.step_deg,
    )?;
    total_rows("x_levels", spec.x_levels.len(), n)
}

/// Runs `one` on each element of `series` (one series of rows each), checking `cancel` before
/// every call.
fn per_series<T: Clone>(
    series: &[T],
    cancel: &Cancel,
    one: impl Fn(&T) -> Result<Vec<StudyRow>, seaarms_core::Error>,
) -> Result<Vec<StudyRowOut>, ComputeError> {
    let mut rows = Vec::new();
    for s in series {
        cancel.check()?;
        rows.extend(one(s)?.iter().map(StudyRowOut::from));
    }
    Ok(rows)
}

impl StudyPlan {
    /// Computes the study, one series at a time; `cancel` is checked between series (the
    /// workspace map is one core call, bounded by [`MAX_MAP_CELLS`]).
    pub fn run(&self, cancel: &Cancel) -> Result<StudyOutput, ComputeError> {
        let m = &self.model;
        let rows = match &self.kind {
            Kind::SweepX(spec, dual) => per_series(&spec.z_levels, cancel, |&z| {
                let one = SweepX {
                    z_levels: vec![z],
                    ..spec.clone()
                };
                match dual {
                    Some(setup) => studies::dual_x(m, &one, setup),
                    None => studies::single_x(m, &one),
                }
            })?,
            Kind::SweepZ(spec) => per_series(&spec.x_levels, cancel, |&x| {
                let one = SweepZ {
                    x_levels: vec![x],
                    ..spec.clone()
                };
                studies::single_z(m, &one)
            })?,
            Kind::PitchYaw(spec, dual) => per_series(&spec.points, cancel, |point| {
                let one = PitchYaw {
                    points: vec![point.clone()],
                    ..spec.clone()
                };
                match dual {
                    Some(setup) => studies::dual_pitch_yaw(m, &one, setup),
                    None => studies::single_pitch_yaw(m, &one),
                }
            })?,
            Kind::Distance(spec, setup) => per_series(&spec.x_levels, cancel, |&x| {
                let one = DistanceSweep {
                    x_levels: vec![x],
                    ..spec.clone()
                };
                studies::dual_distance(m, &one, setup)
            })?,
            Kind::Map(spec, orientation) => {
                cancel.check()?;
                return Ok(StudyOutput(Output::Map {
                    robot: m.name.clone(),
                    orientation: orientation.clone(),
                    map: studies::workspace_map(m, spec)?,
                }));
            }
        };
        Ok(StudyOutput(Output::Rows {
            study: self.name,
            robot: m.name.clone(),
            params: self.params.clone(),
            rows,
        }))
    }
}

/// A computed study, rendered on demand as JSON or CSV.
#[derive(Debug, Clone)]
pub struct StudyOutput(Output);

#[derive(Debug, Clone)]
enum Output {
    /// A case study's rows (study name, model name, the parameters as sent, the rows).
    Rows {
        study: &'static str,
        robot: String,
        params: Value,
        rows: Vec<StudyRowOut>,
    },
    /// The workspace map (model name, `nominal` or `free`, the grid).
    Map {
        robot: String,
        orientation: String,
        map: WorkspaceMap,
    },
}

const NOTES: &str = "Translational measures (rows vx vy vz). Fixed orientation = the posture at q = 0 \
     (approach axis horizontal along +X), pitch 90 deg / yaw 90 deg; pitch > 90 deg tilts the jaw \
     down, yaw > 90 deg turns it towards +Y. Targets in each arm's base \
     frame; left arm base at Y = left_base_y_m. Unreachable rows have null measures; the first \
     unreachable row of a sweep marks the workspace boundary.";

/// The JSON document of a case study.
#[derive(Serialize)]
struct RowsDocument<'a> {
    study: &'a str,
    robot: &'a str,
    params: &'a Value,
    notes: &'static str,
    columns: &'static [&'static str],
    summary: Value,
    rows: &'a [StudyRowOut],
}

/// The JSON document of a workspace map.
#[derive(Serialize)]
struct MapDocument<'a> {
    study: &'static str,
    robot: &'a str,
    orientation: &'a str,
    y: f64,
    x: &'a [f64],
    z: &'a [f64],
    layout: &'static str,
    yoshikawa: Vec<Vec<Option<f64>>>,
    isotropy: Vec<Vec<Option<f64>>>,
    hong: Vec<Vec<Option<f64>>>,
    summary: Value,
}

fn bytes<T: Serialize>(doc: &T, pretty: bool) -> Result<Vec<u8>, serde_json::Error> {
    if pretty {
        serde_json::to_vec_pretty(doc)
    } else {
        serde_json::to_vec(doc)
    }
}

impl StudyOutput {
    /// The JSON document (compact, or indented for people).
    pub fn json(&self, pretty: bool) -> Result<Vec<u8>, serde_json::Error> {
        match &self.0 {
            Output::Rows {
                study,
                robot,
                params,
                rows,
            } => bytes(
                &RowsDocument {
                    study,
                    robot,
                    params,
                    notes: NOTES,
                    columns: ROW_COLUMNS,
                    summary: summary(rows),
                    rows,
                },
                pretty,
            ),
            Output::Map {
                robot,
                orientation,
                map,
            } => bytes(&map_document(robot, orientation, map), pretty),
        }
    }

    /// The rows (or cells) as CSV.
    pub fn csv(&self) -> String {
        match &self.0 {
            Output::Rows { rows, .. } => rows_csv(rows),
            Output::Map { map, .. } => map_csv(map),
        }
    }
}

/// One study row on the wire (and in the CSV): flat, measures `null` when unreachable.
#[derive(Debug, Clone, Serialize)]
struct StudyRowOut {
    series: String,
    parameter: f64,
    x: f64,
    y: f64,
    z: f64,
    pitch_deg: f64,
    yaw_deg: f64,
    reachable: bool,
    yoshikawa: Option<f64>,
    isotropy: Option<f64>,
    hong: Option<f64>,
    left_yoshikawa: Option<f64>,
    left_isotropy: Option<f64>,
    left_hong: Option<f64>,
    dual_yoshikawa: Option<f64>,
    dual_isotropy: Option<f64>,
    dual_hong: Option<f64>,
    distance_m: Option<f64>,
    q: Option<Vec<f64>>,
    q_left: Option<Vec<f64>>,
}

impl From<&StudyRow> for StudyRowOut {
    /// An unreachable row carries no measures and no posture, whatever an arm of it reached
    /// (a dual row is reachable only when both arms are).
    fn from(r: &StudyRow) -> Self {
        let r = &if r.reachable {
            r.clone()
        } else {
            StudyRow {
                single: None,
                left: None,
                dual: None,
                distance_m: None,
                q: None,
                q_left: None,
                ..r.clone()
            }
        };
        StudyRowOut {
            series: r.series.clone(),
            parameter: r.parameter,
            x: r.position[0],
            y: r.position[1],
            z: r.position[2],
            pitch_deg: r.pitch_deg,
            yaw_deg: r.yaw_deg,
            reachable: r.reachable,
            yoshikawa: r.single.map(|m| m.yoshikawa),
            isotropy: r.single.map(|m| m.isotropy),
            hong: r.single.map(|m| m.hong),
            left_yoshikawa: r.left.map(|m| m.yoshikawa),
            left_isotropy: r.left.map(|m| m.isotropy),
            left_hong: r.left.map(|m| m.hong),
            dual_yoshikawa: r.dual.map(|m| m.yoshikawa),
            dual_isotropy: r.dual.map(|m| m.isotropy),
            dual_hong: r.dual.map(|m| m.hong),
            distance_m: r.distance_m,
            q: r.q.clone(),
            q_left: r.q_left.clone(),
        }
    }
}

const ROW_COLUMNS: &[&str] = &[
    "series",
    "parameter",
    "x",
    "y",
    "z",
    "pitch_deg",
    "yaw_deg",
    "reachable",
    "yoshikawa",
    "isotropy",
    "hong",
    "left_yoshikawa",
    "left_isotropy",
    "left_hong",
    "dual_yoshikawa",
    "dual_isotropy",
    "dual_hong",
    "distance_m",
];

fn rows_csv(rows: &[StudyRowOut]) -> String {
    crate::csv_out::table_of(ROW_COLUMNS, rows)
}

/// Per series: row counts, the last reachable parameter (the boundary of a sweep) and where
/// each measure peaks.
fn summary(rows: &[StudyRowOut]) -> Value {
    let mut names: Vec<&str> = Vec::new();
    for r in rows {
        if !names.contains(&r.series.as_str()) {
            names.push(&r.series);
        }
    }
    let peak = |rs: &[&StudyRowOut], f: &dyn Fn(&StudyRowOut) -> Option<f64>| -> Value {
        rs.iter()
            .filter_map(|r| f(r).map(|v| (r.parameter, v)))
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(p, v)| json!({"parameter": p, "value": v}))
            .unwrap_or(Value::Null)
    };
    let series: Vec<Value> = names
        .iter()
        .map(|name| {
            let rs: Vec<&StudyRowOut> = rows.iter().filter(|r| r.series == *name).collect();
            let reachable: Vec<&StudyRowOut> = rs.iter().copied().filter(|r| r.reachable).collect();
            json!({
                "series": name,
                "rows": rs.len(),
                "reachable": reachable.len(),
                "last_reachable_parameter": reachable.last().map(|r| r.parameter),
                "max_yoshikawa": peak(&reachable, &|r| r.yoshikawa),
                "max_isotropy": peak(&reachable, &|r| r.isotropy),
                "max_hong": peak(&reachable, &|r| r.hong),
                "max_dual_yoshikawa": peak(&reachable, &|r| r.dual_yoshikawa),
                "max_dual_isotropy": peak(&reachable, &|r| r.dual_isotropy),
            })
        })
        .collect();
    json!({ "series": series })
}

fn map_document<'a>(
    robot: &'a str,
    orientation: &'a str,
    map: &'a WorkspaceMap,
) -> MapDocument<'a> {
    let grid = |f: &dyn Fn(&studies::MeasureTriple) -> f64| -> Vec<Vec<Option<f64>>> {
        map.cells
            .chunks(map.x.len().max(1))
            .map(|row| row.iter().map(|c| c.measures.map(|m| f(&m))).collect())
            .collect()
    };
    let reachable = map.cells.iter().filter(|c| c.measures.is_some()).count();
    let best = |f: &dyn Fn(&studies::MeasureTriple) -> f64| -> Value {
        map.cells
            .iter()
            .filter_map(|c| c.measures.map(|m| (c.x, c.z, f(&m))))
            .max_by(|a, b| a.2.total_cmp(&b.2))
            .map(|(x, z, v)| json!({"x": x, "z": z, "value": v}))
            .unwrap_or(Value::Null)
    };
    MapDocument {
        study: "workspace-map",
        robot,
        orientation,
        y: map.y,
        x: &map.x,
        z: &map.z,
        layout: "grids are [iz][ix]; null = unreachable within the joint limits",
        yoshikawa: grid(&|m| m.yoshikawa),
        isotropy: grid(&|m| m.isotropy),
        hong: grid(&|m| m.hong),
        summary: json!({
            "cells": map.cells.len(),
            "reachable": reachable,
            "max_yoshikawa": best(&|m| m.yoshikawa),
            "max_isotropy": best(&|m| m.isotropy),
        }),
    }
}

fn map_csv(map: &WorkspaceMap) -> String {
    crate::csv_out::table(
        &["x", "z", "reachable", "yoshikawa", "isotropy", "hong"],
        map.cells.iter().map(|c| {
            let m = c.measures;
            [
                c.x.into(),
                c.z.into(),
                m.is_some().into(),
                m.map(|m| m.yoshikawa).into(),
                m.map(|m| m.isotropy).into(),
                m.map(|m| m.hong).into(),
            ]
        }),
    )
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    fn run(name: &str, params: &Value) -> Result<StudyOutput, String> {
        let plan = plan(name, params).map_err(|e| e.error)?;
        plan.run(&Cancel::never()).map_err(|e| e.to_string())
    }

    #[test]
    fn every_listed_study_runs_with_small_parameters() {
        let small: &[(&str, Value)] = &[
            ("single-x", json!({"z_levels": [0.2], "x_step": 0.05})),
            ("single-z", json!({"x_levels": [1.2], "z_step": 0.05})),
            (
                "single-pitch-yaw",
                json!({"points": [{"name": "A", "position": [1.0, 0.0, 0.2]}], "step_deg": 15}),
            ),
            ("dual-x", json!({"z_levels": [0.2], "x_step": 0.05})),
            (
                "dual-pitch-yaw",
                json!({"points": [{"name": "F", "position": [1.3, 0.0, 0.3]}], "step_deg": 15}),
            ),
            ("dual-distance", json!({"x_levels": [1.2], "step_deg": 5})),
            ("workspace-map", json!({"nx": 8, "nz": 6})),
        ];
        assert_eq!(small.len(), STUDIES.len());
        for (name, params) in small {
            let out = run(name, params).unwrap_or_else(|e| panic!("{name}: {e}"));
            let csv = out.csv();
            assert!(csv.lines().count() > 1, "{name}");
            let text = String::from_utf8(out.json(false).unwrap()).unwrap();
            assert!(!text.contains("NaN"), "{name}");
            let doc: Value = serde_json::from_str(&text).unwrap();
            assert!(doc.get("summary").is_some(), "{name}");
            assert_eq!(doc["study"], *name);
        }
        assert!(run("nope", &Value::Null).is_err());
        assert!(run("single-x", &json!({"bogus": 1})).is_err());
        assert!(run("single-x", &json!({"x_step": -1.0})).is_err());
        assert!(
            run(
                "workspace-map",
                &json!({"robot": "orion", "nx": 4, "nz": 4})
            )
            .is_ok()
        );
    }

    /// Running series by series gives the rows of one core call over all series (the core
    /// starts every series afresh: Lim §4.3 sweeps are independent per level / point).
    #[test]
    fn series_by_series_equals_one_core_call() {
        let model = builtin_model("magnum").unwrap();
        let spec = SweepX {
            z_levels: vec![0.0, 0.2, 0.4],
            step: 0.02,
            ..SweepX::default()
        };
        let setup = DualSetup::default();
        let whole = studies::dual_x(&model, &spec, &setup).unwrap();
        let params = json!({"z_levels": [0.0, 0.2, 0.4], "x_step": 0.02});
        let out = plan("dual-x", &params)
            .unwrap()
            .run(&Cancel::never())
            .unwrap();
        let Output::Rows { rows, .. } = &out.0 else {
            panic!("rows expected")
        };
        assert_eq!(rows.len(), whole.len());
        for (a, b) in rows.iter().zip(&whole) {
            let b = StudyRowOut::from(b);
            assert_eq!(
                serde_json::to_value(a).unwrap(),
                serde_json::to_value(&b).unwrap()
            );
        }
        let spec = PitchYaw::default();
        let whole = studies::single_pitch_yaw(&model, &spec).unwrap();
        let out = plan("single-pitch-yaw", &Value::Null)
            .unwrap()
            .run(&Cancel::never())
            .unwrap();
        assert_eq!(
            out.csv(),
            rows_csv(&whole.iter().map(StudyRowOut::from).collect::<Vec<_>>())
        );
    }

    /// Issue 13: the attack requests are refused before anything runs, naming the limit.
    #[test]
    fn over_limit_and_absurd_requests_are_400s_naming_the_limit() {
        let levels: Vec<f64> = (0..13_000).map(|i| i as f64 * 1e-4).collect();
        let cases = [
            (
                "single-x",
                json!({"z_levels": levels, "x_step": 1e-4}),
                "max_study_series",
            ),
            (
                "single-x",
                json!({"z_levels": vec![0.0; 40], "x_step": 1e-4}),
                "max_study_rows",
            ),
            (
                "single-x",
                json!({"x_step": 1e-300, "x_end": 1e308}),
                "max_study_coordinate_m",
            ),
            ("single-x", json!({"x_step": 1e-300}), "max_study_rows"),
            (
                "dual-x",
                json!({"left_base_y_m": 1e9}),
                "max_study_coordinate_m",
            ),
            ("single-z", json!({"z_step": 1e-5}), "max_study_rows"),
            (
                "single-pitch-yaw",
                json!({"step_deg": 1e-4}),
                "max_study_rows",
            ),
            (
                "dual-pitch-yaw",
                json!({"pitch_deg": [0, 1e6]}),
                "max_study_angle_deg",
            ),
            (
                "dual-distance",
                json!({"swing_max_deg": 1e300, "step_deg": 1}),
                "max_study_angle_deg",
            ),
            (
                "workspace-map",
                json!({"nx": 1000, "nz": 1000}),
                "max_map_cells",
            ),
            (
                "workspace-map",
                json!({"nx": usize::MAX, "nz": 2}),
                "max_map_cells",
            ),
            (
                "workspace-map",
                json!({"x_range": [-1e300, 1e300]}),
                "max_study_coordinate_m",
            ),
        ];
        for (name, params, limit) in cases {
            let e = plan(name, &params).expect_err(name);
            assert_eq!(e.status, 400, "{name}");
            assert_eq!(
                e.detail.as_ref().unwrap()["limit"],
                limit,
                "{name}: {}",
                e.error
            );
            assert!(e.error.contains(limit), "{}", e.error);
        }
        for (name, params) in [
            ("single-x", json!({"x_step": 0.0})),
            ("single-x", json!({"x_start": 2.0, "x_end": 1.0})),
            ("dual-distance", json!({"step_deg": -1})),
            ("workspace-map", json!({"nx": 0})),
            ("workspace-map", json!({"orientation": "sideways"})),
            ("single-x", json!([1, 2])),
        ] {
            assert_eq!(
                plan(name, &params).expect_err(name).status,
                400,
                "{name} {params}"
            );
        }
        // At the limit exactly: accepted.
        // Binary-exact step 2⁻¹⁰ m from 0 to 999·2⁻¹⁰ m: 1000 samples per level, 20 levels.
        let step = 1.0 / 1024.0;
        let params = json!({"z_levels": vec![0.0; 20], "x_start": 0.0, "x_end": 999.0 * step, "x_step": step});
        assert_eq!(plan("single-x", &params).unwrap().rows, MAX_STUDY_ROWS);
        let params = json!({"z_levels": vec![0.0; 20], "x_start": 0.0, "x_end": 1000.0 * step, "x_step": step});
        assert!(plan("single-x", &params).is_err());
    }

    #[test]
    fn a_cancelled_study_stops() {
        let cancel = Cancel::until(std::time::Duration::ZERO);
        let e = plan("single-x", &Value::Null)
            .unwrap()
            .run(&cancel)
            .unwrap_err();
        assert!(matches!(e, ComputeError::Deadline { .. }), "{e}");
    }
}
