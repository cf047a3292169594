//! `GET /api/scenarios`, `POST /api/scenarios/{name}/run` and the CSV of a run.

use std::collections::VecDeque;
use std::sync::Mutex;

use axum::Json;
use axum::extract::{Path, State};
use axum::http::header;
use axum::response::{IntoResponse, Response};
use serde::Serialize;

use crate::app::AppState;
use crate::catalogue::SCRIPTED;
use crate::compute::ComputeError;
use crate::error::ApiError;
use crate::scenarios::{ScenarioError, run_scenario};

/// CSVs of recent runs kept for download (oldest dropped first).
pub const KEPT_RUNS: usize = 16;

/// Recent runs' CSV text by run id.
#[derive(Default)]
pub struct RunStore {
    runs: Mutex<VecDeque<(String, String)>>,
}

impl RunStore {
    fn put(&self, id: String, csv: String) {
        let mut runs = self.runs.lock().unwrap_or_else(|e| e.into_inner());
        if runs.len() >= KEPT_RUNS {
            runs.pop_front();
        }
        runs.push_back((id, csv));
    }
    fn get(&self, id: &str) -> Option<String> {
        let runs = self.runs.lock().unwrap_or_else(|e| e.into_inner());
        runs.iter().find(|(i, _)| i == id).map(|(_, c)| c.clone())
    }
}

/// One scenario.
#[derive(Debug, Serialize)]
pub struct ScenarioInfo {
    /// Name to run.
    pub name: String,
    /// What it reproduces.
    pub description: String,
}

/// Lists the scenarios.
pub async fn list() -> Json<Vec<ScenarioInfo>> {
    Json(
        SCRIPTED
            .iter()
            .map(|(name, description)| ScenarioInfo {
                name: name.to_string(),
                description: description.to_string(),
            })
            .collect(),
    )
}

/// Runs one scenario on the compute pool (a fixed ~40 s of simulated time, well under a
/// second of CPU) and returns its summary with `csv_url` for the post-processing data.
pub async fn run(
    State(state): State<AppState>,
    Path(name): Path<String>,
) -> Result<Response, ComputeError> {
    if !SCRIPTED.iter().any(|(n, _)| *n == name) {
        return Err(ApiError::not_found(ScenarioError::Unknown(name).to_string()).into());
    }
    let n = name.clone();
    let (summary, csv) = state
        .compute
        .run(move |_| {
            run_scenario(&n).map_err(|e| {
                ComputeError::Api(ApiError {
                    status: axum::http::StatusCode::INTERNAL_SERVER_ERROR,
                    error: e.to_string(),
                    detail: None,
                })
            })
        })
        .await?;
    let run_id = format!("{name}-{}.csv", crate::ids::random_hex(4));
    state.scenario_runs.put(run_id.clone(), csv);
    let mut body = serde_json::to_value(&summary).map_err(|_| ComputeError::Failed)?;
    body["csv_url"] = serde_json::json!(format!("/api/scenarios/runs/{run_id}"));
    Ok(Json(body).into_response())
}

/// The CSV of a recent run.
pub async fn download(
    State(state): State<AppState>,
    Path(run): Path<String>,
) -> Result<Response, ApiError> {
    let csv = state.scenario_runs.get(&run).ok_or_else(|| {
        ApiError::not_found(format!(
            "no run `{run}` (only the last {KEPT_RUNS} are kept)"
        ))
    })?;
    Ok(([(header::CONTENT_TYPE, "text/csv; charset=utf-8")], csv).into_response())
}
