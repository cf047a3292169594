//! `POST /api/optimal-posture` (Jun §3, SQP over TOMM and JLM), `GET /api/studies` and
//! `POST /api/studies/{name}` (Lim §4.3 manipulability studies, workspace map). Both compute
//! on the compute pool after their limits are checked.

use axum::Json;
use axum::body::Bytes;
use axum::extract::rejection::BytesRejection;
use axum::extract::{Path, Query, State};
use axum::http::header;
use axum::response::{IntoResponse, Response};
use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::app::AppState;
use crate::compute::ComputeError;
use crate::error::ApiError;
use crate::json::{ApiJson, body_rejection};
use crate::posture::{PostureAnswer, PostureRequest};
use crate::studies::{self, STUDIES};

/// Handler of `POST /api/optimal-posture`; a target outside the workspace is a 422.
pub async fn posture(
    State(state): State<AppState>,
    ApiJson(body): ApiJson<PostureRequest>,
) -> Result<Json<PostureAnswer>, ComputeError> {
    let model = state.robots.resolve(&body.robot)?;
    let opts = body.options(&model)?;
    let answer = state
        .compute
        .run(move |_| {
            let r = seaarms_core::optimize::optimal_posture(&model, &body.target_position, &opts)?;
            Ok(PostureAnswer(r))
        })
        .await?;
    Ok(Json(answer))
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
        STUDIES
            .iter()
            .map(|&(name, description)| StudyInfo { name, description })
            .collect(),
    )
}

/// Query of `POST /api/studies/{name}`.
#[derive(Debug, Deserialize)]
pub struct StudyQuery {
    /// `json` (default) or `csv`.
    pub format: Option<String>,
}

/// Handler of `POST /api/studies/{name}`: body = optional parameters object. The parameters
/// are checked against the limits here; the study runs and is rendered on the compute pool.
pub async fn study(
    State(state): State<AppState>,
    Path(name): Path<String>,
    Query(q): Query<StudyQuery>,
    body: Result<Bytes, BytesRejection>,
) -> Result<Response, ComputeError> {
    let body = body.map_err(body_rejection)?;
    if !STUDIES.iter().any(|(n, _)| *n == name) {
        let known: Vec<&str> = STUDIES.iter().map(|(n, _)| *n).collect();
        return Err(ApiError::not_found(format!("unknown study `{name}`"))
            .with_detail(serde_json::json!({ "known": known }))
            .into());
    }
    let csv = match q.format.as_deref() {
        None | Some("json") => false,
        Some("csv") => true,
        Some(other) => {
            return Err(ApiError::bad_request(format!(
                "format must be `json` or `csv`, got `{other}`"
            ))
            .into());
        }
    };
    let params: Value = if body.iter().all(u8::is_ascii_whitespace) {
        Value::Null
    } else {
        serde_json::from_slice(&body)
            .map_err(|e| ApiError::bad_request(format!("malformed JSON: {e}")))?
    };
    let plan = studies::plan(&name, &params)?;
    let (content_type, bytes) = state
        .compute
        .run(move |cancel| {
            let out = plan.run(cancel)?;
            cancel.check()?;
            if csv {
                Ok(("text/csv; charset=utf-8", out.csv().into_bytes()))
            } else {
                let bytes = out.json(false).map_err(|_| ComputeError::Failed)?;
                Ok(("application/json", bytes))
            }
        })
        .await?;
    Ok(([(header::CONTENT_TYPE, content_type)], bytes).into_response())
}
