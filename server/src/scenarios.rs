//! Scripted scenarios (Lim §4.2 dynamic case studies) for the CLI and HTTP API: runs one in
//! the core, measures the wall time, returns the summary (JSON-serializable) and the CSV of
//! post-processing rows.

use std::time::Instant;

use seaarms_core::sim::scenario::{self, Row, Summary};

use crate::catalogue::SCRIPTED;

use crate::csv_out::CsvOut;
use seaarms_core::{Model, ModelSpec, robots};
use serde::Serialize;

/// Errors of a scenario run.
#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
    /// No scenario of that name.
    #[error("unknown scenario {0:?}")]
    Unknown(String),
    /// The core refused (model or parameters).
    #[error(transparent)]
    Core(#[from] seaarms_core::Error),
    /// The built-in Magnum model did not load.
    #[error("built-in model: {0}")]
    Model(String),
    /// Writing the CSV failed.
    #[error("CSV: {0}")]
    Csv(#[from] std::io::Error),
}

/// Summary of a run: the core's [`Summary`] (its fields at the top level of the JSON) plus
/// wall-clock figures.
#[derive(Debug, Clone, Serialize)]
pub struct ScenarioSummary {
    /// What the run did.
    #[serde(flatten)]
    pub run: Summary,
    /// Wall-clock time of the run, CSV formatting included (s).
    pub wall_seconds: f64,
    /// sim_seconds / wall_seconds.
    pub realtime_factor: f64,
    /// CSV rows written (one per 10 ms).
    pub rows: usize,
}

fn magnum() -> Result<Model, ScenarioError> {
    let text = robots::builtin_text("magnum")
        .ok_or_else(|| ScenarioError::Model("magnum missing".into()))?;
    let spec: ModelSpec =
        serde_json::from_str(text).map_err(|e| ScenarioError::Model(e.to_string()))?;
    Ok(Model::from_spec(&spec)?)
}

/// Runs scenario `name` with two built-in Magnum arms; returns the summary and the CSV text.
pub fn run_scenario(name: &str) -> Result<(ScenarioSummary, String), ScenarioError> {
    if !SCRIPTED.iter().any(|(n, _)| *n == name) {
        return Err(ScenarioError::Unknown(name.to_string()));
    }
    let m = magnum()?;
    let sc = scenario::scenario(name, &m, &m)?;
    // Every row goes through the one CSV writer (crate::csv_out) into one buffer.
    let mut out = CsvOut::new(Vec::with_capacity(1 << 20));
    out.header(&Row::header())?;
    let mut rows = 0usize;
    let mut failed: Option<std::io::Error> = None;
    let t0 = Instant::now();
    let s = scenario::run(&sc, &m, &m, |r| {
        let mut res = Ok(());
        r.cells(|c| {
            if res.is_ok() {
                res = out.field(c.into());
            }
        });
        match res.and_then(|()| out.end_row()) {
            Ok(()) => rows += 1,
            Err(e) => {
                failed.get_or_insert(e);
            }
        }
    })?;
    if let Some(e) = failed {
        return Err(e.into());
    }
    // Numbers, identifiers and commas only: always valid UTF-8.
    let text = String::from_utf8(out.into_inner()?)
        .unwrap_or_else(|e| String::from_utf8_lossy(e.as_bytes()).into_owned());
    let wall = t0.elapsed().as_secs_f64();
    Ok((
        ScenarioSummary {
            wall_seconds: wall,
            realtime_factor: if wall > 0.0 {
                s.sim_seconds / wall
            } else {
                f64::INFINITY
            },
            rows,
            run: s,
        },
        text,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_four_and_rejects_unknown() {
        assert_eq!(SCRIPTED.len(), 4);
        assert!(matches!(
            run_scenario("nope"),
            Err(ScenarioError::Unknown(_))
        ));
    }

    /// The core's rows, written by the one CSV module and read back by the `csv` crate's
    /// reader, are the same f64 values bit for bit (shortest round-trip format). The rows are
    /// produced twice — once collected in memory, once written — relying on the runner's
    /// determinism (server/core/tests/determinism.rs).
    #[test]
    fn scenario_rows_round_trip_through_the_csv() {
        let m = magnum().expect("magnum");
        let sc = scenario::scenario("case2-single-arm-load", &m, &m).expect("scenario");
        let mut expected: Vec<Vec<crate::csv_out::Field<'static>>> = Vec::new();
        scenario::run(&sc, &m, &m, |r| {
            let mut v = Vec::new();
            r.cells(|c| v.push(c.into()));
            expected.push(v);
        })
        .expect("run");
        let (summary, text) = run_scenario("case2-single-arm-load").expect("run");
        assert_eq!(summary.rows, expected.len());
        let mut reader = csv::Reader::from_reader(text.as_bytes());
        assert_eq!(reader.headers().expect("header").len(), Row::header().len());
        let mut n = 0;
        let mut numbers = 0;
        for (rec, want) in reader.records().zip(&expected) {
            let rec = rec.expect("row");
            assert_eq!(rec.len(), want.len());
            for (field, w) in rec.iter().zip(want) {
                match *w {
                    crate::csv_out::Field::Num(x) => {
                        let back: f64 = field.parse().expect("number");
                        assert_eq!(back.to_bits(), x.to_bits(), "{x:e} written as {field}");
                        numbers += 1;
                    }
                    crate::csv_out::Field::Text(s) => assert_eq!(field, s),
                    ref other => panic!("unexpected field {other:?}"),
                }
            }
            n += 1;
        }
        assert_eq!(n, expected.len());
        assert!(numbers > 100_000, "{numbers} numbers compared");
    }

    #[test]
    fn case1_gives_csv_and_summary_json() {
        let (summary, csv) = run_scenario("case1-single-arm").expect("run");
        let header = csv.lines().next().expect("header");
        for col in [
            "t_s",
            "left_q1_rad",
            "right_qd6_rad_s",
            "left_u2",
            "left_p_in2_pa",
            "left_p_out2_pa",
            "left_contact_fx_n",
            "internal_fx_n",
            "object_z_m",
            "grasp_state",
            "dual_yoshikawa",
        ] {
            assert!(header.split(',').any(|h| h == col), "missing column {col}");
        }
        assert_eq!(csv.lines().count(), summary.rows + 1);
        // A real CSV reader (the csv crate) reads every row with every column, and every
        // column but the two names is a number.
        let mut reader = csv::Reader::from_reader(csv.as_bytes());
        let names = reader.headers().expect("header").clone();
        let mut n = 0;
        for rec in reader.records() {
            let rec = rec.expect("well-formed row");
            assert_eq!(rec.len(), names.len());
            for (name, field) in names.iter().zip(rec.iter()) {
                if name != "stage" && name != "grasp_state" {
                    assert!(field.parse::<f64>().is_ok(), "{name} = {field:?}");
                }
            }
            n += 1;
        }
        assert_eq!(n, summary.rows);
        assert!(summary.rows > 3900);
        let json = serde_json::to_value(&summary).expect("json");
        for key in [
            "peak_line_pressure_pa",
            "peak_internal_force_n",
            "peak_internal_torque_nm",
            "relief_events",
            "object_lift_m",
            "final_grasp_state",
            "sim_seconds",
            "wall_seconds",
            "realtime_factor",
        ] {
            assert!(json.get(key).is_some(), "missing {key}");
        }
        assert_eq!(json["final_grasp_state"], "free");
        assert!(summary.realtime_factor > 1.0);
    }
}
