//! Wire types and plain functions for the optimisation and study endpoints; the HTTP layer
//! (routes, robot resolution, error mapping) calls these.
//!
//! * [`optimal_posture`]: Jun 2008 §3 optimal posture for a resolved model
//!   (`POST` body [`OptimalPostureRequest`], answer [`OptimalPostureResponse`]); a target
//!   outside the workspace is [`seaarms_core::Error::Unreachable`] (→ 422).
//! * [`run_study`]: one of the Lim 2005 §4.3 case studies or the workspace map by name, with
//!   optional JSON parameters; returns the JSON document (rows + summary) and the same rows as
//!   CSV. [`list_studies`] names them.
//!
//! Parameters are parsed here into typed core inputs (unknown study parameters are rejected);
//! the core validates ranges and returns its own errors.

use serde::{Deserialize, Serialize};
use serde_json::{Value, json};

use seaarms_core::studies::{
    self, DistanceSweep, DualSetup, MapSpec, PitchYaw, StudyRow, SweepX, SweepZ, WorkspaceMap,
};
use seaarms_core::{Error, Model, ModelSpec, optimize};

/// Body of an optimal-posture request (the robot is resolved by the caller).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OptimalPostureRequest {
    /// Target of the tool point, base frame (m).
    pub target_position: [f64; 3],
    /// Weight α ∈ [0, 1] of TOMM in f = −α·TOMM − (1 − α)·JLM (Jun eq. 17).
    pub alpha: f64,
    /// Task rows of the Jacobian for TOMM (0..6: vx vy vz wx wy wz); default [0, 1, 2].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rows: Option<Vec<usize>>,
    /// Number of initial candidates, 1..=64; default 8.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub starts: Option<usize>,
}

/// Answer of an optimal-posture request.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OptimalPostureResponse {
    /// Optimal joint values (rad or m).
    pub q: Vec<f64>,
    /// TOMM of the task rows at `q`.
    pub tomm: f64,
    /// JLM at `q` (Jun eq. 16).
    pub jlm: f64,
    /// f(q) = −α·TOMM − (1 − α)·JLM.
    pub objective: f64,
    /// Objective evaluations of the winning SQP run.
    pub iterations: usize,
    /// Distance between tool point and target (m), ≤ 1e-6.
    pub constraint_violation_m: f64,
    /// Index of the winning initial candidate.
    pub start: usize,
}

/// Optimal posture of `model` for `req` (validated: α ∈ [0, 1], finite target, valid rows,
/// starts 1..=64).
pub fn optimal_posture(
    model: &Model,
    req: &OptimalPostureRequest,
) -> Result<OptimalPostureResponse, Error> {
    let defaults = optimize::PostureOptions::default();
    let opts = optimize::PostureOptions {
        alpha: req.alpha,
        rows: req.rows.clone().unwrap_or(defaults.rows.clone()),
        starts: req.starts.unwrap_or(defaults.starts),
        ..defaults
    };
    if opts.starts == 0 {
        return Err(Error::InvalidParameter {
            what: "starts",
            reason: "must be in 1..=64".into(),
        });
    }
    let r = optimize::optimal_posture(model, &req.target_position, &opts)?;
    Ok(OptimalPostureResponse {
        q: r.q,
        tomm: r.tomm,
        jlm: r.jlm,
        objective: r.objective,
        iterations: r.iterations,
        constraint_violation_m: r.constraint_violation_m,
        start: r.start,
    })
}

/// (name, description) of every study [`run_study`] accepts.
pub fn list_studies() -> Vec<(&'static str, &'static str)> {
    vec![
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
    ]
}

fn bad(what: &'static str, e: serde_json::Error) -> Error {
    Error::InvalidParameter {
        what,
        reason: e.to_string(),
    }
}

/// Parses `params` (null or an object) into `T`, defaults for missing fields.
fn parse<T: for<'de> Deserialize<'de> + Default>(params: &Value) -> Result<T, Error> {
    if params.is_null() {
        return Ok(T::default());
    }
    serde_json::from_value(params.clone()).map_err(|e| bad("study parameters", e))
}

