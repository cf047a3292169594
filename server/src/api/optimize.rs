//! `POST /api/optimal-posture` (Jun §3, SQP over TOMM and JLM), `GET /api/studies` and
//! `POST /api/studies/{name}` (Lim §4.3 manipulability studies, workspace map).

use axum::Json;
use axum::extract::{Path, Query, State};
use axum::http::header;
use axum::response::{IntoResponse, Response};
use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::analysis_ext::{
    OptimalPostureRequest, OptimalPostureResponse, list_studies, optimal_posture, run_study,
};
use crate::app::AppState;
use crate::error::ApiError;
use crate::json::ApiJson;

/// Body of `POST /api/optimal-posture`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PostureBody {
    /// Built-in name or inline model.
    pub robot: Value,
    /// Tool-point target, base frame (m).
    pub target_position: [f64; 3],
    /// Weight α ∈ [0, 1] of TOMM in f = −α·TOMM − (1 − α)·JLM (Jun eq. 17).
    pub alpha: f64,
    /// TOMM task rows (default translational 0, 1, 2).
    #[serde(default)]
    pub rows: Option<Vec<usize>>,
    /// Initial candidates, 1..=64 (default 8).
    #[serde(default)]
    pub starts: Option<usize>,
}

fn internal(e: impl std::fmt::Display) -> ApiError {
    ApiError {
        status: axum::http::StatusCode::INTERNAL_SERVER_ERROR,
        error: e.to_string(),
        detail: None,
    }
}

/// Handler of `POST /api/optimal-posture`; a target outside the workspace is a 422.
pub async fn posture(
    State(state): State<AppState>,
    ApiJson(body): ApiJson<PostureBody>,
) -> Result<Json<OptimalPostureResponse>, ApiError> {
    let model = state.robots.resolve(&body.robot)?;
    if !(0.0..=1.0).contains(&body.alpha) {
        return Err(ApiError::bad_request(format!(
            "alpha must be in [0, 1], got {}",
            body.alpha
        )));
    }
    if body
        .target_position
        .iter()
        .any(|v| !v.is_finite() || v.abs() > 1.0e3)
    {
        return Err(ApiError::bad_request(
            "target_position must be finite and within ±1000 m",
        ));
    }
    if let Some(s) = body.starts {
        if !(1..=64).contains(&s) {
            return Err(ApiError::bad_request(format!(
                "starts must be in 1..=64, got {s}"
            )));
        }
    }
    let req = OptimalPostureRequest {
        target_position: body.target_position,
        alpha: body.alpha,
        rows: body.rows,
        starts: body.starts,
    };
    let result = tokio::task::spawn_blocking(move || optimal_posture(&model, &req))
        .await
        .map_err(internal)??;
    Ok(Json(result))
}

/// One study.
#[derive(Debug, Serialize)]
pub struct StudyInfo {
    /// Name.
    pub name: &'static str,
    /// What it reproduces.
    pub description: &'static str,
}

/// Handler of `GET /api/studies`.
pub async fn studies() -> Json<Vec<StudyInfo>> {
    Json(
        list_studies()
            .into_iter()
            .map(|(name, description)| StudyInfo { name, description })
            .collect(),
    )
}

/// Query of `POST /api/studies/{name}`.
#[derive(Debug, Deserialize)]
pub struct StudyQuery {
    /// `json` (default) or `csv`.
    pub format: Option<String>,
}

/// Handler of `POST /api/studies/{name}`: body = optional parameters object.
pub async fn study(
    Path(name): Path<String>,
    Query(q): Query<StudyQuery>,
    body: axum::body::Bytes,
) -> Result<Response, ApiError> {
    if !list_studies().iter().any(|(n, _)| *n == name) {
        let known: Vec<&str> = list_studies().iter().map(|(n, _)| *n).collect();
        return Err(ApiError::not_found(format!("unknown study `{name}`"))
            .with_detail(serde_json::json!({ "known": known })));
    }
    let params: Value = if body.iter().all(u8::is_ascii_whitespace) {
        Value::Null
    } else {
        serde_json::from_slice(&body)
            .map_err(|e| ApiError::bad_request(format!("malformed JSON: {e}")))?
    };
    let (doc, csv) = tokio::task::spawn_blocking(move || run_study(&name, &params))
        .await
        .map_err(internal)??;
    match q.format.as_deref() {
        None | Some("json") => Ok(Json(doc).into_response()),
        Some("csv") => {
            Ok(([(header::CONTENT_TYPE, "text/csv; charset=utf-8")], csv).into_response())
        }
        Some(other) => Err(ApiError::bad_request(format!(
            "format must be `json` or `csv`, got `{other}`"
        ))),
    }
}