fn builtin_model(name: &str) -> Result<Model, Error> {
    let text = seaarms_core::robots::builtin_text(name).ok_or_else(|| Error::InvalidParameter {
        what: "robot",
        reason: format!("unknown built-in robot {name:?}"),
    })?;
    let spec: ModelSpec = serde_json::from_str(text).map_err(|e| bad("robot", e))?;
    Model::from_spec(&spec)
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

fn dual_setup(left_base_y_m: Option<f64>) -> DualSetup {
    DualSetup {
        left_base_y_m: left_base_y_m.unwrap_or(DualSetup::default().left_base_y_m),
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
    fn from(r: &StudyRow) -> Self {
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

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

fn num(v: Option<f64>) -> String {
    v.map(|x| format!("{x}")).unwrap_or_default()
}

fn rows_csv(rows: &[StudyRowOut]) -> String {
    let mut out = ROW_COLUMNS.join(",");
    out.push('\n');
    for r in rows {
        let fields = [
            csv_field(&r.series),
            num(Some(r.parameter)),
            num(Some(r.x)),
            num(Some(r.y)),
            num(Some(r.z)),
            num(Some(r.pitch_deg)),
            num(Some(r.yaw_deg)),
            r.reachable.to_string(),
            num(r.yoshikawa),
            num(r.isotropy),
            num(r.hong),
            num(r.left_yoshikawa),
            num(r.left_isotropy),
            num(r.left_hong),
            num(r.dual_yoshikawa),
            num(r.dual_isotropy),
            num(r.dual_hong),
            num(r.distance_m),
        ];
        out.push_str(&fields.join(","));
        out.push('\n');
    }
    out
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

fn study_document(name: &str, model: &Model, params: Value, rows: &[StudyRow]) -> (Value, String) {
    let out: Vec<StudyRowOut> = rows.iter().map(StudyRowOut::from).collect();
    let csv = rows_csv(&out);
    let doc = json!({
        "study": name,
        "robot": model.name,
        "params": params,
        "notes": "Translational measures (rows vx vy vz). Fixed orientation = the posture at q = 0 \
                  (approach axis horizontal along +X), pitch 90 deg / yaw 90 deg. Targets in each \
                  arm's base frame; left arm base at Y = left_base_y_m. Unreachable rows have null \
                  measures; the first unreachable row of a sweep marks the workspace boundary.",
        "columns": ROW_COLUMNS,
        "summary": summary(&out),
        "rows": out,
    });
    (doc, csv)
}

fn map_document(model: &Model, map: &WorkspaceMap, orientation: &str) -> (Value, String) {
    let grid = |f: &dyn Fn(&studies::MeasureTriple) -> f64| -> Vec<Vec<Option<f64>>> {
        map.z
            .iter()
            .enumerate()
            .map(|(iz, _)| {
                (0..map.x.len())
                    .map(|ix| map.cells[iz * map.x.len() + ix].measures.map(|m| f(&m)))
                    .collect()
            })
            .collect()
    };
    let mut csv = String::from("x,z,reachable,yoshikawa,isotropy,hong\n");
    for c in &map.cells {
        csv.push_str(&format!(
            "{},{},{},{},{},{}\n",
            c.x,
            c.z,
            c.measures.is_some(),
            num(c.measures.map(|m| m.yoshikawa)),
            num(c.measures.map(|m| m.isotropy)),
            num(c.measures.map(|m| m.hong))
        ));
    }
    let reachable = map.cells.iter().filter(|c| c.measures.is_some()).count();
    let best = |f: &dyn Fn(&studies::MeasureTriple) -> f64| -> Value {
        map.cells
            .iter()
            .filter_map(|c| c.measures.map(|m| (c.x, c.z, f(&m))))
            .max_by(|a, b| a.2.total_cmp(&b.2))
            .map(|(x, z, v)| json!({"x": x, "z": z, "value": v}))
            .unwrap_or(Value::Null)
    };
    let doc = json!({
        "study": "workspace-map",
        "robot": model.name,
        "orientation": orientation,
        "y": map.y,
        "x": map.x,
        "z": map.z,
        "layout": "grids are [iz][ix]; null = unreachable within the joint limits",
        "yoshikawa": grid(&|m| m.yoshikawa),
        "isotropy": grid(&|m| m.isotropy),
        "hong": grid(&|m| m.hong),
        "summary": {
            "cells": map.cells.len(),
            "reachable": reachable,
            "max_yoshikawa": best(&|m| m.yoshikawa),
            "max_isotropy": best(&|m| m.isotropy),
        },
    });
    (doc, csv)
}

/// Runs the study `name` (see [`list_studies`]) with `params` (null or an object; see each
/// study's fields: `single-x`/`dual-x`: `z_levels, x_start, x_step, x_end, left_base_y_m`;
/// `single-z`: `x_levels, z_start, z_step, z_end`; `*-pitch-yaw`: `points [{name, position}],
/// pitch_deg [a, b], yaw_deg [a, b], step_deg, left_base_y_m`; `dual-distance`: `x_levels, z,
/// swing_max_deg, step_deg, left_base_y_m`; `workspace-map`: `robot, x_range, z_range, nx, nz,
/// y, orientation ("nominal" | "free")`). Returns the JSON document and the CSV rows.
pub fn run_study(name: &str, params: &Value) -> Result<(Value, String), Error> {
    if !(params.is_null() || params.is_object()) {
        return Err(Error::InvalidParameter {
            what: "study parameters",
            reason: "must be an object".into(),
        });
    }
    if name == "workspace-map" {
        let p: MapParams = parse(params)?;
        let model = builtin_model(p.robot.as_deref().unwrap_or("magnum"))?;
        let d = MapSpec::case_study(&model);
        let magnum = seaarms_core::ik::MagnumLengths::from_model(&model).is_ok();
        let orientation = p
            .orientation
            .clone()
            .unwrap_or_else(|| if magnum { "nominal" } else { "free" }.to_string());
        let fixed = match orientation.as_str() {
            "nominal" => Some(studies::nominal_orientation(&model)),
            "free" => None,
            other => {
                return Err(Error::InvalidParameter {
                    what: "orientation",
                    reason: format!("{other:?} is not \"nominal\" or \"free\""),
                });
            }
        };
        let spec = MapSpec {
            x_range: p.x_range.unwrap_or(d.x_range),
            z_range: p.z_range.unwrap_or(d.z_range),
            nx: p.nx.unwrap_or(d.nx),
            nz: p.nz.unwrap_or(d.nz),
            y: p.y.unwrap_or(d.y),
            orientation: fixed,
        };
        let map = studies::workspace_map(&model, &spec)?;
        return Ok(map_document(&model, &map, &orientation));
    }
    let model = builtin_model("magnum")?;
    let rows = match name {
        "single-x" => studies::single_x(&model, &parse::<SweepXParams>(params)?.spec())?,
        "dual-x" => {
            let p: SweepXParams = parse(params)?;
            studies::dual_x(&model, &p.spec(), &dual_setup(p.left_base_y_m))?
        }
        "single-z" => {
            let p: SweepZParams = parse(params)?;
            let d = SweepZ::default();
            let spec = SweepZ {
                x_levels: p.x_levels.unwrap_or(d.x_levels),
                start: p.z_start.unwrap_or(d.start),
                step: p.z_step.unwrap_or(d.step),
                end: p.z_end.unwrap_or(d.end),
            };
            studies::single_z(&model, &spec)?
        }
        "single-pitch-yaw" => {
            studies::single_pitch_yaw(&model, &parse::<PitchYawParams>(params)?.spec())?
        }
        "dual-pitch-yaw" => {
            let p: PitchYawParams = parse(params)?;
            studies::dual_pitch_yaw(&model, &p.spec(), &dual_setup(p.left_base_y_m))?
        }
        "dual-distance" => {
            let p: DistanceParams = parse(params)?;
            let d = DistanceSweep::default();
            let spec = DistanceSweep {
                x_levels: p.x_levels.unwrap_or(d.x_levels),
                z: p.z.unwrap_or(d.z),
                swing_max_deg: p.swing_max_deg.unwrap_or(d.swing_max_deg),
                step_deg: p.step_deg.unwrap_or(d.step_deg),
            };
            studies::dual_distance(&model, &spec, &dual_setup(p.left_base_y_m))?
        }
        other => {
            let names: Vec<&str> = list_studies().iter().map(|(n, _)| *n).collect();
            return Err(Error::InvalidParameter {
                what: "study",
                reason: format!("unknown study {other:?}; known: {}", names.join(", ")),
            });
        }
    };
    Ok(study_document(name, &model, params.clone(), &rows))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn orion() -> Model {
        builtin_model("orion").expect("orion")
    }

    #[test]
    fn optimal_posture_round_trips_and_validates() {
        let req: OptimalPostureRequest = serde_json::from_value(
            json!({"target_position": [0.9, 0.1, 0.1], "alpha": 0.5, "starts": 4}),
        )
        .expect("parses");
        let r = optimal_posture(&orion(), &req).expect("reachable");
        assert!(r.constraint_violation_m <= 1e-6);
        let v = serde_json::to_value(&r).expect("serialises");
        for k in [
            "q",
            "tomm",
            "jlm",
            "objective",
            "iterations",
            "constraint_violation_m",
            "start",
        ] {
            assert!(v.get(k).is_some(), "{k}");
        }
        let far = OptimalPostureRequest {
            target_position: [5.0, 0.0, 0.0],
            ..req.clone()
        };
        assert!(matches!(
            optimal_posture(&orion(), &far),
            Err(Error::Unreachable { .. })
        ));
        for bad in [
            OptimalPostureRequest {
                alpha: -0.1,
                ..req.clone()
            },
            OptimalPostureRequest {
                starts: Some(0),
                ..req.clone()
            },
            OptimalPostureRequest {
                starts: Some(65),
                ..req.clone()
            },
            OptimalPostureRequest {
                rows: Some(vec![7]),
                ..req.clone()
            },
            OptimalPostureRequest {
                target_position: [f64::INFINITY, 0.0, 0.0],
                ..req.clone()
            },
        ] {
            assert!(optimal_posture(&orion(), &bad).is_err(), "{bad:?}");
        }
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
        assert_eq!(small.len(), list_studies().len());
        for (name, params) in small {
            let (doc, csv) = run_study(name, params).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert!(!csv.is_empty() && csv.lines().count() > 1, "{name}");
            let text = serde_json::to_string(&doc).expect("json");
            assert!(!text.contains("NaN"), "{name}");
            assert!(doc.get("summary").is_some(), "{name}");
        }
        assert!(run_study("nope", &Value::Null).is_err());
        assert!(run_study("single-x", &json!({"bogus": 1})).is_err());
        assert!(run_study("single-x", &json!({"x_step": -1.0})).is_err());
        assert!(
            run_study(
                "workspace-map",
                &json!({"robot": "orion", "nx": 4, "nz": 4})
            )
            .is_ok()
        );
    }
}
